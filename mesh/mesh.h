#pragma once
// A triangle mesh of a trained scene's surface: marching cubes (OpenVDB's volume-to-mesh, without
// adaptivity) on the density field sampled over the scene box [-1, 1]^3 of the normalised frame.

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <functional>
#include <vector>

#include "base/enum_names.h"
#include "base/triangle_mesh.h"
#include "nerf/nerf_model.h"

namespace p2n {

// The cube meshed (export.region): the whole scene box, or a cube round what the views look at (FitCube).
enum class MeshRegion { kAuto, kBox, kFocus };
template <>
struct EnumNames<MeshRegion> {
  static constexpr std::pair<MeshRegion, const char*> kValues[] = {
      {MeshRegion::kAuto, "auto"}, {MeshRegion::kBox, "box"}, {MeshRegion::kFocus, "focus"}};
};

// Where the mesh's surface is (export.surface): where the density crosses a threshold, or where the training views'
// rendered depths agree (mesh/depth_fusion.h); auto: by the scene's kind (the export stage's
// SurfaceKind).
enum class MeshSurface { kAuto, kDensity, kDepths };
template <>
struct EnumNames<MeshSurface> {
  static constexpr std::pair<MeshSurface, const char*> kValues[] = {
      {MeshSurface::kAuto, "auto"}, {MeshSurface::kDensity, "density"}, {MeshSurface::kDepths, "depths"}};
};

struct MeshOptions {
  static constexpr const char* kName = "mesh";  // checks name mesh.FIELD
  int resolution = 256;                         // density samples along each side of the box
  float density_threshold = 25;                 // the surface: where the density (1 / world unit) crosses this
  // The box meshed: a cube of this centre and half size (world units); the scene box [-1, 1]^3 by default.
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double half_size = 1;

  template <class V>
  void Visit(V& v) {
    v("resolution", resolution);
    v("density_threshold", density_threshold);
    v("centre", centre);
    v("half_size", half_size);
  }
  // std::invalid_argument naming the field and its rule (ExtractMesh checks its options).
  void Check() const;
};

// Fits options' cube to where `points` lie (e.g. where the middle of the training views ends: the subject of an
// unbounded capture): their 5th to 95th percentile along each axis, the longest side widened by a fifth, moved and
// shrunk to stay inside the scene box [-1, 1]^3. The cube is left as it is for fewer than 100 points or when the
// points lie outside the box, unless `beyond_box` (the field covers the space beyond the box as it is: a
// forward-facing scene's frustum, whose normalisation may leave all it sees outside the box): then it spans them
// there.
void FitCube(const std::vector<Eigen::Vector3d>& points, MeshOptions* options, bool beyond_box = false);

// The field's densities (1 / world unit) at world points.
std::vector<float> DensitiesAt(const NerfModel& model, const std::vector<Eigen::Vector3d>& points);
// A density threshold for ExtractMesh from points where rendered rays end (their expected depth, where opaque):
// half the median density there. Inside a surface of density s the expected depth lies about 1 / s behind it,
// where the density is s: the threshold s / 2 puts the mesh on the surface the views see, whatever the scale
// of the densities a field learnt. 0 for no points.
float SurfaceThreshold(const NerfModel& model, const std::vector<Eigen::Vector3d>& surface_points);

// The surface where the density crosses the threshold. Cells the occupancy grid marks empty are not
// evaluated (their density counts as 0); where the surface meets the box it is closed by the box's faces, so the
// mesh is watertight. Vertices are coloured by the field seen along minus their normal (looking at the
// surface from outside). `on_slices_done`, when given, is called with the number of density slices just
// sampled (resolution in all), from TBB's threads but never two calls at once.
Mesh ExtractMesh(const NerfModel& model, const MeshOptions& options,
                 const std::function<void(size_t)>& on_slices_done = {});

// The centre of lattice cell (i, j, k) of the options' cube, `resolution` cells a side (fractional indices
// interpolate).
Eigen::Vector3d LatticePoint(const MeshOptions& options, double i, double j, double k);

// The zero crossing of a level set sampled on the options' lattice (value (i * n + j) * n + k at LatticePoint(i, j,
// k), in [-1, 1], negative inside; FuseDepths's), where every corner of the cell it crosses is below 1 in magnitude:
// a step between saturated values (behind a surface and seen through or never seen; the cube's edge) is no surface.
// Normals from the triangles, colours from the field seen from outside.
Mesh ExtractFusedSurface(const NerfModel& model, const MeshOptions& options, const std::vector<float>& level_set);

// `triangles` (of `mesh`'s vertices) with the vertices they use, renumbered in order of first use, with their
// normals and colours.
Mesh WithTriangles(const Mesh& mesh, const std::vector<std::array<uint32_t, 3>>& triangles);

// The field's colour at surface points (normalised frame) seen from outside, along minus their unit normals.
std::vector<std::array<uint8_t, 3>> SurfaceColours(const NerfModel& model, const std::vector<Eigen::Vector3f>& points,
                                                   const std::vector<Eigen::Vector3f>& normals);

// How closed a mesh is, by its undirected edges (vertices compared by index): an edge of one triangle is on a
// hole's border, an edge of three or more is non-manifold, and a pair of triangles that runs an edge the same
// way round is inconsistently oriented.
struct MeshEdges {
  size_t edges = 0, border = 0, non_manifold = 0, misoriented = 0;
  // Closed and consistently oriented: every edge shared by exactly two triangles running it opposite ways.
  bool watertight() const { return edges > 0 && border == 0 && non_manifold == 0 && misoriented == 0; }
};
MeshEdges CountEdges(const Mesh& mesh);

}  // namespace p2n

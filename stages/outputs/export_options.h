#pragma once
// The export stage's options (export.*), apart from the stage as every stage's are.

#include "formats/output_frame.h"
#include "mesh/mesh.h"
#include "pipeline/options.h"

namespace p2n {

struct ExportOptions {
  static constexpr const char* kSection = "export";  // its options are export.NAME

  MeshSurface surface = MeshSurface::kAuto;
  int resolution = 256;                  // density samples along each side of the scene box
  double threshold = 0;                  // surface density (1 / normalised unit); 0: from the field (SurfaceThreshold)
  FrameKind frame = FrameKind::kSource;  // the files' coordinates
  bool obj = false;                      // also write mesh.obj (textured, with mesh.mtl)
  int max_triangles = 200000;            // the mesh simplified to at most this many; 0: as marching cubes made it
  int texture_size = 2048;               // the side of the textured mesh's texture
  bool points = true;                    // write points.ply
  int points_width = 128;        // the training views are rendered this wide for the point cloud (at most 2 M pixels)
  double points_opacity = 0.95;  // pixels at least this opaque give points
  MeshRegion region = MeshRegion::kAuto;  // the cube meshed

  template <class V>
  void Visit(V& v) {
    v("surface", surface,
      "where the mesh's surface is: density (where the field's density crosses export.threshold), depths (where "
      "the training views' rendered depths agree: a fused signed distance), auto: depths for unbounded and "
      "forward-facing scenes (their floaters carved away), density for bounded ones");
    v("resolution", resolution, "density samples along each side of the scene box (memory and time grow as its cube)",
      "samples");
    v("threshold", threshold,
      "the surface's density, per normalised unit; 0: half the median density where the "
      "training views' rays end (mesh/mesh.h)",
      "1/unit");
    v("frame", frame,
      "coordinates of the files: source (COLMAP's world, or the dataset's) or normalized (the "
      "training frame)");
    v("obj", obj, "also write the textured mesh as mesh.obj (with mesh.mtl and mesh_texture.jpg)");
    v("max_triangles", max_triangles,
      "the mesh is simplified (edge collapses) to at most this many triangles; 0: keep every one", "triangles");
    v("texture_size", texture_size, "side of the square texture of mesh.glb (and mesh.obj)", "pixels");
    v("points", points, "write points.ply, a coloured point cloud from the rendered depth of the training views");
    v("points_width", points_width,
      "width the training views are rendered at for the point cloud (narrower beyond 2 M pixels in all)", "pixels");
    v("points_opacity", points_opacity, "pixels at least this opaque give points");
    v("region", region,
      "the cube meshed: box (the whole scene box [-1, 1]^3), focus (around where the middle of the training views "
      "ends: the subject, not the walls and floaters around it), auto: focus for unbounded and forward-facing "
      "scenes, box for bounded ones");
  }
  void Check() const;
};

}  // namespace p2n

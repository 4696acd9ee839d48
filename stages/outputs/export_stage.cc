#include "stages/outputs/export_stage.h"

#include <Eigen/Geometry>

#include <cmath>
#include <map>
#include <optional>

#include "base/camera.h"
#include "base/errors.h"
#include "base/file_util.h"
#include "base/format.h"
#include "formats/dataset_import.h"
#include "formats/gltf_io.h"
#include "formats/mesh_io.h"
#include "formats/output_frame.h"
#include "formats/ply.h"
#include "formats/transforms_json.h"
#include "mesh/depth_fusion.h"
#include "mesh/mesh.h"
#include "mesh/mesh_simplify.h"
#include "mesh/texture_atlas.h"
#include "nerf/nerf_model.h"
#include "nerf/renderer.h"
#include "photo2nerf/version.h"
#include "pipeline/cancel.h"
#include "pipeline/log.h"
#include "pipeline/progress.h"
#include "stages/camera_corrections.h"
#include "stages/stage_io.h"
#include "stages/stage_reports.h"
#include "stages/view_renders.h"

namespace p2n {
namespace fs = std::filesystem;
namespace {

constexpr float kFallbackThreshold = 25;  // per normalised unit: what fits lego's surface
// mesh_preview.glb, the report page's view: about 1.5 MB
constexpr size_t kPreviewTriangles = 20000;
constexpr int kPreviewTextureSize = 1024;
// The depth surface and the point cloud come from at most this many training views, spread out (SpreadCameras):
// fusing them costs the lattice's points times the views, and a few hundred views around a scene see what a
// thousand do.
constexpr size_t kMaxDepthViews = 200;

// The training views' cameras as the field saw them: corrected where camera refinement moved them.
void ApplyCameraCorrections(const std::map<std::string, CameraCorrection>& corrections, ImportedDataset* dataset) {
  for (ImportedView& view : dataset->views) {
    const auto found = corrections.find(view.source.filename().string());
    if (view.view.split == ViewSplit::kTrain && found != corrections.end()) {
      view.view.camera = CorrectedCamera(view.view.camera, found->second.data());
    }
  }
}

// transforms.json of every view (the training ones as refined) in the files' frame, naming the images by their full
// paths so that the file works from where it is.
void WriteCameras(const fs::path& path, const ImportedDataset& dataset, const OutputFrame& frame, bool refined) {
  TransformsFile transforms;
  for (const ImportedView& view : dataset.views) {
    transforms.views.push_back(frame.Camera(view.view));
    transforms.views.back().file_path = fs::absolute(view.source).string();
  }
  transforms.meta.frame = frame.description;
  transforms.meta.cameras_refined = refined;
  transforms.Write(path);
}

// export.region resolved: box or focus.
MeshRegion RegionKind(const NerfModel& model, const ExportOptions& options) {
  if (options.region != MeshRegion::kAuto) return options.region;
  return model.space == SceneSpace::kBounded ? MeshRegion::kBox : MeshRegion::kFocus;
}

// export.surface resolved: the depths fused where a field's floaters and unseen space are (unbounded and
// forward-facing scenes), the density where the scene is an object in a box (docs/benchmarks.md).
MeshSurface SurfaceKind(const NerfModel& model, const ExportOptions& options) {
  if (options.surface != MeshSurface::kAuto) return options.surface;
  return model.space == SceneSpace::kBounded ? MeshSurface::kDensity : MeshSurface::kDepths;
}

// Where the training views' rays end (their median depth), where they are opaque: at most kMaxDepthViews of them.
struct DepthSamples {
  std::vector<ColouredPoint> points;  // coloured, one per opaque pixel (at most kMaxSmallViewPixels)
  // Every one from the middle half (in width and height) of each view; only for the focus region (FitCube).
  std::vector<Eigen::Vector3d> central;
  std::shared_ptr<const ViewRenders> views;  // the renders they come from
};

DepthSamples SampleDepths(const StageContext& context, const fs::path& model_file, const NerfModel& model,
                          const ImportedDataset& dataset, const ExportOptions& options) {
  std::vector<TrainView> training;  // the training views' cameras, without their pixels
  std::vector<PinholeCamera> cameras;
  for (const ImportedView& view : dataset.views) {
    if (view.view.split != ViewSplit::kTrain) continue;
    training.push_back({view.view.camera, view.view.near, view.view.far, 3, {}, view.source.filename().string(), {}});
    cameras.push_back(view.view.camera);
  }
  std::vector<TrainView> views;
  for (size_t i : SpreadCameras(cameras, kMaxDepthViews)) views.push_back(std::move(training[i]));
  const std::shared_ptr<const ViewRenders> views_rendered =
      RenderViewsSmall(context, model_file, model, views, options.points_width, "export: point cloud");
  DepthSamples samples;
  samples.views = views_rendered;
  const bool want_central = RegionKind(model, options) == MeshRegion::kFocus;
  for (size_t v = 0; v < views.size(); ++v) {
    const PinholeCamera& camera = views_rendered->cameras[v];
    const RenderedView& rendered = views_rendered->renders[v];
    for (int y = 0; y < camera.height; ++y) {
      for (int x = 0; x < camera.width; ++x) {
        const size_t i = size_t(y) * camera.width + x;
        if (rendered.opacity.pixels[i] < options.points_opacity) continue;
        const Ray ray = CameraRay(camera, x + 0.5, y + 0.5);
        const Eigen::Vector3d p = ray.origin + rendered.depth.pixels[i] * ray.direction;
        if (!p.allFinite()) continue;
        if (want_central && 4 * std::abs(2 * x + 1 - camera.width) < 2 * camera.width &&
            4 * std::abs(2 * y + 1 - camera.height) < 2 * camera.height)
          samples.central.push_back(p);
        if (model.space == SceneSpace::kBounded && p.cwiseAbs().maxCoeff() > 1) continue;
        ColouredPoint& point = samples.points.emplace_back();
        point.position = p.cast<float>();
        for (int c = 0; c < 3; ++c) {
          point.rgb[c] =
              static_cast<uint8_t>(std::lround(255 * std::clamp(rendered.rgb.pixels[3 * i + c], 0.0f, 1.0f)));
        }
      }
    }
  }
  return samples;
}

// The mesh's region, resolution and threshold: export.threshold, or, when it is 0, SurfaceThreshold at the depth
// points inside the region (the fixed kFallbackThreshold when no pixel of a training view is opaque there).
MeshOptions ChooseMeshOptions(const NerfModel& model, const ExportOptions& options, const DepthSamples& depths) {
  MeshOptions mesh;
  mesh.resolution = options.resolution;
  if (RegionKind(model, options) == MeshRegion::kFocus)
    FitCube(depths.central, &mesh, model.space == SceneSpace::kForward);
  mesh.density_threshold = static_cast<float>(options.threshold);
  if (options.threshold > 0) return mesh;
  std::vector<Eigen::Vector3d> surface;
  for (const ColouredPoint& point : depths.points) {
    // Only what the mesh covers: beyond the box an unbounded field's densities are in contracted units.
    const Eigen::Vector3d p = point.position.cast<double>();
    if ((p - mesh.centre).cwiseAbs().maxCoeff() <= mesh.half_size) surface.push_back(p);
  }
  const float threshold = SurfaceThreshold(model, surface);
  mesh.density_threshold = threshold > 0 ? threshold : kFallbackThreshold;
  return mesh;
}

// The surface (a Mesh or a TexturedMesh) in the files' frame: points mapped, normals turned, triangles turned over
// where the frame mirrors.
template <class SomeMesh>
SomeMesh InFrame(SomeMesh mesh, const OutputFrame& frame) {
  for (Eigen::Vector3f& p : mesh.positions) p = frame.Point(p);
  for (Eigen::Vector3f& n : mesh.normals) n = frame.Direction(n);
  if (frame.rotation.determinant() < 0) {
    for (auto& t : mesh.triangles) std::swap(t[1], t[2]);
  }
  return mesh;
}

// `surface` textured with the field's colour in a square of `texture_size`: with the texture as JPEG, or none when
// the texture has no room for the surface's charts (a warning says so).
std::optional<std::pair<TexturedMesh, std::string>> Bake(const NerfModel& model, const Mesh& surface,
                                                         int texture_size) {
  try {
    TexturedMesh textured = BakeTexture(surface, texture_size, [&](const auto& points, const auto& normals) {
      return SurfaceColours(model, points, normals);
    });
    std::string jpeg = TextureJpeg(textured);
    return std::pair{std::move(textured), std::move(jpeg)};
  } catch (const UserError& e) {
    LogWarning(format("export: no textured mesh: {}", e.what()));
    return std::nullopt;
  }
}

// The simplified surface textured: mesh_texture.jpg, mesh.glb, mesh_preview.glb (smaller, for the report page),
// and mesh.obj with mesh.mtl when asked. Nothing when the texture has no room for the surface (Bake).
ExportReport::Textured WriteTextured(const NerfModel& model, const ExportOptions& options, const Mesh& mesh,
                                     const OutputFrame& frame, const std::vector<std::string>& comments,
                                     const ExportResult& out) {
  Progress progress("export: texture", 2, "textures");
  const std::string generator = "photo2nerf " + std::string(kVersion);
  const auto baked = Bake(model, mesh, options.texture_size);
  if (!baked) return {};
  const auto& [textured, jpeg] = *baked;
  WriteFileAtomic(out.mesh_glb(), MeshGlbBytes(InFrame(textured, UprightFrame(frame)), jpeg, generator));
  WriteFileAtomic(out.texture(), jpeg);
  progress.Add(1);
  if (const auto preview = Bake(model, SimplifyMesh(mesh, kPreviewTriangles).mesh,
                                std::min(options.texture_size, kPreviewTextureSize))) {
    WriteFileAtomic(out.mesh_preview(),
                    MeshGlbBytes(InFrame(preview->first, UprightFrame(frame)), preview->second, generator));
  }
  progress.Add(1);
  ExportReport::Textured report{ExportResult{}.mesh_glb().string(), fs::file_size(out.mesh_glb()),
                                ExportResult{}.texture().string(), options.texture_size, ""};
  if (options.obj) {
    WriteTexturedObj(out.mesh_obj(), InFrame(textured, frame), out.texture().filename().string(), comments);
    report.obj = ExportResult{}.mesh_obj().string();
  }
  return report;
}

// The surface export.surface chooses, over the cube and at the resolution of `mesh_options`.
Mesh ExtractSurface(const NerfModel& model, const ExportOptions& options, const MeshOptions& mesh_options,
                    const DepthSamples& depths) {
  if (SurfaceKind(model, options) == MeshSurface::kDepths) {
    std::vector<DepthMap> maps;
    for (size_t v = 0; v < depths.views->cameras.size(); ++v) {
      const RenderedView& rendered = depths.views->renders[v];
      maps.push_back({depths.views->cameras[v], &rendered.depth, &rendered.opacity});
    }
    return ExtractFusedSurface(model, mesh_options, FuseDepths(maps, mesh_options, {}));
  }
  Progress progress("export: density", options.resolution, "slices");
  return ExtractMesh(model, mesh_options, [&](size_t n) {
    progress.Add(static_cast<int64_t>(n));
    ThrowIfCancelled();
  });
}

// Extracts the mesh (ChooseMeshOptions, ExtractSurface) and simplifies it to export.max_triangles; writes mesh.ply
// in `frame` and the textured files (WriteTextured); returns what the report says of them.
ExportReport::Mesh WriteMesh(const NerfModel& model, const ExportOptions& options, const DepthSamples& depths,
                             const OutputFrame& frame, const ExportResult& out, ExportReport::Textured* textured) {
  const MeshOptions mesh_options = ChooseMeshOptions(model, options, depths);
  const Mesh marched = ExtractSurface(model, options, mesh_options, depths);
  const SimplifiedMesh simplified =
      SimplifyMesh(marched, options.max_triangles > 0 ? size_t(options.max_triangles) : marched.triangles.size());
  const Mesh& mesh = simplified.mesh;
  const MeshEdges edges = CountEdges(mesh);
  const MeshRegion region = RegionKind(model, options);
  const bool auto_threshold = options.threshold == 0;
  const std::vector<std::string> comments = {
      frame.description,
      format("marching cubes at {}^3 samples of the cube of half size {:.4g} around ({:.4g}, {:.4g}, {:.4g}) "
             "(normalised; the {}), {}; {} of its {} triangles kept",
             options.resolution, mesh_options.half_size, mesh_options.centre.x(), mesh_options.centre.y(),
             mesh_options.centre.z(), region == MeshRegion::kBox ? "scene box" : "focus region",
             SurfaceKind(model, options) == MeshSurface::kDepths
                 ? format("the depths of {} training views fused", depths.views->renders.size())
                 : format("density threshold {:.4g}{}", mesh_options.density_threshold,
                          auto_threshold ? " (from the field)" : ""),
             mesh.triangles.size(), marched.triangles.size())};
  WriteMeshPly(out.mesh(), InFrame(mesh, frame), comments);
  if (mesh.triangles.empty() && SurfaceKind(model, options) == MeshSurface::kDepths) {
    LogWarning("export: no training view sees a surface inside the region meshed: the mesh is empty");
  } else if (mesh.triangles.empty()) {
    LogWarning(
        format("export: the density never reaches {:.4g} inside the region meshed: the mesh is empty; lower --{}",
               mesh_options.density_threshold, OptionKey(&ExportOptions::threshold)));
  } else {
    *textured = WriteTextured(model, options, mesh, frame, comments, out);
  }
  return {ExportResult{}.mesh().string(),
          mesh.positions.size(),
          mesh.triangles.size(),
          marched.triangles.size(),
          simplified.error * frame.Scale(),
          edges.watertight(),
          edges.border,
          edges.non_manifold,
          edges.misoriented,
          options.resolution,
          mesh_options.density_threshold,
          auto_threshold,
          region,
          {mesh_options.centre.x(), mesh_options.centre.y(), mesh_options.centre.z()},
          mesh_options.half_size,
          SurfaceKind(model, options)};
}

}  // namespace

void ExportOptions::Check() const {
  CheckField(*this, resolution, resolution >= 8 && resolution <= 1024, "must be 8..1024");
  CheckField(*this, threshold, threshold >= 0 && std::isfinite(threshold), "must be 0 (from the field) or positive");
  CheckField(*this, points_width, points_width >= 8 && points_width <= 8192, "must be 8..8192");
  CheckField(*this, max_triangles, max_triangles >= 0, "must be 0 (all) or positive");
  CheckField(*this, texture_size, texture_size >= 64 && texture_size <= 16384, "must be 64..16384");
  CheckField(*this, points_opacity, points_opacity > 0 && points_opacity <= 1, "must be in (0, 1]");
}

void ExportStage::Run(StageContext& context) const {
  const ExportOptions options = ReadOptions<ExportOptions>(context.config);
  const TrainResult train = Upstream<TrainResult>(context);
  const fs::path model_file = train.model();
  const TrainedField trained = ReadTrainedField(train);
  const NerfModel& model = trained.model;
  ImportedDataset dataset = LoadTransformsJson(Upstream<PosesResult>(context).transforms(), context.workspace.root());
  const OutputFrame frame = MakeOutputFrame(options.frame, dataset);
  const std::map<std::string, CameraCorrection>& corrections = trained.corrections;
  ApplyCameraCorrections(corrections, &dataset);
  DepthSamples depths;
  if (options.points || options.threshold == 0 || RegionKind(model, options) == MeshRegion::kFocus ||
      SurfaceKind(model, options) == MeshSurface::kDepths)
    depths = SampleDepths(context, model_file, model, dataset, options);

  const ExportResult out{context.output_dir};
  ExportReport report;
  report.mesh = WriteMesh(model, options, depths, frame, out, &report.textured);
  report.frame = options.frame;
  WriteCameras(out.cameras(), dataset, frame, !corrections.empty());
  report.cameras = {ExportResult{}.cameras().string(), dataset.views.size(), !corrections.empty()};
  if (depths.views) report.depth_views = depths.views->renders.size();
  if (options.points) {
    std::vector<ColouredPoint>& points = depths.points;
    for (ColouredPoint& point : points) point.position = frame.Point(point.position);
    WritePly(out.points(), points,
             {frame.description,
              format("points where the rendered opacity of a training view is at least {}", options.points_opacity)});
    report.points = ExportedPoints{ExportResult{}.points().string(), points.size()};
  }
  WriteJsonAtomic(out.report(), report.ToJson());
  const ExportReport::Mesh& mesh = report.mesh;
  context.summary = {{"mesh_triangles", mesh.triangles}, {"watertight", mesh.watertight}};
  if (report.points) context.summary["points"] = report.points->count;
  LogInfo(format("export: mesh of {} vertices and {} triangles ({}watertight) at density {:.4g}{}", mesh.vertices,
                 mesh.triangles, mesh.watertight ? "" : "not ", mesh.threshold,
                 report.points ? format(", {} points", report.points->count) : ""));
}

}  // namespace p2n

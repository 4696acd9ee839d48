#pragma once
// Each stage's identity and what it writes, declared once (docs/design.md §2). A stage class takes its name and folder
// from its result type (StageOf<R>); whatever reads a result, a later stage or the CLI, takes the paths from the
// same type. A result is a folder: a complete one in the workspace, or the staging folder its stage writes into;
// with an empty folder (SplatResult{}.splats()) each file's path is its name inside the result.

#include <filesystem>
#include <optional>
#include <string>

#include "base/format.h"
#include "pipeline/stage.h"
#include "pipeline/workspace.h"

namespace p2n {

// A stage's name (on the command line, in upstream lists and manifests) and its folder in the workspace.
struct StageId {
  const char* name;
  const char* folder;
};

struct IngestResult {
  static constexpr StageId kId{"ingest", "00_ingest"};
  std::filesystem::path dir;
  std::filesystem::path images() const { return dir / "images"; }
  std::filesystem::path masks() const { return dir / "masks"; }  // the photos' masks, named as their images
  std::filesystem::path report() const { return dir / "ingest_report.json"; }
};

struct SfmResult {
  static constexpr StageId kId{"sfm", "10_sfm"};
  std::filesystem::path dir;
  std::filesystem::path report() const { return dir / "sfm_report.json"; }
  std::filesystem::path database() const { return dir / "database.db"; }
  std::filesystem::path vocab_tree() const { return dir / "vocab_tree.bin"; }
  std::filesystem::path logs() const { return dir / "logs"; }
  // The chosen model undistorted to pinhole cameras, in COLMAP's layout: its images and its model.
  std::filesystem::path undistorted() const { return dir / "undistorted"; }
  std::filesystem::path undistorted_images() const { return undistorted() / "images"; }
  std::filesystem::path undistorted_model() const { return undistorted() / "sparse"; }
  // The photos' masks undistorted as their images, named as them (when the photo folder has masks).
  std::filesystem::path undistorted_masks() const { return dir / "undistorted_masks" / "images"; }
};

// Written by the poses stage from COLMAP's model, or by the import stage from a dataset with cameras.
struct PosesResult {
  static constexpr StageId kId{"poses", "20_poses"};
  std::filesystem::path dir;
  std::filesystem::path transforms() const { return dir / "transforms.json"; }
  std::filesystem::path sparse_points() const { return dir / "sparse_points.ply"; }
  std::filesystem::path sparse_tracks() const { return dir / "sparse_tracks.json"; }  // formats/sparse_tracks.h
  std::filesystem::path images() const { return dir / "images"; }  // images imported or downsized here, if any
};

struct TrainResult {
  static constexpr StageId kId{"train", "30_train"};
  std::filesystem::path dir;
  std::filesystem::path model() const { return dir / "model.bin"; }
  std::filesystem::path report() const { return dir / "train_report.json"; }
  std::filesystem::path metrics() const { return dir / "metrics.csv"; }
  std::filesystem::path psnr_plot() const { return dir / "psnr.png"; }
};

struct SplatResult {
  static constexpr StageId kId{"splat", "35_splat"};
  std::filesystem::path dir;
  std::filesystem::path splats() const { return dir / "splats.ply"; }
  std::filesystem::path spz() const { return dir / "splats.spz"; }  // the same splats in Niantic's SPZ
  std::filesystem::path glb() const { return dir / "splats.glb"; }  // and in glTF (KHR_gaussian_splatting), upright
  std::filesystem::path report() const { return dir / "splat_report.json"; }
  std::filesystem::path viewer() const { return dir / "viewer.html"; }
  std::filesystem::path metrics() const { return dir / "metrics.csv"; }
  std::filesystem::path psnr_plot() const { return dir / "psnr.png"; }
};

struct RenderResult {
  static constexpr StageId kId{"render", "40_render"};
  std::filesystem::path dir;
  std::filesystem::path eval() const { return dir / "eval.json"; }             // the held-out views' scores
  std::filesystem::path report() const { return dir / "render_report.json"; }  // the camera path's
  std::filesystem::path heldout() const { return dir / "heldout"; }
  std::filesystem::path path() const { return dir / "path.json"; }
  std::filesystem::path frames() const { return dir / "frames"; }
  // Frame `index` of the path is frames/NNNN.png (and .exr), depth/NNNN.png, opacity/NNNN.png.
  static std::string FrameStem(int index) { return format("{:04d}", index); }
  std::filesystem::path depth() const { return dir / "depth"; }
  std::filesystem::path opacity() const { return dir / "opacity"; }
  std::filesystem::path video() const { return dir / "video.mp4"; }
};

struct ExportResult {
  static constexpr StageId kId{"export", "50_export"};
  std::filesystem::path dir;
  std::filesystem::path mesh() const { return dir / "mesh.ply"; }
  std::filesystem::path mesh_obj() const { return dir / "mesh.obj"; }
  std::filesystem::path mesh_mtl() const { return dir / "mesh.mtl"; }
  std::filesystem::path mesh_glb() const { return dir / "mesh.glb"; }
  std::filesystem::path mesh_preview() const { return dir / "mesh_preview.glb"; }  // small, for the report page
  std::filesystem::path texture() const { return dir / "mesh_texture.jpg"; }
  std::filesystem::path points() const { return dir / "points.ply"; }
  std::filesystem::path cameras() const { return dir / "transforms.json"; }
  std::filesystem::path report() const { return dir / "export_report.json"; }
};

struct ReportResult {
  static constexpr StageId kId{"report", "60_report"};
  std::filesystem::path dir;
  std::filesystem::path page() const { return dir / "report.html"; }
};

// A stage's checkpoint in its resume folder (StageContext::resume_dir).
inline std::filesystem::path CheckpointFile(const StageContext& context) {
  return context.resume_dir / "checkpoint.bin";
}

// The stage that writes `Result`: its name and folder come from Result::kId.
template <class Result>
class StageOf : public Stage {
 public:
  std::string name() const override { return Result::kId.name; }
  std::string folder() const override { return Result::kId.folder; }
};

// The result of upstream stage `Result` that `context`'s stage reads (std::out_of_range when it does not).
template <class Result>
Result Upstream(const StageContext& context) {
  return Result{context.upstream_dirs.at(Result::kId.name)};
}

// The same, or nothing when the stage's options leave that stage out (Stage::UpstreamFor).
template <class Result>
std::optional<Result> UpstreamIfRead(const StageContext& context) {
  const auto found = context.upstream_dirs.find(Result::kId.name);
  if (found == context.upstream_dirs.end()) return std::nullopt;
  return Result{found->second};
}

// The result's paths relative to the workspace (for messages: WorkspaceRelative<SfmResult>().report() is
// 10_sfm/sfm_report.json).
template <class Result>
Result WorkspaceRelative() {
  return Result{Result::kId.folder};
}

// The result's folder in `workspace`, made or not.
template <class Result>
Result InWorkspace(const Workspace& workspace) {
  return Result{workspace.StageDir(Result::kId.folder)};
}

}  // namespace p2n

#pragma once
// The reports that one stage writes and others read (docs/design.md §5), one struct each: the writer fills it and
// writes it with ToJson(), every reader reads it with Read(), both from one declaration of its JSON per struct
// (Describe in stage_reports.cc), so a field has one name and one type. A reader
// meets a missing or mistyped field as a UserError that names the file and the field and says which stage to
// rerun, never as an internal error at a distance.
//   00_ingest/ingest_report.json IngestReport (its image-count check, the sfm stage's camera groups)
//   10_sfm/sfm_report.json       SfmReport   (the sfm stage's registration check, report)
//   30_train/train_report.json   TrainReport (splat, render and export through ReadTrainedField, report)
//   35_splat/splat_report.json   SplatReport (render, its view renderer, report, splat_bench)
//   40_render/eval.json          EvalReport  (report, the run summary)
//   40_render/render_report.json PathReport, under "path" (report)
//   50_export/export_report.json ExportReport (report)

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "base/enum_names.h"
#include "formats/output_frame.h"
#include "formats/transforms_json.h"
#include "mesh/mesh.h"
#include "stages/fitting/splat_options.h"
#include "stages/fitting/train_options.h"

namespace p2n {

// One photo as ingest wrote it to images/.
struct IngestedImage {
  std::string name;    // output file name inside images/
  std::string source;  // input file name
  int width = 0, height = 0, channels = 0;
  int source_width = 0, source_height = 0;
  int orientation = 1;  // EXIF (written "exif_orientation")
  bool from_cmyk = false;
  std::string fingerprint;      // of the decoded pixels: copies of one photo share it
  std::string camera;           // CameraIdentity of its EXIF, or "video FILE" for a video's frames; may be empty
  std::optional<size_t> frame;  // a video's frame: its index in the video named by `source`
  std::optional<double> time;   // and its time stamp, in seconds
};

// A file ingest left out, and why.
struct SkippedPhoto {
  std::string file, reason;
};

// A video ingest took frames from (frame_choice.h): every frame's sharpness, the frames taken, the repeats left
// out; every other frame was left out for a sharper one of its window.
struct IngestedVideo {
  std::string file;
  size_t frames = 0;  // decoded
  double fps = 0, seconds = 0;
  int width = 0, height = 0;      // of the decoded frames, turned as the video says
  std::vector<double> sharpness;  // each frame's, as frame_choice.h measures it
  struct Frame {
    size_t index = 0;
    double time = 0;    // seconds
    std::string image;  // its name in images/ (a copy of an earlier image is then skipped under this name)
  };
  std::vector<Frame> taken;
  struct Repeat {
    size_t index = 0, of = 0;  // a frame left out, and the taken frame it nearly repeats
  };
  std::vector<Repeat> repeats;
};

struct IngestReport {
  std::string input_folder;  // or the one video given
  std::vector<IngestedImage> images;
  std::vector<SkippedPhoto> skipped;
  std::vector<IngestedVideo> videos;

  nlohmann::json ToJson() const;
  static IngestReport Read(const std::filesystem::path& file);
};

// Why the mapper left a photo out of the chosen model (left_out.h says how each is decided).
enum class LeftOutReason { kNoFeatures, kNoMatches, kApart, kTooFewInliers, kOtherModel, kNotPlaced, kUnknown };
template <>
struct EnumNames<LeftOutReason> {
  static constexpr std::pair<LeftOutReason, const char*> kValues[] = {
      {LeftOutReason::kNoFeatures, "no_features"},
      {LeftOutReason::kNoMatches, "no_matches"},
      {LeftOutReason::kApart, "apart"},
      {LeftOutReason::kTooFewInliers, "too_few_inliers"},
      {LeftOutReason::kOtherModel, "other_model"},
      {LeftOutReason::kNotPlaced, "not_placed"},
      {LeftOutReason::kUnknown, "unknown"}};
};

struct SfmReport {
  size_t images_given = 0, registered = 0, points = 0;
  double registered_percent = 0;
  struct LeftOut {
    std::string image;
    LeftOutReason reason = LeftOutReason::kNotPlaced;
    std::string detail;  // the figures behind the reason, as a sentence
  };
  std::vector<LeftOut> left_out;  // photos COLMAP did not register in the chosen model
  double mean_reprojection_error_px = 0, mean_track_length = 0;
  std::optional<double> median_axis_to_focus_angle_deg;  // none when the cameras have no common focus point
  std::string colmap_version, matcher, chosen_model;
  struct Model {
    std::string path;  // relative to 10_sfm/
    size_t registered = 0;
  };
  std::vector<Model> models;  // every model COLMAP's mapper made
  struct Step {
    std::string step, log;
    double wall_seconds = 0;
  };
  std::vector<Step> steps;  // the COLMAP runs in order

  nlohmann::json ToJson() const;
  static SfmReport Read(const std::filesystem::path& file);
};

// A sign of a failed fit that a stage found in its own result (fit_checks.h): a code, the figure that tripped it,
// and a sentence saying what it means and what to try.
struct FitWarning {
  std::string code;
  double figure = 0;
  std::string message;
};

struct TrainReport {
  int steps = 0, skipped_steps = 0, resumed_from_step = 0;
  double wall_seconds = 0;  // of training
  size_t training_views = 0, heldout_views = 0;
  // The training photos in memory at once when they did not all fit (train.photo_memory); none when all were.
  std::optional<size_t> training_views_in_memory;
  // false: each evaluation read the held-out photos from their decoded copy (beside the training photos they did not
  // fit in train.photo_memory); older reports: true.
  bool heldout_views_in_memory = true;
  ViewSplit heldout_split = ViewSplit::kVal;
  int heldout_pixels_per_view = 0;     // 0: every pixel (written "all")
  std::optional<double> heldout_psnr;  // none without held-out views
  // The sample spacing of that evaluation, as a multiple of the march step (render.step_scale's meaning); none in
  // reports written before it was recorded.
  std::optional<double> heldout_step_scale;
  // Each held-out photo scored as NeRF-W does (its colour transform fitted on its left half, PSNR on the right).
  std::optional<double> heldout_psnr_fitted;
  struct ViewPsnr {
    std::string view;
    double psnr = 0;
  };
  std::vector<ViewPsnr> heldout_per_view;
  std::string heldout_rule;             // how the held-out views were chosen (transforms.json); empty: the dataset's
  std::optional<double> training_psnr;  // some training views scored as the held-out ones (none in older reports)
  std::vector<FitWarning> warnings;     // signs of a failed fit (none in older reports)
  struct Evaluations {
    int count = 0;
    double seconds = 0;
    int pixels_per_view = 0;  // 0: every pixel
  } evaluations_during_training;
  double samples_per_ray_rendered = 0, render_seconds_per_view = 0, occupied_fraction = 0;
  // The steps of this session of the run (a resumed run counts from its resumption): their time, the rays they
  // trained on and the samples they marched and evaluated. None in reports written before it was recorded.
  struct Throughput {
    int steps = 0;
    double seconds = 0;
    size_t rays = 0, samples = 0;
    double SamplesPerSecond() const { return seconds > 0 ? samples / seconds : 0.0; }
    double SamplesPerRay() const { return rays > 0 ? double(samples) / rays : 0.0; }
  };
  std::optional<Throughput> throughput;
  nlohmann::json field = nlohmann::json::object();  // the field's config, as MakeField reads it
  struct Trainer {
    double march_step = 0;           // sample spacing along a ray (unbounded: near the centre), at the start
    double rendered_march_step = 0;  // the model's at the end, which renders use (finer after a refinement)
    double learning_rate = 0, distortion_weight = 0;
    size_t batch_samples = 0;
    size_t late_batch_samples = 0;  // in the run's second half; 0: batch_samples throughout
    std::string scene;              // bounded | unbounded | forward
    bool appearance = false, refine_cameras = false, error_sampling = false;
    BackgroundChoice background = BackgroundChoice::kFixed;  // random (behind images with alpha), learnt or fixed
    std::array<double, 3> background_colour{};  // behind the scene after training (the learnt one, or the fixed)
  } trainer;
  struct AppearanceView {
    std::string view;
    double gain = 0;  // what the transform makes of white
    std::vector<float> transform;
  };
  struct Appearance {
    bool enabled = false;
    double gain_min = 0, gain_max = 0;
    std::vector<AppearanceView> per_view;
  } appearance;
  // The section camera_corrections.h writes (CameraRefinementJson) and reads back (CameraCorrections), and
  // the summary of it that Read() takes from it.
  nlohmann::json camera_refinement = {{"enabled", false}};
  struct Refinement {
    bool enabled = false;
    double rotation_degrees_median = 0, rotation_degrees_max = 0, shift_median = 0, shift_max = 0;
  } refinement;

  nlohmann::json ToJson() const;
  static TrainReport Read(const std::filesystem::path& file);
};

struct SplatReport {
  bool enabled = false;  // false: the stage was off, and nothing else is written
  size_t splats = 0, initial_splats = 0;
  SplatInit init = SplatInit::kField;  // where the first splats came from: the field or the sparse points
  double view_share = 1;  // the mean share of the splats placed a training view sees (splat/scene_size.h); older: 1
  int sh_degree = 0, steps = 0, resumed_from_step = 0;
  double seconds = 0;  // of optimisation
  size_t heldout_views = 0;
  // The training photos in memory at once when they did not all fit (splat.photo_memory); none when all were.
  std::optional<size_t> training_views_in_memory;
  bool heldout_views_in_memory = true;               // as the train report's (splat.photo_memory)
  std::optional<double> heldout_psnr, heldout_ssim;  // none without held-out views
  std::vector<double> heldout_psnr_per_view;
  double seconds_per_view = 0;  // rendering a held-out view on the CPU
  FrameKind frame = FrameKind::kNormalized;
  std::string frame_description;
  double near = 0.01;
  std::array<float, 3> background{1, 1, 1};
  size_t file_bytes = 0, spz_bytes = 0, glb_bytes = 0, viewer_bytes = 0;  // splats.ply, .spz, .glb, viewer.html
  std::vector<FitWarning> warnings;  // signs of a failed fit (none in older reports)

  nlohmann::json ToJson() const;
  static SplatReport Read(const std::filesystem::path& file);
};

// One held-out view's scores and images (paths of the render and the error map relative to 40_render/).
struct HeldoutScore {
  std::string view, render, error_map, photo;
  double psnr = 0, ssim = 0, seconds = 0;
};

// What draws the views (render.source); a ViewRenderer is the field or the splats, never auto.
enum class RenderSource { kAuto, kField, kSplats };
template <>
struct EnumNames<RenderSource> {
  static constexpr std::pair<RenderSource, const char*> kValues[] = {
      {RenderSource::kAuto, "auto"}, {RenderSource::kField, "field"}, {RenderSource::kSplats, "splats"}};
};

// The render stage's camera path (render.path); a path rendered is never auto or none.
enum class PathChoice { kAuto, kOrbit, kSpiral, kFile, kNone };
template <>
struct EnumNames<PathChoice> {
  static constexpr std::pair<PathChoice, const char*> kValues[] = {{PathChoice::kAuto, "auto"},
                                                                   {PathChoice::kOrbit, "orbit"},
                                                                   {PathChoice::kSpiral, "spiral"},
                                                                   {PathChoice::kFile, "file"},
                                                                   {PathChoice::kNone, "none"}};
};

struct EvalReport {
  ViewSplit split = ViewSplit::kVal;           // the held-out split
  RenderSource source = RenderSource::kField;  // what rendered it: the field or the splats
  std::vector<HeldoutScore> views;
  std::optional<double> psnr, ssim;  // means over the views; none without views
  double seconds_per_view = 0;
  std::optional<double> samples_per_ray;  // none from the splats
  std::optional<double> step_scale;       // the field's sample spacing (as TrainReport's); none from the splats
  double heat_map_max_error = 0;
  std::optional<double> field_psnr, splats_psnr;  // both sources' held-out PSNR, where known

  nlohmann::json ToJson() const;
  static EvalReport Read(const std::filesystem::path& file);
};

// The video of a path (outside PathReport: clang cannot tell whether a nested struct with member initialisers is
// constructible while the struct around it is incomplete, so std::optional of one fails to build).
struct PathVideo {
  std::string file, codec;
  double fps = 0;
};

struct PathReport {
  RenderSource source = RenderSource::kField;  // the field or the splats
  PathChoice kind = PathChoice::kOrbit;
  int frames = 0, width = 0, height = 0;
  int rendered_frames = 0;  // the others repeat an earlier frame's camera (an arc's way back)
  double seconds_per_frame = 0, frames_per_second = 0;  // of the rendered frames
  std::optional<double> samples_per_ray;                // none from the splats
  double depth_png_max = 0;                             // the depth that 65535 stands for in the depth PNGs
  std::optional<PathVideo> video;                       // none when no encoder could write one

  // render_report.json holds {"path": ToJson()}.
  nlohmann::json ToJson() const;
  static PathReport Read(const std::filesystem::path& render_report);
};

// The export's point cloud (outside ExportReport for the reason PathVideo is outside PathReport).
struct ExportedPoints {
  std::string file;
  size_t count = 0;
};

struct ExportReport {
  struct Mesh {
    std::string file;
    size_t vertices = 0, triangles = 0;
    size_t marched_triangles = 0;     // before the simplification to export.max_triangles
    double simplification_error = 0;  // the farthest the simplification moved the surface (the file's units)
    bool watertight = false;
    size_t border_edges = 0, non_manifold_edges = 0, misoriented_edges = 0;
    int resolution = 0;
    double threshold = 0;  // the density the surface crosses
    bool threshold_from_field = false;
    MeshRegion region = MeshRegion::kBox;  // the cube meshed (normalised units) ...
    std::array<double, 3> centre{};
    double half_size = 1;
    MeshSurface surface = MeshSurface::kDensity;  // where the surface was found (export.surface resolved)
  } mesh;
  // The same surface textured: mesh.glb (upright, glTF's +Y up), and mesh.obj with its .mtl when asked.
  struct Textured {
    std::string file;
    size_t bytes = 0;
    std::string texture;  // the texture image (JPEG)
    int texture_size = 0;
    std::string obj;  // empty without export.obj
  } textured;
  FrameKind frame = FrameKind::kSource;
  struct Cameras {
    std::string file;
    size_t views = 0;
    bool refined = false;
  } cameras;
  // The training views whose renders gave the point cloud, the focus region and the depth surface: at most 200,
  // spread over the capture; 0 when none of them was asked for.
  size_t depth_views = 0;
  std::optional<ExportedPoints> points;  // none with export.points false

  nlohmann::json ToJson() const;
  static ExportReport Read(const std::filesystem::path& file);
};

}  // namespace p2n

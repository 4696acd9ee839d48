#include "stages/outputs/render_stage.h"

#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>

#include "base/camera_path.h"
#include "base/errors.h"
#include "base/file_util.h"
#include "base/float_image.h"
#include "base/format.h"
#include "base/video_io.h"
#include "formats/dataset_import.h"
#include "nerf/nerf_model.h"
#include "nerf/renderer.h"
#include "pipeline/cancel.h"
#include "pipeline/hash.h"
#include "pipeline/log.h"
#include "pipeline/progress.h"
#include "stages/fitting/splat_options.h"
#include "stages/outputs/view_renderer.h"
#include "stages/stage_io.h"
#include "stages/stage_reports.h"
#include "stages/training_data.h"

namespace p2n {
namespace fs = std::filesystem;
namespace {

constexpr float kHeatMapMaxError = 0.2f;  // mean absolute error over RGB shown as the brightest colour
constexpr double kSplatPsnrMargin = 0.5;  // dB: render.source auto takes splats this close to the field
// The orbit: all the way round when the photos leave no gap wider than this between neighbours (a view from the
// middle of such a gap is within half of it of a photo); else over the arc they cover, there and back.
constexpr double kOrbitMaxGapDeg = 60;
// An orbit asked of photos taken from one side sweeps at least this much.
constexpr double kForwardArcDeg = 30;

// render.path resolved: auto is a spiral for a forward-facing capture (which trains in normalised device
// coordinates, where an orbit would leave what the field holds), else an orbit.
PathChoice PathKind(const RenderStageOptions& options, const ImportedDataset& dataset) {
  if (options.path != PathChoice::kAuto) return options.path;
  return ForwardFacingCapture(dataset) ? PathChoice::kSpiral : PathChoice::kOrbit;
}

// Image writes fail for the user's reasons (a full disk, permissions): UserError naming the file.
void Save(const FloatImage& image, const fs::path& path, bool sixteen_bits = false) {
  WriteOrExplain([&] {
    if (path.extension() == ".exr") {
      SaveFloatImageExr(image, path);
    } else {
      SaveFloatImage(image, path, sixteen_bits);
    }
  });
}

Eigen::Matrix4d MatrixField(const nlohmann::json& value, const std::string& where) {
  if (!value.is_array() || value.size() < 3) throw UserError(where + " must be a 4x4 (or 3x4) matrix");
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  for (int r = 0; r < std::min<int>(4, value.size()); ++r) {
    if (!value[r].is_array() || value[r].size() != 4)
      throw UserError(format("{} row {} must have 4 numbers", where, r));
    for (int c = 0; c < 4; ++c) {
      if (!value[r][c].is_number() || !std::isfinite(value[r][c].get<double>())) {
        throw UserError(format("{} [{}][{}] must be a finite number", where, r, c));
      }
      m(r, c) = value[r][c].get<double>();
    }
  }
  const Eigen::Matrix3d rotation = m.topLeftCorner<3, 3>();
  if (!(rotation.transpose() * rotation).isApprox(Eigen::Matrix3d::Identity(), 1e-3)) {
    throw UserError(where + "'s rotation is not orthonormal");
  }
  return m;
}

// Intrinsics from `json` (w, h, fl_x, fl_y, cx, cy, or camera_angle_x) over those of `camera`.
PinholeCamera WithIntrinsics(const nlohmann::json& json, PinholeCamera camera, const std::string& where) {
  const auto number = [&](const char* key, double* value) {
    if (!json.contains(key)) return false;
    if (!json[key].is_number() || !(json[key].get<double>() > 0) || !std::isfinite(json[key].get<double>())) {
      throw UserError(format("{}: \"{}\" must be a positive number", where, key));
    }
    *value = json[key].get<double>();
    return true;
  };
  double w = camera.width, h = camera.height, angle = 0;
  const bool has_width = number("w", &w), has_height = number("h", &h);  // both read and checked
  if (has_width || has_height) {
    camera.cx = 0.5 * w;
    camera.cy = 0.5 * h;
  }
  camera.width = static_cast<int>(w);
  camera.height = static_cast<int>(h);
  if (camera.width > 16384 || camera.height > 16384) throw UserError(where + ": images above 16384 pixels a side");
  if (number("camera_angle_x", &angle)) camera.fx = camera.fy = 0.5 * camera.width / std::tan(0.5 * angle);
  number("fl_x", &camera.fx);
  if (!number("fl_y", &camera.fy) && json.contains("fl_x")) camera.fy = camera.fx;
  number("cx", &camera.cx);
  number("cy", &camera.cy);
  return camera;
}

EvalReport RenderHeldout(const ViewRenderer& renderer, const ImportedDataset& dataset, const RenderResult& out) {
  EvalReport eval;
  eval.split = HeldoutSplit(dataset);
  eval.source = renderer.source;
  eval.heat_map_max_error = kHeatMapMaxError;
  const ViewSplit split = eval.split;
  std::vector<const ImportedView*> views;
  size_t pixels = 0;
  for (const ImportedView& view : dataset.views) {
    if (view.view.split != split) continue;
    views.push_back(&view);
    pixels += size_t(view.view.camera.width) * view.view.camera.height;
  }
  std::vector<double> psnrs, ssims;
  double seconds = 0;
  size_t samples = 0, rays = 0;
  if (views.empty()) return eval;
  fs::create_directories(out.heldout());
  Progress progress("render: held-out views", static_cast<int64_t>(pixels), "pixels");
  const auto on_pixels_done = [&](size_t n) {
    progress.Add(static_cast<int64_t>(n));
    ThrowIfCancelled();  // Ctrl-C stops within a tile
  };
  for (const ImportedView* view : views) {
    const TrainView photo_view = LoadTrainView(*view);
    const FloatImage photo = PhotoOnBackground(photo_view, renderer.background);
    const RenderedView rendered = renderer.render(photo_view.camera, photo_view.near, photo_view.far, on_pixels_done);
    const std::string stem = view->source.stem().string();
    // Named in eval.json relative to the stage's folder.
    const fs::path render_name = RenderResult{}.heldout() / (stem + ".png");
    const fs::path error_name = RenderResult{}.heldout() / (stem + "_error.png");
    double psnr = 0, ssim = 0;
    // Each on one core: side by side.
    tbb::parallel_invoke([&] { Save(rendered.rgb, out.dir / render_name); },
                         [&] { Save(ErrorHeatMap(rendered.rgb, photo, kHeatMapMaxError), out.dir / error_name); },
                         [&] { psnr = Psnr(rendered.rgb, photo); }, [&] { ssim = Ssim(rendered.rgb, photo); });
    psnrs.push_back(psnr);
    ssims.push_back(ssim);
    seconds += rendered.stats.seconds;
    samples += rendered.stats.samples_evaluated;
    rays += rendered.stats.rays;
    eval.views.push_back({view->source.filename().string(), render_name.generic_string(), error_name.generic_string(),
                          view->source.string(), psnrs.back(), ssims.back(), rendered.stats.seconds});
  }
  eval.psnr = Mean(psnrs);
  eval.ssim = Mean(ssims);
  eval.seconds_per_view = seconds / views.size();
  if (renderer.source == RenderSource::kField) eval.samples_per_ray = double(samples) / std::max<size_t>(rays, 1);
  return eval;
}

std::vector<PinholeCamera> PathCameras(const RenderStageOptions& options, PathChoice kind,
                                       const ImportedDataset& dataset, const PinholeCamera& reference) {
  if (kind == PathChoice::kFile) return ReadCameraPath(options.path_file, reference);
  const std::vector<PinholeCamera> cameras = dataset.Cameras();
  CameraPathOptions path;
  path.frames = options.frames;
  if (kind == PathChoice::kSpiral) {
    path.radius = options.radius > 0 ? options.radius : 1.0;
    double focus = 0;  // the distance from the mean camera to the centre, which the normalisation put at the origin
    for (const PinholeCamera& camera : cameras) focus += camera.world_from_cam.block<3, 1>(0, 3).norm();
    return SpiralPath(cameras, reference, focus / cameras.size(), path);
  }
  double radius = 0, elevation = 0;
  MeanCameraPlacement(cameras, &radius, &elevation);
  path.radius = options.radius > 0 ? options.radius : radius;
  path.elevation_deg = options.elevation.value.value_or(elevation);
  CapturedArc(cameras, kOrbitMaxGapDeg, &path.start_deg, &path.sweep_deg);
  if (path.sweep_deg < kForwardArcDeg) {  // photos from one side, orbited on request
    path.start_deg -= 0.5 * (kForwardArcDeg - path.sweep_deg);
    path.sweep_deg = kForwardArcDeg;
  }
  return OrbitPath(reference, path);
}

// The range along the rays of a path camera that holds the scene: the views' nearest near and farthest far,
// the far end moved out by how much farther from the centre the camera is than the views on average.
struct PathRange {
  bool known = true;  // false when a view's range is unknown: the whole scene
  double near = std::numeric_limits<double>::infinity(), far = 0, mean_distance = 0;

  explicit PathRange(const ImportedDataset& dataset) {
    for (const ImportedView& view : dataset.views) {
      known = known && view.view.near >= 0 && view.view.far > view.view.near;
      near = std::min(near, view.view.near);
      far = std::max(far, view.view.far);
      mean_distance += view.view.camera.world_from_cam.block<3, 1>(0, 3).norm() / dataset.views.size();
    }
  }
  Eigen::Vector2d For(const PinholeCamera& camera) const {
    if (!known) return {-1, -1};
    return {near, far + std::max(0.0, camera.world_from_cam.block<3, 1>(0, 3).norm() - mean_distance)};
  }
};

// Path frame `name`'s images, and the video's next frame when it has the video's size (`first` is the path's
// first camera), each on one core.
void WriteFrame(const RenderedView& frame, const std::string& name, const RenderStageOptions& options, double depth_max,
                const RenderResult& out, VideoWriter* video, const PinholeCamera& first) {
  tbb::parallel_invoke(
      [&] {
        Save(frame.rgb, out.frames() / (name + ".png"));
        if (options.exr) Save(frame.rgb, out.frames() / (name + ".exr"));
      },
      [&] {
        if (!options.depth) return;
        FloatImage depth = frame.depth;
        for (float& d : depth.pixels) d = static_cast<float>(d / depth_max);
        Save(depth, out.depth() / (name + ".png"), /*sixteen_bits=*/true);
        if (options.exr) Save(frame.depth, out.depth() / (name + ".exr"));
      },
      [&] {
        if (options.depth) Save(frame.opacity, out.opacity() / (name + ".png"));
      },
      [&] {
        if (video && frame.rgb.width == first.width && frame.rgb.height == first.height) video->Add(frame.rgb);
      });
}

PathReport RenderPath(const ViewRenderer& renderer, const ImportedDataset& dataset,
                      const std::vector<PinholeCamera>& cameras, const RenderStageOptions& options,
                      const RenderResult& out) {
  fs::create_directories(out.frames());
  if (options.depth) {
    fs::create_directories(out.depth());
    fs::create_directories(out.opacity());
  }
  WriteCameraPath(out.path(), cameras);
  // Depth PNGs share one scale (16 bits over 0..depth_max) so that the frames of a video match.
  double depth_max = 0;
  for (const PinholeCamera& camera : cameras)
    depth_max = std::max(depth_max, camera.world_from_cam.block<3, 1>(0, 3).norm());
  depth_max = (depth_max + std::sqrt(3.0)) * (renderer.bounded ? 1 : 2);

  size_t pixels = 0;
  for (const PinholeCamera& camera : cameras) pixels += size_t(camera.width) * camera.height;
  Progress progress("render: path", static_cast<int64_t>(pixels), "pixels");
  const auto on_pixels_done = [&](size_t n) {
    progress.Add(static_cast<int64_t>(n));
    ThrowIfCancelled();  // Ctrl-C stops within a tile
  };
  std::unique_ptr<VideoWriter> video;
  if (options.video) {
    video = std::make_unique<VideoWriter>(out.video(), cameras[0].width, cameras[0].height, options.fps);
    if (video->codec() != "avc1")
      LogWarning("render: no H.264 encoder; video.mp4 is MPEG-4 part 2, which browsers may not play");
  }
  const PathRange path_range(dataset);
  const std::vector<size_t> original = FirstOfEqualCameras(cameras);
  std::vector<size_t> last_use(cameras.size());
  for (size_t f = 0; f < cameras.size(); ++f) last_use[original[f]] = f;
  std::map<size_t, RenderedView> kept;  // frames that a later one repeats, until then
  double seconds = 0;
  size_t samples = 0, rays = 0, rendered = 0;
  for (size_t f = 0; f < cameras.size(); ++f) {
    RenderedView frame;
    if (original[f] == f) {
      const Eigen::Vector2d range = path_range.For(cameras[f]);
      frame = renderer.render(cameras[f], range[0], range[1], on_pixels_done);
      seconds += frame.stats.seconds;
      samples += frame.stats.samples_evaluated;
      rays += frame.stats.rays;
      ++rendered;
      if (last_use[f] > f) kept[f] = frame;
    } else {
      frame = kept.at(original[f]);
      if (last_use[original[f]] == f) kept.erase(original[f]);
      on_pixels_done(size_t(cameras[f].width) * cameras[f].height);
    }
    WriteFrame(frame, RenderResult::FrameStem(f), options, depth_max, out, video.get(), cameras[0]);
  }
  PathReport report;
  report.source = renderer.source;
  report.frames = static_cast<int>(cameras.size());
  report.width = cameras[0].width;
  report.height = cameras[0].height;
  report.rendered_frames = static_cast<int>(rendered);
  report.seconds_per_frame = seconds / rendered;
  report.frames_per_second = rendered / std::max(seconds, 1e-9);
  if (renderer.source == RenderSource::kField) report.samples_per_ray = double(samples) / std::max<size_t>(rays, 1);
  report.depth_png_max = depth_max;
  if (video) {
    video->Close();
    report.video = PathVideo{RenderResult{}.video().string(), video->codec(), options.fps};
  }
  return report;
}

// What the render stage reads of its upstream stages, each file once.
struct RenderInputs {
  NerfModel model;
  ImportedDataset poses;
  std::optional<double> field_psnr;  // as the train stage measured it (train.final_eval_pixels per view)
  std::optional<SplatResult> splat;  // when render.source lets the stage read the splats
  std::optional<SplatReport> splat_report;
};

RenderInputs ReadInputs(const StageContext& context) {
  RenderInputs in;
  TrainedField trained = ReadTrainedField(Upstream<TrainResult>(context));
  in.model = std::move(trained.model);
  in.poses = LoadTransformsJson(Upstream<PosesResult>(context).transforms(), context.workspace.root());
  in.field_psnr = trained.report.heldout_psnr;
  in.splat = UpstreamIfRead<SplatResult>(context);
  if (in.splat) in.splat_report = SplatReport::Read(in.splat->report());
  return in;
}

std::string DbText(const std::optional<double>& psnr) { return psnr ? format("{:.2f} dB", *psnr) : "none"; }

// render.source resolved: auto takes the splats when their held-out PSNR is within kSplatPsnrMargin of the
// field's (they render tens of times faster), else the field.
ViewRenderer ChooseRenderer(const RenderStageOptions& options, const RenderInputs& in, const RenderOptions& render) {
  const NerfModel& model = in.model;
  if (options.source == RenderSource::kField || !in.splat_report) return FieldRenderer(model, render);
  const SplatReport& splats = *in.splat_report;
  if (!splats.enabled) {
    if (options.source == RenderSource::kSplats) {
      throw UserError(format("{} splats: the splat stage is off ({} false); turn it on or render the field",
                             OptionKey(options, options.source), OptionKey(&SplatOptions::enabled)));
    }
    return FieldRenderer(model, render);
  }
  const std::optional<double> field_psnr = in.field_psnr, splat_psnr = splats.heldout_psnr;
  const bool good = field_psnr && splat_psnr && *splat_psnr >= *field_psnr - kSplatPsnrMargin;
  if (options.source == RenderSource::kAuto && !good) {
    LogInfo(format("render: the splats' held-out PSNR ({}) is below the field's ({}): rendering the field",
                   DbText(splat_psnr), DbText(field_psnr)));
    return FieldRenderer(model, render);
  }
  return SplatRenderer(*in.splat, splats, in.poses, model.space == SceneSpace::kBounded);
}

}  // namespace

void RenderStageOptions::Check() const {
  CheckField(*this, path_file, path != PathChoice::kFile || !path_file.empty(),
             format("must name a file when {} is file", OptionKey(*this, path)));
  CheckField(*this, frames, frames >= 1 && frames <= 100000, "must be 1..100000");
  CheckField(*this, width, width >= 0 && width <= 16384, "must be 0 (the photos') or 1..16384");
  const std::optional<double>& degrees = elevation.value;
  CheckField(*this, elevation, !degrees || (*degrees > -90 && *degrees < 90), "must be between -90 and 90 degrees");
  CheckField(*this, radius, radius >= 0 && std::isfinite(radius), "must be 0 (from the cameras) or positive");
  CheckField(*this, fps, fps > 0 && fps <= 240, "must be in (0, 240]");
  CheckField(*this, step_scale, step_scale == 0 || (step_scale >= 0.01 && step_scale <= 100),
             "must be 0 (by the scene) or 0.01..100");
}

std::vector<PinholeCamera> ReadCameraPath(const fs::path& file, const PinholeCamera& reference) {
  const nlohmann::json json = ReadJsonFile(file);
  const std::string where = file.string();
  if (!json.is_object() || !json.contains("frames") || !json["frames"].is_array() || json["frames"].empty()) {
    throw UserError(format("'{}' has no \"frames\" (a list of cameras with \"transform_matrix\")", where));
  }
  const PinholeCamera shared = WithIntrinsics(json, reference, where);
  std::vector<PinholeCamera> cameras;
  for (size_t i = 0; i < json["frames"].size(); ++i) {
    const nlohmann::json& frame = json["frames"][i];
    const std::string frame_where = format("{}: frames[{}]", where, i);
    if (!frame.is_object() || !frame.contains("transform_matrix")) {
      throw UserError(frame_where + " has no \"transform_matrix\"");
    }
    PinholeCamera camera = WithIntrinsics(frame, shared, frame_where);
    camera.world_from_cam = MatrixField(frame["transform_matrix"], frame_where + ".transform_matrix");
    cameras.push_back(camera);
  }
  return cameras;
}

void WriteCameraPath(const fs::path& file, const std::vector<PinholeCamera>& cameras) {
  nlohmann::json frames = nlohmann::json::array();
  for (const PinholeCamera& camera : cameras) {
    nlohmann::json matrix = nlohmann::json::array();
    for (int r = 0; r < 4; ++r) {
      matrix.push_back({camera.world_from_cam(r, 0), camera.world_from_cam(r, 1), camera.world_from_cam(r, 2),
                        camera.world_from_cam(r, 3)});
    }
    frames.push_back({{"w", camera.width},
                      {"h", camera.height},
                      {"fl_x", camera.fx},
                      {"fl_y", camera.fy},
                      {"cx", camera.cx},
                      {"cy", camera.cy},
                      {"transform_matrix", matrix}});
  }
  WriteJsonAtomic(file, {{"frames", frames}});
}

std::vector<std::string> RenderStage::UpstreamFor(const Config& config) const {
  if (ReadOptions<RenderStageOptions>(config).source == RenderSource::kField)
    return {PosesResult::kId.name, TrainResult::kId.name};
  return upstream();
}

std::map<std::string, std::string> RenderStage::ExternalInputs(const Workspace&, const Config& config) const {
  const RenderStageOptions options = ReadOptions<RenderStageOptions>(config);
  if (options.path != PathChoice::kFile) return {};
  if (!fs::is_regular_file(options.path_file)) {
    throw UserError(format("{} '{}' is not a file", OptionKey(options, options.path_file), options.path_file));
  }
  return {{"camera path " + options.path_file, Sha1OfFile(options.path_file)}};
}

void RenderStage::Run(StageContext& context) const {
  const RenderStageOptions options = ReadOptions<RenderStageOptions>(context.config);
  const RenderInputs in = ReadInputs(context);
  const NerfModel& model = in.model;
  const ImportedDataset& dataset = in.poses;
  const RenderResult out{context.output_dir};
  RenderOptions render;
  render.step_scale = options.step_scale;
  const ViewRenderer renderer = ChooseRenderer(options, in, render);

  nlohmann::json summary = nlohmann::json::object();
  if (options.heldout) {
    EvalReport eval = RenderHeldout(renderer, dataset, out);
    if (renderer.source == RenderSource::kField) eval.step_scale = StepScale(model, render);
    eval.field_psnr = renderer.source == RenderSource::kField ? eval.psnr : in.field_psnr;
    if (renderer.source == RenderSource::kSplats) {
      eval.splats_psnr = eval.psnr;
    } else if (in.splat_report) {
      eval.splats_psnr = in.splat_report->heldout_psnr;
    }
    WriteJsonAtomic(out.eval(), eval.ToJson());
    if (eval.psnr) {
      summary["heldout_psnr"] = *eval.psnr;
      summary["heldout_ssim"] = *eval.ssim;
      LogInfo(format("render: held-out {} views from the {}: PSNR {:.2f} dB, SSIM {:.3f}, {:.2f} s per view",
                     eval.views.size(), EnumName(renderer.source), *eval.psnr, *eval.ssim, eval.seconds_per_view));
    }
  }
  const PathChoice kind = PathKind(options, dataset);
  if (kind != PathChoice::kNone) {
    const ImportedView* first = &dataset.views.front();
    for (const ImportedView& view : dataset.views) {
      if (view.view.split == ViewSplit::kTrain) {
        first = &view;
        break;
      }
    }
    const int width = options.width > 0 ? options.width : std::min(first->view.camera.width, kDefaultMaxPathWidth);
    const PinholeCamera reference = ScaledCamera(first->view.camera, width);
    const std::vector<PinholeCamera> cameras = PathCameras(options, kind, dataset, reference);
    PathReport path = RenderPath(renderer, dataset, cameras, options, out);
    path.kind = kind;
    WriteJsonAtomic(out.report(), {{"path", path.ToJson()}});
    summary["frames"] = path.frames;
    summary["frames_per_second"] = path.frames_per_second;
    const std::string repeats =
        path.rendered_frames < path.frames ? format(" ({} drawn, the others repeat them)", path.rendered_frames) : "";
    LogInfo(format("render: {} path from the {}, {} frames of {}x{}{} at {:.2f} frames per second", EnumName(kind),
                   EnumName(renderer.source), path.frames, path.width, path.height, repeats, path.frames_per_second));
  }
  context.summary = summary;
}

}  // namespace p2n

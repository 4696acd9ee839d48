#include "stages/stage_reports.h"

#include <algorithm>
#include <type_traits>

#include "pipeline/errors.h"
#include "pipeline/file_util.h"
#include "pipeline/format.h"
#include "stages/stage_results.h"

namespace p2n {
namespace fs = std::filesystem;
namespace {

// Typed fields of one report object; every error names the file, the field and the stage that writes it.
class Fields {
 public:
  Fields(const nlohmann::json& json, const fs::path& file, const char* stage, std::string prefix = "")
      : json_(json), file_(file), stage_(stage), prefix_(std::move(prefix)) {
    if (!json_.is_object()) Fail("", "must be an object");
  }

  template <class T>
  void Get(const char* key, T* value) const {
    if (!json_.contains(key)) Fail(key, "is missing");
    Convert(key, json_.at(key), value);
  }
  // Exactly N numbers.
  template <class T, size_t N>
  void Get(const char* key, std::array<T, N>* value) const {
    std::vector<T> values;
    Get(key, &values);
    if (values.size() != N) Fail(key, "must be " + std::to_string(N) + " numbers");
    std::copy(values.begin(), values.end(), value->begin());
  }
  // Missing or null: none.
  template <class T>
  void Get(const char* key, std::optional<T>* value) const {
    value->reset();
    if (!json_.contains(key) || json_.at(key).is_null()) return;
    T converted;
    Convert(key, json_.at(key), &converted);
    *value = converted;
  }
  // Calls read(fields of the element) for each element of the array at `key`, in order.
  template <class Read>
  void ForEach(const char* key, Read read) const {
    const nlohmann::json& array = At(key);
    if (!array.is_array()) Fail(key, "must be an array");
    for (size_t i = 0; i < array.size(); ++i)
      read(Fields(array[i], file_, stage_, format("{}{}[{}].", prefix_, key, i)));
  }
  // The object at `key`, to read further fields from.
  Fields Object(const char* key) const { return Fields(At(key), file_, stage_, prefix_ + key + "."); }
  bool Has(const char* key) const { return json_.contains(key) && !json_.at(key).is_null(); }
  const nlohmann::json& At(const char* key) const {
    if (!json_.contains(key)) Fail(key, "is missing");
    return json_.at(key);
  }
  [[noreturn]] void Fail(const std::string& key, const std::string& problem) const {
    throw UserError(format("'{}': \"{}{}\" {}; rerun the {} stage (photo2nerf {} -w WORKSPACE --force)", file_.string(),
                           prefix_, key, problem, stage_, stage_));
  }

 private:
  template <class T>
  void Convert(const char* key, const nlohmann::json& value, T* out) const {
    const bool number_wanted = std::is_arithmetic_v<T> && !std::is_same_v<T, bool>;
    if (number_wanted && !value.is_number()) Fail(key, format("must be a number, not {}", value.type_name()));
    try {
      *out = value.get<T>();
    } catch (const nlohmann::json::exception&) {
      Fail(key, format("has the wrong type ({})", value.type_name()));
    }
  }

  const nlohmann::json& json_;
  const fs::path& file_;
  const char* stage_;
  std::string prefix_;
};

nlohmann::json OrNull(const std::optional<double>& value) {
  return value ? nlohmann::json(*value) : nlohmann::json(nullptr);
}

// The rates are written beside the counts for whoever reads the file; Read() takes the counts.
nlohmann::json ThroughputJson(const std::optional<TrainReport::Throughput>& throughput) {
  if (!throughput) return nullptr;
  const TrainReport::Throughput& t = *throughput;
  return {{"steps", t.steps},
          {"seconds", t.seconds},
          {"rays", t.rays},
          {"samples", t.samples},
          {"samples_per_second", t.SamplesPerSecond()},
          {"samples_per_ray", t.SamplesPerRay()}};
}

// A pixels-per-view count as written: the number, or "all" for 0.
nlohmann::json PixelsPerView(int pixels) { return pixels == 0 ? nlohmann::json("all") : nlohmann::json(pixels); }

int ReadPixelsPerView(const Fields& fields, const char* key) {
  const nlohmann::json& value = fields.At(key);
  if (value == "all") return 0;
  if (!value.is_number_integer() || value.get<int64_t>() < 1) fields.Fail(key, "must be \"all\" or a positive count");
  return value.get<int>();
}

void ReadAppearance(const Fields& fields, TrainReport::Appearance* appearance) {
  fields.Get("enabled", &appearance->enabled);
  if (!appearance->enabled) return;
  fields.Get("gain_min", &appearance->gain_min);
  fields.Get("gain_max", &appearance->gain_max);
  fields.ForEach("per_view", [&](const Fields& view) {
    TrainReport::AppearanceView& out = appearance->per_view.emplace_back();
    view.Get("view", &out.view);
    view.Get("gain", &out.gain);
    view.Get("transform", &out.transform);
  });
}

nlohmann::json WarningsJson(const std::vector<FitWarning>& warnings) {
  nlohmann::json json = nlohmann::json::array();
  for (const FitWarning& w : warnings) json.push_back({{"code", w.code}, {"figure", w.figure}, {"message", w.message}});
  return json;
}

// "warnings", where the report has them (reports written before they were checked have none).
std::vector<FitWarning> ReadWarnings(const Fields& fields) {
  std::vector<FitWarning> warnings;
  if (!fields.Has("warnings")) return warnings;
  fields.ForEach("warnings", [&](const Fields& warning) {
    FitWarning& read = warnings.emplace_back();
    warning.Get("code", &read.code);
    warning.Get("figure", &read.figure);
    warning.Get("message", &read.message);
  });
  return warnings;
}

}  // namespace

nlohmann::json IngestReport::ToJson() const {
  nlohmann::json images_json = nlohmann::json::array(), skipped_json = nlohmann::json::array();
  for (const IngestedImage& image : images) {
    images_json.push_back({{"name", image.name},
                           {"source", image.source},
                           {"width", image.width},
                           {"height", image.height},
                           {"channels", image.channels},
                           {"source_width", image.source_width},
                           {"source_height", image.source_height},
                           {"exif_orientation", image.orientation},
                           {"from_cmyk", image.from_cmyk},
                           {"fingerprint", image.fingerprint}});
  }
  for (const SkippedPhoto& skip : skipped) skipped_json.push_back({{"file", skip.file}, {"reason", skip.reason}});
  return {{"input_folder", input_folder}, {"images", images_json}, {"skipped", skipped_json}};
}

IngestReport IngestReport::Read(const fs::path& file) {
  const nlohmann::json json = ReadJsonFile(file);
  const Fields fields(json, file, IngestResult::kId.name);
  IngestReport report;
  fields.Get("input_folder", &report.input_folder);
  fields.ForEach("images", [&](const Fields& image) {
    IngestedImage& out = report.images.emplace_back();
    image.Get("name", &out.name);
    image.Get("source", &out.source);
    image.Get("width", &out.width);
    image.Get("height", &out.height);
    image.Get("channels", &out.channels);
    image.Get("source_width", &out.source_width);
    image.Get("source_height", &out.source_height);
    image.Get("exif_orientation", &out.orientation);
    image.Get("from_cmyk", &out.from_cmyk);
    image.Get("fingerprint", &out.fingerprint);
    if (out.width < 1 || out.height < 1) image.Fail("width", "and height must be positive");
  });
  fields.ForEach("skipped", [&](const Fields& skip) {
    SkippedPhoto& out = report.skipped.emplace_back();
    skip.Get("file", &out.file);
    skip.Get("reason", &out.reason);
  });
  return report;
}

nlohmann::json SfmReport::ToJson() const {
  nlohmann::json models_json = nlohmann::json::array(), steps_json = nlohmann::json::array();
  for (const Model& m : models) models_json.push_back({{"path", m.path}, {"registered", m.registered}});
  for (const Step& step : steps)
    steps_json.push_back({{"step", step.step}, {"wall_seconds", step.wall_seconds}, {"log", step.log}});
  nlohmann::json json = {{"images_given", images_given},
                         {"registered", registered},
                         {"registered_percent", registered_percent},
                         {"left_out", left_out},
                         {"points", points},
                         {"mean_reprojection_error_px", mean_reprojection_error_px},
                         {"mean_track_length", mean_track_length},
                         {"colmap_version", colmap_version},
                         {"matcher", matcher},
                         {"models", models_json},
                         {"chosen_model", chosen_model},
                         {"steps", steps_json}};
  if (median_axis_to_focus_angle_deg) json["median_axis_to_focus_angle_deg"] = *median_axis_to_focus_angle_deg;
  return json;
}

SfmReport SfmReport::Read(const fs::path& file) {
  const nlohmann::json json = ReadJsonFile(file);
  const Fields fields(json, file, SfmResult::kId.name);
  SfmReport report;
  fields.Get("images_given", &report.images_given);
  fields.Get("registered", &report.registered);
  fields.Get("registered_percent", &report.registered_percent);
  fields.Get("left_out", &report.left_out);
  fields.Get("points", &report.points);
  fields.Get("mean_reprojection_error_px", &report.mean_reprojection_error_px);
  fields.Get("mean_track_length", &report.mean_track_length);
  fields.Get("median_axis_to_focus_angle_deg", &report.median_axis_to_focus_angle_deg);
  fields.Get("colmap_version", &report.colmap_version);
  fields.Get("matcher", &report.matcher);
  fields.Get("chosen_model", &report.chosen_model);
  fields.ForEach("models", [&](const Fields& model) {
    Model& out = report.models.emplace_back();
    model.Get("path", &out.path);
    model.Get("registered", &out.registered);
  });
  fields.ForEach("steps", [&](const Fields& step) {
    Step& out = report.steps.emplace_back();
    step.Get("step", &out.step);
    step.Get("wall_seconds", &out.wall_seconds);
    step.Get("log", &out.log);
  });
  if (report.images_given == 0 || report.registered > report.images_given)
    fields.Fail("registered", "must be at most images_given, which must be positive");
  return report;
}

nlohmann::json TrainReport::ToJson() const {
  nlohmann::json per_view = nlohmann::json::array();
  for (const ViewPsnr& v : heldout_per_view) per_view.push_back({{"view", v.view}, {"psnr", v.psnr}});
  nlohmann::json appearance_json = {{"enabled", appearance.enabled}};
  if (appearance.enabled) {
    nlohmann::json views = nlohmann::json::array();
    for (const AppearanceView& v : appearance.per_view)
      views.push_back({{"view", v.view}, {"gain", v.gain}, {"transform", v.transform}});
    appearance_json.update({{"gain_min", appearance.gain_min}, {"gain_max", appearance.gain_max}, {"per_view", views}});
  }
  return {{"steps", steps},
          {"wall_seconds", wall_seconds},
          {"heldout_psnr", OrNull(heldout_psnr)},
          {"heldout_step_scale", OrNull(heldout_step_scale)},
          {"heldout_views", heldout_views},
          {"heldout_split", heldout_split},
          {"heldout_pixels_per_view", PixelsPerView(heldout_pixels_per_view)},
          {"heldout_per_view", per_view},
          {"heldout_rule", heldout_rule},
          {"training_psnr", OrNull(training_psnr)},
          {"warnings", WarningsJson(warnings)},
          {"heldout_psnr_fitted", OrNull(heldout_psnr_fitted)},
          {"heldout_psnr_fitted_is",
           "each held-out photo's colour transform fitted (least squares) on its left half, PSNR on its right half "
           "(NeRF-W)"},
          {"evaluations_during_training",
           {{"count", evaluations_during_training.count},
            {"seconds", evaluations_during_training.seconds},
            {"pixels_per_view", PixelsPerView(evaluations_during_training.pixels_per_view)}}},
          {"skipped_steps", skipped_steps},
          {"resumed_from_step", resumed_from_step},
          {"training_views", training_views},
          {"samples_per_ray_rendered", samples_per_ray_rendered},
          {"render_seconds_per_view", render_seconds_per_view},
          {"occupied_fraction", occupied_fraction},
          {"throughput", ThroughputJson(throughput)},
          {"field", field},
          {"trainer",
           {{"march_step", trainer.march_step},
            {"rendered_march_step", trainer.rendered_march_step},
            {"batch_samples", trainer.batch_samples},
            {"late_batch_samples", trainer.late_batch_samples},
            {"scene", trainer.scene},
            {"learning_rate", trainer.learning_rate},
            {"distortion_weight", trainer.distortion_weight},
            {"appearance", trainer.appearance},
            {"refine_cameras", trainer.refine_cameras},
            {"error_sampling", trainer.error_sampling},
            {"background", trainer.background},
            {"background_colour", trainer.background_colour}}},
          {"appearance", appearance_json},
          {"camera_refinement", camera_refinement}};
}

TrainReport TrainReport::Read(const fs::path& file) {
  const nlohmann::json json = ReadJsonFile(file);
  const Fields fields(json, file, TrainResult::kId.name);
  TrainReport report;
  fields.Get("steps", &report.steps);
  fields.Get("wall_seconds", &report.wall_seconds);
  fields.Get("heldout_psnr", &report.heldout_psnr);
  fields.Get("heldout_step_scale", &report.heldout_step_scale);
  fields.Get("heldout_views", &report.heldout_views);
  fields.Get("heldout_split", &report.heldout_split);
  report.heldout_pixels_per_view = ReadPixelsPerView(fields, "heldout_pixels_per_view");
  fields.ForEach("heldout_per_view", [&](const Fields& view) {
    ViewPsnr& score = report.heldout_per_view.emplace_back();
    view.Get("view", &score.view);
    view.Get("psnr", &score.psnr);
  });
  fields.Get("heldout_psnr_fitted", &report.heldout_psnr_fitted);
  if (fields.Has("heldout_rule")) fields.Get("heldout_rule", &report.heldout_rule);
  fields.Get("training_psnr", &report.training_psnr);
  report.warnings = ReadWarnings(fields);
  const Fields evaluations = fields.Object("evaluations_during_training");
  evaluations.Get("count", &report.evaluations_during_training.count);
  evaluations.Get("seconds", &report.evaluations_during_training.seconds);
  report.evaluations_during_training.pixels_per_view = ReadPixelsPerView(evaluations, "pixels_per_view");
  fields.Get("skipped_steps", &report.skipped_steps);
  fields.Get("resumed_from_step", &report.resumed_from_step);
  fields.Get("training_views", &report.training_views);
  fields.Get("samples_per_ray_rendered", &report.samples_per_ray_rendered);
  fields.Get("render_seconds_per_view", &report.render_seconds_per_view);
  fields.Get("occupied_fraction", &report.occupied_fraction);
  if (json.contains("throughput") && !json.at("throughput").is_null()) {
    const Fields throughput = fields.Object("throughput");
    TrainReport::Throughput read;
    throughput.Get("steps", &read.steps);
    throughput.Get("seconds", &read.seconds);
    throughput.Get("rays", &read.rays);
    throughput.Get("samples", &read.samples);
    report.throughput = read;
  }
  fields.Get("field", &report.field);
  const Fields trainer = fields.Object("trainer");
  trainer.Get("march_step", &report.trainer.march_step);
  trainer.Get("rendered_march_step", &report.trainer.rendered_march_step);
  trainer.Get("batch_samples", &report.trainer.batch_samples);
  trainer.Get("late_batch_samples", &report.trainer.late_batch_samples);
  trainer.Get("scene", &report.trainer.scene);
  trainer.Get("learning_rate", &report.trainer.learning_rate);
  trainer.Get("distortion_weight", &report.trainer.distortion_weight);
  trainer.Get("appearance", &report.trainer.appearance);
  trainer.Get("refine_cameras", &report.trainer.refine_cameras);
  trainer.Get("error_sampling", &report.trainer.error_sampling);
  trainer.Get("background", &report.trainer.background);
  trainer.Get("background_colour", &report.trainer.background_colour);
  ReadAppearance(fields.Object("appearance"), &report.appearance);
  fields.Get("camera_refinement", &report.camera_refinement);
  const Fields refinement = fields.Object("camera_refinement");
  refinement.Get("enabled", &report.refinement.enabled);
  if (report.refinement.enabled) {
    refinement.Get("rotation_degrees_median", &report.refinement.rotation_degrees_median);
    refinement.Get("rotation_degrees_max", &report.refinement.rotation_degrees_max);
    refinement.Get("shift_median", &report.refinement.shift_median);
    refinement.Get("shift_max", &report.refinement.shift_max);
  }
  return report;
}

nlohmann::json SplatReport::ToJson() const {
  if (!enabled) return {{"enabled", false}};
  return {{"enabled", true},
          {"splats", splats},
          {"initial_splats", initial_splats},
          {"init", init},
          {"sh_degree", sh_degree},
          {"steps", steps},
          {"seconds", seconds},
          {"resumed_from_step", resumed_from_step},
          {"heldout_views", heldout_views},
          {"heldout_psnr", OrNull(heldout_psnr)},
          {"heldout_ssim", OrNull(heldout_ssim)},
          {"heldout_psnr_per_view", heldout_psnr_per_view},
          {"seconds_per_view", seconds_per_view},
          {"frame", frame},
          {"frame_description", frame_description},
          {"near", near},
          {"background", background},
          {"file", SplatResult{}.splats().string()},
          {"file_bytes", file_bytes},
          {"viewer", SplatResult{}.viewer().string()},
          {"viewer_bytes", viewer_bytes},
          {"warnings", WarningsJson(warnings)}};
}

SplatReport SplatReport::Read(const fs::path& file) {
  const nlohmann::json json = ReadJsonFile(file);
  const Fields fields(json, file, SplatResult::kId.name);
  SplatReport report;
  fields.Get("enabled", &report.enabled);
  if (!report.enabled) return report;
  fields.Get("splats", &report.splats);
  fields.Get("initial_splats", &report.initial_splats);
  fields.Get("init", &report.init);
  fields.Get("sh_degree", &report.sh_degree);
  fields.Get("steps", &report.steps);
  fields.Get("seconds", &report.seconds);
  fields.Get("resumed_from_step", &report.resumed_from_step);
  fields.Get("heldout_views", &report.heldout_views);
  fields.Get("heldout_psnr", &report.heldout_psnr);
  fields.Get("heldout_ssim", &report.heldout_ssim);
  fields.Get("heldout_psnr_per_view", &report.heldout_psnr_per_view);
  fields.Get("seconds_per_view", &report.seconds_per_view);
  fields.Get("frame", &report.frame);
  fields.Get("frame_description", &report.frame_description);
  fields.Get("near", &report.near);
  fields.Get("background", &report.background);
  fields.Get("file_bytes", &report.file_bytes);
  fields.Get("viewer_bytes", &report.viewer_bytes);
  report.warnings = ReadWarnings(fields);
  if (report.frame != "normalized" && report.frame != "source") fields.Fail("frame", "must be normalized or source");
  if (!(report.near > 0)) fields.Fail("near", "must be positive");
  return report;
}

nlohmann::json EvalReport::ToJson() const {
  nlohmann::json per_view = nlohmann::json::array();
  for (const HeldoutScore& v : views) {
    per_view.push_back({{"view", v.view},
                        {"render", v.render},
                        {"error_map", v.error_map},
                        {"photo", v.photo},
                        {"psnr", v.psnr},
                        {"ssim", v.ssim},
                        {"seconds", v.seconds}});
  }
  return {{"split", split},
          {"source", source},
          {"views", per_view},
          {"psnr", OrNull(psnr)},
          {"ssim", OrNull(ssim)},
          {"seconds_per_view", seconds_per_view},
          {"samples_per_ray", OrNull(samples_per_ray)},
          {"step_scale", OrNull(step_scale)},
          {"heat_map_max_error", heat_map_max_error},
          {"field_psnr", OrNull(field_psnr)},
          {"splats_psnr", OrNull(splats_psnr)}};
}

EvalReport EvalReport::Read(const fs::path& file) {
  const nlohmann::json json = ReadJsonFile(file);
  const Fields fields(json, file, RenderResult::kId.name);
  EvalReport report;
  fields.Get("split", &report.split);
  fields.Get("source", &report.source);
  fields.ForEach("views", [&](const Fields& view) {
    HeldoutScore& score = report.views.emplace_back();
    view.Get("view", &score.view);
    view.Get("render", &score.render);
    view.Get("error_map", &score.error_map);
    view.Get("photo", &score.photo);
    view.Get("psnr", &score.psnr);
    view.Get("ssim", &score.ssim);
    view.Get("seconds", &score.seconds);
  });
  fields.Get("psnr", &report.psnr);
  fields.Get("ssim", &report.ssim);
  fields.Get("seconds_per_view", &report.seconds_per_view);
  fields.Get("samples_per_ray", &report.samples_per_ray);
  fields.Get("step_scale", &report.step_scale);
  fields.Get("heat_map_max_error", &report.heat_map_max_error);
  fields.Get("field_psnr", &report.field_psnr);
  fields.Get("splats_psnr", &report.splats_psnr);
  return report;
}

nlohmann::json PathReport::ToJson() const {
  nlohmann::json json = {{"source", source},
                         {"kind", kind},
                         {"frames", frames},
                         {"rendered_frames", rendered_frames},
                         {"width", width},
                         {"height", height},
                         {"seconds_per_frame", seconds_per_frame},
                         {"frames_per_second", frames_per_second},
                         {"samples_per_ray", OrNull(samples_per_ray)},
                         {"depth_png_max", depth_png_max}};
  if (video) json["video"] = {{"file", video->file}, {"codec", video->codec}, {"fps", video->fps}};
  return json;
}

PathReport PathReport::Read(const fs::path& render_report) {
  const nlohmann::json json = ReadJsonFile(render_report);
  const Fields fields = Fields(json, render_report, RenderResult::kId.name).Object("path");
  PathReport report;
  fields.Get("source", &report.source);
  fields.Get("kind", &report.kind);
  fields.Get("frames", &report.frames);
  fields.Get("rendered_frames", &report.rendered_frames);
  fields.Get("width", &report.width);
  fields.Get("height", &report.height);
  fields.Get("seconds_per_frame", &report.seconds_per_frame);
  fields.Get("frames_per_second", &report.frames_per_second);
  fields.Get("samples_per_ray", &report.samples_per_ray);
  fields.Get("depth_png_max", &report.depth_png_max);
  if (fields.Has("video")) {
    const Fields video = fields.Object("video");
    PathVideo& out = report.video.emplace();
    video.Get("file", &out.file);
    video.Get("codec", &out.codec);
    video.Get("fps", &out.fps);
  }
  return report;
}

nlohmann::json ExportReport::ToJson() const {
  nlohmann::json json = {
      {"mesh",
       {{"file", mesh.file},
        {"vertices", mesh.vertices},
        {"triangles", mesh.triangles},
        {"watertight", mesh.watertight},
        {"border_edges", mesh.border_edges},
        {"non_manifold_edges", mesh.non_manifold_edges},
        {"misoriented_edges", mesh.misoriented_edges},
        {"resolution", mesh.resolution},
        {"threshold", mesh.threshold},
        {"threshold_from_field", mesh.threshold_from_field},
        {"region", {{"kind", mesh.region}, {"centre", mesh.centre}, {"half_size", mesh.half_size}}}}},
      {"frame", frame},
      {"cameras", {{"file", cameras.file}, {"views", cameras.views}, {"refined", cameras.refined}}}};
  if (points) json["points"] = {{"file", points->file}, {"count", points->count}};
  return json;
}

ExportReport ExportReport::Read(const fs::path& file) {
  const nlohmann::json json = ReadJsonFile(file);
  const Fields fields(json, file, ExportResult::kId.name);
  ExportReport report;
  const Fields mesh = fields.Object("mesh");
  mesh.Get("file", &report.mesh.file);
  mesh.Get("vertices", &report.mesh.vertices);
  mesh.Get("triangles", &report.mesh.triangles);
  mesh.Get("watertight", &report.mesh.watertight);
  mesh.Get("border_edges", &report.mesh.border_edges);
  mesh.Get("non_manifold_edges", &report.mesh.non_manifold_edges);
  mesh.Get("misoriented_edges", &report.mesh.misoriented_edges);
  mesh.Get("resolution", &report.mesh.resolution);
  mesh.Get("threshold", &report.mesh.threshold);
  mesh.Get("threshold_from_field", &report.mesh.threshold_from_field);
  const Fields region = mesh.Object("region");
  region.Get("kind", &report.mesh.region);
  region.Get("centre", &report.mesh.centre);
  region.Get("half_size", &report.mesh.half_size);
  fields.Get("frame", &report.frame);
  const Fields cameras = fields.Object("cameras");
  cameras.Get("file", &report.cameras.file);
  cameras.Get("views", &report.cameras.views);
  cameras.Get("refined", &report.cameras.refined);
  if (fields.Has("points")) {
    const Fields points = fields.Object("points");
    ExportedPoints& out = report.points.emplace();
    points.Get("file", &out.file);
    points.Get("count", &out.count);
  }
  return report;
}

}  // namespace p2n

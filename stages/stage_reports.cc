#include "stages/stage_reports.h"

#include <algorithm>
#include <type_traits>

#include "pipeline/errors.h"
#include "pipeline/file_util.h"
#include "pipeline/format.h"

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
  // Missing or null: none.
  template <class T>
  void Get(const char* key, std::optional<T>* value) const {
    value->reset();
    if (!json_.contains(key) || json_.at(key).is_null()) return;
    T converted;
    Convert(key, json_.at(key), &converted);
    *value = converted;
  }
  // The object at `key`, to read further fields from.
  Fields Object(const char* key) const {
    if (!json_.contains(key)) Fail(key, "is missing");
    return Fields(json_.at(key), file_, stage_, prefix_ + key + ".");
  }
  bool Has(const char* key) const { return json_.contains(key) && !json_.at(key).is_null(); }
  [[noreturn]] void Fail(const std::string& key, const std::string& problem) const {
    throw UserError(format("'{}': \"{}{}\" {}; rerun the {} stage (photo2nerf {} -w WORKSPACE --force)",
                           file_.string(), prefix_, key, problem, stage_, stage_));
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

}  // namespace

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
          {"file", "splats.ply"},
          {"file_bytes", file_bytes},
          {"viewer", "viewer.html"},
          {"viewer_bytes", viewer_bytes}};
}

SplatReport SplatReport::Read(const fs::path& file) {
  const nlohmann::json json = ReadJsonFile(file);
  const Fields fields(json, file, "splat");
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
  std::vector<float> background;
  fields.Get("background", &background);
  if (background.size() != 3) fields.Fail("background", "must be 3 numbers");
  std::copy(background.begin(), background.end(), report.background.begin());
  fields.Get("file_bytes", &report.file_bytes);
  fields.Get("viewer_bytes", &report.viewer_bytes);
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
          {"heat_map_max_error", heat_map_max_error},
          {"field_psnr", OrNull(field_psnr)},
          {"splats_psnr", OrNull(splats_psnr)}};
}

EvalReport EvalReport::Read(const fs::path& file) {
  const nlohmann::json json = ReadJsonFile(file);
  const Fields fields(json, file, "render");
  EvalReport report;
  fields.Get("split", &report.split);
  fields.Get("source", &report.source);
  if (!json.contains("views") || !json["views"].is_array()) fields.Fail("views", "must be an array");
  for (size_t i = 0; i < json["views"].size(); ++i) {
    const Fields view(json["views"][i], file, "render", format("views[{}].", i));
    HeldoutScore& score = report.views.emplace_back();
    view.Get("view", &score.view);
    view.Get("render", &score.render);
    view.Get("error_map", &score.error_map);
    view.Get("photo", &score.photo);
    view.Get("psnr", &score.psnr);
    view.Get("ssim", &score.ssim);
    view.Get("seconds", &score.seconds);
  }
  fields.Get("psnr", &report.psnr);
  fields.Get("ssim", &report.ssim);
  fields.Get("seconds_per_view", &report.seconds_per_view);
  fields.Get("samples_per_ray", &report.samples_per_ray);
  fields.Get("heat_map_max_error", &report.heat_map_max_error);
  fields.Get("field_psnr", &report.field_psnr);
  fields.Get("splats_psnr", &report.splats_psnr);
  return report;
}

nlohmann::json PathReport::ToJson() const {
  nlohmann::json json = {{"source", source},
                         {"kind", kind},
                         {"frames", frames},
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
  const Fields fields = Fields(json, render_report, "render").Object("path");
  PathReport report;
  fields.Get("source", &report.source);
  fields.Get("kind", &report.kind);
  fields.Get("frames", &report.frames);
  fields.Get("width", &report.width);
  fields.Get("height", &report.height);
  fields.Get("seconds_per_frame", &report.seconds_per_frame);
  fields.Get("frames_per_second", &report.frames_per_second);
  fields.Get("samples_per_ray", &report.samples_per_ray);
  fields.Get("depth_png_max", &report.depth_png_max);
  if (fields.Has("video")) {
    const Fields video = fields.Object("video");
    PathReport::Video& out = report.video.emplace();
    video.Get("file", &out.file);
    video.Get("codec", &out.codec);
    video.Get("fps", &out.fps);
  }
  return report;
}

}  // namespace p2n

#include "stages/stage_reports.h"

#include <algorithm>
#include <optional>
#include <type_traits>

#include "base/errors.h"
#include "base/file_util.h"
#include "base/format.h"
#include "base/json_number.h"
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
    if constexpr (std::is_integral_v<T> && !std::is_same_v<T, bool>) {
      const std::optional<T> n = JsonInteger<T>(value);
      if (!n) Fail(key, format("must be a whole number in range, not {}", value.dump()));
      *out = *n;
    } else {
      try {
        *out = value.get<T>();
      } catch (const nlohmann::json::exception&) {
        Fail(key, format("has the wrong type ({})", value.type_name()));
      }
    }
  }

  const nlohmann::json& json_;
  const fs::path& file_;
  const char* stage_;
  std::string prefix_;
};

template <class T>
struct IsOptional : std::false_type {};
template <class T>
struct IsOptional<std::optional<T>> : std::true_type {};
template <class T>
struct IsVector : std::false_type {};
template <class T>
struct IsVector<std::vector<T>> : std::true_type {};

// A report's struct declares its JSON once, in Describe(s, value) below: s(key, field) for each field, and
//   s.Optional(key, field)  a field older reports lack (read as its default when missing);
//   s.Written(key, value)   written for whoever reads the file, never read back (rates, file names);
//   s.ReadOnly(key, field)  read from a section another field writes (a summary of it);
//   s.With<Codec>(key, field) written and read by Codec (a count written "all" for 0);
//   s.Object(key, fn)       fields of this struct nested in an object;
//   s.Check(key, problem, ok) a rule that a file read must satisfy.
// Describe takes the struct by non-const reference; the writer only reads it.
template <class T, class = void>
struct HasDescribe : std::false_type {};

class JsonWriter;
template <class T>
struct HasDescribe<T, std::void_t<decltype(Describe(std::declval<JsonWriter&>(), std::declval<T&>()))>>
    : std::true_type {};

template <class T>
nlohmann::json ToJsonValue(const T& value);

class JsonWriter {
 public:
  template <class T>
  void operator()(const char* key, const T& value) {
    json[key] = ToJsonValue(value);
  }
  template <class T>
  void Optional(const char* key, const T& value) {
    (*this)(key, value);
  }
  template <class T>
  void Written(const char* key, const T& value) {
    (*this)(key, value);
  }
  template <class T>
  void ReadOnly(const char*, const T&) {}
  template <class Codec, class T>
  void With(const char* key, const T& value) {
    json[key] = Codec::Write(value);
  }
  template <class Fn>
  void Object(const char* key, Fn describe) {
    JsonWriter inner;
    describe(inner);
    json[key] = std::move(inner.json);
  }
  template <class Ok>
  void Check(const char*, const char*, Ok) {}

  nlohmann::json json = nlohmann::json::object();
};

template <class T>
nlohmann::json ToJsonValue(const T& value) {
  if constexpr (IsOptional<T>::value) {
    return value ? ToJsonValue(*value) : nlohmann::json(nullptr);
  } else if constexpr (IsVector<T>::value) {
    nlohmann::json array = nlohmann::json::array();
    for (const auto& element : value) array.push_back(ToJsonValue(element));
    return array;
  } else if constexpr (std::is_enum_v<T>) {
    return EnumName(value);
  } else if constexpr (HasDescribe<T>::value) {
    JsonWriter writer;
    Describe(writer, const_cast<T&>(value));
    return std::move(writer.json);
  } else {
    return nlohmann::json(value);
  }
}

template <class T>
struct IsDescribedVector : std::false_type {};
template <class T>
struct IsDescribedVector<std::vector<T>> : HasDescribe<T> {};

class JsonReader {
 public:
  explicit JsonReader(Fields fields) : fields_(std::move(fields)) {}

  template <class T>
  void operator()(const char* key, T& value) {
    Read(fields_, key, &value);
  }
  template <class T>
  void Optional(const char* key, T& value) {
    if (fields_.Has(key)) Read(fields_, key, &value);
  }
  template <class T>
  void Written(const char*, const T&) {}
  template <class T>
  void ReadOnly(const char* key, T& value) {
    Read(fields_, key, &value);
  }
  template <class Codec, class T>
  void With(const char* key, T& value) {
    value = Codec::Read(fields_, key);
  }
  template <class Fn>
  void Object(const char* key, Fn describe) {
    JsonReader inner(fields_.Object(key));
    describe(inner);
  }
  template <class Ok>
  void Check(const char* key, const char* problem, Ok ok) {
    if (!ok()) fields_.Fail(key, problem);
  }

  template <class T>
  static void Read(const Fields& fields, const char* key, T* value) {
    if constexpr (IsOptional<T>::value) {
      value->reset();
      if (!fields.Has(key)) return;
      typename T::value_type read{};  // not emplace(): clang takes a nested struct for one it cannot default-construct
      Read(fields, key, &read);
      *value = std::move(read);
    } else if constexpr (IsDescribedVector<T>::value) {
      value->clear();
      fields.ForEach(key, [&](const Fields& element) {
        JsonReader reader(element);
        Describe(reader, value->emplace_back());
      });
    } else if constexpr (std::is_enum_v<T>) {
      std::string name;
      fields.Get(key, &name);
      const std::optional<T> named = EnumFromName<T>(name);
      if (!named) fields.Fail(key, format("must be {}, not '{}'", EnumNamesText<T>(), name));
      *value = *named;
    } else if constexpr (HasDescribe<T>::value) {
      JsonReader reader(fields.Object(key));
      Describe(reader, *value);
    } else {
      fields.Get(key, value);
    }
  }

 private:
  Fields fields_;
};

// A report read from `file` (from its object `section`, when given), written by `stage`.
template <class Report>
Report ReadReport(const fs::path& file, const char* stage, const char* section = nullptr) {
  const nlohmann::json json = ReadJsonFile(file);
  const Fields fields(json, file, stage);
  JsonReader reader{section ? fields.Object(section) : fields};
  Report report;
  Describe(reader, report);
  return report;
}

// A pixels-per-view count as written: the number, or "all" for 0.
struct PixelsPerView {
  static nlohmann::json Write(int pixels) { return pixels == 0 ? nlohmann::json("all") : nlohmann::json(pixels); }
  static int Read(const Fields& fields, const char* key) {
    const nlohmann::json& value = fields.At(key);
    if (value == "all") return 0;
    const std::optional<int> pixels = JsonInteger<int>(value);
    if (!pixels || *pixels < 1) fields.Fail(key, "must be \"all\" or a positive count");
    return *pixels;
  }
};

}  // namespace

template <class S>
void Describe(S& s, IngestedImage& image) {
  s("name", image.name);
  s("source", image.source);
  s("width", image.width);
  s("height", image.height);
  s("channels", image.channels);
  s("source_width", image.source_width);
  s("source_height", image.source_height);
  s("exif_orientation", image.orientation);
  s("from_cmyk", image.from_cmyk);
  s("fingerprint", image.fingerprint);
  s.Optional("camera", image.camera);
  s.Optional("frame", image.frame);
  s.Optional("time", image.time);
  s.Check("width", "and height must be positive", [&] { return image.width >= 1 && image.height >= 1; });
}

template <class S>
void Describe(S& s, SkippedPhoto& skip) {
  s("file", skip.file);
  s("reason", skip.reason);
}

template <class S>
void Describe(S& s, IngestedVideo::Frame& frame) {
  s("index", frame.index);
  s("time", frame.time);
  s("image", frame.image);
}

template <class S>
void Describe(S& s, IngestedVideo::Repeat& repeat) {
  s("index", repeat.index);
  s("of", repeat.of);
}

template <class S>
void Describe(S& s, IngestedVideo& video) {
  s("file", video.file);
  s("frames", video.frames);
  s("fps", video.fps);
  s("seconds", video.seconds);
  s("width", video.width);
  s("height", video.height);
  s("sharpness", video.sharpness);
  s("taken", video.taken);
  s("repeats", video.repeats);
  s.Written("left_for_a_sharper_frame", video.frames - video.taken.size() - video.repeats.size());
  s.Check("sharpness", "must have one value a frame", [&] { return video.sharpness.size() == video.frames; });
}

template <class S>
void Describe(S& s, IngestReport& report) {
  s("input_folder", report.input_folder);
  s("images", report.images);
  s("skipped", report.skipped);
  s.Optional("videos", report.videos);
}

template <class S>
void Describe(S& s, SfmReport::LeftOut& left_out) {
  s("image", left_out.image);
  s("reason", left_out.reason);
  s("detail", left_out.detail);
}

template <class S>
void Describe(S& s, SfmReport::Model& model) {
  s("path", model.path);
  s("registered", model.registered);
}

template <class S>
void Describe(S& s, SfmReport::Step& step) {
  s("step", step.step);
  s("wall_seconds", step.wall_seconds);
  s("log", step.log);
}

template <class S>
void Describe(S& s, SfmReport& report) {
  s("images_given", report.images_given);
  s("registered", report.registered);
  s("registered_percent", report.registered_percent);
  s("left_out", report.left_out);
  s("points", report.points);
  s("mean_reprojection_error_px", report.mean_reprojection_error_px);
  s("mean_track_length", report.mean_track_length);
  s("median_axis_to_focus_angle_deg", report.median_axis_to_focus_angle_deg);
  s("colmap_version", report.colmap_version);
  s("matcher", report.matcher);
  s("models", report.models);
  s("chosen_model", report.chosen_model);
  s("steps", report.steps);
  s.Check("registered", "must be at most images_given, which must be positive",
          [&] { return report.images_given > 0 && report.registered <= report.images_given; });
}

template <class S>
void Describe(S& s, FitWarning& warning) {
  s("code", warning.code);
  s("figure", warning.figure);
  s("message", warning.message);
}

template <class S>
void Describe(S& s, TrainReport::ViewPsnr& view) {
  s("view", view.view);
  s("psnr", view.psnr);
}

template <class S>
void Describe(S& s, TrainReport::Evaluations& evaluations) {
  s("count", evaluations.count);
  s("seconds", evaluations.seconds);
  s.template With<PixelsPerView>("pixels_per_view", evaluations.pixels_per_view);
}

template <class S>
void Describe(S& s, TrainReport::Throughput& throughput) {
  s("steps", throughput.steps);
  s("seconds", throughput.seconds);
  s("rays", throughput.rays);
  s("samples", throughput.samples);
  s.Written("samples_per_second", throughput.SamplesPerSecond());
  s.Written("samples_per_ray", throughput.SamplesPerRay());
}

template <class S>
void Describe(S& s, TrainReport::Trainer& trainer) {
  s("march_step", trainer.march_step);
  s("rendered_march_step", trainer.rendered_march_step);
  s("batch_samples", trainer.batch_samples);
  s("late_batch_samples", trainer.late_batch_samples);
  s("scene", trainer.scene);
  s("learning_rate", trainer.learning_rate);
  s("distortion_weight", trainer.distortion_weight);
  s("appearance", trainer.appearance);
  s("refine_cameras", trainer.refine_cameras);
  s("error_sampling", trainer.error_sampling);
  s("background", trainer.background);
  s("background_colour", trainer.background_colour);
}

template <class S>
void Describe(S& s, TrainReport::AppearanceView& view) {
  s("view", view.view);
  s("gain", view.gain);
  s("transform", view.transform);
}

template <class S>
void Describe(S& s, TrainReport::Appearance& appearance) {
  s("enabled", appearance.enabled);
  if (!appearance.enabled) return;
  s("gain_min", appearance.gain_min);
  s("gain_max", appearance.gain_max);
  s("per_view", appearance.per_view);
}

template <class S>
void Describe(S& s, TrainReport::Refinement& refinement) {
  s("enabled", refinement.enabled);
  if (!refinement.enabled) return;
  s("rotation_degrees_median", refinement.rotation_degrees_median);
  s("rotation_degrees_max", refinement.rotation_degrees_max);
  s("shift_median", refinement.shift_median);
  s("shift_max", refinement.shift_max);
}

template <class S>
void Describe(S& s, TrainReport& report) {
  s("steps", report.steps);
  s("wall_seconds", report.wall_seconds);
  s("heldout_psnr", report.heldout_psnr);
  s("heldout_step_scale", report.heldout_step_scale);
  s("heldout_views", report.heldout_views);
  s("heldout_split", report.heldout_split);
  s.template With<PixelsPerView>("heldout_pixels_per_view", report.heldout_pixels_per_view);
  s("heldout_per_view", report.heldout_per_view);
  s.Optional("heldout_rule", report.heldout_rule);
  s("training_psnr", report.training_psnr);
  s.Optional("warnings", report.warnings);
  s("heldout_psnr_fitted", report.heldout_psnr_fitted);
  s.Written("heldout_psnr_fitted_is",
            "each held-out photo's colour transform fitted (least squares) on its left half, PSNR on its right half "
            "(NeRF-W)");
  s("evaluations_during_training", report.evaluations_during_training);
  s("skipped_steps", report.skipped_steps);
  s("resumed_from_step", report.resumed_from_step);
  s("training_views", report.training_views);
  s("training_views_in_memory", report.training_views_in_memory);
  s.Optional("heldout_views_in_memory", report.heldout_views_in_memory);
  s("samples_per_ray_rendered", report.samples_per_ray_rendered);
  s("render_seconds_per_view", report.render_seconds_per_view);
  s("occupied_fraction", report.occupied_fraction);
  s("throughput", report.throughput);
  s("field", report.field);
  s("trainer", report.trainer);
  s("appearance", report.appearance);
  s("camera_refinement", report.camera_refinement);
  s.ReadOnly("camera_refinement", report.refinement);
}

template <class S>
void Describe(S& s, SplatReport& report) {
  s("enabled", report.enabled);
  if (!report.enabled) return;
  s("splats", report.splats);
  s("initial_splats", report.initial_splats);
  s("init", report.init);
  s.Optional("view_share", report.view_share);
  s("sh_degree", report.sh_degree);
  s("steps", report.steps);
  s("seconds", report.seconds);
  s("resumed_from_step", report.resumed_from_step);
  s("heldout_views", report.heldout_views);
  s.Optional("training_views_in_memory", report.training_views_in_memory);
  s.Optional("heldout_views_in_memory", report.heldout_views_in_memory);
  s("heldout_psnr", report.heldout_psnr);
  s("heldout_ssim", report.heldout_ssim);
  s("heldout_psnr_per_view", report.heldout_psnr_per_view);
  s("seconds_per_view", report.seconds_per_view);
  s("frame", report.frame);
  s("frame_description", report.frame_description);
  s("near", report.near);
  s("background", report.background);
  s.Written("file", SplatResult{}.splats().string());
  s("file_bytes", report.file_bytes);
  s.Written("spz", SplatResult{}.spz().string());
  s("spz_bytes", report.spz_bytes);
  s.Written("glb", SplatResult{}.glb().string());
  s("glb_bytes", report.glb_bytes);
  s.Written("viewer", SplatResult{}.viewer().string());
  s("viewer_bytes", report.viewer_bytes);
  s.Optional("warnings", report.warnings);
  s.Check("near", "must be positive", [&] { return report.near > 0; });
  s.Check("view_share", "must be 0..1", [&] { return report.view_share >= 0 && report.view_share <= 1; });
}

template <class S>
void Describe(S& s, HeldoutScore& score) {
  s("view", score.view);
  s("render", score.render);
  s("error_map", score.error_map);
  s("photo", score.photo);
  s("psnr", score.psnr);
  s("ssim", score.ssim);
  s("seconds", score.seconds);
}

template <class S>
void Describe(S& s, EvalReport& report) {
  s("split", report.split);
  s("source", report.source);
  s("views", report.views);
  s("psnr", report.psnr);
  s("ssim", report.ssim);
  s("seconds_per_view", report.seconds_per_view);
  s("samples_per_ray", report.samples_per_ray);
  s("step_scale", report.step_scale);
  s("heat_map_max_error", report.heat_map_max_error);
  s("field_psnr", report.field_psnr);
  s("splats_psnr", report.splats_psnr);
}

template <class S>
void Describe(S& s, PathVideo& video) {
  s("file", video.file);
  s("codec", video.codec);
  s("fps", video.fps);
}

template <class S>
void Describe(S& s, PathReport& report) {
  s("source", report.source);
  s("kind", report.kind);
  s("frames", report.frames);
  s("rendered_frames", report.rendered_frames);
  s("width", report.width);
  s("height", report.height);
  s("seconds_per_frame", report.seconds_per_frame);
  s("frames_per_second", report.frames_per_second);
  s("samples_per_ray", report.samples_per_ray);
  s("depth_png_max", report.depth_png_max);
  s("video", report.video);
}

template <class S>
void Describe(S& s, ExportReport::Mesh& mesh) {
  s("file", mesh.file);
  s("surface", mesh.surface);
  s("vertices", mesh.vertices);
  s("triangles", mesh.triangles);
  s("marched_triangles", mesh.marched_triangles);
  s("simplification_error", mesh.simplification_error);
  s("watertight", mesh.watertight);
  s("border_edges", mesh.border_edges);
  s("non_manifold_edges", mesh.non_manifold_edges);
  s("misoriented_edges", mesh.misoriented_edges);
  s("resolution", mesh.resolution);
  s("threshold", mesh.threshold);
  s("threshold_from_field", mesh.threshold_from_field);
  s.Object("region", [&](auto& region) {
    region("kind", mesh.region);
    region("centre", mesh.centre);
    region("half_size", mesh.half_size);
  });
}

template <class S>
void Describe(S& s, ExportReport::Textured& textured) {
  s("file", textured.file);
  s("bytes", textured.bytes);
  s("texture", textured.texture);
  s("texture_size", textured.texture_size);
  s("obj", textured.obj);
}

template <class S>
void Describe(S& s, ExportReport::Cameras& cameras) {
  s("file", cameras.file);
  s("views", cameras.views);
  s("refined", cameras.refined);
}

template <class S>
void Describe(S& s, ExportedPoints& points) {
  s("file", points.file);
  s("count", points.count);
}

template <class S>
void Describe(S& s, ExportReport& report) {
  s("mesh", report.mesh);
  s("textured", report.textured);
  s("frame", report.frame);
  s("cameras", report.cameras);
  s("depth_views", report.depth_views);
  s("points", report.points);
}

nlohmann::json IngestReport::ToJson() const { return ToJsonValue(*this); }
IngestReport IngestReport::Read(const fs::path& file) { return ReadReport<IngestReport>(file, IngestResult::kId.name); }

nlohmann::json SfmReport::ToJson() const { return ToJsonValue(*this); }
SfmReport SfmReport::Read(const fs::path& file) { return ReadReport<SfmReport>(file, SfmResult::kId.name); }

nlohmann::json TrainReport::ToJson() const { return ToJsonValue(*this); }
TrainReport TrainReport::Read(const fs::path& file) { return ReadReport<TrainReport>(file, TrainResult::kId.name); }

nlohmann::json SplatReport::ToJson() const { return ToJsonValue(*this); }
SplatReport SplatReport::Read(const fs::path& file) { return ReadReport<SplatReport>(file, SplatResult::kId.name); }

nlohmann::json EvalReport::ToJson() const { return ToJsonValue(*this); }
EvalReport EvalReport::Read(const fs::path& file) { return ReadReport<EvalReport>(file, RenderResult::kId.name); }

nlohmann::json PathReport::ToJson() const { return ToJsonValue(*this); }
PathReport PathReport::Read(const fs::path& render_report) {
  return ReadReport<PathReport>(render_report, RenderResult::kId.name, "path");
}

nlohmann::json ExportReport::ToJson() const { return ToJsonValue(*this); }
ExportReport ExportReport::Read(const fs::path& file) { return ReadReport<ExportReport>(file, ExportResult::kId.name); }

}  // namespace p2n

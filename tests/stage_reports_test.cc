// The reports between stages (stages/stage_reports.h): each reads back exactly what its writer wrote, and a
// missing or mistyped field is a UserError that names the file, the field and the stage to rerun.

#include <catch2/catch.hpp>

#include "base/errors.h"
#include "base/file_util.h"
#include "stages/stage_reports.h"
#include "test_util.h"

namespace p2n::testing {
namespace fs = std::filesystem;
namespace {

IngestReport SomeIngestReport() {
  IngestReport report;
  report.input_folder = "/photos";
  report.images = {{"a.png", "a.jpg", 800, 600, 3, 4000, 3000, 6, false, "f1", "Apple iPhone 12, 4.2 mm", {}, {}},
                   {"b.png", "b.tif", 800, 600, 3, 800, 600, 1, true, "f2", "", {}, {}},
                   {"clip_00004.jpg", "clip.mp4", 360, 640, 3, 720, 1280, 1, false, "f3", "video clip.mp4", 4, 0.133}};
  report.skipped = {{"c.jpg", "not an image"}};
  report.videos = {
      {"clip.mp4", 6, 30, 0.2, 720, 1280, {10, 12.5, 3, 14, 11, 2}, {{4, 0.133, "clip_00004.jpg"}}, {{5, 4}}}};
  return report;
}

SfmReport SomeSfmReport() {
  SfmReport report;
  report.images_given = 12;
  report.registered = 11;
  report.registered_percent = 100.0 * 11 / 12;
  report.left_out = {{"blurred.jpg", LeftOutReason::kNoMatches, "none of its 12 features has a verified match"}};
  report.points = 4000;
  report.mean_reprojection_error_px = 0.75;
  report.mean_track_length = 4.5;
  report.median_axis_to_focus_angle_deg = 2.5;
  report.colmap_version = "3.8";
  report.matcher = "exhaustive";
  report.chosen_model = "sparse/0";
  report.models = {{"sparse/0", 11}, {"sparse/1", 3}};
  report.steps = {{"feature extraction", "logs/feature_extraction.log", 4.5}, {"mapping", "logs/mapping.log", 9}};
  return report;
}

TrainReport SomeTrainReport() {
  TrainReport report;
  report.steps = 500;
  report.skipped_steps = 1;
  report.resumed_from_step = 200;
  report.wall_seconds = 61.5;
  report.training_views = 10;
  report.heldout_views = 2;
  report.heldout_split = ViewSplit::kVal;
  report.heldout_pixels_per_view = 0;  // every pixel: "all"
  report.heldout_psnr = 27.25;
  report.heldout_psnr_fitted = 27.5;
  report.heldout_step_scale = 0.5;
  report.heldout_per_view = {{"a.png", 27.0}, {"b.png", 27.5}};
  report.evaluations_during_training = {6, 1.5, 4096};
  report.samples_per_ray_rendered = 9.5;
  report.render_seconds_per_view = 0.25;
  report.occupied_fraction = 0.125;
  report.throughput = TrainReport::Throughput{480, 60.25, 4096 * 480, 4096 * 480 * 12};
  report.field = {{"otype", "ngp"}};
  report.trainer = {
      0.0135,           0.00675, 0.01, 0.002, 65536, 131072, "unbounded", true, true, false, BackgroundChoice::kLearnt,
      {0.25, 0.5, 0.75}};
  report.appearance = {true, 0.875, 1.125, {{"a.png", 0.875, std::vector<float>(12, 0.5f)}}};
  report.camera_refinement = {{"enabled", true},
                              {"rotation_degrees_median", 0.125},
                              {"rotation_degrees_max", 0.25},
                              {"shift_median", 0.001},
                              {"shift_max", 0.002},
                              {"per_view", nlohmann::json::array()}};
  return report;
}

SplatReport SomeSplatReport() {
  SplatReport report;
  report.enabled = true;
  report.splats = 12345;
  report.initial_splats = 9000;
  report.init = SplatInit::kSparse;
  report.view_share = 0.125;
  report.sh_degree = 2;
  report.steps = 77;
  report.resumed_from_step = 40;
  report.seconds = 12.5;
  report.heldout_views = 2;
  report.heldout_psnr = 24.25;
  report.heldout_ssim = 0.81;
  report.heldout_psnr_per_view = {24.0, 24.5};
  report.seconds_per_view = 0.031;
  report.frame = FrameKind::kSource;
  report.frame_description = "COLMAP's world";
  report.near = 0.02;
  report.background = {0.0f, 0.5f, 1.0f};
  report.file_bytes = 1000;
  report.spz_bytes = 90;
  report.glb_bytes = 120;
  report.viewer_bytes = 2000;
  return report;
}

EvalReport SomeEvalReport() {
  EvalReport report;
  report.split = ViewSplit::kVal;
  report.source = RenderSource::kSplats;
  report.views = {{"a.png", "heldout/a.png", "heldout/a_error.png", "/photos/a.png", 25.5, 0.8, 0.1},
                  {"b.png", "heldout/b.png", "heldout/b_error.png", "/photos/b.png", 23.5, 0.7, 0.2}};
  report.psnr = 24.5;
  report.ssim = 0.75;
  report.seconds_per_view = 0.15;
  report.heat_map_max_error = 0.2;
  report.field_psnr = 24.0;
  report.splats_psnr = 24.5;  // samples_per_ray stays none: the splats rendered it
  return report;
}

PathReport SomePathReport() {
  PathReport report;
  report.source = RenderSource::kField;
  report.kind = PathChoice::kOrbit;
  report.frames = 60;
  report.rendered_frames = 31;
  report.width = 320;
  report.height = 240;
  report.seconds_per_frame = 0.5;
  report.frames_per_second = 2;
  report.samples_per_ray = 7.5;
  report.depth_png_max = 6.25;
  report.video = PathVideo{"video.mp4", "avc1", 24};
  return report;
}

ExportReport SomeExportReport() {
  ExportReport report;
  report.mesh = {"mesh.ply",
                 1000,
                 1990,
                 40000,
                 0.0125,
                 false,
                 4,
                 1,
                 0,
                 256,
                 21.5,
                 true,
                 MeshRegion::kFocus,
                 {0.125, -0.25, 0.5},
                 0.375,
                 MeshSurface::kDepths};
  report.textured = {"mesh.glb", 123456, "mesh_texture.jpg", 1024, ""};
  report.frame = FrameKind::kSource;
  report.cameras = {"transforms.json", 50, true};
  report.points = ExportedPoints{"points.ply", 12345};
  return report;
}

// The UserError that reading `file` after replacing `key` of its JSON (a JSON pointer) by `value` throws.
template <class Report>
std::string ErrorAfterEdit(const fs::path& file, const nlohmann::json& written, const std::string& key,
                           const nlohmann::json& value) {
  nlohmann::json edited = written;
  if (value.is_discarded()) {
    edited.erase(nlohmann::json::json_pointer(key).back());
  } else {
    edited[nlohmann::json::json_pointer(key)] = value;
  }
  WriteJsonAtomic(file, edited);
  try {
    Report::Read(file);
  } catch (const UserError& error) {
    return error.what();
  }
  return "no error";
}

}  // namespace

TEST_CASE("Reports between stages read back exactly what was written: ingest and sfm", "[reports]") {
  TempDir dir;
  const IngestReport ingest = SomeIngestReport();
  WriteJsonAtomic(dir.path() / "ingest_report.json", ingest.ToJson());
  const IngestReport ingest_read = IngestReport::Read(dir.path() / "ingest_report.json");
  CHECK(ingest_read.ToJson() == ingest.ToJson());
  CHECK(ingest_read.images.at(0).orientation == 6);
  CHECK(ingest_read.images.at(1).from_cmyk);
  CHECK_FALSE(ingest_read.images.at(1).frame.has_value());
  CHECK(ingest_read.images.at(2).frame == 4u);
  CHECK(ingest_read.videos.at(0).taken.at(0).image == "clip_00004.jpg");
  CHECK(ingest.ToJson()["videos"][0]["left_for_a_sharper_frame"] == 4);

  const SfmReport sfm = SomeSfmReport();
  WriteJsonAtomic(dir.path() / "sfm_report.json", sfm.ToJson());
  const SfmReport sfm_read = SfmReport::Read(dir.path() / "sfm_report.json");
  CHECK(sfm_read.ToJson() == sfm.ToJson());
  REQUIRE(sfm_read.left_out.size() == 1);
  CHECK(sfm_read.left_out[0].image == "blurred.jpg");
  CHECK(sfm_read.left_out[0].reason == LeftOutReason::kNoMatches);
  SfmReport unfocused = sfm;
  unfocused.median_axis_to_focus_angle_deg.reset();
  WriteJsonAtomic(dir.path() / "sfm_report.json", unfocused.ToJson());
  CHECK_FALSE(SfmReport::Read(dir.path() / "sfm_report.json").median_axis_to_focus_angle_deg.has_value());
}

TEST_CASE("Reports between stages read back exactly what was written: train and splat", "[reports]") {
  TempDir dir;
  const TrainReport train = SomeTrainReport();
  WriteJsonAtomic(dir.path() / "train_report.json", train.ToJson());
  const TrainReport train_read = TrainReport::Read(dir.path() / "train_report.json");
  CHECK(train_read.ToJson() == train.ToJson());
  CHECK(train_read.heldout_pixels_per_view == 0);
  CHECK(train_read.refinement.enabled);
  CHECK(train_read.refinement.rotation_degrees_max == 0.25);
  CHECK(train_read.appearance.per_view.at(0).transform.size() == 12);
  CHECK(train_read.throughput.value().samples == 4096 * 480 * 12);
  CHECK(train.ToJson()["throughput"]["samples_per_ray"] == 12.0);
  TrainReport plain = train;
  plain.appearance = {};
  plain.camera_refinement = {{"enabled", false}};
  plain.heldout_psnr.reset();
  plain.heldout_step_scale.reset();  // as in reports written before it was recorded
  plain.throughput.reset();
  WriteJsonAtomic(dir.path() / "train_report.json", plain.ToJson());
  CHECK(TrainReport::Read(dir.path() / "train_report.json").ToJson() == plain.ToJson());
  nlohmann::json older = plain.ToJson();
  older.erase("throughput");  // written before it was recorded
  WriteJsonAtomic(dir.path() / "train_report.json", older);
  CHECK_FALSE(TrainReport::Read(dir.path() / "train_report.json").throughput.has_value());

  const SplatReport splat = SomeSplatReport();
  WriteJsonAtomic(dir.path() / "splat_report.json", splat.ToJson());
  CHECK(SplatReport::Read(dir.path() / "splat_report.json").ToJson() == splat.ToJson());
  nlohmann::json older_splat = splat.ToJson();
  older_splat.erase("view_share");  // written before it was recorded
  WriteJsonAtomic(dir.path() / "splat_report.json", older_splat);
  CHECK(SplatReport::Read(dir.path() / "splat_report.json").view_share == 1);
  WriteJsonAtomic(dir.path() / "off.json", SplatReport{}.ToJson());
  CHECK_FALSE(SplatReport::Read(dir.path() / "off.json").enabled);
}

TEST_CASE("Reports between stages read back exactly what was written: render and export", "[reports]") {
  TempDir dir;
  const EvalReport eval = SomeEvalReport();
  WriteJsonAtomic(dir.path() / "eval.json", eval.ToJson());
  const EvalReport eval_read = EvalReport::Read(dir.path() / "eval.json");
  CHECK(eval_read.ToJson() == eval.ToJson());
  CHECK_FALSE(eval_read.samples_per_ray.has_value());
  CHECK(eval_read.views.at(1).psnr == 23.5);

  const PathReport path = SomePathReport();
  WriteJsonAtomic(dir.path() / "render_report.json", {{"path", path.ToJson()}});
  const PathReport path_read = PathReport::Read(dir.path() / "render_report.json");
  CHECK(path_read.ToJson() == path.ToJson());
  REQUIRE(path_read.video.has_value());
  CHECK(path_read.video->codec == "avc1");
  PathReport no_video = path;
  no_video.video.reset();
  no_video.samples_per_ray.reset();
  WriteJsonAtomic(dir.path() / "render_report.json", {{"path", no_video.ToJson()}});
  CHECK_FALSE(PathReport::Read(dir.path() / "render_report.json").video.has_value());

  const ExportReport exported = SomeExportReport();
  WriteJsonAtomic(dir.path() / "export_report.json", exported.ToJson());
  const ExportReport exported_read = ExportReport::Read(dir.path() / "export_report.json");
  CHECK(exported_read.ToJson() == exported.ToJson());
  CHECK(exported_read.mesh.centre[1] == -0.25);
  ExportReport no_points = exported;
  no_points.points.reset();
  WriteJsonAtomic(dir.path() / "export_report.json", no_points.ToJson());
  CHECK_FALSE(ExportReport::Read(dir.path() / "export_report.json").points.has_value());
  CHECK_THAT(ErrorAfterEdit<ExportReport>(dir.path() / "export_report.json", exported.ToJson(), "/mesh/region/centre",
                                          nlohmann::json::array({1, 2})),
             Catch::Contains("export_report.json") && Catch::Contains("\"mesh.region.centre\"") &&
                 Catch::Contains("photo2nerf export"));
  CHECK_THAT(
      ErrorAfterEdit<ExportReport>(dir.path() / "export_report.json", exported.ToJson(), "/mesh/region/kind", "sphere"),
      Catch::Contains("\"mesh.region.kind\" must be auto, box or focus, not 'sphere'"));
}

TEST_CASE("A damaged report names its file, the field and the stage to rerun", "[reports]") {
  TempDir dir;
  const fs::path ingest = dir.path() / "ingest_report.json";
  const nlohmann::json ingest_json = SomeIngestReport().ToJson();
  CHECK_THAT(
      ErrorAfterEdit<IngestReport>(ingest, ingest_json, "/images/1/width", 0),
      Catch::Contains("\"images[1].width\" and height must be positive") && Catch::Contains("photo2nerf ingest"));
  CHECK_THAT(ErrorAfterEdit<IngestReport>(ingest, ingest_json, "/skipped/0/reason", 7),
             Catch::Contains("\"skipped[0].reason\" has the wrong type (number)"));
  CHECK_THAT(ErrorAfterEdit<IngestReport>(ingest, ingest_json, "/videos/0/frames", 7),
             Catch::Contains("\"videos[0].sharpness\" must have one value a frame"));

  const fs::path sfm = dir.path() / "sfm_report.json";
  const nlohmann::json sfm_json = SomeSfmReport().ToJson();
  CHECK_THAT(ErrorAfterEdit<SfmReport>(sfm, sfm_json, "/registered", 13),
             Catch::Contains("\"registered\" must be at most images_given") && Catch::Contains("photo2nerf sfm"));
  // Numbers no integer field holds (undefined behaviour if cast) are refused like any damage.
  CHECK_THAT(ErrorAfterEdit<SfmReport>(sfm, sfm_json, "/points", 1e30),
             Catch::Contains("\"points\" must be a whole number in range, not 1e+30"));
  CHECK_THAT(ErrorAfterEdit<SfmReport>(sfm, sfm_json, "/points", -1),
             Catch::Contains("\"points\" must be a whole number in range, not -1"));
  CHECK_THAT(ErrorAfterEdit<SfmReport>(sfm, sfm_json, "/left_out", "none"),
             Catch::Contains("\"left_out\" must be an array"));
  CHECK_THAT(ErrorAfterEdit<SfmReport>(sfm, sfm_json, "/left_out/0/reason", "blurry"),
             Catch::Contains("\"left_out[0].reason\" must be") && Catch::Contains("not 'blurry'"));
  CHECK_THAT(ErrorAfterEdit<SfmReport>(sfm, sfm_json, "/steps/1/wall_seconds", "long"),
             Catch::Contains("\"steps[1].wall_seconds\" must be a number, not string"));

  const fs::path train = dir.path() / "train_report.json";
  const nlohmann::json train_json = SomeTrainReport().ToJson();
  CHECK_THAT(ErrorAfterEdit<TrainReport>(train, train_json, "/heldout_psnr", "good"),
             Catch::Contains("train_report.json") && Catch::Contains("\"heldout_psnr\" must be a number, not string") &&
                 Catch::Contains("photo2nerf train -w WORKSPACE --force"));
  CHECK_THAT(ErrorAfterEdit<TrainReport>(train, train_json, "/evaluations_during_training/pixels_per_view", "some"),
             Catch::Contains("\"evaluations_during_training.pixels_per_view\" must be \"all\" or a positive count"));
  CHECK_THAT(ErrorAfterEdit<TrainReport>(train, train_json, "/camera_refinement/shift_max", nullptr),
             Catch::Contains("\"camera_refinement.shift_max\" must be a number, not null"));
  CHECK_THAT(ErrorAfterEdit<TrainReport>(train, train_json, "/trainer/background_colour", nlohmann::json::array()),
             Catch::Contains("\"trainer.background_colour\" must be 3 numbers"));
  CHECK_THAT(ErrorAfterEdit<TrainReport>(train, train_json, "/appearance/per_view/0/transform", "identity"),
             Catch::Contains("\"appearance.per_view[0].transform\" has the wrong type (string)"));

  const fs::path splat = dir.path() / "splat_report.json";
  const nlohmann::json splat_json = SomeSplatReport().ToJson();
  CHECK_THAT(ErrorAfterEdit<SplatReport>(splat, splat_json, "/near", "far"),
             Catch::Contains("splat_report.json") && Catch::Contains("\"near\" must be a number, not string") &&
                 Catch::Contains("photo2nerf splat -w WORKSPACE --force"));
  CHECK_THAT(ErrorAfterEdit<SplatReport>(splat, splat_json, "/near", -1), Catch::Contains("\"near\" must be positive"));
  CHECK_THAT(ErrorAfterEdit<SplatReport>(splat, splat_json, "/background", nlohmann::json::array({1, 1})),
             Catch::Contains("\"background\" must be 3 numbers"));
  CHECK_THAT(ErrorAfterEdit<SplatReport>(splat, splat_json, "/frame", "sideways"),
             Catch::Contains("\"frame\" must be source or normalized, not 'sideways'"));
  CHECK_THAT(ErrorAfterEdit<SplatReport>(splat, splat_json, "/steps", nlohmann::json::value_t::discarded),
             Catch::Contains("\"steps\" is missing"));
  CHECK_THAT(ErrorAfterEdit<SplatReport>(splat, splat_json, "/view_share", 2),
             Catch::Contains("\"view_share\" must be 0..1"));

  const fs::path eval = dir.path() / "eval.json";
  const nlohmann::json eval_json = SomeEvalReport().ToJson();
  CHECK_THAT(ErrorAfterEdit<EvalReport>(eval, eval_json, "/views/1/psnr", nullptr),
             Catch::Contains("\"views[1].psnr\" must be a number, not null") && Catch::Contains("photo2nerf render"));
  CHECK_THAT(ErrorAfterEdit<EvalReport>(eval, eval_json, "/views", "none"),
             Catch::Contains("\"views\" must be an array"));
  CHECK_THAT(ErrorAfterEdit<EvalReport>(eval, eval_json, "/psnr", "high"),
             Catch::Contains("\"psnr\" must be a number, not string"));

  const fs::path render = dir.path() / "render_report.json";
  const nlohmann::json render_json = {{"path", SomePathReport().ToJson()}};
  CHECK_THAT(ErrorAfterEdit<PathReport>(render, render_json, "/path/video/fps", "fast"),
             Catch::Contains("\"path.video.fps\" must be a number"));
  CHECK_THAT(ErrorAfterEdit<PathReport>(render, render_json, "/path", nlohmann::json::value_t::discarded),
             Catch::Contains("\"path\" is missing"));
}

}  // namespace p2n::testing

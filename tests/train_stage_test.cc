// The train stage in the pipeline: its outputs, its cache, and resuming a cancelled run from its checkpoint.

#include <catch2/catch.hpp>

#include <OpenImageIO/imagebufalgo.h>

#include <algorithm>
#include <functional>
#include <thread>

#include "base/errors.h"
#include "base/file_util.h"
#include "nerf/nerf_model.h"
#include "nerf/ngp_field.h"
#include "pipeline/cancel.h"
#include "stage_fixtures.h"
#include "stages/fitting/train_presets.h"
#include "stages/fitting/train_settings.h"
#include "stages/fitting/train_stage.h"
#include "stages/stage_reports.h"
#include "stages/stages.h"
#include "test_camera.h"

namespace p2n::testing {
namespace fs = std::filesystem;

TEST_CASE(
    "train stage: train.scene auto is bounded for Blender and .npz data, forward for one-sided captures of any format",
    "[train]") {
  const auto dataset = [](std::optional<DatasetKind> kind, const std::vector<double>& azimuths_deg) {
    ImportedDataset poses;
    poses.meta.dataset_kind = kind;
    for (const PinholeCamera& camera : RingOfCameras(azimuths_deg)) {
      ImportedView view;
      view.view.camera = camera;
      poses.views.push_back(std::move(view));
    }
    return poses;
  };
  const std::vector<double> one_side = {-10, 0, 10}, around = {0, 60, 120, 180, 240, 300};
  TrainOptions options;
  CHECK(ResolveSceneSpace(options, dataset(DatasetKind::kBlender, one_side)) == SceneSpace::kBounded);
  CHECK(ResolveSceneSpace(options, dataset(DatasetKind::kNpz, around)) == SceneSpace::kBounded);
  CHECK(ResolveSceneSpace(options, dataset(DatasetKind::kLlff, one_side)) == SceneSpace::kForward);
  // poses_bounds.npy holds captures taken around an object too (maryrose): unbounded like any such photos
  CHECK(ResolveSceneSpace(options, dataset(DatasetKind::kLlff, around)) == SceneSpace::kUnbounded);
  CHECK(ResolveSceneSpace(options, dataset(std::nullopt, one_side)) == SceneSpace::kForward);
  CHECK(ResolveSceneSpace(options, dataset(DatasetKind::kColmap, around)) == SceneSpace::kUnbounded);
  options.scene = SceneChoice::kUnbounded;
  CHECK(ResolveSceneSpace(options, dataset(std::nullopt, one_side)) == SceneSpace::kUnbounded);
}

TEST_CASE("train stage: bounded scenes get the default preset's larger hash table, occupancy grid and late batch",
          "[train]") {
  const auto table_log2 = [](const TrainOptions& options, SceneSpace space) {
    return NgpFieldConfig::FromJson(MakeTrainerOptions(options, space).field).grid.log2_table_size;
  };
  TrainOptions options;
  CHECK(table_log2(options, SceneSpace::kBounded) == 19);
  CHECK(table_log2(options, SceneSpace::kUnbounded) == 17);
  CHECK(table_log2(options, SceneSpace::kForward) == 17);
  CHECK(MakeTrainerOptions(options, SceneSpace::kBounded).occupancy_resolution == 256);
  CHECK(MakeTrainerOptions(options, SceneSpace::kUnbounded).occupancy_resolution == 128);
  CHECK(MakeTrainerOptions(options, SceneSpace::kForward).occupancy_resolution == 128);
  // And steps of twice the samples in the run's second half, unless train.batch_samples says otherwise.
  CHECK(MakeTrainerOptions(options, SceneSpace::kBounded).batch_samples == 65536);
  CHECK(MakeTrainerOptions(options, SceneSpace::kBounded).late_batch_samples == 131072);
  CHECK(MakeTrainerOptions(options, SceneSpace::kUnbounded).late_batch_samples == 0);
  CHECK(MakeTrainerOptions(options, SceneSpace::kForward).late_batch_samples == 0);
  options.batch_samples = 32768;
  CHECK(MakeTrainerOptions(options, SceneSpace::kBounded).late_batch_samples == 0);
  options.batch_samples = 0;
  options.preset = PresetName::kFast;
  CHECK(table_log2(options, SceneSpace::kBounded) == 15);
  CHECK(MakeTrainerOptions(options, SceneSpace::kBounded).occupancy_resolution == 64);
  CHECK(MakeTrainerOptions(options, SceneSpace::kBounded).late_batch_samples == 0);
  options.hash_table_log2 = 16;
  CHECK(table_log2(options, SceneSpace::kBounded) == 16);
  CHECK(table_log2(options, SceneSpace::kUnbounded) == 16);
}

TEST_CASE("train stage: planes take the image plane's resolution by the scene, or as the options say", "[train]") {
  const auto planes = [](const TrainOptions& options, SceneSpace space) {
    return NgpFieldConfig::FromJson(MakeTrainerOptions(options, space).field).planes;
  };
  TrainOptions options;
  CHECK_FALSE(planes(options, SceneSpace::kForward).has_value());  // ngp: a hash grid
  options.field = FieldKind::kPlanes;
  REQUIRE(planes(options, SceneSpace::kForward).has_value());
  CHECK(planes(options, SceneSpace::kForward)->depth_resolution <
        planes(options, SceneSpace::kForward)->finest_resolution);
  CHECK(planes(options, SceneSpace::kUnbounded)->depth_resolution ==
        planes(options, SceneSpace::kUnbounded)->finest_resolution);
  options.plane_resolution = 512;
  options.plane_depth_resolution = 128;
  CHECK(planes(options, SceneSpace::kBounded) ==
        PlaneGridConfig{.levels = 4, .features_per_level = 8, .finest_resolution = 512, .depth_resolution = 128});
  options.plane_depth_resolution = 4;
  CHECK_THROWS_WITH(options.Check(), Catch::Contains("train.plane_depth_resolution"));
}

TEST_CASE("train stage: train.depth auto weighs the depth loss in captures of few photos only", "[train]") {
  TrainOptions options;
  CHECK(DepthWeight(options, kFewViews - 1) == kAutoDepth);
  CHECK(DepthWeight(options, 5) == kAutoDepth);
  CHECK(DepthWeight(options, kFewViews) == 0.0);
  options.depth.value = 0.0;
  CHECK(DepthWeight(options, 5) == 0.0);
  options.depth.value = 0.25;
  CHECK(DepthWeight(options, 200) == 0.25);
  options.depth.value = -1.0;
  CHECK_THROWS_WITH(options.Check(), Catch::Contains("train.depth"));
}

TEST_CASE("train stage: a short time budget trains with the fast preset's sizes, whatever the preset", "[train]") {
  const auto table_log2 = [](const TrainOptions& options, SceneSpace space) {
    return NgpFieldConfig::FromJson(MakeTrainerOptions(options, space).field).grid.log2_table_size;
  };
  TrainOptions options;
  for (const PresetName preset : {PresetName::kDefault, PresetName::kQuality}) {
    options.preset = preset;
    options.time_budget = kShortBudget - 1;
    CHECK(table_log2(options, SceneSpace::kBounded) == 15);
    CHECK(MakeTrainerOptions(options, SceneSpace::kBounded).occupancy_resolution == 64);
    CHECK(MakeTrainerOptions(options, SceneSpace::kBounded).batch_samples == 32768);
    CHECK(MakeTrainerOptions(options, SceneSpace::kBounded).late_batch_samples == 0);
    CHECK(ResolvedTimeBudget(options) == kShortBudget - 1);
    options.time_budget = kShortBudget;
    CHECK(table_log2(options, SceneSpace::kBounded) == 19);
  }
  // A run by steps keeps the preset's sizes.
  options.preset = PresetName::kDefault;
  options.time_budget = 0;
  options.steps = 100;
  CHECK(table_log2(options, SceneSpace::kBounded) == 19);
}

TEST_CASE("train stage: model.bin, metrics.csv and train_report.json, fresh on a rerun, stale on a new seed",
          "[train]") {
  StageWorkspace setup;
  const TempDir& dir = setup.dir;
  Workspace& workspace = setup.workspace;
  const Runner& runner = setup.runner;
  Config config = SmallStageConfig(40);
  runner.Run(workspace, config, Until("train"));

  const fs::path out = dir / "ws" / "30_train";
  const nlohmann::json report = ReadJsonFile(out / "train_report.json");
  CHECK(report["steps"] == 40);
  CHECK(report["wall_seconds"].get<double>() > 0);
  CHECK(report["heldout_views"].get<int>() == 2);  // as many as every 8th of 12, inside the cameras' span
  CHECK_THAT(report["heldout_rule"].get<std::string>(), Catch::Contains("2 of 12 views"));
  CHECK(std::isfinite(report["training_psnr"].get<double>()));
  CHECK(report["warnings"].is_array());
  CHECK(std::isfinite(report["heldout_psnr"].get<double>()));
  CHECK(report["heldout_per_view"].size() == 2);
  // Photos: an unbounded scene; the held-out score with each photo's colour transform fitted on its left half.
  CHECK(report["trainer"]["scene"] == "unbounded");
  CHECK(report["appearance"]["enabled"] == false);
  CHECK(std::isfinite(report["heldout_psnr_fitted"].get<double>()));
  const std::string metrics = ReadText(out / "metrics.csv");
  CHECK(metrics.rfind("wall_seconds,step,train_loss,heldout_psnr\n", 0) == 0);
  CHECK(std::count(metrics.begin(), metrics.end(), '\n') >= 2);  // the header and at least the final row
  const NerfModel model = LoadModel(out / "model.bin");
  CHECK(model.info["steps"] == 40);
  // Photos without alpha: the colour behind the scene is learnt (trainer_test: towards the sky's), and the report
  // says which it is. Forty steps do not tell where it goes: a young field paints the sky as haze in front of it.
  CHECK(report["trainer"]["background"] == "learnt");
  for (int c = 0; c < 3; ++c) CHECK(report["trainer"]["background_colour"][c] == model.background[c]);
  CHECK(fs::exists(out / "psnr.png"));
  CHECK_FALSE(fs::exists(dir / "ws" / "30_train.resume"));

  CHECK(setup.Status(config, "poses").state == StageState::kFresh);
  CHECK(setup.Status(config, "train").state == StageState::kFresh);
  config.Set("train.seed", 3, "test");
  const StageStatus after = setup.Status(config, "train");
  CHECK(after.state == StageState::kStale);
  CHECK_THAT(after.reasons.front(), Catch::Contains("train.seed"));
}

TEST_CASE("train stage: held-out evaluations during training take at most train.eval_share of the time", "[train]") {
  // Asked to evaluate after every step, on every held-out pixel (an evaluation costs about a step or more).
  for (const double share : {1.0, 0.1}) {
    StageWorkspace setup;
    Config config = SmallStageConfig(40);
    config.Set("train.eval_interval", 1e-6, "test");
    config.Set("train.eval_pixels", 0, "test");
    config.Set("train.eval_share", share, "test");
    setup.runner.Run(setup.workspace, config, Until("train"));
    const fs::path out = setup.dir / "ws" / "30_train";
    const nlohmann::json evaluations = ReadJsonFile(out / "train_report.json")["evaluations_during_training"];
    const std::string metrics = ReadText(out / "metrics.csv");
    INFO("eval_share " << share);
    CHECK(evaluations["count"].get<long>() == std::count(metrics.begin(), metrics.end(), '\n') - 1);  // its rows
    CHECK(evaluations["pixels_per_view"] == "all");
    if (share == 1.0) {
      CHECK(evaluations["count"] == 40);
    } else {
      CHECK(evaluations["count"].get<int>() <= 20);
    }
  }
}

TEST_CASE("train stage: with train.appearance on, the report lists each training photo's colour transform", "[train]") {
  StageWorkspace setup;
  Config config = SmallStageConfig(10);
  config.Set("train.appearance", "on", "test");
  setup.runner.Run(setup.workspace, config, Until("train"));
  const nlohmann::json report = ReadJsonFile(setup.dir / "ws" / "30_train" / "train_report.json");
  const nlohmann::json& appearance = report["appearance"];
  CHECK(appearance["enabled"] == true);
  CHECK(report["trainer"]["appearance"] == true);
  REQUIRE(appearance["per_view"].size() == 10);
  CHECK(appearance["per_view"][0]["transform"].size() == 12);
  CHECK(appearance["gain_min"].get<double>() <= appearance["gain_max"].get<double>());
  CHECK(appearance["gain_min"].get<double>() > 0.5);  // ten steps move a transform by about a percent at most
  CHECK(appearance["gain_max"].get<double>() < 1.5);
}

TEST_CASE("train stage: a cancelled run resumes from its checkpoint and finishes the same number of steps", "[train]") {
  StageWorkspace setup;
  const TempDir& dir = setup.dir;
  Workspace& workspace = setup.workspace;
  const Runner& runner = setup.runner;
  Config config = SmallStageConfig(60);
  config.Set("train.checkpoint_interval", 0.05, "test");
  config.Set("train.eval_interval", 1e6, "test");  // only the final evaluation: it is not what this test is about
  const fs::path checkpoint = dir / "ws" / "30_train.resume" / "checkpoint.bin";
  // Cancel (as Ctrl-C does) once a checkpoint exists.
  std::thread canceller([&] {
    while (!fs::exists(checkpoint)) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    RequestCancel();
  });
  CHECK_THROWS_AS(runner.Run(workspace, config, Until("train")), Cancelled);
  canceller.join();
  ResetCancel();
  REQUIRE(fs::exists(checkpoint));
  CHECK_FALSE(fs::exists(dir / "ws" / "30_train"));

  runner.Run(workspace, config, Until("train"));
  const nlohmann::json report = ReadJsonFile(dir / "ws" / "30_train" / "train_report.json");
  CHECK(report["steps"] == 60);
  CHECK(report["resumed_from_step"].get<int>() > 0);
  CHECK(report["resumed_from_step"].get<int>() < 60);
  const nlohmann::json& throughput = report["throughput"];  // of this session of the run
  CHECK(throughput["steps"] == 60 - report["resumed_from_step"].get<int>());
  CHECK(throughput["rays"].get<size_t>() > 0);
  CHECK(throughput["samples"].get<size_t>() > 0);
  CHECK_FALSE(fs::exists(checkpoint));  // removed once the stage is complete

  // A checkpoint of other options is not resumed from: it would be another result.
  fs::create_directories(checkpoint.parent_path());
  WriteText(checkpoint, "not a checkpoint");
  config.Set("train.seed", 9, "test");
  runner.Run(workspace, config, Until("train"));
  CHECK(ReadJsonFile(dir / "ws" / "30_train" / "train_report.json")["resumed_from_step"] == 0);
}

TEST_CASE("train stage: train.blocks trains the field whole, then by slabs, and keeps their composite in model.bin",
          "[train][blocks]") {
  StageWorkspace setup;
  Config config = SmallStageConfig(200);
  config.Set("train.blocks", 2, "test");
  setup.runner.Run(setup.workspace, config, Until("train"));
  const fs::path out = setup.dir / "ws" / "30_train";
  const nlohmann::json report = ReadJsonFile(out / "train_report.json");
  // The whole part's 100 steps, then each block's 100.
  CHECK(report["steps"] == 300);
  CHECK(report["field"]["otype"] == "BlockedField");
  REQUIRE(report["field"]["fields"].size() == 2);
  CHECK(std::isfinite(report["heldout_psnr"].get<double>()));
  const NerfModel model = LoadModel(out / "model.bin");
  CHECK(model.info["steps"] == 300);
  CHECK_FALSE(fs::exists(setup.dir / "ws" / "30_train.resume"));

  // The composite scores about as the field trained whole for as many steps (a capture this small: every view sees
  // both slabs).
  Config whole = SmallStageConfig(200);
  StageWorkspace other;
  other.runner.Run(other.workspace, whole, Until("train"));
  const double whole_psnr =
      ReadJsonFile(other.dir / "ws" / "30_train" / "train_report.json")["heldout_psnr"].get<double>();
  CHECK(report["heldout_psnr"].get<double>() > whole_psnr - 1.0);
  // The training photos lent to the blocks came back: the final evaluation scores the composite on them.
  CHECK(report["training_psnr"].get<double>() > report["heldout_psnr"].get<double>() - 1.0);
}

// Ten training photos of 9 KB; 0.06 MB hold six: the whole part's window of four, each block's as many.
TEST_CASE("train stage: by blocks, photos beyond train.photo_memory train through a window, the blocks' too",
          "[train][blocks]") {
  StageWorkspace setup;
  Config config = SmallStageConfig(200);
  config.Set("train.blocks", 2, "test");
  config.Set("train.photo_memory", 0.06, "test");
  setup.runner.Run(setup.workspace, config, Until("train"));
  const nlohmann::json report = ReadJsonFile(setup.dir / "ws" / "30_train" / "train_report.json");
  CHECK(report["steps"] == 300);
  CHECK(report["training_views_in_memory"] == 4);
  CHECK(std::isfinite(report["heldout_psnr"].get<double>()));
  // The window's photos let go while the blocks trained are back: the final evaluation scores the composite on them.
  CHECK(report["training_psnr"].get<double>() > report["heldout_psnr"].get<double>() - 1.0);
}

// A field block's job (its part run alone, as a scheduler runs it) decodes no photo but its block's: every other
// photo, held out or training, is cut to half its bytes while the job runs (its header still read, its pixels not:
// a job that decoded it would fail), in memory or through a window (0.06 MB: each block's photos decoded into its own
// copy), and the composite is the run's in turn.
TEST_CASE("train stage: a field block's job decodes its block's photos alone", "[train][blocks]") {
  const double photo_memory = GENERATE(2048.0, 0.06);
  Config config = SmallStageConfig(200);
  config.Set("train.blocks", 2, "test");
  config.Set("train.photo_memory", photo_memory, "test");
  StageWorkspace in_turn;
  in_turn.runner.Run(in_turn.workspace, config, Until("train"));
  const nlohmann::json here = ReadJsonFile(in_turn.dir / "ws" / "30_train" / "train_report.json");

  StageWorkspace setup;
  setup.runner.Run(setup.workspace, config, Until("poses"));
  std::vector<std::pair<fs::path, std::string>> photos;  // each photo the poses stage keeps and its split
  const fs::path poses_dir = setup.dir / "ws" / "20_poses";
  const nlohmann::json poses = ReadJsonFile(poses_dir / "transforms.json");
  for (const nlohmann::json& frame : poses["frames"]) {
    photos.emplace_back(poses_dir / frame["file_path"].get<std::string>(), frame["split"]);
  }
  const fs::path staging = setup.workspace.StagingDir("30_train");
  fs::create_directories(staging);
  size_t jobs = 0, cut = 0;
  StageWork work;
  work.parts = [&](const std::string& kind, const std::vector<int>& parts, const std::function<void(int)>&) {
    REQUIRE(kind == kBlockWork);
    const nlohmann::json start = ReadJsonFile(setup.dir / "ws" / "30_train.resume" / "blocks.json");
    for (const int part : parts) {
      const std::vector<size_t> views = start["views"][part - 1];
      std::vector<std::pair<fs::path, std::string>> kept;  // each photo cut and its bytes
      size_t train = 0;
      for (const auto& [photo, split] : photos) {
        const bool mine = split == "train" && std::count(views.begin(), views.end(), train++) > 0;
        if (mine) continue;
        kept.emplace_back(photo, ReadText(photo));
        WriteText(photo, kept.back().second.substr(0, kept.back().second.size() / 2));
      }
      StageWork job;
      job.part = part;
      job.work = kind;
      setup.runner.RunWork(setup.workspace, config, "train", "key", job);
      for (const auto& [photo, bytes] : kept) WriteText(photo, bytes);
      cut += kept.size();
      ++jobs;
    }
  };
  setup.runner.RunWork(setup.workspace, config, "train", "key", work);
  CHECK(jobs == 2);
  CHECK(cut >= 2 * 2);  // at least the two held-out photos, in each job
  const nlohmann::json there = ReadJsonFile(staging / "train_report.json");
  CHECK(there["steps"] == 300);
  CHECK(there["field"]["fields"].size() == 2);
  CHECK(there["heldout_psnr"].get<double>() == Approx(here["heldout_psnr"].get<double>()).margin(0.3));
}

// A training photo gone from a block's job's machine (transforms.json's reader leaves its frame out, which would shift
// the training views the blocks index): the job refuses, naming the photo, and trains no block on other views.
TEST_CASE("train stage: a field block's job without a training photo of the blocks names it",
          "[train][blocks][bad_input]") {
  StageWorkspace setup;
  Config config = SmallStageConfig(200);
  config.Set("train.blocks", 2, "test");
  setup.runner.Run(setup.workspace, config, Until("poses"));
  const fs::path photo = setup.FirstTrainingPhoto();
  const StageWorkspace::JobsRun run = setup.RunJobsWithout(config, "train", "30_train", photo);
  REQUIRE(run.jobs.size() == 2);
  for (const std::string& job : run.jobs) {
    CHECK_THAT(job, Catch::Contains(photo.filename().string()) && Catch::Contains("can be read on this machine"));
  }
  CHECK_THAT(run.stage, Catch::Contains("did not finish"));
  CHECK_FALSE(fs::exists(setup.dir / "ws" / "30_train.resume" / "block1.json"));
}

TEST_CASE("train stage: a run by blocks cancelled after a block resumes with the blocks left", "[train][blocks]") {
  StageWorkspace setup;
  Config config = SmallStageConfig(200);
  config.Set("train.blocks", 2, "test");
  const fs::path first_done = setup.dir / "ws" / "30_train.resume" / "block1.json";
  std::thread canceller([&] {
    while (!fs::exists(first_done)) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    RequestCancel();
  });
  CHECK_THROWS_AS(setup.runner.Run(setup.workspace, config, Until("train")), Cancelled);
  canceller.join();
  ResetCancel();
  REQUIRE(fs::exists(first_done));
  setup.runner.Run(setup.workspace, config, Until("train"));
  const nlohmann::json report = ReadJsonFile(setup.dir / "ws" / "30_train" / "train_report.json");
  CHECK(report["steps"] == 300);
  CHECK(report["field"]["fields"].size() == 2);
  CHECK(report["resumed_from_step"] == 100);  // the whole part's end
}

}  // namespace p2n::testing

namespace p2n::testing {

TEST_CASE("train stage: a held-out photo that does not match its camera is named in a warning", "[train][fit]") {
  StageWorkspace setup;
  Config config = SmallStageConfig(300);
  setup.runner.Run(setup.workspace, config, Until("poses"));
  const nlohmann::json poses = ReadJsonFile(setup.dir / "ws" / "20_poses" / "transforms.json");
  std::vector<std::string> heldout;
  for (const nlohmann::json& frame : poses["frames"]) {
    if (frame["split"] == "val") heldout.push_back(fs::path(frame["file_path"].get<std::string>()).filename());
  }
  REQUIRE(heldout.size() == 2);
  // The first held-out photo becomes its own negative: what its camera sees is no longer in it (as when structure
  // from motion gives a photo a wrong camera, with far more certainty on a scene this small and a field this young).
  const fs::path photo = setup.data / heldout[0];
  OIIO::ImageBuf image(photo.string());
  OIIO::ImageBuf negative = OIIO::ImageBufAlgo::sub(1.0f, image);
  REQUIRE(negative.write(photo.string()));
  setup.runner.Run(setup.workspace, config, Until("train"));
  const TrainReport report = TrainReport::Read(setup.dir / "ws" / "30_train" / "train_report.json");
  INFO(report.ToJson().dump(1));
  const auto low = std::find_if(report.warnings.begin(), report.warnings.end(),
                                [](const FitWarning& w) { return w.code == "heldout_view_low"; });
  REQUIRE(low != report.warnings.end());
  CHECK(low->figure > 5);
  CHECK_THAT(low->message, Catch::Contains(heldout[0]) && Catch::Contains("among the training cameras"));
}

}  // namespace p2n::testing

namespace p2n::testing {

// Ten training photos of 64 x 48 x 3 bytes (9 KB); 0.06 MB hold six: a window of four and one being read.
TEST_CASE("train stage: photos beyond train.photo_memory train through a window, a resumed run alike", "[train]") {
  Config config = SmallStageConfig(100);
  config.Set("train.photo_memory", 0.06, "test");
  config.Set("train.eval_interval", 1e6, "test");
  StageWorkspace whole;
  whole.runner.Run(whole.workspace, config, Until("train"));
  const fs::path out = whole.dir / "ws" / "30_train";
  const nlohmann::json report = ReadJsonFile(out / "train_report.json");
  CHECK(report["training_views"] == 10);
  CHECK(report["training_views_in_memory"] == 4);
  CHECK(report["steps"] == 100);
  CHECK(std::isfinite(report["heldout_psnr"].get<double>()));

  // Cancelled at a checkpoint and resumed: the window stands where it stood, the same photos train the same model.
  StageWorkspace resumed;
  config.Set("train.checkpoint_interval", 0.05, "test");
  const fs::path checkpoint = resumed.dir / "ws" / "30_train.resume" / "checkpoint.bin";
  std::thread canceller([&] {
    while (!fs::exists(checkpoint)) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    RequestCancel();
  });
  CHECK_THROWS_AS(resumed.runner.Run(resumed.workspace, config, Until("train")), Cancelled);
  canceller.join();
  ResetCancel();
  resumed.runner.Run(resumed.workspace, config, Until("train"));
  const fs::path resumed_out = resumed.dir / "ws" / "30_train";
  CHECK(ReadJsonFile(resumed_out / "train_report.json")["resumed_from_step"].get<int>() > 0);
  NerfModel first = LoadModel(out / "model.bin"), second = LoadModel(resumed_out / "model.bin");
  CHECK(first.background == second.background);
  Encoding<float>* grid = first.field->TrainableEncoding();
  REQUIRE(grid != nullptr);
  const std::vector<float> first_grid(grid->params(), grid->params() + grid->num_params());
  grid = second.field->TrainableEncoding();
  CHECK(first_grid == std::vector<float>(grid->params(), grid->params() + grid->num_params()));

  SECTION("a budget of fewer than five photos is refused, naming the option") {
    config.Set("train.photo_memory", 0.03, "test");
    config.Set("train.seed", 1, "test");
    CHECK_THROWS_WITH(whole.runner.Run(whole.workspace, config, Until("train")),
                      Catch::Contains("train.photo_memory is 0.03 MB") && Catch::Contains("raise it"));
  }
}

}  // namespace p2n::testing

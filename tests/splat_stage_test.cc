// The splat stage: splats.ply in the standard layout and splats.spz, placed where the scene is, with their held-out
// scores; off when asked.

#include <catch2/catch.hpp>

#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "base/errors.h"
#include "base/file_util.h"
#include "formats/output_frame.h"
#include "formats/ply.h"
#include "pipeline/cancel.h"
#include "splat/splat_ply.h"
#include "splat/splat_schedule.h"
#include "splat/spz.h"
#include "stage_fixtures.h"
#include "stages/fitting/splat_optimisation.h"
#include "stages/fitting/splat_stage.h"

namespace p2n::testing {
namespace fs = std::filesystem;

TEST_CASE("splat stage: splats where the scene is, scored on the held-out views, with their curve ending at that score",
          "[splat]") {
  StageWorkspace setup;
  Config config = SmallStageConfig(150);
  config.Set("poses.holdout_every", 2, "test");  // more held-out views than a cheap evaluation might take
  setup.runner.Run(setup.workspace, config, Until("splat"));
  const fs::path out = setup.dir / "ws" / "35_splat";
  const nlohmann::json report = ReadJsonFile(out / "splat_report.json");
  CHECK(report["heldout_views"] == 6);
  CHECK(report["init"] == "field");  // splat.init auto: the small dataset comes with its cameras and no points
  const Gaussians<float> splats = ReadSplatPly(out / "splats.ply");
  CHECK(splats.size() == report["splats"].get<size_t>());
  CHECK(splats.sh_degree == 3);
  // The same splats in SPZ, a fraction of the PLY's size.
  const Gaussians<float> compact = ParseSpz(ReadTextFile(out / "splats.spz"), "splats.spz");
  CHECK(compact.size() == splats.size());
  CHECK(report["spz_bytes"].get<size_t>() == fs::file_size(out / "splats.spz"));
  CHECK(report["spz_bytes"].get<size_t>() < report["file_bytes"].get<size_t>() / 3);
  CHECK(report["steps"] == 30);
  CHECK(report["heldout_psnr"].get<double>() > 15);
  // An orbit: each view sees most of the scene.
  CHECK(report["view_share"].get<double>() > 0.5);
  CHECK(report["heldout_psnr_per_view"].size() == report["heldout_views"].get<size_t>());
  const std::string metrics = ReadTextFile(out / "metrics.csv");
  CHECK(metrics.find("wall_seconds,step,splats,train_loss,heldout_psnr\n") == 0);
  // The curve ends where the report does: its last row is the final evaluation, on the same views.
  const std::string last = metrics.substr(metrics.rfind('\n', metrics.size() - 2) + 1);
  std::vector<double> fields;
  std::stringstream row(last);
  for (std::string field; std::getline(row, field, ',');) fields.push_back(std::stod(field));
  REQUIRE(fields.size() == 5);
  CHECK(fields[1] == 30);
  CHECK(fields[2] == report["splats"].get<double>());
  CHECK(fields[4] == Approx(report["heldout_psnr"].get<double>()).margin(1e-3));

  // In the source frame, the splats lie where the normalised scene's unit box maps to.
  const fs::path ws = setup.dir / "ws";
  const OutputFrame frame =
      MakeOutputFrame(FrameKind::kSource, LoadTransformsJson(ws / "20_poses" / "transforms.json", ws));
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < splats.size(); ++i) {
    mean += Eigen::Vector3d(splats.positions[3 * i], splats.positions[3 * i + 1], splats.positions[3 * i + 2]);
  }
  mean /= static_cast<double>(splats.size());
  CHECK((mean - frame.translation).norm() < 1.5 * frame.Scale());
}

TEST_CASE("splat stage: the coarse part ends at its share of the budget or after 40 passes over the photos",
          "[splat]") {
  // 17 photos: 680 steps make 40 passes.
  CHECK(InCoarsePart(0.75, 0.1, 0, 17));
  CHECK(InCoarsePart(0.75, 0.1, 679, 17));
  CHECK_FALSE(InCoarsePart(0.75, 0.1, 680, 17));
  CHECK_FALSE(InCoarsePart(0.75, 0.75, 10, 17));
  // Many photos: the share ends it first.
  CHECK(InCoarsePart(0.75, 0.74, 3000, 100));
  CHECK_FALSE(InCoarsePart(0.75, 0.76, 3000, 100));
  // No coarse part.
  CHECK_FALSE(InCoarsePart(0, 0, 0, 17));
}

TEST_CASE("splat stage: the means' schedule is 2,000 steps, stretched in proportion by a budget above 320 s",
          "[splat]") {
  for (const double budget : {0.0, 30.0, 180.0, 320.0}) CHECK(SplatScheduleSteps(budget) == 2000);
  CHECK(SplatScheduleSteps(480) == 3000);
  CHECK(SplatScheduleSteps(960) == 6000);
}

TEST_CASE("splat stage: the splats placed follow the scene's size", "[splat]") {
  const size_t pixels = 64 * 1'000'000;  // room for a million
  CHECK(PlacedSplats(100'000, 1, pixels) == 100'000);
  CHECK(PlacedSplats(100'000, 0.5, pixels) == 100'000);
  CHECK(PlacedSplats(100'000, 0.1, pixels) == 500'000);
  CHECK(PlacedSplats(100'000, 0.01, pixels) == 1'000'000);  // 5 M asked, one per 64 pixels
  CHECK(PlacedSplats(100'000, 0, pixels) == 1'000'000);
  CHECK(PlacedSplats(100'000, 1, 64 * 2'000) == 2'000);  // small photos
}

TEST_CASE("splat stage: splat.blocks optimises whole, then each block, merged into one set of splats", "[splat]") {
  StageWorkspace setup;
  Config config = SmallStageConfig(150);
  setup.runner.Run(setup.workspace, config, Until("splat"));
  const fs::path out = setup.dir / "ws" / "35_splat";
  const double at_once = ReadJsonFile(out / "splat_report.json")["heldout_psnr"];
  config.Set("splat.blocks", 2, "test");
  setup.runner.Run(setup.workspace, config, Until("splat"));
  const nlohmann::json report = ReadJsonFile(out / "splat_report.json");
  CHECK(report["steps"] == 45);  // 15 whole, then 15 a block: every block is seen by some training view
  CHECK(ReadSplatPly(out / "splats.ply").size() == report["splats"].get<size_t>());
  CHECK(report["heldout_psnr"].get<double>() > at_once - 1);
  // The curve goes on through the blocks, and ends at the merged splats' score.
  const std::string metrics = ReadTextFile(out / "metrics.csv");
  const std::string last = metrics.substr(metrics.rfind('\n', metrics.size() - 2) + 1);
  CHECK(last.find(",45,") != std::string::npos);
}

TEST_CASE("splat stage: a block run cancelled in its last block resumes there, the parts before it kept", "[splat]") {
  StageWorkspace setup;
  Config config = SmallStageConfig(60);
  setup.runner.Run(setup.workspace, config, Until("train"));
  config.Set("splat.blocks", 2, "test");
  config.Set("splat.steps", 300, "test");  // 150 whole, then 150 a block
  config.Set("splat.checkpoint_interval", 0.05, "test");
  config.Set("splat.eval_interval", 1e6, "test");
  const fs::path resume = setup.dir / "ws" / "35_splat.resume";
  // Cancel (as Ctrl-C does) once the last block has a checkpoint of its own.
  std::thread canceller([&] {
    while (!fs::exists(resume / "checkpoint_block2.bin")) std::this_thread::sleep_for(std::chrono::milliseconds(2));
    RequestCancel();
  });
  CHECK_THROWS_AS(setup.runner.Run(setup.workspace, config, Until("splat")), Cancelled);
  canceller.join();
  ResetCancel();
  CHECK(fs::exists(resume / "checkpoint.bin"));
  CHECK(fs::exists(resume / "checkpoint_block1.bin"));

  setup.runner.Run(setup.workspace, config, Until("splat"));
  const nlohmann::json report = ReadJsonFile(setup.dir / "ws" / "35_splat" / "splat_report.json");
  CHECK(report["steps"] == 450);
  // The whole part and the first block resumed at their ends, the last block where it was cancelled.
  CHECK(report["resumed_from_step"].get<int>() > 300);
  CHECK(report["resumed_from_step"].get<int>() < 450);
  CHECK_FALSE(fs::exists(resume));
}

TEST_CASE("splat stage: a block's job without a training photo of the blocks names it", "[splat][bad_input]") {
  StageWorkspace setup;
  Config config = SmallStageConfig(60);
  setup.runner.Run(setup.workspace, config, Until("train"));
  config.Set("splat.blocks", 2, "test");
  config.Set("splat.steps", 40, "test");
  const fs::path photo = setup.FirstTrainingPhoto();  // every view after it would shift
  const StageWorkspace::JobsRun run = setup.RunJobsWithout(config, "splat", "35_splat", photo);
  REQUIRE(run.jobs.size() == 2);
  for (const std::string& job : run.jobs) {
    CHECK_THAT(job, Catch::Contains(photo.filename().string()) && Catch::Contains("can be read on this machine"));
  }
  CHECK_THAT(run.stage, Catch::Contains("did not finish"));
  CHECK_FALSE(fs::exists(setup.dir / "ws" / "35_splat.resume" / "block1.json"));
}

// Ten training photos of 64 x 48 x 3 bytes (9 KB); 0.06 MB hold six: a window of four and one being read.
TEST_CASE("splat stage: photos beyond splat.photo_memory are optimised through a window, a resumed run alike",
          "[splat]") {
  StageWorkspace setup;
  Config config = SmallStageConfig(60);
  setup.runner.Run(setup.workspace, config, Until("train"));
  config.Set("splat.steps", 1000, "test");  // a second or so: the resumed run's canceller sees a checkpoint first
  config.Set("splat.eval_interval", 1e6, "test");
  const fs::path out = setup.dir / "ws" / "35_splat";
  setup.runner.Run(setup.workspace, config, Until("splat"));
  const nlohmann::json in_memory = ReadJsonFile(out / "splat_report.json");
  CHECK(in_memory["training_views_in_memory"].is_null());

  config.Set("splat.photo_memory", 0.06, "test");
  setup.runner.Run(setup.workspace, config, Until("splat"));
  const nlohmann::json report = ReadJsonFile(out / "splat_report.json");
  CHECK(report["training_views_in_memory"] == 4);
  CHECK(report["steps"] == 1000);
  CHECK(report["heldout_psnr"].get<double>() > in_memory["heldout_psnr"].get<double>() - 1.5);
  const std::string windowed = ReadTextFile(out / "splats.ply");

  // Cancelled at a checkpoint and resumed: the window stands where it stood, the same photos make the same splats.
  config.Set("splat.checkpoint_interval", 0.05, "test");
  RunRequest again = Until("splat");
  again.force = {"splat"};
  const fs::path checkpoint = setup.dir / "ws" / "35_splat.resume" / "checkpoint.bin";
  std::thread canceller([&] {
    while (!fs::exists(checkpoint)) std::this_thread::sleep_for(std::chrono::milliseconds(2));
    RequestCancel();
  });
  CHECK_THROWS_AS(setup.runner.Run(setup.workspace, config, again), Cancelled);
  canceller.join();
  ResetCancel();
  setup.runner.Run(setup.workspace, config, again);
  CHECK(ReadJsonFile(out / "splat_report.json")["resumed_from_step"].get<int>() > 0);
  CHECK(ReadTextFile(out / "splats.ply") == windowed);

  // A budget of fewer than five photos is refused, naming the option.
  config.Set("splat.photo_memory", 0.03, "test");
  CHECK_THROWS_WITH(setup.runner.Run(setup.workspace, config, Until("splat")),
                    Catch::Contains("splat.photo_memory is 0.03 MB") && Catch::Contains("raise it"));
}

// Ten training photos of 9 KB (90 KB) and two held-out ones: 0.09 MB holds the training photos but not the held-out
// ones beside them, which each evaluation then reads from their decoded copy, to the same scores.
TEST_CASE(
    "train and splat stages: held-out photos beyond what the training photos leave of photo_memory are read at "
    "each evaluation, to the same scores",
    "[splat][train]") {
  Config config = SmallStageConfig(60);
  const auto run = [&](const StageWorkspace& setup) {
    setup.runner.Run(setup.workspace, config, Until("splat"));
    return std::pair{ReadJsonFile(setup.dir / "ws" / "30_train" / "train_report.json"),
                     ReadJsonFile(setup.dir / "ws" / "35_splat" / "splat_report.json")};
  };
  StageWorkspace in_memory, from_disk;
  const auto [train, splat] = run(in_memory);
  CHECK(train["heldout_views_in_memory"] == true);
  CHECK(splat["heldout_views_in_memory"] == true);
  config.Set("train.photo_memory", 0.09, "test");
  config.Set("splat.photo_memory", 0.09, "test");
  const auto [train_read, splat_read] = run(from_disk);
  REQUIRE(train_read["heldout_views"] == 2);
  CHECK(train_read["training_views_in_memory"].is_null());
  CHECK(train_read["heldout_views_in_memory"] == false);
  CHECK(splat_read["training_views_in_memory"].is_null());
  CHECK(splat_read["heldout_views_in_memory"] == false);
  CHECK(train_read["heldout_psnr"] == train["heldout_psnr"]);
  CHECK(train_read["heldout_psnr_fitted"] == train["heldout_psnr_fitted"]);
  CHECK(splat_read["heldout_psnr_per_view"] == splat["heldout_psnr_per_view"]);
  CHECK(splat_read["heldout_ssim"] == splat["heldout_ssim"]);
}

// In turn, the blocks borrow the photos the whole part holds (and give them back for the next block), or beyond
// splat.photo_memory their windows read the whole part's decoded copy; as a scheduler's jobs, each job reads its
// block's photos from their files (into a decoded copy of its own beyond the setting).
TEST_CASE("splat stage: by blocks, in memory or beyond splat.photo_memory, in turn and as jobs, the same splats",
          "[splat][blocks]") {
  const double photo_memory = GENERATE(2048.0, 0.06);
  StageWorkspace setup;
  Config config = SmallStageConfig(60);
  setup.runner.Run(setup.workspace, config, Until("train"));
  config.Set("splat.blocks", 2, "test");
  config.Set("splat.steps", 120, "test");
  config.Set("splat.photo_memory", photo_memory, "test");
  const fs::path staging = setup.workspace.StagingDir("35_splat");
  const auto run = [&](bool jobs) {
    fs::remove_all(setup.workspace.ResumeDir("35_splat"));
    fs::create_directories(staging);
    StageWork work;
    work.parts = [&](const std::string& kind, const std::vector<int>& parts, const std::function<void(int)>& here) {
      for (const int part : parts) {
        if (!jobs) {
          here(part);
          continue;
        }
        StageWork job;
        job.part = part;
        job.work = kind;
        setup.runner.RunWork(setup.workspace, config, "splat", "key", job);
      }
    };
    setup.runner.RunWork(setup.workspace, config, "splat", "key", work);
    const nlohmann::json report = ReadJsonFile(staging / "splat_report.json");
    CHECK(report["training_views_in_memory"] == (photo_memory < 1 ? nlohmann::json(4) : nlohmann::json()));
    CHECK(report["steps"] == 180);  // 60 whole, then 60 a block
    return ReadTextFile(staging / "splats.ply");
  };
  const std::string in_turn = run(false);
  CHECK(run(true) == in_turn);
}

TEST_CASE("splat stage: splat.enabled false writes no splats and says so", "[splat]") {
  StageWorkspace setup;
  Config config = SmallStageConfig(30);
  config.Set("splat.enabled", false, "test");
  setup.runner.Run(setup.workspace, config, Until("splat"));
  const fs::path out = setup.dir / "ws" / "35_splat";
  CHECK(ReadJsonFile(out / "splat_report.json")["enabled"] == false);
  CHECK_FALSE(fs::exists(out / "splats.ply"));
}

TEST_CASE("splat stage: splat.init sparse without sparse points says where they would be and what to do", "[splat]") {
  StageWorkspace setup;
  Config config = SmallStageConfig(30);
  config.Set("splat.init", "sparse", "test");  // the small dataset comes with its cameras and no points
  CHECK_THROWS_WITH(setup.runner.Run(setup.workspace, config, Until("splat")),
                    Catch::Contains("sparse_points.ply") && Catch::Contains("--splat.init field"));
}

TEST_CASE("splat stage: splat.init auto starts an unbounded scene from its sparse points where there are enough",
          "[splat]") {
  TempDir dir;
  const fs::path ply = dir / "sparse_points.ply";
  const auto resolve = [&](SplatInit init, SceneSpace space) { return ResolveSplatInit(init, space, kFewViews, ply); };
  // No file: a dataset imported without points.
  CHECK(resolve(SplatInit::kAuto, SceneSpace::kUnbounded) == SplatInit::kField);
  const auto write = [&](size_t count) {
    std::vector<ColouredPoint> points;
    for (size_t i = 0; i < count; ++i) points.push_back({Eigen::Vector3f(float(i), 0, 1), {128, 64, 32}});
    WritePly(ply, points);
  };
  write(kMinSparseInitPoints - 1);
  CHECK(resolve(SplatInit::kAuto, SceneSpace::kUnbounded) == SplatInit::kField);
  write(kMinSparseInitPoints);
  CHECK(resolve(SplatInit::kAuto, SceneSpace::kUnbounded) == SplatInit::kSparse);
  // Fewer training photos, forward-facing and bounded scenes keep the field's placement.
  CHECK(ResolveSplatInit(SplatInit::kAuto, SceneSpace::kUnbounded, kFewViews - 1, ply) == SplatInit::kField);
  CHECK(resolve(SplatInit::kAuto, SceneSpace::kForward) == SplatInit::kField);
  CHECK(resolve(SplatInit::kAuto, SceneSpace::kBounded) == SplatInit::kField);
  // A choice made is kept, with or without points.
  CHECK(resolve(SplatInit::kField, SceneSpace::kUnbounded) == SplatInit::kField);
  CHECK(ResolveSplatInit(SplatInit::kSparse, SceneSpace::kBounded, 1, dir / "none.ply") == SplatInit::kSparse);
}

}  // namespace p2n::testing

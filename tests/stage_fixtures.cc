#include "stage_fixtures.h"

#include <functional>
#include <stdexcept>

#include "base/file_util.h"
#include "examples/synthetic_scene.h"
#include "stages/stages.h"

namespace p2n::testing {
namespace fs = std::filesystem;

fs::path SmallDataset(const TempDir& dir) {
  SyntheticSceneOptions scene;
  scene.num_views = 12;
  scene.width = 64;
  scene.height = 48;
  WriteSyntheticScene(scene, dir / "data");
  fs::rename(dir / "data" / "ground_truth_cameras.json", dir / "data" / "transforms.json");
  return dir / "data";
}

Config SmallStageConfig(int steps) {
  static const OptionRegistry registry = AllOptions();
  Config config(registry);
  config.Set("run.progress", "none", "test");
  config.Set("train.preset", "fast", "test");
  config.Set("train.steps", steps, "test");
  config.Set("train.eval_interval", 1.0, "test");
  config.Set("train.eval_pixels", 512, "test");  // of 3072 per view: evaluations stay cheap (under sanitizers too)
  config.Set("splat.steps", 30, "test");
  config.Set("splat.init_width", 48, "test");
  config.Set("render.frames", 6, "test");
  config.Set("render.fps", 6.0, "test");
  config.Set("export.resolution", 48, "test");
  config.Set("export.points_width", 32, "test");
  config.Set("export.texture_size", 256, "test");
  return config;
}

StageWorkspace::StageWorkspace()
    : data(SmallDataset(dir)), workspace(Workspace::Open(dir / "ws", true)), runner(MakeRunner(data)) {
  workspace.SetInput(data);
}

StageStatus StageWorkspace::Status(const Config& config, const std::string& stage) const {
  for (const StageStatus& status : runner.Status(workspace, config)) {
    if (status.stage->name() == stage) return status;
  }
  throw std::invalid_argument("no stage " + stage);
}

std::filesystem::path StageWorkspace::FirstTrainingPhoto() const {
  const std::filesystem::path poses = dir / "ws" / "20_poses";
  const nlohmann::json transforms = ReadJsonFile(poses / "transforms.json");
  for (const nlohmann::json& frame : transforms["frames"]) {
    if (frame["split"] == "train") return poses / frame["file_path"].get<std::string>();
  }
  throw std::invalid_argument("no training photo in " + poses.string());
}

StageWorkspace::JobsRun StageWorkspace::RunJobsWithout(const Config& config, const std::string& stage,
                                                       const std::string& folder, const std::filesystem::path& photo) {
  const auto error = [](const std::function<void()>& run) {
    try {
      run();
    } catch (const std::exception& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  std::filesystem::create_directories(workspace.StagingDir(folder));
  JobsRun out;
  StageWork work;
  work.parts = [&](const std::string& kind, const std::vector<int>& parts, const std::function<void(int)>&) {
    std::filesystem::rename(photo, photo.string() + ".away");
    for (const int part : parts) {
      StageWork job;
      job.part = part;
      job.work = kind;
      out.jobs.push_back(error([&] { runner.RunWork(workspace, config, stage, "key", job); }));
    }
    std::filesystem::rename(photo.string() + ".away", photo);
  };
  out.stage = error([&] { runner.RunWork(workspace, config, stage, "key", work); });
  return out;
}

RunRequest Until(const std::string& stage) {
  RunRequest request;
  request.until = stage;
  return request;
}

IngestFixture::IngestFixture()
    : registry(AllOptions()), config(registry), workspace(Workspace::Open(dir / "ws", true)), runner(MakeRunner()) {
  fs::create_directories(photos);
  workspace.SetInput(photos);
}

nlohmann::json IngestFixture::Run() {
  runner.Run(workspace, config, Until("ingest"));
  return ReadJsonFile(workspace.StageDir("00_ingest") / "ingest_report.json");
}

StageStatus IngestFixture::Status() { return runner.Status(workspace, config).at(0); }

}  // namespace p2n::testing

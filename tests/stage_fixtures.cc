#include "stage_fixtures.h"

#include "base/file_util.h"
#include "nerf/synthetic_scene.h"
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

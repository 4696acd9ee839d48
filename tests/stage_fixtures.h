#pragma once
// A small dataset with cameras and a workspace on it, for the tests of the stages after poses.

#include <filesystem>
#include <string>
#include <vector>

#include "pipeline/options.h"
#include "pipeline/runner.h"
#include "pipeline/workspace.h"
#include "test_util.h"

namespace p2n::testing {

// The synthetic scene's 12 views of 64 x 48 with their true cameras as transforms.json, in `dir`/data.
std::filesystem::path SmallDataset(const TempDir& dir);

// Quiet, the fast preset, `steps` training steps, evaluation every second, small render and export settings.
Config SmallStageConfig(int steps);

// A workspace made from SmallDataset(), with its runner (import, then train, render, export, report).
struct StageWorkspace {
  StageWorkspace();
  TempDir dir;
  std::filesystem::path data;
  Workspace workspace;
  Runner runner;
  // The status of one stage.
  StageStatus Status(const Config& config, const std::string& stage) const;
  // The first training photo of the poses stage (which must have run).
  std::filesystem::path FirstTrainingPhoto() const;
  // Runs `stage` (output folder `folder`) with its parts run as a scheduler's jobs would (RunWork with each part)
  // while `photo` is moved away: what each job threw ("" when it did not), and what the stage threw.
  struct JobsRun {
    std::vector<std::string> jobs;
    std::string stage;
  };
  JobsRun RunJobsWithout(const Config& config, const std::string& stage, const std::string& folder,
                         const std::filesystem::path& photo);
};

// A request that runs the stages up to `stage`.
RunRequest Until(const std::string& stage);

// A workspace whose input is the empty folder `photos`, for the ingest stage alone.
struct IngestFixture {
  IngestFixture();
  TempDir dir;
  std::filesystem::path photos = dir / "photos";
  OptionRegistry registry;
  Config config;
  Workspace workspace;
  Runner runner;
  // Runs ingest; its report.
  nlohmann::json Run();
  StageStatus Status();
};

}  // namespace p2n::testing

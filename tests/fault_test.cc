// Faults on the real program: Ctrl-C (SIGINT) stops cleanly with exit status 130 and training resumes from its
// checkpoint; SIGKILL at many moments never leaves a stage that looks finished but is not, and the run that
// follows gives the same result as an uninterrupted one; a file-size limit (a full disk, as far as writes are
// concerned) gives a clear error naming the file and leaves the workspace consistent.

#include <catch2/catch.hpp>

#include <signal.h>
#include <sys/wait.h>

#include <algorithm>
#include <chrono>
#include <thread>

#include "base/file_util.h"
#include "tests/program_runs.h"
#include "tests/stage_fixtures.h"

namespace p2n::testing {
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

// `args` run under a file-size limit of `kib` KiB (a full disk, as far as writes are concerned).
std::vector<std::string> WithFileSizeLimit(int kib, const std::vector<std::string>& args) {
  std::vector<std::string> limited = {"/bin/bash", "-c", "ulimit -f " + std::to_string(kib) + " && exec \"$@\"",
                                      "limited"};
  limited.insert(limited.end(), args.begin(), args.end());
  return limited;
}

// The run's arguments, ending after `stage`.
std::vector<std::string> RunArgsUntil(const fs::path& data, const fs::path& workspace, const std::string& stage) {
  std::vector<std::string> args = RunArgs(data, workspace);
  args.insert(args.end(), {"--until", stage});
  return args;
}

}  // namespace

TEST_CASE("faults: Ctrl-C stops with exit status 130, the stage is incomplete, the next run resumes training",
          "[fault]") {
  TempDir dir;
  const fs::path data = SmallDataset(dir), workspace = dir / "ws";
  const pid_t pid = Spawn(RunArgs(data, workspace), dir / "run.log");
  const auto deadline = Clock::now() + std::chrono::seconds(120);
  while (!fs::exists(workspace / "30_train.resume" / "checkpoint.bin") && Clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  REQUIRE(fs::exists(workspace / "30_train.resume" / "checkpoint.bin"));
  ::kill(pid, SIGINT);
  CHECK(Wait(pid) == 130);
  INFO(ReadText(dir / "run.log"));
  CHECK_THAT(ReadText(dir / "run.log"), Catch::Contains("interrupted"));

  std::string status;
  REQUIRE(RunCommand({P2N_BINARY, "status", "-w", workspace.string()}, &status) == 0);
  CHECK_THAT(status, Catch::Matches("(.|\n)*train +incomplete(.|\n)*"));
  std::string output;
  const int rerun = RunCommand(RunArgs(data, workspace), &output);
  INFO(output);  // what the rerun printed (under the sanitizers: their reports)
  REQUIRE(rerun == 0);
  const nlohmann::json report = ReadJsonFile(workspace / "30_train" / "train_report.json");
  CHECK(report["resumed_from_step"].get<int>() > 0);
  CHECK(report["steps"] == 120);
}

TEST_CASE("faults: SIGKILL at many moments, then a rerun, gives the uninterrupted result", "[fault]") {
  TempDir dir;
  const fs::path data = SmallDataset(dir);
  std::string output;
  REQUIRE(RunCommand(RunArgs(data, dir / "reference"), &output) == 0);
  const std::map<std::string, std::string> reference = CheckedKeys(dir / "reference");
  REQUIRE(reference.size() == 6);  // poses (import), train, splat, render, export, report
  const double reference_psnr = ReadJsonFile(dir / "reference" / "40_render" / "eval.json")["psnr"];

  // Each run is killed the moment a file or folder appears (polled every millisecond): every stage's start, a
  // checkpoint being written, results half written, manifests written but not yet moved into place. Each
  // next run goes on from what the last one left.
  const fs::path workspace = dir / "ws";
  const std::vector<std::string> moments = {"20_poses.partial",
                                            "20_poses.partial/manifest.json",
                                            "30_train.partial",
                                            "30_train.resume/checkpoint.bin.tmp",
                                            "30_train.resume/checkpoint.bin",
                                            "30_train.partial/model.bin.tmp",
                                            "30_train.partial/metrics.csv",
                                            "35_splat.partial",
                                            "35_splat.resume/checkpoint.bin",
                                            "35_splat.partial/splats.ply",
                                            "40_render.partial",
                                            "40_render.partial/video.mp4",
                                            "50_export.partial",
                                            "50_export.partial/mesh.ply",
                                            "50_export.partial/mesh.glb",
                                            "60_report.partial",
                                            "60_report.partial/manifest.json"};
  const std::vector<std::string> folders = {"20_poses", "30_train", "35_splat", "40_render", "50_export", "60_report"};
  const std::vector<std::string> stages = {"poses", "train", "splat", "render", "export", "report"};
  std::vector<std::string> hit;
  for (const std::string& moment : moments) {
    // A moment of a stage that an earlier run finished: that stage and the later ones are removed first.
    const std::string folder = moment.substr(0, moment.find_first_of("./"));
    if (fs::exists(workspace / folder / "manifest.json")) {
      const size_t first = std::find(folders.begin(), folders.end(), folder) - folders.begin();
      std::vector<std::string> clean = {P2N_BINARY, "clean", "-w", workspace.string()};
      for (size_t i = first; i < stages.size(); ++i) clean.insert(clean.end(), {"--stage", stages[i]});
      std::string ignored;
      REQUIRE(RunCommand(clean, &ignored) == 0);
    }
    const pid_t pid = Spawn(RunArgs(data, workspace), dir / "kills.log");
    const auto deadline = Clock::now() + std::chrono::seconds(60);
    int status = 0;
    bool exited = false;
    while (!fs::exists(workspace / moment) && Clock::now() < deadline) {
      if (::waitpid(pid, &status, WNOHANG) == pid) {
        exited = true;
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    if (exited) continue;  // the moment went by between two polls, or never came: the run finished
    ::kill(pid, SIGKILL);
    if (Wait(pid) != 128 + SIGKILL) continue;
    hit.push_back(moment);
    // Whatever looks finished is: every output as its manifest says, of the same inputs as the reference.
    for (const auto& [stage, key] : CheckedKeys(workspace)) CHECK(key == reference.at(stage));
    std::string status_text;
    REQUIRE(RunCommand({P2N_BINARY, "status", "-w", workspace.string()}, &status_text) == 0);
    // The report stage can finish within the millisecond between its manifest appearing and the kill.
    if (!fs::exists(workspace / folders.back() / "manifest.json")) {
      CHECK_THAT(status_text, Catch::Contains("incomplete") || Catch::Contains("missing"));
    }
  }
  INFO("killed at " << Catch::Detail::stringify(hit) << "\n" << ReadText(dir / "kills.log"));
  CHECK(hit.size() >= 8);
  REQUIRE(RunCommand(RunArgs(data, workspace), &output) == 0);
  CHECK(CheckedKeys(workspace) == reference);
  // Training resumed to the very same parameters, so the renders match to the last bit.
  CHECK(ReadJsonFile(workspace / "40_render" / "eval.json")["psnr"].get<double>() == reference_psnr);
}

TEST_CASE("faults: SIGKILL while the field trains by blocks, then a rerun, gives the uninterrupted result", "[fault]") {
  TempDir dir;
  const fs::path data = SmallDataset(dir);
  const auto blocks_until_train = [&](const fs::path& workspace) {
    std::vector<std::string> args = RunArgsUntil(data, workspace, "train");
    args.insert(args.end(), {"--train.blocks", "2"});
    return args;
  };
  std::string output;
  REQUIRE(RunCommand(blocks_until_train(dir / "reference"), &output) == 0);
  const std::string reference = CheckedKeys(dir / "reference").at("30_train");
  const double reference_psnr = ReadJsonFile(dir / "reference" / "30_train" / "train_report.json")["heldout_psnr"];
  // Killed where the blocks begin, as each is saved and once each is done; each next run goes on from there.
  const fs::path workspace = dir / "ws";
  int hits = 0;
  for (const std::string moment :
       {"blocks.json", "block1_model.bin", "block1.json", "checkpoint_block2.bin", "block2.json"}) {
    const pid_t pid = Spawn(blocks_until_train(workspace), dir / "kills.log");
    const auto deadline = Clock::now() + std::chrono::seconds(60);
    int status = 0;
    bool exited = false;
    while (!fs::exists(workspace / "30_train.resume" / moment) && Clock::now() < deadline) {
      if (::waitpid(pid, &status, WNOHANG) == pid) {
        exited = true;
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    if (exited) break;  // the run finished
    ::kill(pid, SIGKILL);
    hits += Wait(pid) == 128 + SIGKILL;
  }
  INFO(ReadText(dir / "kills.log"));
  CHECK(hits >= 3);
  REQUIRE(RunCommand(blocks_until_train(workspace), &output) == 0);
  CHECK(CheckedKeys(workspace).at("30_train") == reference);
  // Each block begins again from the whole field's end, or resumes from its checkpoint: the very same parameters.
  CHECK(ReadJsonFile(workspace / "30_train" / "train_report.json")["heldout_psnr"].get<double>() == reference_psnr);
}

TEST_CASE("faults: a file-size limit gives a clear error naming the file and keeps the finished stages", "[fault]") {
  TempDir dir;
  const fs::path data = SmallDataset(dir), workspace = dir / "ws";
  const std::vector<std::string> limited = WithFileSizeLimit(256, RunArgs(data, workspace));
  std::string output;
  CHECK(RunCommand(limited, &output) == 1);  // a user error: the environment, not a bug
  INFO(output);
  CHECK_THAT(output, Catch::Contains("30_train") && Catch::Contains("File too large") && Catch::Contains("free space"));
  std::string status;
  REQUIRE(RunCommand({P2N_BINARY, "status", "-w", workspace.string()}, &status) == 0);
  CHECK_THAT(status, Catch::Matches("(.|\n)*poses +fresh(.|\n)*"));
  CHECK_THAT(status, Catch::Matches("(.|\n)*train +incomplete(.|\n)*"));
  REQUIRE(RunCommand(RunArgs(data, workspace), &output) == 0);
  CHECK_THAT(output, Catch::Contains("poses: fresh, skipped"));
}

TEST_CASE("faults: a full disk in the splat stage names its file and keeps the trained field", "[fault]") {
  TempDir dir;
  const fs::path data = SmallDataset(dir), workspace = dir / "ws";
  std::string output;
  REQUIRE(RunCommand(RunArgsUntil(data, workspace, "train"), &output) == 0);
  // 16 KiB: the splat stage of this scene writes about 150 splats, 248 bytes each, in one file.
  const std::vector<std::string> limited = WithFileSizeLimit(16, RunArgs(data, workspace));
  CHECK(RunCommand(limited, &output) == 1);
  INFO(output);
  CHECK_THAT(output, Catch::Contains("35_splat") && Catch::Contains("File too large") && Catch::Contains("free space"));
  std::string status;
  REQUIRE(RunCommand({P2N_BINARY, "status", "-w", workspace.string()}, &status) == 0);
  CHECK_THAT(status, Catch::Matches("(.|\n)*train +fresh(.|\n)*"));
  CHECK_THAT(status, Catch::Matches("(.|\n)*splat +(incomplete|missing)(.|\n)*"));
  REQUIRE(RunCommand(RunArgs(data, workspace), &output) == 0);
  CHECK_THAT(output, Catch::Contains("train: fresh, skipped"));
  CHECK(fs::exists(workspace / "35_splat" / "splats.ply"));
}

// The field's window and the splats', and the held-out photos' copy where only the training photos fit.
TEST_CASE("faults: a full disk while the photos are decoded for a window names the folder", "[fault]") {
  const std::string stage = GENERATE(as<std::string>{}, "train", "splat");
  // Ten training photos of 9 KiB and two held out: 0.06 MB of photo_memory hold six (a window of four), and their
  // decoded copy takes 90 KiB; 0.09 MB holds the training photos, and the held-out ones' copy takes 18 KiB.
  const std::string memory = GENERATE(as<std::string>{}, "0.06", "0.09");
  const std::string before = stage == "train" ? "poses" : "train";
  const std::string folder = stage == "train" ? "30_train" : "35_splat";
  TempDir dir;
  const fs::path data = SmallDataset(dir), workspace = dir / "ws";
  std::string output;
  REQUIRE(RunCommand(RunArgsUntil(data, workspace, before), &output) == 0);
  std::vector<std::string> windowed = RunArgsUntil(data, workspace, stage);
  windowed.insert(windowed.end(), {"--" + stage + ".photo_memory", memory});
  CHECK(RunCommand(WithFileSizeLimit(16, windowed), &output) == 1);
  INFO(output);
  CHECK_THAT(output, Catch::Contains("decoded photos") && Catch::Contains(folder + ".resume") &&
                         Catch::Contains("File too large") && Catch::Contains("free space"));
  CHECK(fs::is_empty(workspace / (folder + ".resume")));  // the copy had no name: nothing is left of it
  REQUIRE(RunCommand(windowed, &output) == 0);
  CHECK_THAT(output, Catch::Contains(before + ": fresh, skipped"));
  const nlohmann::json report = ReadJsonFile(workspace / folder / (stage + "_report.json"));
  CHECK(report["heldout_views_in_memory"] == false);
  if (memory == "0.06") CHECK(report["training_views_in_memory"] == 4);
  if (memory == "0.09") CHECK(report["training_views_in_memory"].is_null());
}

TEST_CASE("faults: a full disk in the export stage names its file and keeps the splats and renders", "[fault]") {
  TempDir dir;
  const fs::path data = SmallDataset(dir), workspace = dir / "ws";
  std::string output;
  REQUIRE(RunCommand(RunArgsUntil(data, workspace, "render"), &output) == 0);
  // 16 KiB: the export's first file, mesh.ply, is larger.
  const std::vector<std::string> limited = WithFileSizeLimit(16, RunArgs(data, workspace));
  CHECK(RunCommand(limited, &output) == 1);
  INFO(output);
  CHECK_THAT(output,
             Catch::Contains("50_export") && Catch::Contains("File too large") && Catch::Contains("free space"));
  std::string status;
  REQUIRE(RunCommand({P2N_BINARY, "status", "-w", workspace.string()}, &status) == 0);
  CHECK_THAT(status, Catch::Matches("(.|\n)*render +fresh(.|\n)*"));
  CHECK_THAT(status, Catch::Matches("(.|\n)*export +(incomplete|missing)(.|\n)*"));
  REQUIRE(RunCommand(RunArgs(data, workspace), &output) == 0);
  CHECK_THAT(output, Catch::Contains("render: fresh, skipped"));
  CHECK(fs::exists(workspace / "50_export" / "mesh.glb"));
}

}  // namespace p2n::testing

// `--run.scheduler slurm` against a real one-machine Slurm cluster (scripts/local_slurm.sh, which CTest starts
// before these tests and stops after them; SLURM_CONF points at it): the results of a local run, a cancelled job
// submitted again with the finished stages kept, one whose node fails requeued by Slurm, a controller that does not
// answer waited for, one killed for its memory not submitted again, the mapper's clusters and splat blocks as job
// arrays (beside the stage's job, taken back by it when there is no room, rerun by it from a checkpoint when
// cancelled), a job's own failure reported and not retried, Ctrl-C cancelling the running job, a killed run's job
// cancelled by the next run, and a missing sbatch.

#include <signal.h>
#include <catch2/catch.hpp>

#include <chrono>
#include <fstream>
#include <sstream>
#include <thread>

#include "base/file_util.h"
#include "base/format.h"
#include "examples/synthetic_scene.h"
#include "tests/pose_truth.h"
#include "tests/program_runs.h"
#include "tests/stage_fixtures.h"

namespace p2n::testing {
namespace fs = std::filesystem;
namespace {

using Clock = std::chrono::steady_clock;

std::vector<std::string> SlurmRunArgs(const fs::path& data, const fs::path& workspace) {
  std::vector<std::string> args = RunArgs(data, workspace);
  args.insert(args.end(), {"--run.scheduler", "slurm"});
  return args;
}

// A Slurm run whose training lasts long enough to stop it while it trains, and ends with it (what these tests
// check of a stopped job is in the stages up to it).
std::vector<std::string> LongSlurmRunArgs(const fs::path& data, const fs::path& workspace) {
  std::vector<std::string> args = SlurmRunArgs(data, workspace);
  args.insert(args.end(), {"--train.steps", "600", "--until", "train"});
  return args;
}

fs::path JobDir(const fs::path& workspace, const std::string& folder) { return workspace / "logs" / "slurm" / folder; }

// The job id in what sbatch said.
std::string SubmittedJob(const fs::path& submit_log) {
  std::ifstream log(submit_log);
  std::string line, id;
  while (std::getline(log, line)) {
    if (!line.empty() && line.find_first_not_of("0123456789") == std::string::npos) id = line;
  }
  REQUIRE(!id.empty());
  return id;
}

// Waits (up to two minutes) until the stage's first job has started its work; its Slurm job id.
std::string StartedJob(const fs::path& workspace, const std::string& folder) {
  const fs::path dir = JobDir(workspace, folder);
  const auto deadline = Clock::now() + std::chrono::seconds(120);
  while (ReadText(dir / "attempt-1.log").find("working in job") == std::string::npos && Clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  REQUIRE_THAT(ReadText(dir / "attempt-1.log"), Catch::Contains("working in job"));
  return SubmittedJob(dir / "submit-1.log");
}

// Waits (up to a minute) until the stage's resume folder has a checkpoint.
void WaitForCheckpoint(const fs::path& resume) {
  const auto deadline = Clock::now() + std::chrono::seconds(60);
  while (!fs::exists(resume / "checkpoint.bin") && Clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

// What squeue says of the job ("RUNNING", "CANCELLED", ...).
std::string JobState(const std::string& id) {
  std::string output;
  RunCommand({"squeue", "--noheader", "--states=all", "--jobs=" + id, "--format=%T"}, &output);
  return output;
}

}  // namespace

TEST_CASE("slurm: a run as Slurm jobs makes the results of a local run", "[slurm]") {
  TempDir dir;
  const fs::path data = SmallDataset(dir);
  std::string output;
  REQUIRE(RunCommand(RunArgs(data, dir / "local"), &output) == 0);
  const int code = RunCommand(SlurmRunArgs(data, dir / "slurm"), &output);
  INFO(output);
  REQUIRE(code == 0);
  // The same stage folders, cache keys and outputs as they list; the same picture within 0.05 dB (equal when the
  // job has as many threads as the local run).
  const std::map<std::string, std::string> local = CheckedKeys(dir / "local");
  CHECK(local.size() == 6);
  CHECK(CheckedKeys(dir / "slurm") == local);
  const double local_psnr = ReadJsonFile(dir / "local" / "40_render" / "eval.json")["psnr"];
  CHECK(ReadJsonFile(dir / "slurm" / "40_render" / "eval.json")["psnr"].get<double>() ==
        Approx(local_psnr).margin(0.05));
  for (const auto& [folder, key] : local) {
    INFO(folder);
    CHECK_THAT(ReadText(JobDir(dir / "slurm", folder) / "attempt-1.log"), Catch::Contains("working in job"));
    CHECK(!fs::exists(JobDir(dir / "slurm", folder) / "submit-2.log"));
  }
  // Everything fresh, also for a local rerun.
  REQUIRE(RunCommand(RunArgs(data, dir / "slurm"), &output) == 0);
  CHECK_THAT(output, Catch::Contains("0 of 6 stages ran"));
}

TEST_CASE("slurm: splat blocks run as a job array beside the stage's job, or in it when there is no room", "[slurm]") {
  TempDir dir;
  const fs::path data = SmallDataset(dir), workspace = dir / "ws";
  std::vector<std::string> local = RunArgs(data, workspace);
  local.insert(local.end(), {"--splat.blocks", "3", "--until", "splat"});
  std::string output;
  REQUIRE(RunCommand(local, &output) == 0);
  const fs::path report = workspace / "35_splat" / "splat_report.json";
  const nlohmann::json here = ReadJsonFile(report);
  const fs::path jobs = JobDir(workspace, "35_splat");
  const std::vector<std::string> splat = {
      P2N_BINARY, "splat", "-w", workspace.string(), "--force", "--run.progress", "plain", "--run.scheduler", "slurm"};

  // A CPU a job: the stage's job optimises the whole, then block 1 while block 2 is element 2 of a job array (block 3
  // runs after it, or in the stage's job if that is free first).
  std::vector<std::string> beside = splat;
  beside.insert(beside.end(), {"--slurm.cpus", "1"});
  int code = RunCommand(beside, &output);
  INFO(output);
  REQUIRE(code == 0);
  INFO(ReadText(jobs / "attempt-1.log"));
  CHECK_THAT(ReadText(jobs / "attempt-1.log"), Catch::Contains("splat: block parts 2,3 as Slurm job array"));
  CHECK_THAT(ReadText(jobs / "block-2.log"),
             Catch::Contains("splat: block part 2 in job") && Catch::Contains("splat: block 2 of 3"));
  CHECK(ReadText(jobs / "exit-block-2") == "0\n");
  // The same steps and metrics rows; the same picture within 0.2 dB (the jobs have one thread, the local run two).
  nlohmann::json there = ReadJsonFile(report);
  CHECK(there["steps"] == here["steps"]);
  CHECK(there["heldout_psnr"].get<double>() == Approx(here["heldout_psnr"].get<double>()).margin(0.2));
  CHECK(there["resumed_from_step"] == 0);

  // A whole node a job (the default): the elements wait for the stage's job, which takes each back in turn (taking
  // one back leaves the other pending) and runs it.
  code = RunCommand(splat, &output);
  INFO(output);
  REQUIRE(code == 0);
  CHECK_THAT(ReadText(jobs / "submit-1.log"), Catch::Contains("--exclusive --mem=0"));  // all the node's memory
  const std::string log = ReadText(jobs / "attempt-1.log");
  CHECK_THAT(log, Catch::Contains("splat: block part 2 was still waiting for room in Slurm; running it here") &&
                      Catch::Contains("splat: block part 3 was still waiting for room in Slurm; running it here") &&
                      !Catch::Contains("without finishing"));
  CHECK(!fs::exists(jobs / "block-2.log"));
  CHECK(!fs::exists(jobs / "block-3.log"));
  there = ReadJsonFile(report);
  CHECK(there["steps"] == here["steps"]);
  CHECK(there["heldout_psnr"].get<double>() == Approx(here["heldout_psnr"].get<double>()).margin(0.05));
}

TEST_CASE("slurm: the field's blocks run as a job array beside the stage's job", "[slurm]") {
  TempDir dir;
  const fs::path data = SmallDataset(dir), workspace = dir / "ws";
  std::vector<std::string> local = RunArgs(data, workspace);
  local.insert(local.end(), {"--train.blocks", "2", "--until", "train"});
  std::string output;
  REQUIRE(RunCommand(local, &output) == 0);
  const fs::path report = workspace / "30_train" / "train_report.json";
  const nlohmann::json here = ReadJsonFile(report);
  REQUIRE(here["field"]["fields"].size() == 2);

  // A CPU a job: the stage's job trains the whole field, then block 1 while block 2 is a job array's element.
  const std::vector<std::string> train = {P2N_BINARY, "train",          "-w",    workspace.string(),
                                          "--force",  "--run.progress", "plain", "--run.scheduler",
                                          "slurm",    "--slurm.cpus",   "1"};
  const int code = RunCommand(train, &output);
  INFO(output);
  REQUIRE(code == 0);
  const fs::path jobs = JobDir(workspace, "30_train");
  INFO(ReadText(jobs / "attempt-1.log"));
  CHECK_THAT(ReadText(jobs / "block-2.log"), Catch::Contains("train: block part 2 in job") &&
                                                 Catch::Contains("train: block 2 of 2") &&
                                                 Catch::Contains(": done in ") && Catch::Contains("MB in memory"));
  CHECK(ReadText(jobs / "exit-block-2") == "0\n");
  // The same steps; the same field within 0.3 dB (the jobs have one thread, the local run two).
  const nlohmann::json there = ReadJsonFile(report);
  CHECK(there["steps"] == here["steps"]);
  CHECK(there["heldout_psnr"].get<double>() == Approx(here["heldout_psnr"].get<double>()).margin(0.3));
}

// Photos the hierarchical mapper would map, under Slurm: their features extracted in blocks and their pairs matched in
// blocks, each a part of the sfm stage (an element of a job array beside the stage's job), and merged; each cluster
// mapped by COLMAP's incremental mapper as a part, the models merged, triangulated anew and adjusted; every view as
// near the truth as the local hierarchical mapper's test asks (0.5 deg, 1% of the spread).
TEST_CASE(
    "slurm: features extracted and matched in blocks, clusters mapped, as job arrays, merged into the true cameras",
    "[slurm]") {
  TempDir dir;
  SyntheticSceneOptions scene;
  scene.num_views = 24;
  WriteSyntheticScene(scene, dir / "photos");
  const fs::path workspace = dir / "ws";
  std::string output;
  const int code =
      RunCommand({P2N_BINARY, "run", (dir / "photos").string(), "-w", workspace.string(), "--until", "poses",
                  "--run.progress", "plain", "--run.scheduler", "slurm", "--slurm.cpus", "1", "--sfm.block_images",
                  "10", "--sfm.hierarchical_min_images", "20", "--sfm.leaf_max_images", "12"},
                 &output);
  INFO(output);
  REQUIRE(code == 0);
  const fs::path jobs = JobDir(workspace, "10_sfm"), sfm = workspace / "10_sfm";
  INFO(ReadText(jobs / "attempt-1.log"));
  CHECK_THAT(ReadText(jobs / "attempt-1.log"),
             Catch::Contains("sfm: features extracted in 3 blocks of at most 10 photos") &&
                 Catch::Contains("sfm: extraction parts 2,3 as Slurm job array") &&
                 Catch::Contains("sfm: 276 pairs matched and verified in 3 blocks") &&
                 Catch::Contains("sfm: matching parts 2,3 as Slurm job array") &&
                 Catch::Contains("sfm: 2 clusters of at most 12 photos (each grown by 3)") &&
                 Catch::Contains("sfm: cluster parts 2 as Slurm job array"));
  // Part 2 of each kind in its element (the node has a CPU for it beside the stage's job); part 3 there too, or taken
  // back by the stage's job when that was free first.
  for (const std::string work : {"extraction", "matching", "cluster"}) {
    CHECK_THAT(ReadText(jobs / (work + "-2.log")), Catch::Contains(format("sfm: {} part 2 in job", work)));
    CHECK(ReadText(jobs / ("exit-" + work + "-2")) == "0\n");
  }
  for (const std::string work : {"extraction", "matching"}) {
    INFO(work);
    CHECK((ReadText(jobs / ("exit-" + work + "-3")) == "0\n" ||
           ReadText(jobs / "attempt-1.log").find(work + " part 3 was still waiting for room") != std::string::npos));
  }
  for (const char* block : {"feature_extraction_block_1.log", "feature_extraction_block_3.log"}) {
    CHECK_THAT(ReadText(sfm / "logs" / block),
               Catch::StartsWith("$ colmap feature_extractor") && Catch::Contains("--image_list_path"));
  }
  for (const char* block : {"verification_block_1.log", "verification_block_3.log"}) {
    CHECK_THAT(ReadText(sfm / "logs" / block),
               Catch::StartsWith("$ colmap matches_importer") && Catch::Contains("--match_list_path"));
  }
  CHECK(!fs::exists(sfm / "extraction"));  // the blocks' databases, merged
  CHECK(!fs::exists(sfm / "matching"));
  for (const char* cluster : {"mapping_cluster_1.log", "mapping_cluster_2.log"}) {
    CHECK_THAT(ReadText(sfm / "logs" / cluster),
               Catch::StartsWith("$ colmap mapper") && Catch::Contains("--image_list_path"));
  }
  CHECK_THAT(ReadText(sfm / "logs" / "merging_models_1.log"), Catch::Contains("Merge succeeded"));
  CHECK_THAT(ReadText(sfm / "logs" / "triangulation.log"), Catch::StartsWith("$ colmap point_triangulator"));
  const nlohmann::json report = ReadJsonFile(sfm / "sfm_report.json");
  CHECK(report["registered"] == 24);
  CHECK(report["chosen_model"] == "sparse/0");
  CHECK(report["steps"][0]["step"] == "feature extraction");
  CHECK(report["steps"][1]["step"] == "merging features");
  CHECK(report["steps"][2]["step"] == "descriptor matching and verification");
  CheckPoses(ReadJsonFile(workspace / "20_poses" / "transforms.json"), TruePoses(dir / "photos"), 0.5, 0.01);
}

TEST_CASE("slurm: a block whose job is cancelled is optimised by the stage's job from its checkpoint", "[slurm]") {
  TempDir dir;
  const fs::path data = SmallDataset(dir), workspace = dir / "ws";
  std::vector<std::string> args = SlurmRunArgs(data, workspace);
  // Blocks long enough to cancel one while it runs (some seconds): 300 steps whole, then 300 each.
  args.insert(args.end(), {"--slurm.cpus", "1", "--splat.blocks", "2", "--splat.steps", "600", "--until", "splat"});
  const pid_t run = Spawn(args, dir / "run.log");
  const fs::path jobs = JobDir(workspace, "35_splat"),
                 checkpoint = workspace / "35_splat.resume" / "checkpoint_block2.bin";
  const auto deadline = Clock::now() + std::chrono::seconds(240);
  while (!fs::exists(checkpoint) && Clock::now() < deadline) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  REQUIRE(fs::exists(checkpoint));
  std::string ignored;
  REQUIRE(RunCommand({"scancel", SubmittedJob(jobs / "submit-block.log") + "_2"}, &ignored) == 0);
  const int code = Wait(run);
  INFO(ReadText(dir / "run.log"));
  REQUIRE(code == 0);
  const std::string job_log = ReadText(jobs / "attempt-1.log");
  INFO(job_log);
  CHECK_THAT(job_log, Catch::Contains("splat: block part 2") && Catch::Contains("running it here"));
  const nlohmann::json report = ReadJsonFile(workspace / "35_splat" / "splat_report.json");
  CHECK(report["steps"] == 900);
  CHECK(report["resumed_from_step"].get<int>() > 0);  // block 2 went on from its checkpoint
}

TEST_CASE("slurm: a cancelled job is submitted again, resumes, and the stages done before it are kept", "[slurm]") {
  TempDir dir;
  const fs::path data = SmallDataset(dir), workspace = dir / "ws";
  const pid_t run = Spawn(LongSlurmRunArgs(data, workspace), dir / "run.log");
  const std::string job = StartedJob(workspace, "30_train");
  const nlohmann::json poses = ReadJsonFile(workspace / "20_poses" / "manifest.json");
  WaitForCheckpoint(workspace / "30_train.resume");
  std::string ignored;
  REQUIRE(RunCommand({"scancel", job}, &ignored) == 0);
  const int code = Wait(run);
  const std::string log = ReadText(dir / "run.log");
  INFO(log);
  REQUIRE(code == 0);
  CHECK_THAT(log, Catch::Contains("ended before finishing (cancelled); submitting it again (1 of 2)"));
  CHECK(fs::exists(JobDir(workspace, "30_train") / "attempt-2.log"));
  CHECK(ReadJsonFile(workspace / "30_train" / "train_report.json")["resumed_from_step"].get<int>() > 0);
  CHECK(ReadJsonFile(workspace / "20_poses" / "manifest.json") == poses);
  CHECK(CheckedKeys(workspace).size() == 2);  // poses (the import), train
}

TEST_CASE("slurm: a job whose node fails is requeued by Slurm, said so, and goes on from its checkpoint", "[slurm]") {
  TempDir dir;
  const fs::path data = SmallDataset(dir), workspace = dir / "ws";
  const pid_t run = Spawn(LongSlurmRunArgs(data, workspace), dir / "run.log");
  const std::string job = StartedJob(workspace, "30_train");
  WaitForCheckpoint(workspace / "30_train.resume");
  std::string output, node;
  REQUIRE(RunCommand({"squeue", "--noheader", "--jobs=" + job, "--format=%N"}, &output) == 0);
  std::istringstream words(output);
  for (std::string word; words >> word;) node = word;  // the last word (before it, the command)
  // The node lost: Slurm ends its jobs and requeues them; it takes the node back once its slurmd answers.
  const int down = RunCommand({"scontrol", "update", "NodeName=" + node, "State=DOWN", "Reason=test"}, &output);
  INFO(output);
  REQUIRE(down == 0);
  const int code = Wait(run);
  RunCommand({"scontrol", "update", "NodeName=" + node, "State=RESUME"}, &output);  // in case it did not
  const std::string log = ReadText(dir / "run.log");
  INFO(log);
  REQUIRE(code == 0);
  CHECK_THAT(log, Catch::Contains("train: Slurm requeued job " + job + " (its node failed"));
  const fs::path jobs = JobDir(workspace, "30_train");
  CHECK(!fs::exists(jobs / "submit-2.log"));  // Slurm's requeue, not a resubmission
  const std::string job_log = ReadText(jobs / "attempt-1.log");
  INFO(job_log);
  CHECK_THAT(job_log, Catch::Contains("DUE TO NODE FAILURE") && Catch::Contains("resumed at step"));
  CHECK(ReadJsonFile(workspace / "30_train" / "train_report.json")["resumed_from_step"].get<int>() > 0);
  CHECK(CheckedKeys(workspace).size() == 2);  // poses (the import), train
}

TEST_CASE("slurm: a controller that does not answer for a while is waited for, not taken for a job lost", "[slurm]") {
  TempDir dir;
  const fs::path data = SmallDataset(dir), workspace = dir / "ws", silent = dir / "silent";
  // squeue as when slurmctld is busy or restarting, while `silent` exists.
  fs::create_directories(dir / "bin");
  const char* path = std::getenv("PATH");
  WriteText(dir / "bin" / "squeue",
            format("#!/bin/sh\nif [ -e '{}' ]; then\n  echo 'squeue: error: slurm_load_jobs error: Socket timed out "
                   "on send/recv operation'\n  exit 1\nfi\nPATH='{}' exec squeue \"$@\"\n",
                   silent.string(), path));
  fs::permissions(dir / "bin" / "squeue", fs::perms::owner_all);
  std::vector<std::string> args = LongSlurmRunArgs(data, workspace);
  args.insert(args.begin(), {"/usr/bin/env", format("PATH={}:{}", (dir / "bin").string(), path)});
  const pid_t run = Spawn(args, dir / "run.log");
  StartedJob(workspace, "30_train");
  WriteText(silent, "");
  std::this_thread::sleep_for(std::chrono::seconds(12));  // two queries unanswered, beyond the exit file's grace
  fs::remove(silent);
  const int code = Wait(run);
  const std::string log = ReadText(dir / "run.log");
  INFO(log);
  REQUIRE(code == 0);
  CHECK_THAT(log, Catch::Contains("Slurm does not answer about job") && Catch::Contains("Socket timed out"));
  CHECK(!fs::exists(JobDir(workspace, "30_train") / "submit-2.log"));  // the job ran on, once
  CHECK(ReadJsonFile(workspace / "30_train" / "train_report.json")["steps"] == 600);
}

TEST_CASE("slurm: a job killed for its memory is not submitted again, and the error says how to ask for more",
          "[slurm]") {
  TempDir dir;
  const fs::path data = SmallDataset(dir), workspace = dir / "ws";
  std::vector<std::string> args = LongSlurmRunArgs(data, workspace);
  std::string output;
  REQUIRE(RunCommand({P2N_BINARY, "run", data.string(), "-w", workspace.string(), "--until", "poses"}, &output) == 0);
  args.insert(args.end(), {"--slurm.cpus", "1", "--slurm.sbatch_args", "--mem=60M"});  // the stage needs about 200
  const int code = RunCommand(args, &output);
  INFO(output);
  CHECK(code == 2);
  CHECK_THAT(output, Catch::Contains("stage train: its Slurm job ran out of memory (more: --slurm.sbatch_args "
                                     "--mem=") &&
                         Catch::Contains("not submitted again"));
  CHECK(!fs::exists(JobDir(workspace, "30_train") / "submit-2.log"));
  CHECK(fs::exists(workspace / "20_poses" / "manifest.json"));
}

TEST_CASE("slurm: a job that fails on its own is not submitted again, and its error is the stage's", "[slurm]") {
  TempDir dir;
  const fs::path data = SmallDataset(dir), photos = dir / "photos";
  fs::create_directories(photos);
  for (int i = 0; i < 4; ++i) {
    const std::string name = format("view_{:03}.png", i);
    fs::copy_file(data / name, photos / name);
  }
  // A COLMAP whose mapper finds no pair to start from: the sfm stage's own error, which a resubmission would repeat.
  const fs::path colmap = dir / "colmap";
  WriteText(colmap,
            "#!/bin/sh\nif [ \"$1\" = help ]; then echo 'COLMAP 3.8 -- Structure-from-Motion'; exit 0; fi\n"
            "if [ \"$1\" = mapper ]; then echo 'No good initial image pair found.'; exit 1; fi\nexit 0\n");
  fs::permissions(colmap, fs::perms::owner_all);
  std::string output;
  const int code = RunCommand({P2N_BINARY, "run", photos.string(), "-w", (dir / "ws").string(), "--colmap",
                               colmap.string(), "--run.scheduler", "slurm", "--run.progress", "plain"},
                              &output);
  INFO(output);
  CHECK(code == 1);  // a user error, as in a local run
  CHECK_THAT(output, Catch::Contains("stage sfm failed in its Slurm job (exit code 1)") &&
                         Catch::Contains("no pair of photos to start the reconstruction from") &&
                         Catch::Contains("attempt-1.log"));
  CHECK(!fs::exists(JobDir(dir / "ws", "10_sfm") / "submit-2.log"));
  CHECK(fs::exists(dir / "ws" / "00_ingest" / "manifest.json"));
  REQUIRE(RunCommand({P2N_BINARY, "status", "-w", (dir / "ws").string(), "--colmap", colmap.string()}, &output) == 0);
  CHECK_THAT(output, Catch::Matches("(.|\n)*sfm +incomplete(.|\n)*"));
}

TEST_CASE("slurm: Ctrl-C cancels the running job", "[slurm]") {
  TempDir dir;
  const fs::path data = SmallDataset(dir), workspace = dir / "ws";
  const pid_t run = Spawn(LongSlurmRunArgs(data, workspace), dir / "run.log");
  const std::string job = StartedJob(workspace, "30_train");
  ::kill(run, SIGINT);
  CHECK(Wait(run) == 130);
  INFO(ReadText(dir / "run.log"));
  CHECK_THAT(ReadText(dir / "run.log"), Catch::Contains("cancelled Slurm job " + job));
  const auto deadline = Clock::now() + std::chrono::seconds(30);
  while (JobState(job).find("CANCELLED") == std::string::npos && Clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  CHECK_THAT(JobState(job), Catch::Contains("CANCELLED"));
}

TEST_CASE("slurm: a run killed with SIGKILL leaves its job running, and the next run cancels it first", "[slurm]") {
  TempDir dir;
  const fs::path data = SmallDataset(dir), workspace = dir / "ws";
  const std::vector<std::string> args = LongSlurmRunArgs(data, workspace);
  const pid_t run = Spawn(args, dir / "run.log");
  const std::string job = StartedJob(workspace, "30_train");
  ::kill(run, SIGKILL);
  Wait(run);
  CHECK_THAT(JobState(job), Catch::Contains("RUNNING"));
  std::string output;
  const int code = RunCommand(args, &output);
  INFO(output);
  REQUIRE(code == 0);
  CHECK_THAT(output, Catch::Contains("train: Slurm job " + job + " of an earlier run still runs; cancelling it"));
  CHECK_THAT(JobState(job), Catch::Contains("CANCELLED"));
  CHECK(CheckedKeys(workspace).size() == 2);  // poses (the import), train
}

TEST_CASE("slurm: without sbatch the run says what to install and runs nothing", "[slurm]") {
  TempDir dir;
  const fs::path data = SmallDataset(dir);
  std::vector<std::string> args = SlurmRunArgs(data, dir / "ws");
  args.insert(args.begin(), {"/usr/bin/env", "PATH=" + (dir / "empty").string()});
  std::string output;
  CHECK(RunCommand(args, &output) == 1);
  CHECK_THAT(output, Catch::Contains("needs Slurm's sbatch on PATH") && Catch::Contains("slurm-client") &&
                         Catch::Contains("--run.scheduler local"));
  CHECK(!fs::exists(dir / "ws" / "20_poses"));
}

}  // namespace p2n::testing

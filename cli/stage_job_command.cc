// stage-job: one stage's work inside a job of a scheduler (pipeline/slurm.h). The run that submitted the job holds
// the workspace lock, made the staging folder and commits it when this returns.

#include <sys/resource.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>

#include "base/errors.h"
#include "base/file_util.h"
#include "base/format.h"
#include "cli/cli_options.h"
#include "cli/commands.h"
#include "pipeline/log.h"
#include "pipeline/slurm.h"
#include "stages/stages.h"

namespace p2n {
namespace fs = std::filesystem;
namespace {

// This process's peak resident memory in MB (what a job's --mem must allow).
long PeakMemoryMB() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss / 1024;  // kB on Linux
}

}  // namespace

int RunStageJob(int argc, char** argv) {
  CLI::App app("Run one stage's work as a job of a scheduler; photo2nerf run --run.scheduler slurm submits it.",
               "photo2nerf stage-job");
  std::string workspace_path;
  std::string job_file;
  app.add_option("-w,--workspace", workspace_path, "workspace folder, as the submitting run gave it")->required();
  app.add_option("--job", job_file, "the job file it wrote (logs/slurm/STAGE/job.json)")->required();
  std::optional<int> part;
  std::string work;
  CLI::Option* part_option =
      app.add_option("--part", part, "one part of the stage's work (an element of the job array its job submitted)");
  part_option->needs(app.add_option("--work", work, "the kind of part (its job array's name)")->needs(part_option));
  if (auto code = Parse(app, OptionRegistry(), argc, argv)) return *code;

  const Workspace workspace = Workspace::Open(workspace_path, /*create=*/false);
  const StageJob job = ReadStageJob(job_file);
  const OptionRegistry registry = AllOptions();
  Config config(registry);
  config.Merge(job.config, job_file);
  // A job given some CPUs of a node uses those, not every core of it.
  const char* job_cpus = std::getenv("SLURM_CPUS_PER_TASK");
  const std::string threads = OptionKey(&RunOptions::threads);
  if (config.Get<int>(threads) == 0 && job_cpus != nullptr)
    config.SetFromText(threads, job_cpus, "SLURM_CPUS_PER_TASK");
  CheckAllOptions(config);
  const auto thread_limit = ApplyRunOptions(config, workspace.LogDir() / "photo2nerf.log");
  const char* job_id = std::getenv("SLURM_JOB_ID");
  const std::string what =
      format("{} in job {}", part ? format("{} part {}", work, *part) : "working", job_id != nullptr ? job_id : "?");
  LogInfo(format("{}: {} (workspace {})", job.stage, what, workspace.root().string()));
  const auto start = std::chrono::steady_clock::now();
  StageWork stage_work{part, work, nullptr};
  if (!part && ReadOptions<RunOptions>(config).scheduler == Scheduler::kSlurm) {
    stage_work.parts = SlurmParts(ReadOptions<SlurmOptions>(config), fs::read_symlink("/proc/self/exe"), workspace,
                                  job_file, job.stage);
  }
  const nlohmann::json summary =
      MakeRunner(workspace.input()).RunWork(workspace, config, job.stage, job.key, stage_work);
  if (!part) WriteJsonAtomic(job.summary_path, summary);
  const std::chrono::duration<double> seconds = std::chrono::steady_clock::now() - start;
  LogInfo(
      format("{}: {}: done in {:.1f} s, at most {} MB in memory", job.stage, what, seconds.count(), PeakMemoryMB()));
  return kExitOk;
}

}  // namespace p2n

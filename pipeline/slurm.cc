#include "pipeline/slurm.h"

#include <unistd.h>

#include <chrono>
#include <fstream>
#include <optional>
#include <sstream>
#include <thread>

#include "base/errors.h"
#include "base/file_util.h"
#include "base/format.h"
#include "pipeline/cancel.h"
#include "pipeline/log.h"
#include "pipeline/slurm_jobs.h"
#include "pipeline/subprocess.h"

namespace p2n {
namespace fs = std::filesystem;
namespace {

bool OnPath(const std::string& program) {
  const char* path = std::getenv("PATH");
  std::stringstream folders(path != nullptr ? path : "");
  std::string folder;
  while (std::getline(folders, folder, ':')) {
    if (!folder.empty() && ::access((fs::path(folder) / program).c_str(), X_OK) == 0) return true;
  }
  return false;
}

// The batch script: photo2nerf stage-job, then its exit code into exit-N (N: the attempt, from the environment).
void WriteBatchScript(const fs::path& script, const fs::path& program, const Workspace& workspace,
                      const fs::path& job_file, const std::string& stage) {
  std::string text = "#!/bin/sh\n";
  text += format("# The {} stage of workspace {} as a Slurm job (written by photo2nerf run --run.scheduler slurm).\n",
                 stage, workspace.root().string());
  text += QuoteCommand({program.string(), "stage-job", "-w", workspace.root().string(), "--job", job_file.string()});
  text += '\n';
  text += slurm::WriteExitCode(job_file.parent_path() / "exit-", "\"$P2N_ATTEMPT\"");
  WriteFileAtomic(script, text);
  fs::permissions(script, fs::perms::owner_exec, fs::perm_options::add);
}

// Waits until the job has written `exit_file`, or Slurm no longer runs it and the file did not come; the last state
// Slurm gave ("" when none). Says when Slurm puts the job back in its queue (it runs again from the start, and its
// log `job_log` says why) and when Slurm does not answer (nothing is concluded from that: the job may still run).
std::string WaitForJob(const std::string& id, const fs::path& exit_file, const fs::path& dir, const std::string& stage,
                       const fs::path& job_log) {
  using Clock = std::chrono::steady_clock;
  auto next_query = Clock::now() + slurm::kQueryInterval;
  std::optional<Clock::time_point> ended;
  int restarts = 0;
  bool unanswered = false;
  std::string state;
  while (!fs::exists(exit_file)) {
    ThrowIfCancelled();
    const auto now = Clock::now();
    if (ended && now > *ended + slurm::kExitFileGrace) return state;
    if (!ended && now >= next_query) {
      next_query = now + slurm::kQueryInterval;
      const std::optional<slurm::JobStatus> status = slurm::QueryJob(id, dir);
      if (!status && !unanswered) {
        LogWarning(format("{}: Slurm does not answer about job {} ({}); waiting for it", stage, id,
                          slurm::LastError(dir / "squeue.log")));
      }
      unanswered = !status;
      if (status) state = status->state;
      if (status && !status->alive) ended = now;
      if (status && status->restarts > restarts) {
        restarts = status->restarts;
        LogWarning(
            format("{}: Slurm requeued job {} (its node failed, or it was preempted: {}); it runs again when "
                   "Slurm starts it, training and splats from their last checkpoint",
                   stage, id, job_log.string()));
      }
    }
    std::this_thread::sleep_for(slurm::kExitFilePoll);
  }
  return state;
}

// Cancels the jobs an earlier run of this stage submitted and left (it was killed while they ran: its stage job or
// the job array of the stage's parts), waits until Slurm has ended them, and empties the staging folder they may
// have written into: one job at a time writes a stage.
void CancelLeftJobs(const fs::path& dir, const fs::path& staging, const std::string& stage) {
  if (!fs::is_directory(dir)) return;
  bool cancelled = false;
  for (const auto& entry : fs::directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("submit-", 0) != 0 || entry.path().extension() != ".log") continue;
    const std::string attempt = entry.path().stem().string().substr(7);  // submit-N.log, submit-WORK.log (parts)
    const std::optional<std::string> id = slurm::JobId(entry.path());
    if (id && !fs::exists(dir / ("exit-" + attempt))) cancelled |= slurm::CancelAndWait(*id, dir, stage);
  }
  if (!cancelled) return;
  fs::remove_all(staging);
  fs::create_directories(staging);
}

// How a stage's job ended: its exit code, or nothing when it ended without one; its log; for one that did not finish
// (no code, or stopped from outside), why, and whether for its memory.
struct JobEnd {
  std::optional<int> code;
  fs::path log;
  std::string why;
  bool out_of_memory = false;
};

// Submits attempt `attempt` and waits for it; scancels the job when this process is interrupted.
JobEnd SubmitAndWait(const SlurmOptions& options, const fs::path& dir, const StageContext& context,
                     const std::string& stage, int attempt) {
  const fs::path submit_log = dir / format("submit-{}.log", attempt);
  const auto start = std::chrono::steady_clock::now();
  const fs::path job_log = dir / format("attempt-{}.log", attempt);
  const std::string id =
      slurm::Submit(slurm::SbatchCommand(options, context.workspace, "p2n-" + stage, job_log,
                                         {format("--export=ALL,P2N_ATTEMPT={}", attempt)}, dir / "job.sh"),
                    submit_log, "the job of stage " + stage);
  const fs::path exit_file = dir / format("exit-{}", attempt);
  std::string state;
  try {
    state = WaitForJob(id, exit_file, dir, stage, job_log);
  } catch (const Cancelled&) {
    RunCleanupSubprocess({"scancel", id}, submit_log, "scancel");
    LogWarning(format("{}: cancelled Slurm job {}", stage, id));
    throw;
  }
  JobEnd end;
  end.code = slurm::ReadExitCode(exit_file);
  end.log = job_log;
  if (!end.code || *end.code == kExitInterrupted) {
    end.why = slurm::WhyUnfinished(state, job_log);
    end.out_of_memory = slurm::OutOfMemory(state, job_log);
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  LogInfo(format("{}: Slurm job {} (attempt {}) ended {} after {:.1f} s", stage, id, attempt,
                 end.code ? format("with exit code {}", *end.code) : format("without finishing: {}", end.why),
                 seconds));
  return end;
}

}  // namespace

void SlurmOptions::Check() const {
  CheckField(*this, cpus, cpus >= 0, format("must be 0 (a whole node) or more, not {}", cpus));
  CheckField(*this, retries, retries >= 0, format("must be 0 or more, not {}", retries));
}

void RequireSbatch() {
  if (OnPath("sbatch")) return;
  throw UserError(
      "--run.scheduler slurm needs Slurm's sbatch on PATH (Debian: the slurm-client package, configured for your "
      "cluster); install it, or run here with --run.scheduler local");
}

StageExecutor SlurmExecutor(const SlurmOptions& options, fs::path program) {
  return [options, program = std::move(program)](const Stage& stage, StageContext& context) {
    const fs::path dir = context.workspace.LogDir() / "slurm" / stage.folder();
    CancelLeftJobs(dir, context.output_dir, stage.name());
    std::error_code error;
    fs::remove_all(dir, error);
    fs::create_directories(dir);
    const fs::path summary = dir / "summary.json";
    WriteJsonAtomic(dir / "job.json", {{"stage", stage.name()},
                                       {"key", context.key},
                                       {"summary", summary.string()},
                                       {"config", context.config.ToJson()}});
    WriteBatchScript(dir / "job.sh", program, context.workspace, dir / "job.json", stage.name());
    for (int attempt = 1; attempt <= options.retries + 1; ++attempt) {
      ThrowIfCancelled();
      const JobEnd end = SubmitAndWait(options, dir, context, stage.name(), attempt);
      const std::optional<int>& code = end.code;
      if (code == 0 && fs::exists(summary)) {
        context.summary = ReadJsonFile(summary);
        return;
      }
      if (code && *code != kExitInterrupted) {  // stopped by SIGTERM: from outside
        const std::string message = format("stage {} failed in its Slurm job (exit code {}): {} (the job's log: {})",
                                           stage.name(), *code, slurm::LastError(end.log), end.log.string());
        if (*code == kExitUserError) throw UserError(message);
        throw ExternalToolError(message);
      }
      if (end.out_of_memory) {  // as it would again
        throw ExternalToolError(
            format("stage {}: its Slurm job ran {}; not submitted again, as it would again (its log: {})", stage.name(),
                   end.why, end.log.string()));
      }
      if (attempt > options.retries) {
        throw ExternalToolError(
            format("stage {}: {} Slurm jobs in a row ended before finishing, the last one: {}; their logs are in {}",
                   stage.name(), options.retries + 1, end.why, dir.string()));
      }
      LogWarning(format("{}: the Slurm job ended before finishing ({}); submitting it again ({} of {})", stage.name(),
                        end.why, attempt, options.retries));
    }
  };
}

StageJob ReadStageJob(const fs::path& path) {
  const nlohmann::json json = ReadJsonFile(path);
  StageJob job;
  for (const char* field : {"stage", "key", "summary"}) {
    if (!json.contains(field) || !json[field].is_string()) {
      throw UserError(
          format("{}: field '{}' is missing or not text; the job file is written by photo2nerf run "
                 "--run.scheduler slurm, run that again",
                 path.string(), field));
    }
  }
  if (!json.contains("config") || !json["config"].is_object()) {
    throw UserError(format("{}: field 'config' is missing or not an object", path.string()));
  }
  job.stage = json["stage"];
  job.key = json["key"];
  job.summary_path = json["summary"].get<std::string>();
  job.config = json["config"];
  return job;
}

}  // namespace p2n

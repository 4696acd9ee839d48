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

std::vector<std::string> SplitSpaces(const std::string& text) {
  std::vector<std::string> words;
  std::stringstream stream(text);
  std::string word;
  while (stream >> word) words.push_back(word);
  return words;
}

// The job id sbatch --parsable printed ("123" or "123;cluster"), from its log; nothing when it printed none.
std::optional<std::string> JobId(const fs::path& submit_log) {
  std::ifstream log(submit_log);
  std::string line;
  while (std::getline(log, line)) {
    const std::string id = line.substr(0, line.find(';'));
    if (!id.empty() && id.find_first_not_of("0123456789") == std::string::npos) return id;
  }
  return std::nullopt;
}

// The last line of a log that says what went wrong ("error: ..."), or its last line.
std::string LastError(const fs::path& log_file) {
  std::ifstream log(log_file);
  std::string line, last, last_error;
  while (std::getline(log, line)) {
    if (line.empty()) continue;
    last = line;
    if (line.find("error") != std::string::npos) last_error = line;
  }
  return last_error.empty() ? last : last_error;
}

std::optional<int> ReadExitCode(const fs::path& path) {
  std::ifstream file(path);
  int code = 0;
  if (file >> code) return code;
  return std::nullopt;
}

// The batch script: photo2nerf stage-job, then its exit code into exit-N (N: the attempt, from the environment).
void WriteBatchScript(const fs::path& script, const fs::path& program, const Workspace& workspace,
                      const fs::path& job_file, const std::string& stage) {
  std::string text = "#!/bin/sh\n";
  text += format("# The {} stage of workspace {} as a Slurm job (written by photo2nerf run --run.scheduler slurm).\n",
                 stage, workspace.root().string());
  text += QuoteCommand({program.string(), "stage-job", "-w", workspace.root().string(), "--job", job_file.string()});
  // Written whole, then renamed: whoever sees the file sees the code.
  const std::string exit_file = QuoteCommand({(job_file.parent_path() / "exit-").string()}) + "\"$P2N_ATTEMPT\"";
  text += format("\necho $? > {0}.part && mv {0}.part {0}\n", exit_file);
  WriteFileAtomic(script, text);
  fs::permissions(script, fs::perms::owner_exec, fs::perm_options::add);
}

std::vector<std::string> SbatchCommand(const SlurmOptions& options, const fs::path& dir, const Workspace& workspace,
                                       const std::string& stage, int attempt) {
  std::vector<std::string> argv = {"sbatch",
                                   "--parsable",
                                   "--job-name=p2n-" + stage,
                                   "--chdir=" + workspace.root().string(),
                                   format("--output={}", (dir / format("attempt-{}.log", attempt)).string()),
                                   format("--export=ALL,P2N_ATTEMPT={}", attempt)};
  if (!options.partition.empty()) argv.push_back("--partition=" + options.partition);
  argv.push_back(options.cpus > 0 ? format("--cpus-per-task={}", options.cpus) : "--exclusive");
  for (std::string& word : SplitSpaces(options.sbatch_args)) argv.push_back(std::move(word));
  argv.push_back((dir / "job.sh").string());
  return argv;
}

constexpr auto kExitFilePoll = std::chrono::milliseconds(200);
// How often Slurm is asked whether the job still runs (for a job that ends without its exit file), and how long the
// exit file may take to appear after the job ended (a network file system's caches).
constexpr auto kQueryInterval = std::chrono::seconds(5);
constexpr auto kExitFileGrace = std::chrono::seconds(5);
// How long a job left by an earlier run may take to end once cancelled.
constexpr auto kLeftJobEnd = std::chrono::minutes(2);

// Whether Slurm still has the job pending or running; false once it ended or is no longer known.
bool JobAlive(const std::string& id, const fs::path& dir) {
  const fs::path answer = dir / "squeue.log";
  std::error_code error;
  fs::remove(answer, error);
  const SubprocessResult result =
      RunSubprocess({"squeue", "--noheader", "--jobs=" + id, "--format=%T"}, answer, "asking Slurm about job " + id);
  if (result.signal != 0 || result.exit_code != 0) return false;
  std::ifstream log(answer);
  std::string line;
  std::getline(log, line);  // the command
  std::getline(log, line);
  for (const char* ended : {"", "COMPLETED", "CANCELLED", "FAILED", "TIMEOUT", "NODE_FAIL", "OUT_OF_MEMORY",
                            "PREEMPTED", "BOOT_FAIL", "DEADLINE"}) {
    if (line == ended) return false;
  }
  return true;
}

// Waits until the job has written `exit_file`, or Slurm no longer runs it and the file did not come.
void WaitForJob(const std::string& id, const fs::path& exit_file, const fs::path& dir) {
  using Clock = std::chrono::steady_clock;
  auto next_query = Clock::now() + kQueryInterval;
  std::optional<Clock::time_point> ended;
  while (!fs::exists(exit_file)) {
    ThrowIfCancelled();
    const auto now = Clock::now();
    if (ended && now > *ended + kExitFileGrace) return;
    if (!ended && now >= next_query) {
      if (!JobAlive(id, dir)) ended = now;
      next_query = now + kQueryInterval;
    }
    std::this_thread::sleep_for(kExitFilePoll);
  }
}

// Cancels the jobs an earlier run of this stage submitted and left (it was killed while they ran), waits until Slurm
// has ended them, and empties the staging folder they may have written into: one job at a time writes a stage.
void CancelLeftJobs(const fs::path& dir, const fs::path& staging, const std::string& stage) {
  if (!fs::is_directory(dir)) return;
  std::vector<std::string> ids;
  for (const auto& entry : fs::directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("submit-", 0) != 0 || entry.path().extension() != ".log") continue;
    const std::string attempt = entry.path().stem().string().substr(7);  // submit-N.log
    const std::optional<std::string> id = JobId(entry.path());
    if (id && !fs::exists(dir / ("exit-" + attempt))) ids.push_back(*id);
  }
  for (const std::string& id : ids) {
    if (!JobAlive(id, dir)) continue;
    LogWarning(format("{}: Slurm job {} of an earlier run still runs; cancelling it", stage, id));
    RunSubprocess({"scancel", id}, dir / "scancel.log", "scancel");
    const auto deadline = std::chrono::steady_clock::now() + kLeftJobEnd;
    while (JobAlive(id, dir)) {
      if (std::chrono::steady_clock::now() > deadline) {
        throw ExternalToolError(
            format("{}: Slurm job {} of an earlier run does not end after scancel; end it (scancel "
                   "--signal=KILL {}) and run again",
                   stage, id, id));
      }
      std::this_thread::sleep_for(kExitFilePoll);
    }
  }
  if (ids.empty()) return;
  fs::remove_all(staging);
  fs::create_directories(staging);
}

// Submits attempt `attempt` and waits for it; scancels the job when this process is interrupted. The job's
// exit code, or nothing when it ended without one.
std::optional<int> SubmitAndWait(const SlurmOptions& options, const fs::path& dir, const StageContext& context,
                                 const std::string& stage, int attempt) {
  const fs::path submit_log = dir / format("submit-{}.log", attempt);
  const auto start = std::chrono::steady_clock::now();
  const SubprocessResult submitted = RunSubprocess(SbatchCommand(options, dir, context.workspace, stage, attempt),
                                                   submit_log, format("submitting stage {} to Slurm", stage));
  const std::optional<std::string> id = JobId(submit_log);
  if (submitted.signal != 0 || submitted.exit_code != 0 || !id) {
    throw ExternalToolError(
        format("sbatch did not take the job of stage {}: {} (sbatch's output: {}); check the "
               "cluster and the slurm.* options",
               stage, LastError(submit_log), submit_log.string()));
  }
  const fs::path exit_file = dir / format("exit-{}", attempt);
  try {
    WaitForJob(*id, exit_file, dir);
  } catch (const Cancelled&) {
    RunCleanupSubprocess({"scancel", *id}, submit_log, "scancel");
    LogWarning(format("{}: cancelled Slurm job {}", stage, *id));
    throw;
  }
  const std::optional<int> code = ReadExitCode(exit_file);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  LogInfo(format("{}: Slurm job {} (attempt {}) ended {} after {:.1f} s", stage, *id, attempt,
                 code ? format("with exit code {}", *code) : std::string("without finishing"), seconds));
  return code;
}

}  // namespace

void SlurmOptions::Check() const {
  CheckOption(*this, cpus, cpus >= 0, format("must be 0 (a whole node) or more, not {}", cpus));
  CheckOption(*this, retries, retries >= 0, format("must be 0 or more, not {}", retries));
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
      const std::optional<int> code = SubmitAndWait(options, dir, context, stage.name(), attempt);
      if (code == 0 && fs::exists(summary)) {
        context.summary = ReadJsonFile(summary);
        return;
      }
      const fs::path job_log = dir / format("attempt-{}.log", attempt);
      if (code && *code != kExitInterrupted) {  // stopped by SIGTERM: from outside
        const std::string message = format("stage {} failed in its Slurm job (exit code {}): {} (the job's log: {})",
                                           stage.name(), *code, LastError(job_log), job_log.string());
        if (*code == kExitUserError) throw UserError(message);
        throw ExternalToolError(message);
      }
      if (attempt <= options.retries) {
        LogWarning(
            format("{}: the Slurm job ended before finishing (cancelled, out of time, or its node lost); "
                   "submitting it again ({} of {})",
                   stage.name(), attempt, options.retries));
      }
    }
    throw ExternalToolError(
        format("stage {}: {} Slurm jobs in a row ended before finishing (cancelled, out of time, or "
               "their node lost); their logs are in {}",
               stage.name(), options.retries + 1, dir.string()));
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

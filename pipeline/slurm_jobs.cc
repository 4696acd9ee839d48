#include "pipeline/slurm_jobs.h"

#include <algorithm>
#include <fstream>
#include <sstream>
#include <thread>

#include "base/errors.h"
#include "base/format.h"
#include "pipeline/log.h"
#include "pipeline/subprocess.h"

namespace p2n::slurm {
namespace fs = std::filesystem;
namespace {

// How long a job may take to end once cancelled.
constexpr auto kCancelledJobEnd = std::chrono::minutes(2);

std::vector<std::string> SplitSpaces(const std::string& text) {
  std::vector<std::string> words;
  std::stringstream stream(text);
  std::string word;
  while (stream >> word) words.push_back(word);
  return words;
}

// What squeue says of job `id` in `format` ("--format=%T", "--Format=State"), one line per job (or array element),
// ended ones too while Slurm keeps them (MinJobAge); no lines when Slurm no longer knows the job, nothing when squeue
// got no answer (the controller busy or restarting).
std::optional<std::vector<std::string>> Squeue(const std::string& id, const std::string& format, bool array,
                                               const fs::path& dir) {
  const fs::path answer = dir / "squeue.log";
  std::error_code error;
  fs::remove(answer, error);
  std::vector<std::string> argv = {"squeue", "--noheader", "--states=all", "--jobs=" + id, format};
  if (array) argv.push_back("--array");
  const SubprocessResult result = RunSubprocess(argv, answer, "asking Slurm about job " + id);
  std::ifstream log(answer);
  std::vector<std::string> lines;
  std::string line;
  std::getline(log, line);  // the command
  while (std::getline(log, line)) lines.push_back(line);
  if (result.signal == 0 && result.exit_code == 0) return lines;
  for (const std::string& said : lines) {
    if (said.find("Invalid job id") != std::string::npos) return std::vector<std::string>{};
  }
  return std::nullopt;
}

}  // namespace

std::vector<std::string> SbatchCommand(const SlurmOptions& options, const Workspace& workspace, const std::string& name,
                                       const fs::path& output, const std::vector<std::string>& extra,
                                       const fs::path& script) {
  std::vector<std::string> argv = {"sbatch", "--parsable", "--job-name=" + name, "--chdir=" + workspace.root().string(),
                                   "--output=" + output.string()};
  // Appending: a job Slurm requeues (its node failed) writes after its first run's lines, which say why, not over them.
  argv.push_back("--open-mode=append");
  if (!options.partition.empty()) argv.push_back("--partition=" + options.partition);
  // A whole node with all its memory (--exclusive alone gives a cluster's default memory a CPU, which may be less);
  // with some CPUs the cluster's default memory for them, unless the further arguments ask for more (they come later).
  if (options.cpus > 0) {
    argv.push_back(format("--cpus-per-task={}", options.cpus));
  } else {
    argv.insert(argv.end(), {"--exclusive", "--mem=0"});
  }
  for (std::string& word : SplitSpaces(options.sbatch_args)) argv.push_back(std::move(word));
  argv.insert(argv.end(), extra.begin(), extra.end());
  argv.push_back(script.string());
  return argv;
}

std::string Submit(const std::vector<std::string>& sbatch, const fs::path& submit_log, const std::string& what) {
  const SubprocessResult submitted = RunSubprocess(sbatch, submit_log, "submitting " + what + " to Slurm");
  const std::optional<std::string> id = JobId(submit_log);
  if (submitted.signal != 0 || submitted.exit_code != 0 || !id) {
    throw ExternalToolError(
        format("sbatch did not take {}: {} (sbatch's output: {}); check the cluster and the slurm.* options", what,
               LastError(submit_log), submit_log.string()));
  }
  return *id;
}

std::optional<std::string> JobId(const fs::path& submit_log) {
  std::ifstream log(submit_log);
  std::string line;
  while (std::getline(log, line)) {
    const std::string id = line.substr(0, line.find(';'));
    if (!id.empty() && id.find_first_not_of("0123456789") == std::string::npos) return id;
  }
  return std::nullopt;
}

std::optional<JobStatus> QueryJob(const std::string& id, const fs::path& dir) {
  const std::optional<std::vector<std::string>> lines = Squeue(id, "--Format=State,RestartCnt", false, dir);
  if (!lines) return std::nullopt;
  JobStatus status;
  for (const std::string& line : *lines) {
    std::istringstream words(line);
    std::string state;
    int restarts = 0;
    if (!(words >> state)) continue;
    words >> restarts;
    status.alive |= !Ended(state);
    status.restarts = std::max(status.restarts, restarts);
    status.state = state;
  }
  return status;
}

bool JobAlive(const std::string& id, const fs::path& dir) {
  const std::optional<JobStatus> status = QueryJob(id, dir);
  return !status || status->alive;
}

std::optional<std::map<int, ElementState>> ArrayStates(const std::string& id, const fs::path& dir) {
  const std::optional<std::vector<std::string>> lines = Squeue(id, "--format=%K %T %r", true, dir);
  if (!lines) return std::nullopt;
  std::map<int, ElementState> states;
  for (const std::string& line : *lines) {
    std::istringstream words(line);
    int index = 0;
    ElementState state;
    if (words >> index >> state.state) {
      std::getline(words >> std::ws, state.reason);
      states[index] = state;
    }
  }
  return states;
}

bool Ended(const std::string& state) {
  for (const char* ended : {"", "COMPLETED", "CANCELLED", "FAILED", "TIMEOUT", "NODE_FAIL", "OUT_OF_MEMORY",
                            "PREEMPTED", "BOOT_FAIL", "DEADLINE"}) {
    if (state == ended) return true;
  }
  return false;
}

bool OutOfMemory(const std::string& state, const fs::path& job_log) {
  if (state == "OUT_OF_MEMORY") return true;  // cgroups
  std::ifstream log(job_log);
  std::string line;
  while (std::getline(log, line)) {
    // slurmstepd's words when it kills a job above its --mem by polling (JobAcctGatherParams=OverMemoryKill)
    if (line.find("xceeded job memory limit") != std::string::npos) return true;
  }
  return false;
}

std::string WhyUnfinished(const std::string& state, const fs::path& job_log) {
  if (OutOfMemory(state, job_log)) {
    return "out of memory (more: --slurm.sbatch_args --mem=16G, or a whole node and its memory: --slurm.cpus 0)";
  }
  static const std::map<std::string, std::string, std::less<>> kWhy = {
      {"CANCELLED", "cancelled"},
      {"TIMEOUT", "out of its time limit (more: --slurm.sbatch_args --time=HH:MM:SS)"},
      {"NODE_FAIL", "its node failed"},
      {"BOOT_FAIL", "its node did not start"},
      {"PREEMPTED", "preempted"},
      {"DEADLINE", "past its deadline"}};
  const auto found = kWhy.find(state);
  if (found != kWhy.end()) return found->second;
  return format("{} ({})", state.empty() ? "ended" : state, LastError(job_log));
}

bool CancelAndWait(const std::string& id, const fs::path& dir, const std::string& stage) {
  if (!JobAlive(id, dir)) return false;
  LogWarning(format("{}: Slurm job {} of an earlier run still runs; cancelling it", stage, id));
  RunSubprocess({"scancel", id}, dir / "scancel.log", "scancel");
  const auto deadline = std::chrono::steady_clock::now() + kCancelledJobEnd;
  while (JobAlive(id, dir)) {
    if (std::chrono::steady_clock::now() > deadline) {
      throw ExternalToolError(
          format("{}: Slurm job {} of an earlier run does not end after scancel, or Slurm does not answer ({}); end "
                 "it (scancel --signal=KILL {}) and run again",
                 stage, id, (dir / "squeue.log").string(), id));
    }
    std::this_thread::sleep_for(kExitFilePoll);
  }
  return true;
}

std::optional<int> ReadExitCode(const fs::path& path) {
  std::ifstream file(path);
  int code = 0;
  if (file >> code) return code;
  return std::nullopt;
}

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

std::string WriteExitCode(const fs::path& exit_file, const std::string& suffix) {
  const std::string file = QuoteCommand({exit_file.string()}) + suffix;
  return format("echo $? > {0}.part && mv {0}.part {0}\n", file);
}

}  // namespace p2n::slurm

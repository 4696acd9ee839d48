#pragma once
// What the Slurm executors share (pipeline/slurm.cc runs stages as jobs, pipeline/slurm_parts.cc a stage's parts as
// a job array): sbatch's command line and job id, Slurm's word on a job, cancelling one, a job's exit file and log.

#include <chrono>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "pipeline/slurm_options.h"
#include "pipeline/workspace.h"

namespace p2n::slurm {

inline constexpr auto kExitFilePoll = std::chrono::milliseconds(200);
// How often Slurm is asked whether a job still runs (for one that ends without its exit file), and how long the exit
// file may take to appear after the job ended (a network file system's caches).
inline constexpr auto kQueryInterval = std::chrono::seconds(5);
inline constexpr auto kExitFileGrace = std::chrono::seconds(5);

// sbatch's command: the job named `name`, started in the workspace, printing into `output`, with the CPUs,
// partition and further arguments of `options`, then `extra` arguments and the batch script.
std::vector<std::string> SbatchCommand(const SlurmOptions& options, const Workspace& workspace, const std::string& name,
                                       const std::filesystem::path& output, const std::vector<std::string>& extra,
                                       const std::filesystem::path& script);
// Runs `sbatch` (its output into `submit_log`) and returns the job id; ExternalToolError saying what sbatch said
// when it took no job (`what`: "the job of stage train").
std::string Submit(const std::vector<std::string>& sbatch, const std::filesystem::path& submit_log,
                   const std::string& what);
// The job id sbatch --parsable printed ("123" or "123;cluster") into its log; nothing when it printed none.
std::optional<std::string> JobId(const std::filesystem::path& submit_log);

// What Slurm says of job `id` (or of the elements of job array `id`): whether it is still pending or running (false
// once it ended or is no longer known), and how many times Slurm has put it back in its queue (its node failed, or it
// was preempted); nothing when Slurm did not answer (its controller busy or restarting: nothing is known). `dir`
// takes squeue's log.
struct JobStatus {
  bool alive = false;
  int restarts = 0;
  std::string state;  // Slurm's ("RUNNING", "TIMEOUT", ...)
};
std::optional<JobStatus> QueryJob(const std::string& id, const std::filesystem::path& dir);
// Whether the job may still be pending or running: true also when Slurm did not answer.
bool JobAlive(const std::string& id, const std::filesystem::path& dir);
// Slurm's state of each element of job array `id` by its index ("RUNNING"; "PENDING" with why: "Resources",
// "Priority", or "None" while the scheduler has not yet looked at it); none it no longer knows; nothing when Slurm
// did not answer.
struct ElementState {
  std::string state, reason;
};
std::optional<std::map<int, ElementState>> ArrayStates(const std::string& id, const std::filesystem::path& dir);
// Whether a state is one of a job that has ended (or is no longer known).
bool Ended(const std::string& state);
// Whether a job that ended in `state`, its log `job_log`, was killed for using more memory than it asked for.
bool OutOfMemory(const std::string& state, const std::filesystem::path& job_log);
// Why a job that ended in `state` without finishing did not, and what to do when it is the cluster's limits ("out of
// its time limit (more: ...)"); otherwise the state and the last error of its log.
std::string WhyUnfinished(const std::string& state, const std::filesystem::path& job_log);

// Cancels job `id` when it still runs and waits until Slurm has ended it; ExternalToolError when it does not end.
// True when it was running.
bool CancelAndWait(const std::string& id, const std::filesystem::path& dir, const std::string& stage);

// The code in a job's exit file, or nothing when there is none (yet).
std::optional<int> ReadExitCode(const std::filesystem::path& path);
// The last line of a log that says what went wrong ("error: ..."), or its last line.
std::string LastError(const std::filesystem::path& log_file);
// Shell text that writes the exit code of the command before it ($?) into `exit_file` followed by `suffix` (shell
// text, such as "\"$P2N_ATTEMPT\""), whole: whoever sees the file sees the code.
std::string WriteExitCode(const std::filesystem::path& exit_file, const std::string& suffix);

}  // namespace p2n::slurm

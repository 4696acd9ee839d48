// The parts of a stage's work as a Slurm job array (pipeline/slurm.h, SlurmParts).

#include <chrono>
#include <set>
#include <thread>

#include "base/errors.h"
#include "base/file_util.h"
#include "base/format.h"
#include "pipeline/cancel.h"
#include "pipeline/log.h"
#include "pipeline/slurm.h"
#include "pipeline/slurm_jobs.h"
#include "pipeline/subprocess.h"

namespace p2n {
namespace fs = std::filesystem;
namespace {

using Clock = std::chrono::steady_clock;

// One submission of a stage's parts of one kind (`work`): the array's files, its job id, the parts it still runs.
struct PartArray {
  fs::path dir;  // beside the stage's job file
  std::string stage;
  std::string work;
  std::string id;
  std::set<int> waiting;

  // Where this job's questions to Slurm are logged: not beside the stage's, which the submitting run asks.
  fs::path Queries() const { return dir / "parts"; }
  fs::path Script() const { return dir / (work + ".sh"); }
  fs::path SubmitLog() const { return dir / format("submit-{}.log", work); }
  fs::path ExitFile(int part) const { return dir / format("exit-{}-{}", work, part); }
  fs::path Log(int part) const { return dir / format("{}-{}.log", work, part); }
  // What the log says of part `part`.
  std::string Name(int part) const { return format("{} part {}", work, part); }
};

// The batch script of an element: photo2nerf stage-job --work --part, then its exit code into its exit file.
void WritePartsScript(const PartArray& array, const fs::path& program, const Workspace& workspace,
                      const fs::path& job_file) {
  std::string text = "#!/bin/sh\n";
  text +=
      format("# Parts ({}) of the {} stage of workspace {} as a Slurm job array (written by photo2nerf stage-job).\n",
             array.work, array.stage, workspace.root().string());
  text += QuoteCommand({program.string(), "stage-job", "-w", workspace.root().string(), "--job", job_file.string(),
                        "--work", array.work, "--part"}) +
          " \"$SLURM_ARRAY_TASK_ID\"\n";
  text += slurm::WriteExitCode(array.dir / format("exit-{}-", array.work), "\"$SLURM_ARRAY_TASK_ID\"");
  WriteFileAtomic(array.Script(), text);
  fs::permissions(array.Script(), fs::perms::owner_exec, fs::perm_options::add);
}

// Part `part` has ended in its element with `code`: done, or run here when it was stopped from outside; an error
// when it failed on its own.
void PartEnded(const PartArray& array, int part, int code, const std::function<void(int)>& here) {
  if (code == kExitOk) return;
  if (code != kExitInterrupted) {
    const std::string message =
        format("{}: {} failed in its Slurm job {}_{} (exit code {}): {} (its log: {})", array.stage, array.Name(part),
               array.id, part, code, slurm::LastError(array.Log(part)), array.Log(part).string());
    if (code == kExitUserError) throw UserError(message);
    throw ExternalToolError(message);
  }
  LogWarning(format("{}: {} was stopped in its Slurm job; running it here", array.stage, array.Name(part)));
  here(part);
}

// Takes part `part` back from the array when its element has not started: true when it is cancelled unstarted. (Not
// `scancel --state=PENDING`: the array's pending elements are one record to Slurm, and that cancels all of them. An
// element that started just before is cancelled after starting, and run here as one that ended unfinished.)
bool TakeBack(const PartArray& array, int part) {
  const std::string element = format("{}_{}", array.id, part);
  RunSubprocess({"scancel", element}, array.Queries() / "scancel.log", "scancel");
  const std::optional<std::map<int, slurm::ElementState>> states = slurm::ArrayStates(array.id, array.Queries());
  if (!states) return false;  // Slurm did not answer: whether it started is not known
  const auto found = states->find(part);
  const std::string state = found == states->end() ? "" : found->second.state;
  return (state.empty() || state == "CANCELLED") && !fs::exists(array.Log(part)) && !fs::exists(array.ExitFile(part));
}

// Waits for the array's parts; runs here those still waiting for room when asked about (this job is free: the
// cluster may have none for them beside it) and those that ended without finishing.
void WaitForParts(PartArray& array, const std::function<void(int)>& here) {
  struct Ended {
    Clock::time_point when;
    std::string state;  // Slurm's
  };
  std::map<int, Ended> ended;  // parts whose element ended without an exit file
  auto next_query = Clock::now();
  while (!array.waiting.empty()) {
    std::this_thread::sleep_for(slurm::kExitFilePoll);
    ThrowIfCancelled();
    for (auto it = array.waiting.begin(); it != array.waiting.end();) {
      const std::optional<int> code = slurm::ReadExitCode(array.ExitFile(*it));
      const auto gone = ended.find(*it);
      const bool lost = !code && gone != ended.end() && Clock::now() > gone->second.when + slurm::kExitFileGrace;
      if (!code && !lost) {
        ++it;
        continue;
      }
      const int part = *it;
      it = array.waiting.erase(it);
      if (code) {
        PartEnded(array, part, *code, here);
      } else {
        LogWarning(format("{}: {} ended in its Slurm job without finishing ({}); running it here", array.stage,
                          array.Name(part), slurm::WhyUnfinished(ended[part].state, array.Log(part))));
        here(part);
      }
    }
    if (array.waiting.empty() || Clock::now() < next_query) continue;
    next_query = Clock::now() + slurm::kQueryInterval;
    const std::optional<std::map<int, slurm::ElementState>> states = slurm::ArrayStates(array.id, array.Queries());
    if (!states) continue;  // Slurm did not answer: ask again later
    for (const int part : std::set<int>(array.waiting)) {
      const auto found = states->find(part);
      const slurm::ElementState element = found == states->end() ? slurm::ElementState{} : found->second;
      const std::string& state = element.state;
      // Pending for want of room (not merely not yet looked at by the scheduler).
      if (state == "PENDING" && element.reason != "None" && TakeBack(array, part)) {
        LogInfo(format("{}: {} was still waiting for room in Slurm; running it here", array.stage, array.Name(part)));
        array.waiting.erase(part);
        here(part);
        break;  // ask Slurm again: time has passed
      }
      if (slurm::Ended(state) && !ended.contains(part)) ended[part] = {Clock::now(), state};
    }
  }
}

}  // namespace

PartsExecutor SlurmParts(const SlurmOptions& options, fs::path program, const Workspace& workspace, fs::path job_file,
                         std::string stage) {
  return [options, program = std::move(program), workspace, job_file = std::move(job_file), stage = std::move(stage)](
             const std::string& work, const std::vector<int>& parts, const std::function<void(int)>& here) {
    if (parts.size() < 2) {
      for (const int part : parts) here(part);
      return;
    }
    PartArray array{job_file.parent_path(), stage, work, "", std::set<int>(parts.begin() + 1, parts.end())};
    // An earlier attempt of this stage job may have left its array running: one writer per part.
    fs::create_directories(array.Queries());
    if (const std::optional<std::string> left = slurm::JobId(array.SubmitLog())) {
      slurm::CancelAndWait(*left, array.Queries(), stage);
    }
    std::string indices;
    for (const int part : array.waiting) {
      std::error_code error;
      fs::remove(array.ExitFile(part), error);
      fs::remove(array.Log(part), error);
      indices += format("{}{}", indices.empty() ? "" : ",", part);
    }
    WritePartsScript(array, program, workspace, job_file);
    array.id = slurm::Submit(
        slurm::SbatchCommand(options, workspace, format("p2n-{}-{}", stage, work),
                             array.dir / format("{}-%a.log", work), {"--array=" + indices}, array.Script()),
        array.SubmitLog(), format("the {} parts of stage {}", work, stage));
    LogInfo(
        format("{}: {} parts {} as Slurm job array {}; part {} here", stage, work, indices, array.id, parts.front()));
    try {
      here(parts.front());
      WaitForParts(array, here);
    } catch (...) {
      RunCleanupSubprocess({"scancel", array.id}, array.SubmitLog(), "scancel");
      throw;
    }
  };
}

}  // namespace p2n

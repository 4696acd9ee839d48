#pragma once
// Runs a graph of stages in a workspace, skipping fresh ones, and tells the state of each (docs/design.md §2).

#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "pipeline/manifest.h"
#include "pipeline/stage.h"

namespace p2n {

// kBlocked: its inputs from outside the workspace cannot be read (the reason says which); it cannot run.
enum class StageState { kFresh, kMissing, kIncomplete, kStale, kBlocked };
const char* StageStateName(StageState state);

struct StageStatus {
  const Stage* stage = nullptr;
  StageState state = StageState::kMissing;
  std::vector<std::string> reasons;  // why it is not fresh
  KeyInputs expected;                // what a fresh result would be made from
  std::string expected_key;
  std::optional<Manifest> manifest;  // of the result on disk, if complete
};

struct RunRequest {
  std::optional<std::string> from;   // stages before it are not run (they must be fresh)
  std::optional<std::string> until;  // stages after it are not run
  std::vector<std::string> force;    // rerun these and everything downstream of them, even if fresh
  StageExecutor executor;            // runs each stage's work; empty: in this process
};

struct StageRun {
  std::string stage;
  bool ran = false;  // false: skipped as fresh
  double wall_seconds = 0;
};

// Which of a stage's work a scheduler's job does (Runner::RunWork): one part of it (Stage::RunPart), or all of it
// with `parts` running its parts.
struct StageWork {
  std::optional<int> part;
  std::string work;  // the kind of part
  PartsExecutor parts = nullptr;
};

class Runner {
 public:
  // Stages in an order where every stage comes after its upstream stages; InternalError otherwise.
  explicit Runner(std::vector<std::unique_ptr<Stage>> stages);

  const std::vector<std::unique_ptr<Stage>>& stages() const { return stages_; }
  // The stage of that name; UserError listing the stages when there is none.
  const Stage& Get(std::string_view name) const;
  // The stage of that name, or nullptr when this table has none (an imported dataset has no sfm stage).
  const Stage* Find(std::string_view name) const;

  std::vector<StageStatus> Status(const Workspace& workspace, const Config& config) const;
  // Runs what the request asks for. Throws what a stage throws (its staging folder stays, so `status` says
  // incomplete); the caller holds the workspace lock.
  std::vector<StageRun> Run(const Workspace& workspace, const Config& config, const RunRequest& request) const;
  // Removes the stage's result and any partial or old copies of it.
  void Clean(const Workspace& workspace, std::string_view name) const;
  // A stage's work alone, for a job of a scheduler (pipeline/slurm.h): runs stage `name` into its staging folder,
  // which the run that submitted the job made, for the result of cache key `key`; returns the stage's summary. The
  // submitting run writes the manifest and commits the folder.
  nlohmann::json RunWork(const Workspace& workspace, const Config& config, std::string_view name,
                         const std::string& key, const StageWork& work = {}) const;

 private:
  size_t IndexOf(std::string_view name) const;
  // Whether stage `i` reads stage `j`'s result under `config`, directly or not.
  bool DependsOn(size_t i, size_t j, const Config& config) const;
  // Makes the stage's result; returns its manifest.
  Manifest RunOne(const Workspace& workspace, const Config& config, const StageStatus& status, RunMemo* memo,
                  const StageExecutor& executor) const;
  // What the stage's Run() sees when it makes the result of cache key `key`.
  StageContext ContextFor(const Workspace& workspace, const Config& config, const Stage& stage, const std::string& key,
                          RunMemo* memo) const;

  std::vector<std::unique_ptr<Stage>> stages_;
};

}  // namespace p2n

#pragma once
// The timed, resumable optimisation loop of the train and splat stages: steps until a time budget or a step count
// is spent, a metrics.csv row at each evaluation, and checkpoints that a killed run resumes from.

#include <filesystem>
#include <functional>
#include <optional>
#include <string>

#include "base/binary_io.h"

namespace p2n {

// The run's state besides its optimiser's, kept in its checkpoints.
struct RunState {
  double seconds = 0;   // optimisation time so far (evaluations not counted)
  std::string metrics;  // metrics.csv rows so far
  double loss_sum = 0;  // the training loss since the last row
  int loss_steps = 0;

  // The mean training loss since the last row (`if_none` when no step counted); the next row's starts.
  double TakeMeanLoss(double if_none);
};

// Writes `key`, `state` and then what `save` adds (the optimiser) to `path`, atomically.
void SaveRunCheckpoint(const std::filesystem::path& path, const std::string& key, const RunState& state,
                       const std::function<void(BinaryWriter*)>& save);
// Resumes from `path` when it is a checkpoint of this very result (same key): fills `state` and lets `load` read the
// optimiser's part. False otherwise, with a log line naming `stage` when a checkpoint was there.
bool LoadRunCheckpoint(const std::filesystem::path& path, const std::string& key, const std::string& stage,
                       RunState* state, const std::function<void(BinaryReader*)>& load);

// The part of a run's budget (and of its schedules: learning rates, densification) an optimisation covers, and its
// optimiser's step when the part begins: a stage working by blocks optimises whole over its first part, then each
// block over the rest (stages/fitting/blocked_run.h).
struct BudgetPart {
  double from = 0, to = 1;
  int start_step = 0;
  double share() const { return to - from; }
};

// What one session of a run did (a resumed run counts from its resumption).
struct RunSession {
  int steps = 0;  // skipped ones too
  double step_seconds = 0;
  int rows = 0;  // metrics rows
  double row_seconds = 0;
};

// How a run goes. Its optimiser is given as callbacks to Run().
struct RunLoop {
  std::string stage;               // in the progress display
  double budget = 0;               // seconds of optimisation; 0: by steps
  int steps = 0;                   // steps at most; 0: by the budget
  double eval_interval = 10;       // seconds of optimisation between metrics rows
  double eval_share = 1;           // rows take at most this share of the wall time (the interval grows)
  bool row_at_end = true;          // the loop adds the last row when it ends (else the caller does)
  double checkpoint_interval = 0;  // wall seconds between checkpoints; 0: none

  // How far a run is, in [0, 1]: of the time budget or of the steps, whichever is further; done at 1.
  double Share(const RunState& state, int step) const;

  // Steps from where `state` left off until the run is done. `step(share)` makes one step at that share of the run
  // and returns its loss, or nothing when it was skipped (no row or checkpoint follows it); `steps_made()` counts
  // the optimiser's steps; `add_row(state)` appends a metrics row (its loss from TakeMeanLoss()); `checkpoint(state)`
  // saves one.
  RunSession Run(RunState* state, const std::function<int()>& steps_made,
                 const std::function<std::optional<double>(double share)>& step,
                 const std::function<void(RunState*)>& add_row,
                 const std::function<void(const RunState&)>& checkpoint) const;
};

}  // namespace p2n

#include "stages/fitting/timed_run.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "base/file_util.h"
#include "base/format.h"
#include "nerf/nerf_model.h"
#include "pipeline/cancel.h"
#include "pipeline/log.h"
#include "pipeline/progress.h"

namespace p2n {
namespace fs = std::filesystem;
namespace {

using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

}  // namespace

double RunState::TakeMeanLoss(double if_none) {
  const double mean = loss_steps > 0 ? loss_sum / loss_steps : if_none;
  loss_sum = 0;
  loss_steps = 0;
  return mean;
}

void SaveRunCheckpoint(const fs::path& path, const std::string& key, const RunState& state,
                       const std::function<void(BinaryWriter*)>& save) {
  BinaryWriter writer;
  writer.PutString(key);
  writer.Put<double>(state.seconds);
  writer.PutString(state.metrics);
  writer.Put<double>(state.loss_sum);
  writer.Put<int32_t>(state.loss_steps);
  save(&writer);
  fs::create_directories(path.parent_path());
  WriteBinaryFileAtomic(path, writer.buffer());
}

bool LoadRunCheckpoint(const fs::path& path, const std::string& key, const std::string& stage, RunState* state,
                       const std::function<void(BinaryReader*)>& load) {
  if (!fs::exists(path)) return false;
  try {
    BinaryReader reader(ReadBinaryFile(path), path.string());
    if (reader.GetString() != key) {
      LogInfo(format("{}: the checkpoint in {} is of other inputs or options; starting over", stage, path.string()));
      return false;
    }
    RunState loaded;
    loaded.seconds = reader.Get<double>();
    loaded.metrics = reader.GetString();
    loaded.loss_sum = reader.Get<double>();
    loaded.loss_steps = reader.Get<int32_t>();
    load(&reader);
    *state = loaded;
    return true;
  } catch (const std::runtime_error& error) {
    LogWarning(format("{}: cannot resume ({}); starting over", stage, error.what()));
    return false;
  }
}

double RunLoop::Share(const RunState& state, int step) const {
  const double by_time = budget > 0 ? state.seconds / budget : 0;
  const double by_steps = steps > 0 ? double(step) / steps : 0;
  return std::clamp(std::max(by_time, by_steps), 0.0, 1.0);
}

RunSession RunLoop::Run(RunState* state, const std::function<int()>& steps_made,
                        const std::function<std::optional<double>(double share)>& step,
                        const std::function<void(RunState*)>& add_row,
                        const std::function<void(const RunState&)>& checkpoint) const {
  const bool by_time = budget > 0;
  const auto next_row_after = [&](double seconds) { return (std::floor(seconds / eval_interval) + 1) * eval_interval; };
  Progress progress(stage, by_time ? static_cast<int64_t>(budget) : steps, by_time ? "s" : "steps");
  progress.Add(by_time ? static_cast<int64_t>(state->seconds) : steps_made());
  double next_row = next_row_after(state->seconds);
  auto last_checkpoint = Clock::now();
  RunSession session;
  while (Share(*state, steps_made()) < 1) {
    ThrowIfCancelled();
    const auto start = Clock::now();
    const std::optional<double> loss = step(Share(*state, steps_made()));
    const double seconds = SecondsSince(start);
    const int64_t whole_before = static_cast<int64_t>(state->seconds);
    state->seconds += seconds;
    ++session.steps;
    session.step_seconds += seconds;
    progress.Add(by_time ? static_cast<int64_t>(state->seconds) - whole_before : 1);
    if (!loss) continue;
    state->loss_sum += *loss;
    ++state->loss_steps;
    const bool done = Share(*state, steps_made()) >= 1;
    if (done ? row_at_end : state->seconds >= next_row) {
      const auto row_start = Clock::now();
      add_row(state);
      const double row_seconds = SecondsSince(row_start);
      ++session.rows;
      session.row_seconds += row_seconds;
      // A row that took long pushes the next one out, so that rows take at most eval_share of the wall time.
      next_row = std::max(next_row_after(state->seconds), state->seconds + row_seconds * (1 - eval_share) / eval_share);
    }
    if (checkpoint_interval > 0 && SecondsSince(last_checkpoint) >= checkpoint_interval) {
      checkpoint(*state);
      last_checkpoint = Clock::now();
    }
  }
  return session;
}

}  // namespace p2n

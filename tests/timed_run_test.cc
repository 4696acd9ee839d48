// The train and splat stages' shared loop: how long it runs, when it writes rows, what it does with skipped steps,
// and its checkpoints' round trip.

#include <catch2/catch.hpp>

#include <cmath>
#include <fstream>

#include "stages/fitting/timed_run.h"
#include "test_util.h"

namespace p2n::testing {
namespace {

// A stand-in optimiser: counts its steps, returns `losses` in turn (NaN: a skipped step).
struct FakeOptimiser {
  explicit FakeOptimiser(std::vector<double> in_turn) : losses(std::move(in_turn)) {}

  std::vector<double> losses;
  int steps = 0;
  std::vector<double> row_losses;

  RunSession Run(const RunLoop& loop, RunState* state) {
    return loop.Run(
        state, [&] { return steps; },
        [&](double) -> std::optional<double> {
          const double loss = losses[steps++ % losses.size()];
          if (std::isnan(loss)) return std::nullopt;
          return loss;
        },
        [&](RunState* run) { row_losses.push_back(run->TakeMeanLoss(-1)); }, [](const RunState&) {});
  }
};

TEST_CASE("a run by steps makes them all, and its last row means their loss", "[timed_run]") {
  RunLoop loop;
  loop.stage = "test";
  loop.steps = 6;
  loop.eval_interval = 1e9;  // no row on the way
  FakeOptimiser optimiser{{1, 2, 3}};
  RunState state;
  const RunSession session = optimiser.Run(loop, &state);
  CHECK(optimiser.steps == 6);
  CHECK(session.steps == 6);
  REQUIRE(optimiser.row_losses.size() == 1);
  CHECK(optimiser.row_losses[0] == Approx(2.0));
  CHECK(session.rows == 1);
  CHECK(state.loss_steps == 0);
  CHECK(loop.Share(state, optimiser.steps) == 1.0);
}

TEST_CASE("a run whose caller makes the last row adds none at its end", "[timed_run]") {
  RunLoop loop;
  loop.stage = "test";
  loop.steps = 4;
  loop.eval_interval = 1e9;
  loop.row_at_end = false;
  FakeOptimiser optimiser{{0.5}};
  RunState state;
  optimiser.Run(loop, &state);
  CHECK(optimiser.row_losses.empty());
  CHECK(state.loss_steps == 4);
  CHECK(state.TakeMeanLoss(-1) == Approx(0.5));
  CHECK(state.TakeMeanLoss(-1) == -1);  // nothing since
}

TEST_CASE("skipped steps count towards the run but not towards its loss", "[timed_run]") {
  RunLoop loop;
  loop.stage = "test";
  loop.steps = 4;
  loop.eval_interval = 1e9;
  loop.row_at_end = false;
  FakeOptimiser optimiser{{1, std::nan(""), 3, std::nan("")}};
  RunState state;
  const RunSession session = optimiser.Run(loop, &state);
  CHECK(session.steps == 4);
  CHECK(state.loss_steps == 2);
  CHECK(state.loss_sum == Approx(4.0));
}

TEST_CASE("a resumed run goes on from its state and stops at once when it was done", "[timed_run]") {
  RunLoop loop;
  loop.stage = "test";
  loop.steps = 5;
  loop.eval_interval = 1e9;
  FakeOptimiser optimiser{{1}};
  optimiser.steps = 3;
  RunState state;
  CHECK(optimiser.Run(loop, &state).steps == 2);
  CHECK(optimiser.Run(loop, &state).steps == 0);
  CHECK(optimiser.steps == 5);
}

TEST_CASE("a run's share is of its budget or its steps, whichever is further", "[timed_run]") {
  RunLoop loop;
  loop.budget = 100;
  loop.steps = 10;
  RunState state;
  state.seconds = 20;
  CHECK(loop.Share(state, 5) == Approx(0.5));
  CHECK(loop.Share(state, 1) == Approx(0.2));
  state.seconds = 150;
  CHECK(loop.Share(state, 1) == 1.0);
}

TEST_CASE("a checkpoint resumes its state and its optimiser's part, only for its own key", "[timed_run]") {
  TempDir dir;
  const std::filesystem::path file = dir.path() / "resume" / "checkpoint.bin";
  RunState state;
  state.seconds = 12.5;
  state.metrics = "1,2,3\n";
  state.loss_sum = 0.75;
  state.loss_steps = 3;
  SaveRunCheckpoint(file, "key-a", state, [](BinaryWriter* w) { w->Put<int32_t>(42); });

  RunState loaded;
  int32_t payload = 0;
  const auto load = [&](BinaryReader* r) { payload = r->Get<int32_t>(); };
  CHECK_FALSE(LoadRunCheckpoint(file, "key-b", "test", &loaded, load));
  CHECK(loaded.seconds == 0);
  REQUIRE(LoadRunCheckpoint(file, "key-a", "test", &loaded, load));
  CHECK(loaded.seconds == 12.5);
  CHECK(loaded.metrics == "1,2,3\n");
  CHECK(loaded.loss_sum == 0.75);
  CHECK(loaded.loss_steps == 3);
  CHECK(payload == 42);

  std::ofstream(file, std::ios::binary | std::ios::trunc) << "not a checkpoint";
  RunState untouched;
  CHECK_FALSE(LoadRunCheckpoint(file, "key-a", "test", &untouched, load));
  CHECK(untouched.metrics.empty());
  CHECK_FALSE(LoadRunCheckpoint(dir.path() / "none.bin", "key-a", "test", &untouched, load));
}

}  // namespace
}  // namespace p2n::testing

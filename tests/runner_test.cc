// The stage framework with fake stages that count their runs (issue 2).

#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <catch2/catch.hpp>

#include <chrono>
#include <thread>

#include "base/errors.h"
#include "base/file_util.h"
#include "tests/fake_stages.h"
#include "tests/test_util.h"

namespace p2n::testing {
namespace fs = std::filesystem;
namespace {

struct Fixture {
  TempDir dir;
  fs::path counters = dir / "counters";
  OptionRegistry registry = FakeOptionsRegistry();
  Config config{registry};
  Workspace workspace = Workspace::Open(dir / "ws", true);

  Fixture() { fs::create_directories(counters); }
  std::vector<StageRun> Run(const RunRequest& request = {}) {
    return MakeFakeRunner(counters).Run(workspace, config, request);
  }
  std::vector<StageStatus> Status() { return MakeFakeRunner(counters).Status(workspace, config); }
  std::vector<int> Counts() { return {RunCount(counters, "a"), RunCount(counters, "b"), RunCount(counters, "c")}; }
};

// Records what the stages before it kept in the run's memo, and keeps its own name there.
class MemoStage : public Stage {
 public:
  MemoStage(std::string name, std::vector<std::string> upstream, std::vector<std::string>* seen)
      : name_(std::move(name)), upstream_(std::move(upstream)), seen_(seen) {}
  std::string name() const override { return name_; }
  int format_version() const override { return 1; }
  std::vector<std::string> upstream() const override { return upstream_; }
  std::vector<std::string> option_sections() const override { return {}; }
  void Run(StageContext& context) const override {
    REQUIRE(context.memo != nullptr);
    for (const std::string& up : upstream_) {
      if (const auto kept = context.memo->Find<std::string>(up)) seen_->push_back(name_ + " found " + *kept);
    }
    CHECK(context.memo->Find<int>(name_) == nullptr);  // nothing of another type under a key
    context.memo->Keep(name_, std::make_shared<const std::string>(name_));
  }

 private:
  std::string name_;
  std::vector<std::string> upstream_;
  std::vector<std::string>* seen_;
};

std::vector<StageState> States(const std::vector<StageStatus>& statuses) {
  std::vector<StageState> states;
  for (const StageStatus& status : statuses) states.push_back(status.state);
  return states;
}

RunRequest From(const std::string& stage) {
  RunRequest request;
  request.from = stage;
  return request;
}
RunRequest Until(const std::string& stage) {
  RunRequest request;
  request.until = stage;
  return request;
}
RunRequest Force(const std::string& stage) {
  RunRequest request;
  request.force = {stage};
  return request;
}

constexpr StageState kFresh = StageState::kFresh;
constexpr StageState kStale = StageState::kStale;

}  // namespace

TEST_CASE("the stages of one run share its memo, and another run starts with an empty one", "[runner]") {
  Fixture f;
  std::vector<std::string> seen;
  std::vector<std::unique_ptr<Stage>> stages;
  stages.push_back(std::make_unique<MemoStage>("first", std::vector<std::string>{}, &seen));
  stages.push_back(std::make_unique<MemoStage>("second", std::vector<std::string>{"first"}, &seen));
  const Runner runner(std::move(stages));
  runner.Run(f.workspace, f.config, {});
  CHECK(seen == std::vector<std::string>{"second found first"});
  RunRequest second_alone;
  second_alone.from = "second";
  second_alone.force = {"second"};
  runner.Run(f.workspace, f.config, second_alone);
  CHECK(seen.size() == 1);  // ran, and found nothing
}

TEST_CASE("a second run runs nothing", "[runner]") {
  Fixture f;
  CHECK(States(f.Status()) == std::vector{StageState::kMissing, StageState::kMissing, StageState::kMissing});
  f.Run();
  CHECK(f.Counts() == std::vector{1, 1, 1});
  CHECK(States(f.Status()) == std::vector{kFresh, kFresh, kFresh});
  const auto runs = f.Run();
  CHECK(f.Counts() == std::vector{1, 1, 1});
  for (const StageRun& run : runs) CHECK_FALSE(run.ran);
  CHECK(ReadText(f.workspace.StageDir("c") / "out.txt") == "c=1;b=1;a=1");
}

TEST_CASE("an executor runs each stage's work elsewhere, and the results are a local run's", "[runner]") {
  Fixture local;
  local.Run();
  Fixture f;
  // A stand-in for a scheduler's job: another runner, as `photo2nerf stage-job` makes, does the work.
  std::vector<std::string> executed;
  RunRequest request;
  request.executor = [&](const Stage& stage, StageContext& context) {
    executed.push_back(stage.name());
    context.summary = MakeFakeRunner(f.counters).RunWork(f.workspace, f.config, stage.name(), context.key);
  };
  f.Run(request);
  CHECK(executed == std::vector<std::string>{"a", "b", "c"});
  CHECK(States(f.Status()) == std::vector{kFresh, kFresh, kFresh});
  for (const char* stage : {"a", "b", "c"}) {
    CHECK(ReadJsonFile(f.workspace.StageDir(stage) / kManifestName)["key"] ==
          ReadJsonFile(local.workspace.StageDir(stage) / kManifestName)["key"]);
  }
  CHECK(ReadText(f.workspace.StageDir("c") / "out.txt") == "c=1;b=1;a=1");
  // A job whose staging folder is gone (its run ended) does nothing and says so.
  CHECK_THROWS_WITH(MakeFakeRunner(f.counters).RunWork(f.workspace, f.config, "b", "key"),
                    Catch::Contains("has no staging folder"));
}

TEST_CASE("an option change reruns its stage and everything downstream, nothing upstream", "[runner]") {
  Fixture f;
  f.Run();
  f.config.Set("b.value", 2, "test");
  const auto statuses = f.Status();
  CHECK(States(statuses) == std::vector{kFresh, kStale, kStale});
  CHECK(statuses[1].reasons == std::vector<std::string>{"option b.value changed (default -> 2)"});
  CHECK(statuses[2].reasons == std::vector<std::string>{"upstream b changed"});
  f.Run();
  CHECK(f.Counts() == std::vector{1, 2, 2});
  CHECK(ReadText(f.workspace.StageDir("c") / "out.txt") == "c=1;b=2;a=1");
  // Going back to the old value is a change too: the cache holds one result per stage.
  f.config.Set("b.value", 1, "test");
  f.Run();
  CHECK(f.Counts() == std::vector{1, 3, 3});
}

TEST_CASE("a stage that its options keep from reading an upstream stage is keyed and run without it", "[runner]") {
  Fixture f;
  f.config.Set("c.read_upstream", false, "test");
  f.Run();
  CHECK(ReadText(f.workspace.StageDir("c") / "out.txt") == "c=1");
  f.config.Set("b.value", 2, "test");
  CHECK(States(f.Status()) == std::vector{kFresh, kStale, kFresh});
  f.Run(From("c"));  // b is stale, but c does not need it
  f.Run(Force("b"));
  CHECK(f.Counts() == std::vector{1, 2, 1});
  MakeFakeRunner(f.counters).Clean(f.workspace, "b");
  CHECK(f.Status()[2].state == kFresh);
  f.config.Set("c.read_upstream", true, "test");
  f.Run();
  CHECK(f.Counts() == std::vector{1, 3, 2});
  CHECK(ReadText(f.workspace.StageDir("c") / "out.txt") == "c=1;b=2;a=1");
}

TEST_CASE("a runtime-only option reruns nothing", "[runner]") {
  Fixture f;
  f.Run();
  f.config.Set("run.threads", 7, "test");
  f.config.Set("a.block", false, "test");
  CHECK(States(f.Status()) == std::vector{kFresh, kFresh, kFresh});
  f.Run();
  CHECK(f.Counts() == std::vector{1, 1, 1});
}

TEST_CASE("an option added at its default, or set back to it, keeps results fresh", "[runner]") {
  Fixture f;
  f.Run();
  OptionRegistry newer = FakeOptionsRegistry();
  newer.Add({"b.added_later", 0.5, "an option of a newer version", "", OptionKind::kResult, {}});
  Config config(newer);
  CHECK(States(MakeFakeRunner(f.counters).Status(f.workspace, config)) == std::vector{kFresh, kFresh, kFresh});
  config.Set("b.added_later", 0.25, "test");
  const auto statuses = MakeFakeRunner(f.counters).Status(f.workspace, config);
  CHECK(statuses[1].reasons == std::vector<std::string>{"option b.added_later changed (default -> 0.25)"});
  f.config.Set("b.value", 1, "test");  // given, but at its default
  f.Run();
  CHECK(f.Counts() == std::vector{1, 1, 1});
}

TEST_CASE("a threshold is not in the key, and a fresh result must pass it", "[runner]") {
  Fixture f;
  f.config.Set("b.value", 3, "test");
  f.Run();
  f.config.Set("b.min_value", 5, "test");
  CHECK(States(f.Status()) == std::vector{kFresh, kFresh, kFresh});
  CHECK_THROWS_WITH(f.Run(), Catch::Contains("b=3 is below b.min_value 5"));
  CHECK(f.Counts() == std::vector{1, 1, 1});
  f.config.Set("b.min_value", 2, "test");
  f.Run();
  CHECK(f.Counts() == std::vector{1, 1, 1});
  f.config.Set("b.value", 1, "test");  // a new result below the threshold: the stage itself refuses it
  CHECK_THROWS_WITH(f.Run(), Catch::Contains("b=1 is below b.min_value 2"));
  CHECK(States(f.Status()) == std::vector{kFresh, StageState::kIncomplete, kStale});
}

TEST_CASE("a stage whose outside input cannot be read is blocked, and the others still have a status", "[runner]") {
  Fixture f;
  f.Run();
  fs::create_directories(f.counters / "input.txt");  // a folder where a file is expected
  const auto statuses = f.Status();
  CHECK(States(statuses) == std::vector{StageState::kBlocked, kStale, kStale});
  CHECK_THAT(statuses[0].reasons.front(), Catch::Contains("input.txt is not a file"));
  CHECK_THROWS_WITH(f.Run(), Catch::Contains("input.txt is not a file"));
  CHECK(f.Counts() == std::vector{1, 1, 1});
}

TEST_CASE("status names changed inputs, format versions and outputs", "[runner]") {
  Fixture f;
  WriteText(f.counters / "input.txt", "one");
  f.Run();
  SECTION("input") {
    WriteText(f.counters / "input.txt", "two");
    const auto statuses = f.Status();
    CHECK(statuses[0].reasons == std::vector<std::string>{"input file input.txt changed"});
    CHECK(statuses[1].reasons == std::vector<std::string>{"upstream a changed"});
    fs::remove(f.counters / "input.txt");
    CHECK(f.Status()[0].reasons == std::vector<std::string>{"input file input.txt removed"});
  }
  SECTION("format version") {
    WriteText(f.counters / "b.version", "2");
    const auto statuses = f.Status();
    CHECK(States(statuses) == std::vector{kFresh, kStale, kStale});
    CHECK(statuses[1].reasons == std::vector<std::string>{"format version 1 -> 2"});
  }
  SECTION("output deleted or modified") {
    WriteText(f.workspace.StageDir("b") / "out.txt", "edited by hand, longer than before");
    const auto statuses = f.Status();
    CHECK(States(statuses) == std::vector{kFresh, kStale, kFresh});
    CHECK(statuses[1].reasons == std::vector<std::string>{"output out.txt is missing or was modified"});
    f.Run();
    CHECK(f.Counts() == std::vector{1, 2, 1});  // b's key is unchanged, so c's is too
  }
  SECTION("a touched input file is not a change") {
    const auto time = fs::last_write_time(f.counters / "input.txt");
    fs::last_write_time(f.counters / "input.txt", time + std::chrono::hours(1));
    CHECK(States(f.Status()) == std::vector{kFresh, kFresh, kFresh});
  }
}

TEST_CASE("a stage that throws is redone next time and never reported fresh", "[runner]") {
  Fixture f;
  f.config.Set("b.fail", true, "test");
  CHECK_THROWS_AS(f.Run(), UserError);
  CHECK(f.Counts() == std::vector{1, 1, 0});
  const auto statuses = f.Status();
  CHECK(States(statuses) == std::vector{kFresh, StageState::kIncomplete, StageState::kMissing});
  CHECK_THAT(statuses[1].reasons.at(0), Catch::Contains("interrupted or failed"));
  f.config.Set("b.fail", false, "test");
  f.Run();
  CHECK(f.Counts() == std::vector{1, 2, 1});
  CHECK(States(f.Status()) == std::vector{kFresh, kFresh, kFresh});
  CHECK_FALSE(fs::exists(f.workspace.StagingDir("b")));
}

TEST_CASE("a process killed with SIGKILL mid-stage leaves the stage incomplete, the next run redoes it",
          "[runner][kill]") {
  Fixture f;
  f.Run();  // a complete earlier result of every stage, with b.value = 1
  const std::vector<std::string> args = {P2N_FAKE_PIPELINE, f.workspace.root().string(), f.counters.string(),
                                         "b.value=5", "b.block=true"};
  std::vector<char*> argv;
  for (const std::string& arg : args) argv.push_back(const_cast<char*>(arg.c_str()));
  argv.push_back(nullptr);
  pid_t pid = 0;
  REQUIRE(posix_spawn(&pid, argv[0], nullptr, nullptr, argv.data(), environ) == 0);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (!fs::exists(f.counters / "started.flag") && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  REQUIRE(fs::exists(f.counters / "started.flag"));
  // The lock is held: a second run on the workspace fails at once and names the holder.
  CHECK_THROWS_WITH(WorkspaceLock(f.workspace, "test"), Catch::Contains("in use by process " + std::to_string(pid)));
  ::kill(pid, SIGKILL);
  int status = 0;
  ::waitpid(pid, &status, 0);
  REQUIRE(WIFSIGNALED(status));

  f.config.Set("b.value", 5, "test");
  const auto statuses = f.Status();
  CHECK(States(statuses) == std::vector{kFresh, StageState::kIncomplete, kStale});
  WorkspaceLock lock(f.workspace, "test");  // released by the kill
  f.Run();
  CHECK(f.Counts() == std::vector{1, 3, 2});
  CHECK(States(f.Status()) == std::vector{kFresh, kFresh, kFresh});
  CHECK(ReadText(f.workspace.StageDir("c") / "out.txt") == "c=1;b=5;a=1");
}

TEST_CASE("run requests: from, until and force", "[runner]") {
  Fixture f;
  SECTION("--until stops early") {
    f.Run(Until("b"));
    CHECK(f.Counts() == std::vector{1, 1, 0});
  }
  SECTION("--force reruns a stage and what depends on it") {
    f.Run();
    f.Run(Force("b"));
    CHECK(f.Counts() == std::vector{1, 2, 2});
  }
  SECTION("--from needs fresh upstream stages") {
    CHECK_THROWS_WITH(f.Run(From("b")), Catch::Contains("the stage a it needs is missing"));
    f.Run(Until("a"));
    f.Run(From("b"));
    CHECK(f.Counts() == std::vector{1, 1, 1});
    f.config.Set("a.value", 3, "test");
    CHECK_THROWS_WITH(f.Run(From("c")), Catch::Contains("option a.value changed (default -> 3)"));
  }
  SECTION("unknown stage names are listed") {
    CHECK_THROWS_WITH(f.Run(From("x")), Catch::Contains("unknown stage 'x'; the stages are: a, b, c"));
  }
}

TEST_CASE("a stage rerun alone with another result makes what read the old one stale", "[runner]") {
  Fixture f;
  f.Run();
  RunRequest b_alone = Force("b");
  b_alone.from = b_alone.until = "b";
  f.Run(b_alone);  // the same result: nothing downstream to redo
  CHECK(States(f.Status()) == std::vector{kFresh, kFresh, kFresh});
  f.config.Set("b.noise", 7, "test");  // runtime, so not in the key: as a time budget's training differs
  SECTION("the next status and run") {
    f.Run(b_alone);
    const auto statuses = f.Status();
    CHECK(States(statuses) == std::vector{kFresh, kFresh, kStale});
    CHECK(statuses[2].reasons == std::vector<std::string>{"upstream b was rerun since and made another result"});
    f.Run();
    CHECK(f.Counts() == std::vector{1, 3, 2});
  }
  SECTION("within one run") {
    fs::remove(f.workspace.StageDir("b") / kManifestName);  // b incomplete: redone, and with another result
    f.Run();
    CHECK(f.Counts() == std::vector{1, 3, 2});
    CHECK(States(f.Status()) == std::vector{kFresh, kFresh, kFresh});
  }
  SECTION("a manifest from before upstream results were recorded is not checked") {
    const fs::path manifest = f.workspace.StageDir("c") / kManifestName;
    nlohmann::json json = ReadJsonFile(manifest);
    json.erase("upstream_results");
    WriteJsonAtomic(manifest, json);
    f.Run(b_alone);
    CHECK(States(f.Status()) == std::vector{kFresh, kFresh, kFresh});
  }
}

TEST_CASE("a manifest that is damaged is reported, not trusted", "[runner]") {
  Fixture f;
  f.Run();
  WriteText(f.workspace.StageDir("b") / "manifest.json", "{\"stage\": \"b\"}");
  auto statuses = f.Status();
  CHECK(statuses[1].state == StageState::kIncomplete);
  CHECK_THAT(statuses[1].reasons.at(0), Catch::Contains("manifest.json' is damaged"));
  // Numbers no integer holds (undefined behaviour if cast) are damage too.
  WriteText(f.workspace.StageDir("b") / "manifest.json",
            R"({"stage": "b", "format_version": 1e30, "options": {}, "upstream": {}, "inputs": {}, "key": "k",
                "outputs": []})");
  CHECK_THAT(f.Status()[1].reasons.at(0), Catch::Contains("format_version is not a whole number in range: 1e+30"));
  WriteText(f.workspace.StageDir("b") / "manifest.json",
            R"({"stage": "b", "format_version": 1, "options": {}, "upstream": {}, "inputs": {}, "key": "k",
                "outputs": [{"path": "x", "size": -1, "sha1": ""}]})");
  CHECK_THAT(f.Status()[1].reasons.at(0), Catch::Contains("outputs[].size is not a whole number in range: -1"));
  fs::remove(f.workspace.StageDir("b") / "manifest.json");
  CHECK(f.Status()[1].state == StageState::kIncomplete);
  f.Run();
  CHECK(f.Counts() == std::vector{1, 2, 1});
}

TEST_CASE("Clean removes one stage's results", "[runner]") {
  Fixture f;
  f.Run();
  MakeFakeRunner(f.counters).Clean(f.workspace, "b");
  CHECK(States(f.Status()) == std::vector{kFresh, StageState::kMissing, kFresh});
  f.Run();
  CHECK(f.Counts() == std::vector{1, 2, 1});
}

}  // namespace p2n::testing

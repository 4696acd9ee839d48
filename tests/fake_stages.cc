#include "tests/fake_stages.h"

#include <chrono>
#include <fstream>
#include <sstream>
#include <thread>

#include "base/errors.h"
#include "base/file_util.h"
#include "base/format.h"
#include "pipeline/hash.h"

namespace p2n::testing {
namespace fs = std::filesystem;
namespace {

std::string ReadText(const fs::path& path) { return ReadTextFile(path); }

class FakeStage : public Stage {
 public:
  FakeStage(std::string name, std::vector<std::string> upstream, fs::path counter_dir, int format_version)
      : name_(std::move(name)),
        upstream_(std::move(upstream)),
        counter_dir_(std::move(counter_dir)),
        format_version_(format_version) {}

  std::string name() const override { return name_; }
  int format_version() const override { return format_version_; }
  std::vector<std::string> upstream() const override { return upstream_; }
  std::vector<std::string> UpstreamFor(const Config& config) const override {
    return ReadOptions<FakeOptions>(config, name_).read_upstream ? upstream_ : std::vector<std::string>{};
  }
  std::map<std::string, std::string> ExternalInputs(const Workspace&, const Config&) const override {
    const fs::path input = counter_dir_ / "input.txt";
    if (name_ != "a" || !fs::exists(input)) return {};
    if (!fs::is_regular_file(input)) throw UserError(format("{} is not a file", input.string()));
    return {{"file input.txt", Sha1OfFile(input)}};
  }
  void CheckResult(const fs::path& result_dir, const Config& config) const override {
    const FakeOptions options = ReadOptions<FakeOptions>(config, name_);
    const std::string text = ReadText(result_dir / "out.txt");
    const std::string own = text.substr(0, text.find(';'));  // "b=3"
    if (std::stoi(own.substr(own.find('=') + 1)) < options.min_value) {
      throw UserError(format("{} is below {}.min_value {}", own, name_, options.min_value));
    }
  }

  void Run(StageContext& context) const override {
    const FakeOptions options = ReadOptions<FakeOptions>(context.config, name_);
    const int count = RunCount(counter_dir_, name_) + 1;
    std::ofstream(counter_dir_ / (name_ + ".count")) << count;
    std::string text = name_ + "=" + std::to_string(options.value);
    for (const auto& [up, dir] : context.upstream_dirs) text += format(";{}", ReadText(dir / "out.txt"));
    std::ofstream(context.output_dir / "out.txt") << text;
    if (options.noise != 0) std::ofstream(context.output_dir / "noise.txt") << options.noise;
    if (options.fail) throw UserError(format("stage {} failed on purpose", name_));
    CheckResult(context.output_dir, context.config);
    if (options.block) {
      std::ofstream(counter_dir_ / "started.flag") << name_;
      std::this_thread::sleep_for(std::chrono::seconds(60));
    }
  }

 private:
  std::string name_;
  std::vector<std::string> upstream_;
  fs::path counter_dir_;
  int format_version_;
};

}  // namespace

OptionRegistry FakeOptionsRegistry() {
  OptionRegistry registry;
  registry.Add({"run.threads", 0, "threads", "", OptionKind::kRuntime, {}});
  for (const char* name : {"a", "b", "c"}) RegisterOptions<FakeOptions>(registry, name);
  return registry;
}

Runner MakeFakeRunner(const fs::path& counter_dir) {
  // The format version is read from the counter folder so that a test can "upgrade" stage b.
  int b_version = 1;
  if (fs::exists(counter_dir / "b.version")) b_version = std::stoi(ReadText(counter_dir / "b.version"));
  std::vector<std::unique_ptr<Stage>> stages;
  stages.push_back(std::make_unique<FakeStage>("a", std::vector<std::string>{}, counter_dir, 1));
  stages.push_back(std::make_unique<FakeStage>("b", std::vector<std::string>{"a"}, counter_dir, b_version));
  stages.push_back(std::make_unique<FakeStage>("c", std::vector<std::string>{"b"}, counter_dir, 1));
  return Runner(std::move(stages));
}

int RunCount(const fs::path& counter_dir, const std::string& stage) {
  const fs::path path = counter_dir / (stage + ".count");
  return fs::exists(path) ? std::stoi(ReadText(path)) : 0;
}

}  // namespace p2n::testing

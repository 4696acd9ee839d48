// A process that runs the fake pipeline once, so that a test can kill it with SIGKILL mid-stage.
// Usage: fake_pipeline WORKSPACE COUNTER_DIR [dotted.key=value ...]

#include <iostream>

#include "base/errors.h"
#include "tests/fake_stages.h"

int main(int argc, char** argv) {
  if (argc < 3) {
    std::cerr << "usage: fake_pipeline WORKSPACE COUNTER_DIR [key=value ...]\n";
    return 1;
  }
  try {
    const p2n::OptionRegistry registry = p2n::testing::FakeOptionsRegistry();
    p2n::Config config(registry);
    for (int i = 3; i < argc; ++i) {
      const std::string setting = argv[i];
      const size_t equals = setting.find('=');
      config.SetFromText(setting.substr(0, equals), setting.substr(equals + 1), "command line");
    }
    const p2n::Workspace workspace = p2n::Workspace::Open(argv[1], true);
    p2n::WorkspaceLock lock(workspace, "fake_pipeline");
    p2n::testing::MakeFakeRunner(argv[2]).Run(workspace, config, {});
  } catch (const std::exception& e) {
    std::cerr << e.what() << "\n";
    return 1;
  }
  return 0;
}

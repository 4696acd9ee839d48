#include "tests/test_util.h"

#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>

#include "base/file_util.h"
#include "pipeline/subprocess.h"

namespace p2n::testing {
namespace fs = std::filesystem;

TempDir::TempDir() {
  std::random_device random;
  path_ = fs::temp_directory_path() / ("p2n_test_" + std::to_string(::getpid()) + "_" + std::to_string(random()));
  fs::create_directories(path_);
}

TempDir::~TempDir() {
  std::error_code error;
  fs::remove_all(path_, error);
}

ScopedEnv::ScopedEnv(const std::string& name, const std::string& value) : name_(name) {
  if (const char* old = std::getenv(name.c_str())) old_ = old;
  ::setenv(name.c_str(), value.c_str(), 1);
}

ScopedEnv::~ScopedEnv() { old_ ? ::setenv(name_.c_str(), old_->c_str(), 1) : ::unsetenv(name_.c_str()); }

void WriteText(const fs::path& path, const std::string& text) { std::ofstream(path) << text; }

std::string ReadText(const fs::path& path) { return ReadTextFile(path); }

int RunCommand(const std::vector<std::string>& argv, std::string* output) {
  TempDir dir;
  const SubprocessResult result = RunSubprocess(argv, dir / "output.log", argv[0]);
  *output = ReadText(dir / "output.log");
  return result.signal != 0 ? 128 + result.signal : result.exit_code;
}

}  // namespace p2n::testing

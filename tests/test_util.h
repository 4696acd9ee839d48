#pragma once
// Helpers shared by the tests: a temporary folder removed at the end, an environment variable set for a scope,
// small file utilities.

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace p2n::testing {

class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

// Sets an environment variable for its lifetime; the old value (or its absence) comes back at its end, whatever
// ends the scope.
class ScopedEnv {
 public:
  ScopedEnv(const std::string& name, const std::string& value);
  ~ScopedEnv();
  ScopedEnv(const ScopedEnv&) = delete;
  ScopedEnv& operator=(const ScopedEnv&) = delete;

 private:
  std::string name_;
  std::optional<std::string> old_;
};

void WriteText(const std::filesystem::path& path, const std::string& text);
std::string ReadText(const std::filesystem::path& path);

// Runs a command (argv) with output captured; returns its exit code and fills `output` with stdout+stderr.
int RunCommand(const std::vector<std::string>& argv, std::string* output);

}  // namespace p2n::testing

#include "tests/program_runs.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <catch2/catch.hpp>

#include "base/file_util.h"
#include "pipeline/hash.h"

extern char** environ;

namespace p2n::testing {
namespace fs = std::filesystem;

std::vector<std::string> RunArgs(const fs::path& data, const fs::path& workspace) {
  return {P2N_BINARY,
          "run",
          data.string(),
          "-w",
          workspace.string(),
          "--run.progress",
          "plain",
          "--train.preset",
          "fast",
          "--train.steps",
          "120",
          "--train.checkpoint_interval",
          "0.2",
          "--train.eval_interval",
          "1",
          "--train.eval_pixels",
          "512",
          "--splat.steps",
          "40",
          "--splat.init_width",
          "48",
          "--splat.checkpoint_interval",
          "0.2",
          "--splat.eval_interval",
          "1",
          "--render.frames",
          "4",
          "--export.resolution",
          "32",
          "--export.points_width",
          "32",
          "--export.threshold",
          "5",
          "--export.texture_size",
          "256"};
}

pid_t Spawn(const std::vector<std::string>& args, const fs::path& log) {
  std::vector<char*> argv;
  for (const std::string& arg : args) argv.push_back(const_cast<char*>(arg.c_str()));
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  pid_t pid = 0;
  const int error = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  REQUIRE(error == 0);
  return pid;
}

int Wait(pid_t pid) {
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFSIGNALED(status) ? 128 + WTERMSIG(status) : WEXITSTATUS(status);
}

std::map<std::string, std::string> CheckedKeys(const fs::path& workspace) {
  std::map<std::string, std::string> keys;
  for (const auto& entry : fs::directory_iterator(workspace)) {
    const fs::path manifest = entry.path() / "manifest.json";
    // Result folders only (not X.partial, X.trash: a kill between the two renames of a commit leaves one).
    if (entry.path().filename().string().find('.') != std::string::npos || !fs::exists(manifest)) continue;
    const nlohmann::json json = ReadJsonFile(manifest);
    for (const nlohmann::json& output : json["outputs"]) {
      const fs::path file = entry.path() / output["path"].get<std::string>();
      INFO(file.string());
      REQUIRE(fs::exists(file));
      CHECK(Sha1OfFile(file) == output["sha1"].get<std::string>());
    }
    keys[entry.path().filename().string()] = json["key"];
  }
  return keys;
}

}  // namespace p2n::testing

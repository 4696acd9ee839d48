#include "pipeline/subprocess.h"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <fstream>
#include <thread>

#include "base/errors.h"
#include "base/format.h"
#include "pipeline/cancel.h"

extern char** environ;

namespace p2n {
namespace {

constexpr auto kPollInterval = std::chrono::milliseconds(20);
constexpr auto kTerminateGrace = std::chrono::seconds(3);

// Stops the child's process group: SIGTERM, then SIGKILL after a grace period. Reaps the child.
void StopChild(pid_t pid) {
  ::kill(-pid, SIGTERM);
  const auto deadline = std::chrono::steady_clock::now() + kTerminateGrace;
  int status = 0;
  while (std::chrono::steady_clock::now() < deadline) {
    if (::waitpid(pid, &status, WNOHANG) == pid) return;
    std::this_thread::sleep_for(kPollInterval);
  }
  ::kill(-pid, SIGKILL);
  ::waitpid(pid, &status, 0);
}

}  // namespace

std::string QuoteCommand(const std::vector<std::string>& argv) {
  std::string line;
  for (const std::string& arg : argv) {
    if (!line.empty()) line += ' ';
    const bool plain = !arg.empty() && arg.find_first_not_of(
                                           "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                           "0123456789-_./=:,+@%") == std::string::npos;
    if (plain) {
      line += arg;
      continue;
    }
    line += '\'';
    for (char c : arg) line += c == '\'' ? std::string("'\\''") : std::string(1, c);
    line += '\'';
  }
  return line;
}

namespace {

SubprocessResult Run(const std::vector<std::string>& argv, const std::filesystem::path& log_file,
                     const std::string& step, bool cancellable) {
  P2N_CHECK(!argv.empty(), "empty command");
  const std::string command = QuoteCommand(argv);
  {
    std::error_code error;
    std::filesystem::create_directories(log_file.parent_path(), error);
    std::ofstream log(log_file, std::ios::app);
    if (!log) throw UserError(format("cannot write the log file '{}'", log_file.string()));
    log << "$ " << command << '\n';
  }

  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log_file.c_str(), O_WRONLY | O_APPEND | O_CREAT, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  posix_spawnattr_setpgroup(&attributes, 0);  // own group: we stop it, the terminal's Ctrl-C does not
  sigset_t default_signals;
  sigemptyset(&default_signals);
  sigaddset(&default_signals, SIGINT);
  sigaddset(&default_signals, SIGTERM);
  posix_spawnattr_setsigdefault(&attributes, &default_signals);
  posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETPGROUP | POSIX_SPAWN_SETSIGDEF);

  std::vector<char*> args;
  for (const std::string& arg : argv) args.push_back(const_cast<char*>(arg.c_str()));
  args.push_back(nullptr);

  const auto start = std::chrono::steady_clock::now();
  pid_t pid = 0;
  const int spawn_error = posix_spawnp(&pid, args[0], &actions, &attributes, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attributes);
  if (spawn_error != 0) {
    throw ExternalToolError(format("{}: cannot start '{}': {} (is it installed and on PATH?); command: {}", step,
                                   argv[0], std::strerror(spawn_error), command));
  }

  int status = 0;
  while (true) {
    const pid_t waited = ::waitpid(pid, &status, WNOHANG);
    if (waited == pid) break;
    if (waited < 0 && errno != EINTR) {
      throw ExternalToolError(format("{}: lost track of the child process: {}", step, std::strerror(errno)));
    }
    if (cancellable && CancelRequested()) {
      StopChild(pid);
      throw Cancelled(format("interrupted during {}", step));
    }
    std::this_thread::sleep_for(kPollInterval);
  }
  SubprocessResult result;
  result.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (WIFSIGNALED(status)) {
    result.signal = WTERMSIG(status);
  } else {
    result.exit_code = WEXITSTATUS(status);
  }
  return result;
}

}  // namespace

SubprocessResult RunSubprocess(const std::vector<std::string>& argv, const std::filesystem::path& log_file,
                               const std::string& step) {
  ThrowIfCancelled();
  return Run(argv, log_file, step, /*cancellable=*/true);
}

SubprocessResult RunCleanupSubprocess(const std::vector<std::string>& argv, const std::filesystem::path& log_file,
                                      const std::string& step) {
  return Run(argv, log_file, step, /*cancellable=*/false);
}

SubprocessResult CheckSubprocess(const std::vector<std::string>& argv, const std::filesystem::path& log_file,
                                 const std::string& step) {
  const SubprocessResult result = RunSubprocess(argv, log_file, step);
  if (result.signal != 0) {
    throw ExternalToolError(format("{} was killed by signal {} ({}); command: {}; log: {}", step, result.signal,
                                   strsignal(result.signal), QuoteCommand(argv), log_file.string()));
  }
  if (result.exit_code != 0) {
    throw ExternalToolError(format("{} failed with exit code {}; command: {}; log: {}", step, result.exit_code,
                                   QuoteCommand(argv), log_file.string()));
  }
  return result;
}

}  // namespace p2n

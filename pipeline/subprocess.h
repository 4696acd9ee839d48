#pragma once
// The one way photo2nerf runs external programs: an argument vector (never a shell string), the child's
// stdout and stderr appended to a per-step log file, stdin from /dev/null, its own process group, and
// cancellation (SIGTERM, then SIGKILL) when the user interrupts.

#include <filesystem>
#include <string>
#include <vector>

namespace p2n {

struct SubprocessResult {
  int exit_code = 0;  // valid when signal == 0
  int signal = 0;     // the signal that ended the child, or 0
  double wall_seconds = 0;
};

// Runs `argv` (argv[0] is looked up on PATH when it has no slash) and waits for it. `step` names the work for
// messages ("feature extraction"). Throws ExternalToolError naming the step, the command and the log when
// the program cannot be started; Cancelled (after stopping the child) when cancellation is requested.
// A non-zero exit is returned, not thrown: use CheckSubprocess for that.
SubprocessResult RunSubprocess(const std::vector<std::string>& argv, const std::filesystem::path& log_file,
                               const std::string& step);

// RunSubprocess, also after cancellation was requested, and never cancelled: for the cleanup that cancellation
// itself needs (scancel of a job the interrupted run submitted).
SubprocessResult RunCleanupSubprocess(const std::vector<std::string>& argv, const std::filesystem::path& log_file,
                                      const std::string& step);

// RunSubprocess, throwing ExternalToolError when the program exits non-zero or is killed.
SubprocessResult CheckSubprocess(const std::vector<std::string>& argv, const std::filesystem::path& log_file,
                                 const std::string& step);

// The command as a shell-quoted line, for messages and logs.
std::string QuoteCommand(const std::vector<std::string>& argv);

}  // namespace p2n

#pragma once
// The two error channels of docs/design.md §5, plus the external-tool and cancellation cases.
// Library code throws these; only cli/main.cc turns them into exit codes.

#include <filesystem>
#include <stdexcept>
#include <string>

namespace p2n {

// The user can fix it: a missing folder, a bad option, a malformed file. The message names the file, the
// field or the image and says what to do.
class UserError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// An external program (COLMAP, ...) could not be started, failed or was killed. The message names the step,
// the command and its log file.
class ExternalToolError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A broken invariant inside photo2nerf: a bug. The message carries file:line.
class InternalError : public std::logic_error {
 public:
  using std::logic_error::logic_error;
};

// The run was interrupted (SIGINT/SIGTERM) and stopped cleanly.
class Cancelled : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Exit codes of the photo2nerf program.
inline constexpr int kExitOk = 0;
inline constexpr int kExitUserError = 1;
inline constexpr int kExitToolFailed = 2;
inline constexpr int kExitInternalError = 3;
inline constexpr int kExitInterrupted = 130;

[[noreturn]] void ThrowInternalError(const char* file, int line, const std::string& message);

// A UserError for a file we read: "'FILE': FIELD PROBLEM", where the problem says what is wrong (and what to do).
[[noreturn]] void ThrowBadField(const std::filesystem::path& file, const std::string& field,
                                const std::string& problem);

}  // namespace p2n

// Checks an internal invariant; throws p2n::InternalError with file:line when it does not hold.
#define P2N_CHECK(condition, message)                                                                           \
  do {                                                                                                          \
    if (!(condition)) {                                                                                         \
      ::p2n::ThrowInternalError(__FILE__, __LINE__, std::string("check failed: " #condition ": ") + (message)); \
    }                                                                                                           \
  } while (false)

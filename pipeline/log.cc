#include "pipeline/log.h"

#include <chrono>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <mutex>

#include "base/errors.h"
#include "base/format.h"
#include "pipeline/progress.h"

namespace p2n {
namespace {

struct LogState {
  std::mutex mutex;
  LogLevel console_level = LogLevel::kInfo;
  std::ofstream file;
};

LogState& State() {
  static LogState state;
  return state;
}

const char* LevelTag(LogLevel level) {
  switch (level) {
    case LogLevel::kDebug:
      return "debug";
    case LogLevel::kInfo:
      return "info";
    case LogLevel::kWarning:
      return "warning";
    case LogLevel::kError:
      return "error";
  }
  return "?";
}

}  // namespace

std::string UtcTimestamp() {
  const auto now = std::chrono::system_clock::now();
  const std::time_t seconds = std::chrono::system_clock::to_time_t(now);
  std::tm utc{};
  gmtime_r(&seconds, &utc);
  char text[32];
  std::strftime(text, sizeof(text), "%Y-%m-%dT%H:%M:%SZ", &utc);
  return text;
}

void SetLogLevel(LogLevel level) {
  std::lock_guard lock(State().mutex);
  State().console_level = level;
}

void SetLogFile(const std::filesystem::path& path) {
  LogState& state = State();
  std::lock_guard lock(state.mutex);
  if (state.file.is_open()) state.file.close();
  if (path.empty()) return;
  std::error_code error;
  std::filesystem::create_directories(path.parent_path(), error);
  state.file.open(path, std::ios::app);
  if (!state.file) throw UserError(format("cannot write the log file '{}'", path.string()));
}

void Log(LogLevel level, std::string_view message) {
  LogState& state = State();
  std::lock_guard lock(state.mutex);
  if (level >= state.console_level) {
    ClearProgressLine();
    if (level == LogLevel::kInfo) {
      std::fprintf(stderr, "%.*s\n", static_cast<int>(message.size()), message.data());
    } else {
      std::fprintf(stderr, "%s: %.*s\n", LevelTag(level), static_cast<int>(message.size()), message.data());
    }
  }
  if (state.file.is_open() && (level >= LogLevel::kInfo || level >= state.console_level)) {
    state.file << UtcTimestamp() << ' ' << LevelTag(level) << ' ' << message << '\n';
    state.file.flush();
  }
}

}  // namespace p2n

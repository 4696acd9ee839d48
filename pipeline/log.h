#pragma once
// Logging to the console (stderr) and, once a workspace is open, to its log file. Thread-safe.

#include <filesystem>
#include <string>
#include <string_view>

#include "base/enum_names.h"

namespace p2n {

enum class LogLevel { kDebug = 0, kInfo = 1, kWarning = 2, kError = 3 };
template <>
struct EnumNames<LogLevel> {
  static constexpr std::pair<LogLevel, const char*> kValues[] = {{LogLevel::kDebug, "debug"},
                                                                 {LogLevel::kInfo, "info"},
                                                                 {LogLevel::kWarning, "warning"},
                                                                 {LogLevel::kError, "error"}};
};

// Console threshold; the log file always receives kInfo and above (kDebug too when the console does).
void SetLogLevel(LogLevel level);
// Appends every later message to `path` (created with its folder); an empty path closes the file.
void SetLogFile(const std::filesystem::path& path);

void Log(LogLevel level, std::string_view message);
// The current time, UTC, as 2026-11-22T05:00:00Z.
std::string UtcTimestamp();
inline void LogDebug(std::string_view message) { Log(LogLevel::kDebug, message); }
inline void LogInfo(std::string_view message) { Log(LogLevel::kInfo, message); }
inline void LogWarning(std::string_view message) { Log(LogLevel::kWarning, message); }
inline void LogError(std::string_view message) { Log(LogLevel::kError, message); }

}  // namespace p2n

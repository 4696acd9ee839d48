#pragma once
// Progress of long work: a live bar with rate and ETA on a terminal, plain periodic lines when stderr is a
// file or CI, or nothing. Thread-safe: workers call Add() from any thread.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>
#include <string_view>

#include "base/enum_names.h"

namespace p2n {

enum class ProgressStyle { kAuto, kBar, kPlain, kNone };
template <>
struct EnumNames<ProgressStyle> {
  static constexpr std::pair<ProgressStyle, const char*> kValues[] = {{ProgressStyle::kAuto, "auto"},
                                                                      {ProgressStyle::kBar, "bar"},
                                                                      {ProgressStyle::kPlain, "plain"},
                                                                      {ProgressStyle::kNone, "none"}};
};

void SetProgressStyle(ProgressStyle style);
// Put before every label from now on: the runner's "[4/7] " says where a stage is in the whole run.
void SetProgressPrefix(std::string prefix);
// Erases a live bar so that a log line can be printed; the next update redraws it.
void ClearProgressLine();

class Progress {
 public:
  // `label` says what is going on ("ingest: decoding"); `unit` what is counted ("images").
  Progress(std::string label, int64_t total, std::string unit);
  ~Progress();  // prints the final line
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  void Add(int64_t count = 1);

 private:
  void Print(bool final);

  std::string label_;
  int64_t total_;
  std::string unit_;
  ProgressStyle style_;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_print_;
  std::atomic<int64_t> done_{0};
  std::mutex print_mutex_;
};

}  // namespace p2n

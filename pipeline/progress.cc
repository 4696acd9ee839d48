#include "pipeline/progress.h"

#include <unistd.h>

#include <cstdio>

#include "base/errors.h"
#include "base/format.h"

namespace p2n {
namespace {

std::atomic<ProgressStyle> g_style{ProgressStyle::kAuto};
std::atomic<bool> g_bar_visible{false};

constexpr std::chrono::milliseconds kBarInterval(100);
constexpr std::chrono::milliseconds kPlainInterval(10000);

ProgressStyle Resolve(ProgressStyle style) {
  if (style != ProgressStyle::kAuto) return style;
  return isatty(STDERR_FILENO) && getenv("CI") == nullptr ? ProgressStyle::kBar : ProgressStyle::kPlain;
}

std::string Duration(double seconds) {
  if (seconds < 60) return format("{:.0f}s", seconds);
  if (seconds < 3600) return format("{}m{:02d}s", static_cast<int>(seconds) / 60, static_cast<int>(seconds) % 60);
  return format("{}h{:02d}m", static_cast<int>(seconds) / 3600, static_cast<int>(seconds) / 60 % 60);
}

}  // namespace

void SetProgressStyle(ProgressStyle style) { g_style = style; }

namespace {
std::mutex g_prefix_mutex;
std::string g_prefix;
std::string CurrentPrefix() {
  std::lock_guard lock(g_prefix_mutex);
  return g_prefix;
}
}  // namespace

void SetProgressPrefix(std::string prefix) {
  std::lock_guard lock(g_prefix_mutex);
  g_prefix = std::move(prefix);
}

void ClearProgressLine() {
  if (g_bar_visible.exchange(false)) std::fputs("\r\033[2K", stderr);
}

Progress::Progress(std::string label, int64_t total, std::string unit)
    : label_(CurrentPrefix() + label),
      total_(total),
      unit_(std::move(unit)),
      style_(Resolve(g_style)),
      start_(std::chrono::steady_clock::now()),
      last_print_(start_) {}

Progress::~Progress() {
  std::lock_guard lock(print_mutex_);
  Print(/*final=*/true);
}

void Progress::Add(int64_t count) {
  done_ += count;
  if (style_ == ProgressStyle::kNone) return;
  std::unique_lock lock(print_mutex_, std::try_to_lock);
  if (!lock.owns_lock()) return;
  const auto now = std::chrono::steady_clock::now();
  if (now - last_print_ < (style_ == ProgressStyle::kBar ? kBarInterval : kPlainInterval)) return;
  last_print_ = now;
  Print(/*final=*/false);
}

void Progress::Print(bool final) {
  if (style_ == ProgressStyle::kNone) return;
  const int64_t done = done_.load();
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const double rate = elapsed > 0 ? done / elapsed : 0.0;
  std::string counts = total_ > 0 ? format("{}/{} {}", done, total_, unit_) : format("{} {}", done, unit_);
  std::string timing = format("{:.1f} {}/s", rate, unit_);
  if (final) {
    timing += ", " + Duration(elapsed);
  } else if (total_ > 0 && rate > 0) {
    timing += ", ETA " + Duration((total_ - done) / rate);
  }
  if (style_ == ProgressStyle::kBar) {
    constexpr int kWidth = 30;
    const double fraction = total_ > 0 ? std::min(1.0, static_cast<double>(done) / total_) : 0.0;
    const int filled = static_cast<int>(fraction * kWidth);
    const std::string bar = std::string(filled, '#') + std::string(kWidth - filled, '.');
    std::fprintf(stderr, "\r\033[2K%s [%s] %s (%s)%s", label_.c_str(), bar.c_str(), counts.c_str(), timing.c_str(),
                 final ? "\n" : "");
    g_bar_visible = !final;
  } else {
    std::fprintf(stderr, "%s: %s (%s)\n", label_.c_str(), counts.c_str(), timing.c_str());
  }
  std::fflush(stderr);
}

}  // namespace p2n

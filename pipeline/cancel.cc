#include "pipeline/cancel.h"

#include <atomic>
#include <csignal>

#include "base/errors.h"

namespace p2n {
namespace {

// Set by the signal handler and by RequestCancel, read by every worker thread: an atomic (lock-free, so safe in
// a signal handler). A volatile sig_atomic_t was a data race between threads (ThreadSanitizer found it).
std::atomic<bool> g_cancel{false};
static_assert(std::atomic<bool>::is_always_lock_free);

void OnSignal(int signal_number) {
  if (g_cancel && signal_number == SIGINT) {
    std::signal(SIGINT, SIG_DFL);
    std::raise(SIGINT);
  }
  g_cancel = true;
}

}  // namespace

void InstallCancelHandlers() {
  struct sigaction action {};
  action.sa_handler = OnSignal;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

void RequestCancel() { g_cancel = true; }
bool CancelRequested() { return g_cancel; }
void ResetCancel() { g_cancel = false; }

void ThrowIfCancelled() {
  if (g_cancel) throw Cancelled("interrupted");
}

}  // namespace p2n

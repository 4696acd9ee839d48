#include "pipeline/cancel.h"

#include <csignal>

#include "pipeline/errors.h"

namespace p2n {
namespace {

volatile std::sig_atomic_t g_cancel = 0;

void OnSignal(int signal_number) {
  if (g_cancel && signal_number == SIGINT) {
    std::signal(SIGINT, SIG_DFL);
    std::raise(SIGINT);
  }
  g_cancel = 1;
}

}  // namespace

void InstallCancelHandlers() {
  struct sigaction action {};
  action.sa_handler = OnSignal;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

void RequestCancel() { g_cancel = 1; }
bool CancelRequested() { return g_cancel != 0; }
void ResetCancel() { g_cancel = 0; }

void ThrowIfCancelled() {
  if (g_cancel) throw Cancelled("interrupted");
}

}  // namespace p2n

#pragma once
// Cooperative cancellation: SIGINT/SIGTERM set a flag; long loops and subprocess waits check it and throw
// Cancelled, so that the stage is left incomplete and children are stopped.

namespace p2n {

// Installs handlers for SIGINT and SIGTERM that request cancellation (a second SIGINT kills at once).
void InstallCancelHandlers();
void RequestCancel();
bool CancelRequested();
void ResetCancel();  // for tests
// Throws Cancelled when cancellation was requested.
void ThrowIfCancelled();

}  // namespace p2n

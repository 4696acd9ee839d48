#pragma once
// The real photo2nerf program run on the small dataset, for the tests of faults and schedulers: its arguments, a
// run in the background, and what a finished workspace holds.

#include <sys/types.h>

#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace p2n::testing {

// `photo2nerf run` on the small dataset with short stages (about 10 s in all), frequent checkpoints and
// evaluations on few pixels.
std::vector<std::string> RunArgs(const std::filesystem::path& data, const std::filesystem::path& workspace);

// Starts a command with its output in `log`.
pid_t Spawn(const std::vector<std::string>& args, const std::filesystem::path& log);

// The exit code, or 128 + the signal.
int Wait(pid_t pid);

// Every stage folder with a manifest: its key, after checking that every output it lists has the SHA-1 it
// lists (a half-written file would not).
std::map<std::string, std::string> CheckedKeys(const std::filesystem::path& workspace);

}  // namespace p2n::testing

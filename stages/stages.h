#pragma once
// The stages of photo2nerf in order, and every option they and the runner read.

#include <filesystem>
#include <memory>
#include <optional>

#include "pipeline/log.h"
#include "pipeline/options.h"
#include "pipeline/progress.h"
#include "pipeline/runner.h"
#include "pipeline/slurm.h"

namespace p2n {

// Options that change no result: not in any cache key, not remembered in the workspace.
struct RunOptions {
  static constexpr const char* kSection = "run";  // its options are run.NAME

  int threads = 0;                                // Worker threads; 0 uses every core.
  LogLevel log_level = LogLevel::kInfo;           // Console log level.
  ProgressStyle progress = ProgressStyle::kAuto;  // Progress display.
  Scheduler scheduler = Scheduler::kLocal;        // Where stages run: here, or as jobs of a Slurm cluster.

  template <class V>
  void Visit(V& v) {
    v("threads", threads, "worker threads; 0 uses every core", "threads", OptionKind::kRuntime);
    v("log_level", log_level, "console log level", "", OptionKind::kRuntime);
    v("progress", progress, "progress display: a live bar, plain lines (files, CI), or none", "", OptionKind::kRuntime);
    v("scheduler", scheduler, "where the stages run: here, or as Slurm jobs (see slurm.*)", "", OptionKind::kRuntime);
  }
  void Check() const;
};

OptionRegistry AllOptions();
// Checks every section's values (XxxOptions::Check()); UserError naming the first bad option.
void CheckAllOptions(const Config& config);
// The stages for `input`: ingest -> sfm -> poses for a folder of photos; one import stage (named poses) for a
// dataset that already has cameras (see dataset_import.h). No input: the photo stages.
Runner MakeRunner(const std::optional<std::filesystem::path>& input = std::nullopt);

}  // namespace p2n

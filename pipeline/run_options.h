#pragma once
// The options of a run that change no result (threads, logging, progress, the scheduler): in no cache key, not
// remembered by the workspace; the runner's, the command line's and any stage's that sizes its own work by them.

#include "pipeline/log.h"
#include "pipeline/options.h"
#include "pipeline/progress.h"
#include "pipeline/slurm.h"

namespace p2n {

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

}  // namespace p2n

#pragma once
// The scheduler a run uses (run.scheduler) and the options of its Slurm jobs (slurm.*), apart from the executors
// (pipeline/slurm.h) so that what they share (pipeline/slurm_jobs.h) includes them alone.

#include <string>

#include "base/enum_names.h"
#include "pipeline/options.h"

namespace p2n {

enum class Scheduler { kLocal, kSlurm };
template <>
struct EnumNames<Scheduler> {
  static constexpr std::pair<Scheduler, const char*> kValues[] = {{Scheduler::kLocal, "local"},
                                                                  {Scheduler::kSlurm, "slurm"}};
};

struct SlurmOptions {
  static constexpr const char* kSection = "slurm";  // its options are slurm.NAME

  std::string partition;    // The partition (queue) of the jobs; empty: the cluster's default.
  int cpus = 0;             // CPUs a job asks for; 0: a whole node with its memory (--exclusive --mem=0).
  std::string sbatch_args;  // Further sbatch arguments, separated by spaces ("--account=geo --time=2:00:00").
  int retries = 2;          // Resubmissions of a stage's job that ended before finishing.

  template <class V>
  void Visit(V& v) {
    v("partition", partition, "Slurm partition of the jobs; empty: the cluster's default", "", OptionKind::kRuntime);
    v("cpus", cpus, "CPUs a Slurm job asks for; 0: a whole node and its memory", "CPUs", OptionKind::kRuntime);
    v("sbatch_args", sbatch_args, "further sbatch arguments, separated by spaces", "", OptionKind::kRuntime);
    v("retries", retries, "resubmissions of a stage's job that ended before finishing (cancelled, node lost)", "jobs",
      OptionKind::kRuntime);
  }
  void Check() const;
};

}  // namespace p2n

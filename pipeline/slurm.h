#pragma once
// Stages as jobs of a Slurm cluster (`--run.scheduler slurm`, docs/design.md §2). The process that runs the pipeline
// keeps the workspace lock, the cache keys, the manifests and the commit of every stage folder, exactly as a local
// run; only a stage's work (Stage::Run into its staging folder) runs elsewhere: `sbatch` submits
// `photo2nerf stage-job`, which reads the stage, its key and the resolved options from a job file and writes the
// stage's summary when it is done. The workspace, on a file system every node sees, is all they share.
//
//   WS/logs/slurm/<stage folder>/job.json       the stage, its cache key, the options
//   WS/logs/slurm/<stage folder>/job.sh         the batch script (it can be submitted by hand)
//   WS/logs/slurm/<stage folder>/submit-N.log   what sbatch said for attempt N (the job id first)
//   WS/logs/slurm/<stage folder>/attempt-N.log  what the job printed
//   WS/logs/slurm/<stage folder>/exit-N         the job's exit code, written when photo2nerf returns
//   WS/logs/slurm/<stage folder>/summary.json   the stage's summary, written when its work is done
//
// A job that ends without an exit code, or with the code of an interrupted run (scancel, a time limit, a node
// lost), is submitted again: its partial work stays in the stage's resume folder (training resumes from its
// checkpoint). One that fails on its own (bad input, a tool's failure) is not: its error is the stage's. Ctrl-C
// cancels the running job; a job left running by a run that was killed is cancelled by the next run of its stage
// before it submits its own.

#include <filesystem>
#include <string>
#include <vector>

#include "pipeline/slurm_options.h"
#include "pipeline/stage.h"

namespace p2n {

// UserError saying what to install or choose when sbatch is not on PATH.
void RequireSbatch();

// A StageExecutor that runs each stage's work as a Slurm job of `program` (the photo2nerf binary, reachable from
// the nodes) and waits for it.
StageExecutor SlurmExecutor(const SlurmOptions& options, std::filesystem::path program);

// The PartsExecutor of a stage's job (photo2nerf stage-job; job_file: its job file): every part of a kind (WORK) but
// the first as an element of a Slurm job array of `program`, the first here. A part whose element is still pending when
// this job is free is taken back and run here (the cluster may have no room for it beside this job), and so is one
// whose element ended without finishing; one that failed on its own is the stage's error. Beside the job file:
//   WORK.sh, submit-WORK.log      the array's batch script, what sbatch said
//   WORK-P.log, exit-WORK-P       what part P's element printed, its exit code
// A later attempt of the stage's job, or a later run of the stage, cancels an array left running.
PartsExecutor SlurmParts(const SlurmOptions& options, std::filesystem::path program, const Workspace& workspace,
                         std::filesystem::path job_file, std::string stage);

// What a stage job is given: the stage, the cache key of the result it makes, the resolved options.
struct StageJob {
  std::string stage;
  std::string key;
  nlohmann::json config;               // Config::ToJson()
  std::filesystem::path summary_path;  // where the stage's summary goes when its work is done
};
// Reads a job file; UserError naming the file and the field.
StageJob ReadStageJob(const std::filesystem::path& path);

}  // namespace p2n

#pragma once
// The subcommands of photo2nerf: each is `int RunX(argc, argv)` with argv[0] the subcommand's name. They throw
// the typed errors of base/errors.h; main() maps them to exit codes.

namespace p2n {

int RunRun(int argc, char** argv);
int RunStage(int argc, char** argv);  // argv[0] names the stage: `photo2nerf ingest -w WS`
int RunStatus(int argc, char** argv);
int RunClean(int argc, char** argv);
int RunOptionsReference(int argc, char** argv);  // the options reference, docs/options.md
int RunFitImage(int argc, char** argv);
int RunStageJob(int argc, char** argv);  // a stage's work as a scheduler's job (pipeline/slurm.h)

}  // namespace p2n

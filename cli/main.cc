// photo2nerf: a dispatch table of subcommands; the only place where errors become exit codes.

#include <csignal>
#include <cstring>
#include <exception>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "base/errors.h"
#include "cli/commands.h"
#include "nerf/heap.h"
#include "photo2nerf/version.h"
#include "pipeline/cancel.h"
#include "pipeline/log.h"
#include "pipeline/options.h"
#include "stages/stages.h"

namespace {

struct Command {
  std::string name;
  int (*run)(int argc, char** argv);
  std::string summary;
};

std::vector<Command> Commands() {
  std::vector<Command> commands = {
      {"run", p2n::RunRun, "run every stage that is not fresh: photo2nerf run PHOTOS -w WORKSPACE"},
      {"status", p2n::RunStatus, "say which stages are fresh, and why the others are not"},
      {"clean", p2n::RunClean, "remove stage results from a workspace"},
      {"options", p2n::RunOptionsReference, "print every option with its default and meaning (docs/options.md)"},
      {"fit-image", p2n::RunFitImage,
       "fit a neural field to one image (the 2D warm-up): photo2nerf fit-image IMG -o DIR"},
      {"stage-job", p2n::RunStageJob, "one stage's work as a Slurm job (run --run.scheduler slurm submits it)"},
  };
  const p2n::Runner runner = p2n::MakeRunner();
  for (const auto& stage : runner.stages()) {
    commands.push_back({stage->name(), p2n::RunStage, "run the " + stage->name() + " stage alone"});
  }
  return commands;
}

void PrintUsage(const std::vector<Command>& commands) {
  std::cout << "photo2nerf " << p2n::kVersion << ": photos in, cameras, a radiance field and a report out.\n\n"
            << "Usage: photo2nerf COMMAND [ARGS...]   (photo2nerf COMMAND --help for its options)\n\nCommands:\n";
  for (const Command& command : commands) std::printf("  %-8s %s\n", command.name.c_str(), command.summary.c_str());
}

}  // namespace

int main(int argc, char** argv) {
  p2n::KeepFreedBlocksInHeap();
  const std::vector<Command> commands = Commands();
  if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h") || !std::strcmp(argv[1], "help")) {
    PrintUsage(commands);
    return argc < 2 ? p2n::kExitUserError : p2n::kExitOk;
  }
  if (!std::strcmp(argv[1], "--version")) {
    std::cout << "photo2nerf " << p2n::kVersion << "\n";
    return p2n::kExitOk;
  }
  const Command* command = nullptr;
  for (const Command& candidate : commands) {
    if (candidate.name == argv[1]) command = &candidate;
  }
  if (command == nullptr) {
    std::string names;
    for (const Command& candidate : commands) names += (names.empty() ? "" : ", ") + candidate.name;
    std::cerr << "error: unknown command '" << argv[1] << "'; the commands are: " << names << " (photo2nerf --help)\n";
    return p2n::kExitUserError;
  }
  p2n::InstallCancelHandlers();
  // Past a file-size limit (ulimit -f), a write fails with EFBIG, which names the file, instead of the
  // signal killing the process without a word.
  std::signal(SIGXFSZ, SIG_IGN);
  try {
    return command->run(argc - 1, argv + 1);
  } catch (const p2n::UserError& e) {
    p2n::LogError(e.what());
    return p2n::kExitUserError;
  } catch (const p2n::ExternalToolError& e) {
    p2n::LogError(e.what());
    return p2n::kExitToolFailed;
  } catch (const std::filesystem::filesystem_error& e) {
    // Permissions, a full disk, a folder removed under us: the user's environment, not a bug.
    p2n::LogError(std::string("file system: ") + e.what() + "; check the path, its permissions and free space");
    return p2n::kExitUserError;
  } catch (const p2n::Cancelled& e) {
    p2n::LogError(std::string(e.what()) + "; the interrupted stage will be redone on the next run");
    return p2n::kExitInterrupted;
  } catch (const std::exception& e) {
    p2n::LogError(std::string("internal error (a bug in photo2nerf; please report it): ") + e.what());
    return p2n::kExitInternalError;
  }
}

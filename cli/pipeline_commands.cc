// run, the per-stage commands, status and clean.

#include <tbb/global_control.h>

#include <array>
#include <filesystem>
#include <iostream>

#include "base/errors.h"
#include "base/file_util.h"
#include "base/format.h"
#include "base/video_io.h"
#include "cli/cli_options.h"
#include "cli/commands.h"
#include "formats/dataset_import.h"
#include "pipeline/log.h"
#include "pipeline/options_reference.h"
#include "pipeline/runner.h"
#include "stages/stage_reports.h"
#include "stages/stage_results.h"
#include "stages/stages.h"

namespace p2n {
namespace fs = std::filesystem;
namespace {

constexpr size_t kMaxReasonsShown = 5;

std::string CommandLine(int argc, char** argv) {
  std::string line = "photo2nerf";
  for (int i = 0; i < argc; ++i) line += std::string(" ") + argv[i];
  return line;
}

// What ran and how long each stage took, then where the results are and how good they are.
void PrintRunSummary(const OptionRegistry& registry, const Workspace& workspace, const std::vector<StageRun>& runs) {
  size_t ran = 0;
  double seconds = 0;
  for (const StageRun& run : runs) {
    ran += run.ran;
    seconds += run.wall_seconds;
  }
  LogInfo(format("{} of {} stages ran ({:.1f} s), {} fresh; workspace {}", ran, runs.size(), seconds, runs.size() - ran,
                 workspace.root().string()));
  for (const StageRun& run : runs) {
    LogInfo(format("  {:<8} {}", run.stage, run.ran ? format("ran in {:.1f} s", run.wall_seconds) : "fresh"));
  }
  const std::string remembered = RememberedOptionsText(registry, workspace);
  if (!remembered.empty()) LogInfo(format("  options the workspace remembers: {}", remembered));
  const fs::path eval = InWorkspace<RenderResult>(workspace).eval();
  if (fs::exists(eval)) {
    const EvalReport report = EvalReport::Read(eval);
    if (report.psnr && report.ssim) {
      LogInfo(format("  held-out: PSNR {:.2f} dB, SSIM {:.3f} over {} views", *report.psnr, *report.ssim,
                     report.views.size()));
    }
  }
  const std::array<std::pair<const char*, fs::path>, 6> results = {
      {{"report", InWorkspace<ReportResult>(workspace).page()},
       {"video", InWorkspace<RenderResult>(workspace).video()},
       {"splats", InWorkspace<SplatResult>(workspace).splats()},
       {"mesh", InWorkspace<ExportResult>(workspace).mesh()},
       {"point cloud", InWorkspace<ExportResult>(workspace).points()},
       {"model", InWorkspace<TrainResult>(workspace).model()}}};
  for (const auto& [what, path] : results) {
    if (fs::exists(path)) LogInfo(format("  {:<12} {}", what, path.string()));
  }
}

// Shared by `run` and the stage commands: `stage` is empty for `run`.
int RunPipeline(int argc, char** argv, const std::string& stage) {
  const OptionRegistry registry = AllOptions();
  const bool is_run = stage.empty();
  CLI::App app(is_run ? "Run every stage that is not fresh, from photos (or a dataset with cameras) to results."
                      : format("Run the {} stage (its upstream stages must be fresh).", stage),
               std::string("photo2nerf ") + argv[0]);
  CommonFlags flags;
  std::string photos;
  RunRequest request;
  bool force = false;
  if (is_run || stage == IngestResult::kId.name) {
    app.add_option("photos", photos,
                   "folder of photos (and videos), a video, or a dataset with cameras (transforms.json, Blender, LLFF, "
                   "COLMAP project, "
                   ".npz); remembered by the workspace");
  }
  if (is_run) {
    app.add_option("--from", request.from, "start at this stage; the stages before it must be fresh");
    app.add_option("--until", request.until, "stop after this stage");
    app.add_option("--force", request.force, "rerun this stage and everything after it, even if fresh");
  } else {
    app.add_flag("--force", force, "rerun the stage even if it is fresh");
  }
  AddCommonFlags(app, registry, &flags);
  if (auto code = Parse(app, registry, argc, argv)) return *code;
  if (!is_run) {
    request.from = request.until = stage;
    if (force) request.force.push_back(stage);
  }
  if (!photos.empty() && !fs::exists(photos)) throw UserError(format("photo folder '{}' does not exist", photos));
  if (!photos.empty() && !fs::is_directory(photos) && !DetectDataset(photos) && !IsVideoFile(photos)) {
    throw UserError(format("'{}' is a file, not a folder or a video; give the folder that holds your photos", photos));
  }
  if (!photos.empty()) {
    // Unknown stage names fail before anything is written.
    const Runner runner = MakeRunner(fs::path(photos));
    for (const auto& name : {request.from, request.until}) {
      if (name) runner.Get(*name);
    }
    for (const std::string& name : request.force) runner.Get(name);
  }

  Workspace workspace = Workspace::Open(flags.workspace, /*create=*/!photos.empty());
  WorkspaceLock lock(workspace, CommandLine(argc, argv));
  if (!photos.empty()) {
    if (fs::equivalent(photos, workspace.root())) {
      throw UserError("the workspace must not be the photo folder itself; choose another folder with -w");
    }
    workspace.SetInput(photos);
  }
  const Runner stages = MakeRunner(workspace.input());
  const Config config = ResolveConfig(registry, workspace, flags, /*remember=*/true);
  const auto thread_limit = ApplyRunOptions(config, workspace.LogDir() / "photo2nerf.log");
  LogInfo(format("{} (workspace {})", CommandLine(argc, argv), workspace.root().string()));
  if (ReadOptions<RunOptions>(config).scheduler == Scheduler::kSlurm) {
    RequireSbatch();
    request.executor = SlurmExecutor(ReadOptions<SlurmOptions>(config), fs::read_symlink("/proc/self/exe"));
  }

  const std::vector<StageRun> runs = stages.Run(workspace, config, request);
  PrintRunSummary(registry, workspace, runs);
  return kExitOk;
}

}  // namespace

int RunRun(int argc, char** argv) { return RunPipeline(argc, argv, ""); }

int RunStage(int argc, char** argv) { return RunPipeline(argc, argv, argv[0]); }

int RunStatus(int argc, char** argv) {
  const OptionRegistry registry = AllOptions();
  CLI::App app("Say for each stage whether it is fresh, missing, incomplete or stale, and why.", "photo2nerf status");
  CommonFlags flags;
  AddCommonFlags(app, registry, &flags);
  if (auto code = Parse(app, registry, argc, argv)) return *code;
  const Workspace workspace = Workspace::Open(flags.workspace, /*create=*/false);
  const Config config = ResolveConfig(registry, workspace, flags, /*remember=*/false);

  const Runner runner = MakeRunner(workspace.input());
  std::cout << "workspace " << workspace.root().string() << "\n";
  if (workspace.input()) {
    const std::optional<DatasetKind> kind = DetectDataset(*workspace.input());
    std::cout << (kind ? "dataset   " : "photos    ") << workspace.input()->string() << "\n";
    if (kind)
      std::cout << "          a " << EnumName(*kind) << " dataset with cameras: ingest and sfm are not needed\n";
  }
  const std::string remembered = RememberedOptionsText(registry, workspace);
  std::cout << "options   " << (remembered.empty() ? "the defaults" : remembered)
            << (remembered.empty() ? "\n" : " (remembered from earlier commands; give another value to change one)\n");
  for (const StageStatus& status : runner.Status(workspace, config)) {
    std::string detail;
    if (status.state == StageState::kFresh) {
      detail = format("key {}, {:.2f} s", status.expected_key.substr(0, 12), status.manifest->wall_seconds);
      for (const auto& [name, value] : status.manifest->summary.items()) {
        detail +=
            format(", {} {}", value.is_number_float() ? format("{:.4g}", value.get<double>()) : value.dump(), name);
      }
    }
    std::cout << format("{:<10} {:<11} {}\n", status.stage->name(), StageStateName(status.state), detail);
    for (size_t i = 0; i < status.reasons.size() && i < kMaxReasonsShown; ++i) {
      std::cout << format("{:<22} {}\n", "", status.reasons[i]);
    }
    if (status.reasons.size() > kMaxReasonsShown) {
      std::cout << format("{:<22} ... and {} more\n", "", status.reasons.size() - kMaxReasonsShown);
    }
  }
  return kExitOk;
}

int RunOptionsReference(int argc, char** argv) {
  CLI::App app("Print the reference of every option (docs/options.md) as Markdown.", "photo2nerf options");
  if (auto code = Parse(app, OptionRegistry(), argc, argv)) return *code;
  std::cout << OptionsReference(AllOptions());
  return kExitOk;
}

int RunClean(int argc, char** argv) {
  CLI::App app("Remove stage results from a workspace (all stages unless --stage is given).", "photo2nerf clean");
  std::string workspace_path;
  std::vector<std::string> stages;
  app.add_option("-w,--workspace", workspace_path, "workspace folder")->required();
  app.add_option("--stage", stages, "a stage whose results to remove (repeatable)");
  if (auto code = Parse(app, OptionRegistry(), argc, argv)) return *code;
  const Workspace workspace = Workspace::Open(workspace_path, /*create=*/false);
  WorkspaceLock lock(workspace, CommandLine(argc, argv));
  const Runner runner = MakeRunner(workspace.input());
  if (stages.empty()) {
    for (const auto& stage : runner.stages()) stages.push_back(stage->name());
  }
  for (const std::string& name : stages) runner.Get(name);
  for (const std::string& name : stages) {
    runner.Clean(workspace, name);
    LogInfo(format("{}: removed", name));
  }
  return kExitOk;
}

}  // namespace p2n

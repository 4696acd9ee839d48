#include "pipeline/runner.h"

#include <chrono>

#include "base/errors.h"
#include "base/file_util.h"
#include "base/format.h"
#include "photo2nerf/version.h"
#include "pipeline/cancel.h"
#include "pipeline/log.h"
#include "pipeline/progress.h"

namespace p2n {
namespace fs = std::filesystem;
namespace {

void RemoveAll(const fs::path& path) {
  std::error_code error;
  fs::remove_all(path, error);
  if (error) throw UserError(format("cannot remove '{}': {}", path.string(), error.message()));
}

// Progress labels carry the stage's position in the run while it runs.
struct ProgressPrefixScope {
  explicit ProgressPrefixScope(const std::string& prefix) { SetProgressPrefix(prefix); }
  ~ProgressPrefixScope() { SetProgressPrefix(""); }
};

// Why `status`'s complete result no longer follows from its upstream stages' results: those remade since with
// other content (a stage rerun alone keeps its key). `statuses` holds at least the stages before it.
std::vector<std::string> RemadeUpstream(const StageStatus& status, const std::vector<StageStatus>& statuses) {
  std::vector<std::string> reasons;
  for (const auto& [up, digest] : status.manifest->upstream_results) {
    for (const StageStatus& other : statuses) {
      if (other.stage->name() == up && other.manifest && OutputsDigest(other.manifest->outputs) != digest)
        reasons.push_back(format("upstream {} was rerun since and made another result", up));
    }
  }
  return reasons;
}

}  // namespace

const char* StageStateName(StageState state) {
  switch (state) {
    case StageState::kFresh:
      return "fresh";
    case StageState::kMissing:
      return "missing";
    case StageState::kIncomplete:
      return "incomplete";
    case StageState::kStale:
      return "stale";
    case StageState::kBlocked:
      return "blocked";
  }
  return "?";
}

Runner::Runner(std::vector<std::unique_ptr<Stage>> stages) : stages_(std::move(stages)) {
  for (size_t i = 0; i < stages_.size(); ++i) {
    for (size_t j = 0; j < i; ++j) {
      P2N_CHECK(stages_[j]->name() != stages_[i]->name(), "two stages named " + stages_[i]->name());
      P2N_CHECK(stages_[j]->folder() != stages_[i]->folder(), "two stages in folder " + stages_[i]->folder());
    }
    for (const std::string& up : stages_[i]->upstream()) {
      bool earlier = false;
      for (size_t j = 0; j < i; ++j) earlier |= stages_[j]->name() == up;
      P2N_CHECK(earlier, "stage " + stages_[i]->name() + " needs " + up + ", which does not come before it");
    }
  }
}

size_t Runner::IndexOf(std::string_view name) const {
  for (size_t i = 0; i < stages_.size(); ++i) {
    if (stages_[i]->name() == name) return i;
  }
  std::string names;
  for (const auto& stage : stages_) names += (names.empty() ? "" : ", ") + stage->name();
  throw UserError(format("unknown stage '{}'; the stages are: {}", name, names));
}

const Stage& Runner::Get(std::string_view name) const { return *stages_[IndexOf(name)]; }

const Stage* Runner::Find(std::string_view name) const {
  for (const auto& stage : stages_) {
    if (stage->name() == name) return stage.get();
  }
  return nullptr;
}

bool Runner::DependsOn(size_t i, size_t j, const Config& config) const {
  for (const std::string& up : stages_[i]->UpstreamFor(config)) {
    const size_t k = IndexOf(up);
    if (k == j || DependsOn(k, j, config)) return true;
  }
  return false;
}

std::vector<StageStatus> Runner::Status(const Workspace& workspace, const Config& config) const {
  std::vector<StageStatus> statuses;
  for (const auto& stage : stages_) {
    StageStatus status;
    status.stage = stage.get();
    KeyInputs& expected = status.expected;
    expected.stage = stage->name();
    expected.format_version = stage->format_version();
    for (const std::string& section : stage->option_sections()) expected.options.update(config.ResultOptions(section));
    for (const std::string& up : stage->UpstreamFor(config)) {
      const size_t k = IndexOf(up);
      P2N_CHECK(k < statuses.size(), "stage " + stage->name() + " reads " + up + ", which does not come before it");
      expected.upstream_keys[up] = statuses[k].expected_key;
    }
    try {
      expected.inputs = stage->ExternalInputs(workspace, config);
    } catch (const UserError& e) {
      status.state = StageState::kBlocked;
      status.reasons.push_back(e.what());
      statuses.push_back(std::move(status));
      continue;
    }
    status.expected_key = expected.Key();

    const fs::path dir = workspace.StageDir(stage->folder());
    const fs::path manifest_path = dir / kManifestName;
    if (fs::exists(workspace.StagingDir(stage->folder()))) {
      status.state = StageState::kIncomplete;
      status.reasons.push_back(format("a run was interrupted or failed; its partial output is in {}",
                                      workspace.StagingDir(stage->folder()).filename().string()));
    } else if (!fs::exists(dir)) {
      status.state = StageState::kMissing;
    } else if (!fs::exists(manifest_path)) {
      status.state = StageState::kIncomplete;
      status.reasons.push_back("its folder has no manifest");
    } else {
      try {
        status.manifest = Manifest::FromJson(ReadJsonFile(manifest_path), manifest_path.string());
      } catch (const UserError& e) {
        status.state = StageState::kIncomplete;
        status.reasons.push_back(e.what());
        statuses.push_back(std::move(status));
        continue;
      }
      if (status.manifest->key != status.expected_key) {
        status.state = StageState::kStale;
        status.reasons = DescribeChanges(status.manifest->inputs, expected);
        if (status.reasons.empty()) status.reasons.push_back("its cache key changed");
      } else {
        for (const std::string& file : ChangedOutputs(dir, status.manifest->outputs)) {
          status.reasons.push_back(format("output {} is missing or was modified", file));
        }
        if (status.reasons.empty()) status.reasons = RemadeUpstream(status, statuses);
        status.state = status.reasons.empty() ? StageState::kFresh : StageState::kStale;
      }
    }
    statuses.push_back(std::move(status));
  }
  return statuses;
}

std::vector<StageRun> Runner::Run(const Workspace& workspace, const Config& config, const RunRequest& request) const {
  const size_t first = request.from ? IndexOf(*request.from) : 0;
  const size_t last = request.until ? IndexOf(*request.until) : stages_.size() - 1;
  if (first > last) throw UserError(format("--from {} comes after --until {}", *request.from, *request.until));
  std::vector<bool> forced(stages_.size(), false);
  for (const std::string& name : request.force) {
    const size_t f = IndexOf(name);
    for (size_t i = 0; i < stages_.size(); ++i) forced[i] = forced[i] || i == f || DependsOn(i, f, config);
  }

  std::vector<StageStatus> statuses = Status(workspace, config);
  for (size_t j = 0; j < first; ++j) {
    const bool needed = [&] {
      for (size_t i = first; i <= last; ++i) {
        if (DependsOn(i, j, config)) return true;
      }
      return false;
    }();
    if (needed && (statuses[j].state != StageState::kFresh || forced[j])) {
      const std::string why = statuses[j].reasons.empty() ? "" : " (" + statuses[j].reasons.front() + ")";
      throw UserError(format("cannot start at {}: the stage {} it needs is {}{}; run it first, or leave out --from",
                             stages_[first]->name(), stages_[j]->name(),
                             forced[j] ? "forced" : StageStateName(statuses[j].state), why));
    }
  }

  for (size_t i = first; i <= last; ++i) {
    if (statuses[i].state == StageState::kBlocked) throw UserError(statuses[i].reasons.front());
  }
  std::vector<StageRun> runs;
  RunMemo memo;
  for (size_t i = first; i <= last; ++i) {
    ThrowIfCancelled();
    const StageStatus& status = statuses[i];
    const std::string& name = stages_[i]->name();
    if (status.state == StageState::kFresh && !forced[i]) {
      stages_[i]->CheckResult(workspace.StageDir(stages_[i]->folder()), config);
      LogInfo(format("{}: fresh, skipped (key {})", name, status.expected_key.substr(0, 12)));
      runs.push_back({name, false, 0});
      continue;
    }
    const std::string why = forced[i]                ? "forced"
                            : status.reasons.empty() ? StageStateName(status.state)
                                                     : status.reasons.front();
    const std::string position = format("[{}/{}] ", i + 1, stages_.size());
    LogInfo(format("{}{}: running ({})", position, name, why));

    const auto start = std::chrono::steady_clock::now();
    {
      const ProgressPrefixScope prefix(position);
      statuses[i].manifest = RunOne(workspace, config, status, &memo, request.executor);
    }
    statuses[i].state = StageState::kFresh;
    for (size_t j = i + 1; j < stages_.size(); ++j) {  // those that read its old result, if this one differs
      StageStatus& later = statuses[j];
      if (later.state != StageState::kFresh) continue;
      later.reasons = RemadeUpstream(later, statuses);
      if (!later.reasons.empty()) later.state = StageState::kStale;
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    LogInfo(format("{}: done in {:.2f} s", name, seconds));
    runs.push_back({name, true, seconds});
  }
  return runs;
}

StageContext Runner::ContextFor(const Workspace& workspace, const Config& config, const Stage& stage,
                                const std::string& key, RunMemo* memo) const {
  StageContext context{.output_dir = workspace.StagingDir(stage.folder()),
                       .workspace = workspace,
                       .config = config,
                       .upstream_dirs = {},
                       .summary = nlohmann::json::object(),
                       .key = key,
                       .resume_dir = workspace.ResumeDir(stage.folder()),
                       .runner = this,
                       .memo = memo};
  for (const std::string& up : stage.UpstreamFor(config)) {
    context.upstream_dirs[up] = workspace.StageDir(Get(up).folder());
  }
  return context;
}

nlohmann::json Runner::RunWork(const Workspace& workspace, const Config& config, std::string_view name,
                               const std::string& key, const StageWork& work) const {
  const Stage& stage = Get(name);
  StageContext context = ContextFor(workspace, config, stage, key, nullptr);
  if (!fs::is_directory(context.output_dir)) {
    throw UserError(format("stage {} has no staging folder {}: the run that submitted this job is gone; run it again",
                           name, context.output_dir.string()));
  }
  if (work.part) {
    stage.RunPart(context, work.work, *work.part);
  } else {
    context.parts = work.parts;
    stage.Run(context);
  }
  return context.summary;
}

Manifest Runner::RunOne(const Workspace& workspace, const Config& config, const StageStatus& status, RunMemo* memo,
                        const StageExecutor& executor) const {
  const Stage& stage = *status.stage;
  const fs::path staging = workspace.StagingDir(stage.folder());
  const fs::path final_dir = workspace.StageDir(stage.folder());
  const fs::path trash = workspace.TrashDir(stage.folder());
  RemoveAll(staging);
  std::error_code error;
  fs::create_directories(staging, error);
  if (error) throw UserError(format("cannot create '{}': {}", staging.string(), error.message()));

  StageContext context = ContextFor(workspace, config, stage, status.expected_key, memo);
  const auto start = std::chrono::steady_clock::now();
  if (executor) {
    executor(stage, context);
  } else {
    stage.Run(context);
  }
  ThrowIfCancelled();
  WriteJsonAtomic(staging / kConfigName, config.ToJson());

  Manifest manifest;
  manifest.inputs = status.expected;
  manifest.key = status.expected_key;
  manifest.photo2nerf_version = kVersion;
  manifest.summary = context.summary;
  manifest.outputs = ListOutputs(staging);
  for (const auto& [up, dir] : context.upstream_dirs) {
    const fs::path path = dir / kManifestName;
    manifest.upstream_results[up] = OutputsDigest(Manifest::FromJson(ReadJsonFile(path), path.string()).outputs);
  }
  manifest.finished_utc = UtcTimestamp();
  manifest.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  WriteJsonAtomic(staging / kManifestName, manifest.ToJson());
  SyncDirectory(staging);

  // Commit: the old result moves aside, the new one into place; a kill in between leaves no complete-looking
  // folder (the staging folder makes `status` say incomplete).
  RemoveAll(trash);
  if (fs::exists(final_dir)) fs::rename(final_dir, trash);
  fs::rename(staging, final_dir);
  SyncDirectory(workspace.root());
  RemoveAll(trash);
  RemoveAll(context.resume_dir);
  return manifest;
}

void Runner::Clean(const Workspace& workspace, std::string_view name) const {
  const Stage& stage = Get(name);
  RemoveAll(workspace.StagingDir(stage.folder()));
  RemoveAll(workspace.StageDir(stage.folder()));
  RemoveAll(workspace.TrashDir(stage.folder()));
  RemoveAll(workspace.ResumeDir(stage.folder()));
}

}  // namespace p2n

#pragma once
// The stage contract (docs/design.md §2): a stage declares its name, folder, format version, upstream stages (those its
// options make it read), the option sections whose result options change its output, and any inputs from outside
// the workspace. Its cache key is a stable hash of those plus the keys of the upstream stages it reads. Run() writes
// into the staging folder; the pipeline writes the manifest and moves the folder into place.

#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "pipeline/options.h"
#include "pipeline/run_memo.h"
#include "pipeline/workspace.h"

namespace p2n {

class Runner;

// Runs `parts` of a stage's work `work`, which need nothing of one another (Stage::RunPart): `here(part)` runs one in
// this process; a scheduler may run some as jobs of their own instead. Returns once every part has finished. `work`
// names the kind of part (a stage may hand out several, one kind after another): a word, as in file names.
using PartsExecutor =
    std::function<void(const std::string& work, const std::vector<int>& parts, const std::function<void(int)>& here)>;

// What a stage's Run() sees.
// The kind of part of the stages that work by spatial blocks (splat.blocks, train.blocks): block b is part b + 1.
inline constexpr const char* kBlockWork = "block";

struct StageContext {
  std::filesystem::path output_dir;  // the staging folder to write into
  const Workspace& workspace;
  const Config& config;
  std::map<std::string, std::filesystem::path> upstream_dirs;  // upstream name -> its complete result folder
  nlohmann::json summary = nlohmann::json::object();           // short facts kept in the manifest
  std::string key;                                             // the cache key of the result being made
  // Where the stage may keep state across a kill (checkpoints; tag them with `key`); removed on completion.
  std::filesystem::path resume_dir;
  const Runner* runner = nullptr;  // the stage table this stage runs in (for a report of every stage)
  RunMemo* memo = nullptr;         // what earlier stages of this run kept for later ones; null outside a run
  PartsExecutor parts = nullptr;   // runs parts of the work; empty: each here, in turn

  // Whether a scheduler runs the parts (each may be a job of its own, at once with the others).
  bool Scheduled() const { return parts != nullptr; }
  // Runs the parts `list` of `work` by `parts`, or each by `here` in turn when there is no executor.
  void RunParts(const std::string& work, const std::vector<int>& list, const std::function<void(int)>& here) const {
    if (parts) return parts(work, list, here);
    for (const int part : list) here(part);
  }
};

class Stage {
 public:
  virtual ~Stage() = default;

  virtual std::string name() const = 0;
  // The folder inside the workspace ("00_ingest"); defaults to the name.
  virtual std::string folder() const { return name(); }
  // Bump when the stage's output changes for the same inputs; results of another version are stale.
  virtual int format_version() const = 0;
  // The stages whose results it may read, under any options: they come before it in a runner's table.
  virtual std::vector<std::string> upstream() const { return {}; }
  // Those of them it reads under `config`: their keys are part of its key, they must be fresh for it to run, and
  // they are its StageContext::upstream_dirs. All of upstream() unless an option leaves one out.
  virtual std::vector<std::string> UpstreamFor(const Config& config) const {
    (void)config;
    return upstream();
  }
  // Sections whose kResult options are part of the key; defaults to the stage's own name.
  virtual std::vector<std::string> option_sections() const { return {name()}; }
  // Inputs from outside the workspace, as label -> fingerprint ("image 0001.jpg" -> SHA-1,
  // "tool colmap" -> "3.8"). Labels appear in `status` messages ("input image 0001.jpg changed").
  virtual std::map<std::string, std::string> ExternalInputs(const Workspace& workspace, const Config& config) const {
    (void)workspace;
    (void)config;
    return {};
  }
  virtual void Run(StageContext& context) const = 0;
  // Part `part` of Run()'s work `work` in a process of its own (a scheduler's job): what Run() hands to
  // StageContext::RunParts. Only stages that hand out parts have any.
  virtual void RunPart(StageContext& context, const std::string& work, int part) const {
    (void)context;
    throw std::logic_error(name() + " has no parts to run (" + work + " " + std::to_string(part) + ")");
  }
  // Applies the stage's kCheck thresholds to its complete result in `result_dir`; throws UserError saying what
  // fails. Run() applies the same check to what it makes; the runner calls this on a fresh result, whose
  // thresholds may have changed since (they are not in the key).
  virtual void CheckResult(const std::filesystem::path& result_dir, const Config& config) const {
    (void)result_dir;
    (void)config;
  }
};

// Runs a stage's work (Stage::Run into context.output_dir, filling context.summary): in this process when none is
// given, or as a job elsewhere (pipeline/slurm.h).
using StageExecutor = std::function<void(const Stage& stage, StageContext& context)>;

}  // namespace p2n

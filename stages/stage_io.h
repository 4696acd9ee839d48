#pragma once
// Reading and writing a stage's binary results with errors a user can act on: the engine (nerf/) throws
// std::runtime_error naming the file; a stage turns it into a UserError that says what to do.

#include <filesystem>
#include <functional>
#include <optional>

#include <nlohmann/json.hpp>

#include "nerf/nerf_model.h"
#include "pipeline/stage.h"
#include "stages/camera_corrections.h"
#include "stages/stage_reports.h"
#include "stages/stage_results.h"

namespace p2n {

// Runs `write`; a std::runtime_error from it (a full disk, a file-size limit, a read-only folder) becomes a
// UserError that adds what to check. UserErrors pass unchanged.
void WriteOrExplain(const std::function<void()>& write);

// The JSON file `path` (a resume folder's) when it was written for this very result (its "key" is the context's),
// else nothing.
std::optional<nlohmann::json> OfThisRun(const StageContext& context, const std::filesystem::path& path);

// LoadModel, with a damaged or foreign file reported as a UserError that says how to remake it.
NerfModel LoadTrainedModel(const std::filesystem::path& model_bin);

// The train stage's result as the later stages take it, each file read once.
struct TrainedField {
  NerfModel model;
  TrainReport report;
  std::map<std::string, CameraCorrection> corrections;  // by training image name; empty without camera refinement
};
TrainedField ReadTrainedField(const TrainResult& train);

}  // namespace p2n

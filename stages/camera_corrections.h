#pragma once
// train_report.json's "camera_refinement": how far camera refinement (nerf/camera_refinement.h) moved each
// training camera. The train stage writes it; export reads it back to place the refined cameras, and the report
// page shows its summary.

#include <array>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "nerf/camera_refinement.h"

namespace p2n {

using CameraCorrection = std::array<float, kPoseParams>;

// The section for training views `names` and their `corrections` (kPoseParams values a view; empty: refinement
// was off): every view's correction, turn (degrees) and shift (normalised units), with their medians and maxima.
nlohmann::json CameraRefinementJson(const std::vector<std::string>& names, const std::vector<float>& corrections);

// Each training view's correction by image name, from the section `camera_refinement` of the file `train_report`
// (TrainReport::camera_refinement; empty when refinement was off, or null when the file predates it); UserError
// naming the file when the section is malformed.
std::map<std::string, CameraCorrection> CameraCorrections(const nlohmann::json& camera_refinement,
                                                          const std::filesystem::path& train_report);

}  // namespace p2n

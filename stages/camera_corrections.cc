#include "stages/camera_corrections.h"

#include <algorithm>
#include <cmath>

#include "base/errors.h"
#include "base/file_util.h"
#include "base/format.h"
#include "stages/stage_results.h"

namespace p2n {
namespace {

double Median(std::vector<double> values) {
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  return values[values.size() / 2];
}

}  // namespace

nlohmann::json CameraRefinementJson(const std::vector<std::string>& names, const std::vector<float>& corrections) {
  if (corrections.empty() || names.empty()) return {{"enabled", false}};
  nlohmann::json per_view = nlohmann::json::array();
  std::vector<double> degrees, shifts;
  for (size_t v = 0; v < names.size(); ++v) {
    const float* correction = &corrections[v * kPoseParams];
    degrees.push_back(CorrectionDegrees(correction));
    shifts.push_back(CorrectionShift(correction));
    per_view.push_back({{"view", names[v]},
                        {"rotation_degrees", degrees.back()},
                        {"shift", shifts.back()},
                        {"correction", std::vector<float>(correction, correction + kPoseParams)}});
  }
  return {{"enabled", true},
          {"correction_is",
           format("a rotation vector about the camera's centre (radians, world axes), then a shift of the centre; "
                  "normalised units, the frame of {}",
                  WorkspaceRelative<PosesResult>().transforms().string())},
          {"rotation_degrees_median", Median(degrees)},
          {"rotation_degrees_max", *std::max_element(degrees.begin(), degrees.end())},
          {"shift_median", Median(shifts)},
          {"shift_max", *std::max_element(shifts.begin(), shifts.end())},
          {"per_view", per_view}};
}

std::map<std::string, CameraCorrection> CameraCorrections(const nlohmann::json& camera_refinement,
                                                          const std::filesystem::path& train_report) {
  std::map<std::string, CameraCorrection> corrections;
  try {
    if (!camera_refinement.is_object() || !camera_refinement.value("enabled", false)) return corrections;
    for (const nlohmann::json& view : camera_refinement.at("per_view")) {
      const CameraCorrection correction = view.at("correction").get<CameraCorrection>();
      if (!std::all_of(correction.begin(), correction.end(), [](float v) { return std::isfinite(v); })) {
        throw UserError(format("'{}': the camera correction of {} is not finite; rerun the train stage",
                               train_report.string(), view.at("view").dump()));
      }
      corrections[view.at("view").get<std::string>()] = correction;
    }
  } catch (const nlohmann::json::exception& error) {
    throw UserError(format("'{}': camera_refinement is malformed ({}); rerun the train stage", train_report.string(),
                           error.what()));
  }
  return corrections;
}

}  // namespace p2n

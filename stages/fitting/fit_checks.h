#pragma once
// The signs of a failed fit that the train and splat stages look for in their own results, so that a default that
// failed on a scene nobody tuned it for says so (in the log, the stage's report and the report page) instead of
// showing a low PSNR as calmly as a high one. Each warning has a code, the figure that tripped it and what to try.
//   heldout_below_training  the held-out views far below the training photos (wrong cameras, too few photos)
//   heldout_view_low        one held-out view far below the others (outside the cameras' span: extrapolation)
//   background_off          a learnt background far from what the photos show where the rays end on nothing
//   fog                     a bounded scene's occupancy grid mostly occupied, or rays needing many samples
//   splats_below_field      the splats far below the field they were baked from

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "nerf/trainer.h"
#include "stages/stage_reports.h"

namespace p2n {

struct HeldoutViewFit {
  std::string view;
  double psnr = 0;
  bool outside_span = false;  // its camera lies outside the training cameras' span (OutsideSpan)
};

// Each held-out view of `data` with its score (`psnrs`, in their order) and where its camera lies.
std::vector<HeldoutViewFit> HeldoutViewFits(const TrainingData& data, const std::vector<double>& psnrs);

// What the train stage measured of its field.
struct FieldFit {
  std::optional<double> heldout_psnr, training_psnr;
  std::vector<HeldoutViewFit> views;
  bool background_learnt = false;
  std::array<double, 3> background{};
  std::optional<std::array<double, 3>> behind_colour;  // the photos where rays end on nothing (BehindScene)
  bool bounded = false;
  double occupied_fraction = 0, samples_per_ray = 0;
};

std::vector<FitWarning> CheckFieldFit(const FieldFit& fit);
// The splats' held-out views, and their mean beside the field's.
std::vector<FitWarning> CheckSplatFit(const std::vector<HeldoutViewFit>& views, std::optional<double> splats_psnr,
                                      std::optional<double> field_psnr);
// Logs each warning as the stage's ("train: warning heldout_view_low: ...").
void LogFitWarnings(const std::string& stage, const std::vector<FitWarning>& warnings);

}  // namespace p2n

#include "stages/fitting/fit_checks.h"

#include <algorithm>
#include <cmath>

#include "base/format.h"
#include "formats/camera_geometry.h"
#include "pipeline/log.h"
#include "pipeline/options.h"
#include "stages/fitting/splat_options.h"
#include "stages/fitting/train_options.h"
#include "stages/ingest/import_options.h"
#include "stages/stage_results.h"

namespace p2n {
namespace {

// A field that generalises scores its held-out views within a few dB of its training photos; a gap wider than
// this is wrong cameras or too few photos, not a hard scene.
constexpr double kHeldoutGapDb = 5;
// One held-out view this far below the median of the others is a problem of that view (or its camera); views of a
// good fit differ by up to about 7 dB (their content differs), docs/benchmarks.md.
constexpr double kViewGapDb = 8;
// A learnt background further than this (in any channel, colours in [0, 1]) from what the photos show behind the
// scene has run away.
constexpr double kBackgroundDistance = 0.25;
// An object's box is mostly empty, and its rays cross a surface in a few samples; fog fills it.
constexpr double kFogOccupied = 0.25, kFogSamplesPerRay = 40;
// Splats baked from a field score about as well as it, or better.
constexpr double kSplatsBelowFieldDb = 3;

std::string Colour(const std::array<double, 3>& c) { return format("({:.2f}, {:.2f}, {:.2f})", c[0], c[1], c[2]); }

double Median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const size_t n = values.size();
  return n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

// A view far below the median of the other held-out views.
void CheckViews(const std::vector<HeldoutViewFit>& views, const char* source, std::vector<FitWarning>* warnings) {
  if (views.size() < 2) return;
  for (size_t v = 0; v < views.size(); ++v) {
    std::vector<double> others;
    for (size_t o = 0; o < views.size(); ++o) {
      if (o != v) others.push_back(views[o].psnr);
    }
    const double median = Median(others), gap = median - views[v].psnr;
    if (!(gap > kViewGapDb)) continue;
    const std::string why =
        views[v].outside_span
            ? "its camera lies outside the span of the training cameras, so it measures extrapolation; photos "
              "taken beyond it would cover what it sees"
            : format(
                  "its camera lies among the training cameras: look at the photo (blur, exposure, something that "
                  "moved) and at its camera ({})",
                  WorkspaceRelative<SfmResult>().report().string());
    warnings->push_back({"heldout_view_low", gap,
                         format("held-out view {} scores {:.1f} dB from the {}, {:.1f} dB below the other held-out "
                                "views' median {:.1f}: {}",
                                views[v].view, views[v].psnr, source, gap, median, why)});
  }
}

}  // namespace

std::vector<HeldoutViewFit> HeldoutViewFits(const TrainingData& data, const std::vector<double>& psnrs) {
  std::vector<Eigen::Vector3d> centres;
  for (const TrainView& view : data.train) centres.push_back(view.camera.world_from_cam.topRightCorner<3, 1>());
  std::vector<HeldoutViewFit> views;
  for (size_t v = 0; v < psnrs.size() && v < data.heldout.size(); ++v) {
    const TrainView& view = data.heldout[v];
    views.push_back({view.name, psnrs[v], OutsideSpan(centres, view.camera.world_from_cam.topRightCorner<3, 1>())});
  }
  return views;
}

std::vector<FitWarning> CheckFieldFit(const FieldFit& fit) {
  std::vector<FitWarning> warnings;
  if (fit.heldout_psnr && fit.training_psnr && *fit.training_psnr - *fit.heldout_psnr > kHeldoutGapDb) {
    const double gap = *fit.training_psnr - *fit.heldout_psnr;
    warnings.push_back(
        {"heldout_below_training", gap,
         format("the held-out views score {:.1f} dB, {:.1f} dB below the training photos' {:.1f}: the field fits its "
                "photos but not new views. Check the cameras ({}: reprojection error, photos left out); with few "
                "photos, take more between the held-out ones; for photos that differ in exposure, try --{} on",
                *fit.heldout_psnr, gap, *fit.training_psnr, WorkspaceRelative<SfmResult>().report().string(),
                OptionKey(&TrainOptions::appearance))});
  }
  CheckViews(fit.views, "field", &warnings);
  if (fit.background_learnt && fit.behind_colour) {
    double distance = 0;
    for (int c = 0; c < 3; ++c) distance = std::max(distance, std::abs(fit.background[c] - (*fit.behind_colour)[c]));
    if (distance > kBackgroundDistance) {
      warnings.push_back(
          {"background_off", distance,
           format("the learnt background {} is {:.2f} from what the held-out photos show where the rays end on "
                  "nothing {}: the field may paint the true background as fog in front of the scene. Images "
                  "rendered or composited on a plain colour: import them with it (--{}) or train with --{} fixed",
                  Colour(fit.background), distance, Colour(*fit.behind_colour), OptionKey(&ImportOptions::background),
                  OptionKey(&TrainOptions::background))});
    }
  }
  if (fit.bounded && (fit.occupied_fraction > kFogOccupied || fit.samples_per_ray > kFogSamplesPerRay)) {
    warnings.push_back(
        {"fog", fit.occupied_fraction,
         format("{:.0f}% of the object's box is occupied and a ray takes {:.0f} samples: the field fills the box "
                "with fog. The usual cause is a background that is not the images' (train_report.json: "
                "trainer.background_colour); images composited on a colour should say which (--{})",
                100 * fit.occupied_fraction, fit.samples_per_ray, OptionKey(&ImportOptions::background))});
  }
  return warnings;
}

std::vector<FitWarning> CheckSplatFit(const std::vector<HeldoutViewFit>& views, std::optional<double> splats_psnr,
                                      std::optional<double> field_psnr) {
  std::vector<FitWarning> warnings;
  CheckViews(views, "splats", &warnings);
  if (splats_psnr && field_psnr && *field_psnr - *splats_psnr > kSplatsBelowFieldDb) {
    const double gap = *field_psnr - *splats_psnr;
    warnings.push_back({"splats_below_field", gap,
                        format("the splats score {:.1f} dB held out, {:.1f} dB below the field's {:.1f}, so the "
                               "render stage shows the field (slower); try a longer --{}",
                               *splats_psnr, gap, *field_psnr, OptionKey(&SplatOptions::time_budget))});
  }
  return warnings;
}

void LogFitWarnings(const std::string& stage, const std::vector<FitWarning>& warnings) {
  for (const FitWarning& warning : warnings)
    LogWarning(format("{}: warning {}: {}", stage, warning.code, warning.message));
}

}  // namespace p2n

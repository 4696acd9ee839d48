#pragma once
// The splat stage: the scene as 3D Gaussians (splat/), placed where the field's surfaces are or at the sparse points
// (ResolveSplatInit) and optimised against the training photos for a time budget; held-out PSNR and SSIM against time
// (metrics.csv, psnr.png), and splats.ply in the standard 3D Gaussian Splatting layout, in COLMAP's (or the
// dataset's) frame like the mesh, which splat viewers and tools open unchanged. Interruptible and resumable as
// training is.

#include <filesystem>
#include <string>

#include "formats/output_frame.h"
#include "formats/transforms_json.h"
#include "nerf/nerf_model.h"
#include "pipeline/options.h"
#include "stages/fitting/splat_options.h"
#include "stages/fitting/train_presets.h"
#include "stages/stage_results.h"

namespace p2n {

// A scene is large where a training view sees less than this share of its splats (its mean over the training views,
// MeanViewShare, measured on the splats placed as for a small scene).
inline constexpr double kLargeSceneShare = 0.5;
// The sparse points a capture needs for splat.init auto to start from them: fewer leave too few splats for the
// densifications of a run's first half to grow from.
inline constexpr size_t kMinSparseInitPoints = 1000;
// splat.init resolved: auto is sparse in an unbounded scene (a capture all round, its field's `space`) of at least
// kFewViews `training_views` where `sparse_points` (the poses stage's sparse_points.ply, which a dataset imported
// without points lacks) holds at least kMinSparseInitPoints, else field: there the field's haze placed opaque splats
// that the optimisation kept, where a forward-facing field's placement, or a few photos', scored better than the
// points (docs/benchmarks.md, splats from the sparse points).
SplatInit ResolveSplatInit(SplatInit init, SceneSpace space, size_t training_views,
                           const std::filesystem::path& sparse_points);

// The splats placed from the field (or the sparse points): `max_gaussians` (splat.max_gaussians), times
// kLargeSceneShare / view_share in a large scene (each view then draws about as many as in a small one), and at most
// one per 64 of the `pixels` training pixels.
size_t PlacedSplats(int max_gaussians, double view_share, size_t pixels);

// splat.time_budget, or the training preset's share when it is 0.
double SplatTimeBudget(const SplatOptions& options, PresetName train_preset);
// The steps over which the means' learning rate decays (SplatTrainerOptions::steps) in a run of `budget` seconds (0:
// bounded by steps): 2,000, stretched in proportion by a budget above 320 s (480 s: 3,000), whose many steps would
// otherwise spend their last part at the final rate (docs/benchmarks.md, splats).
int SplatScheduleSteps(double budget);

class SplatStage : public StageOf<SplatResult> {
 public:
  // 2: the SSIM term; 3: placed from at most 2 M pixels (the export's renders); 4: the background learnt (auto);
  // 5: optimised on photos of at most splat.max_image_size (halved); 6: downsized to it with an area filter
  // 7: a background the import knows stays fixed (auto); 8: splats.spz beside splats.ply; 9: and splats.glb;
  // 10: the coarse part's dilation a full-size pixel's; 11: densification under the cap by the largest gradients;
  // 12: the coarse part at most 40 passes; 13: the means' schedule stretched by a budget above 320 s;
  // 14: more splats for a large scene, the trainer's cap in its checkpoints; 15: placed from the sparse points where
  // there are enough (splat.init auto)
  int format_version() const override { return 15; }
  std::vector<std::string> upstream() const override { return {PosesResult::kId.name, TrainResult::kId.name}; }
  void Run(StageContext& context) const override;
  // Block `part` (from 1) of splat.blocks (stages/fitting/splat_optimisation.h).
  void RunPart(StageContext& context, const std::string& work, int part) const override;
};

}  // namespace p2n

#pragma once
// Optimises Gaussians against posed photos (3D Gaussian Splatting's recipe, sized for a CPU): one training view
// per step, rendered whole by the rasterizer, a loss of L1 and SSIM against the photo on the background,
// Adam with a learning rate per parameter (the means' decaying exponentially and scaled by the scene's extent), the
// spherical harmonics' degrees joining one at a time, and densification: Gaussians whose mean the loss pulls hard
// across the screen are cloned when small and split in two when large, transparent ones are pruned. Behind photos
// without alpha the colour behind every splat is learnt with them (SplatScene::learn_background).

#include <array>
#include <cstdint>
#include <random>
#include <vector>

#include "base/binary_io.h"
#include "base/float_image.h"
#include "base/posed_image.h"
#include "nerf/adam.h"
#include "splat/gaussians.h"
#include "splat/rasterizer.h"
#include "splat/ssim_loss.h"

namespace p2n {

struct SplatTrainerOptions {
  static constexpr const char* kName = "splat";  // checks name splat.FIELD
  // The nominal run: the means' learning rate decays over it, and it measures the run's progress (densification's
  // end) unless the trainer's owner does (SplatTrainer::SetProgress).
  int steps = 2000;
  double position_lr = 1.6e-4;  // × the extent, decaying to final_position_lr × the extent at the last step
  double final_position_lr = 1.6e-6;
  double colour_lr = 1e-2;  // the degree-0 coefficients; the higher ones at a twentieth of it
  double opacity_lr = 0.025;
  double scale_lr = 5e-3;
  double rotation_lr = 1e-3;
  // Steps between the joining of each higher SH degree: all three by step 300 (3D Gaussian Splatting's 1,000 of
  // 30,000 steps, scaled towards the few hundred steps a CPU run makes; docs/benchmarks.md, splats).
  int sh_interval = 100;
  int densify_interval = 100;      // steps between densifications
  int densify_from = 100;          // the first densification's step
  double densify_until = 0.5;      // share of the run after which the Gaussians' number stays
  double densify_gradient = 2e-4;  // mean screen-space gradient (normalised device units) that densifies
  double dense_fraction = 0.01;    // of the extent: larger Gaussians split, smaller ones clone
  double prune_opacity = 0.005;
  double ssim_weight = 0.1;          // the loss: (1 - ssim_weight) L1 + ssim_weight (1 - SSIM) (ssim_loss.h)
  size_t max_gaussians = 1'500'000;  // densification's cap: the run's, which a checkpoint keeps (Save, Load)
  uint64_t seed = 0;

  template <class V>
  void Visit(V& v) {
    v("steps", steps);
    v("position_lr", position_lr);
    v("final_position_lr", final_position_lr);
    v("colour_lr", colour_lr);
    v("opacity_lr", opacity_lr);
    v("scale_lr", scale_lr);
    v("rotation_lr", rotation_lr);
    v("sh_interval", sh_interval);
    v("densify_interval", densify_interval);
    v("densify_from", densify_from);
    v("densify_until", densify_until);
    v("densify_gradient", densify_gradient);
    v("dense_fraction", dense_fraction);
    v("prune_opacity", prune_opacity);
    v("ssim_weight", ssim_weight);
    v("max_gaussians", max_gaussians);
    v("seed", seed);
  }
  // std::invalid_argument naming the field and its rule.
  void Check() const;
};

// The scene the Gaussians learn: training views (cameras in the Gaussians' frame), the background behind them,
// the scene's extent (a radius around the cameras, for learning rates and densification) and the near plane.
struct SplatScene {
  const std::vector<TrainView>* views = nullptr;
  std::array<float, 3> background{1, 1, 1};  // the first, when learnt
  double extent = 1;
  double near = 0.01;
  // Learn the colour behind every splat (what lies beyond them: a sky, a far wall) with them; only for photos
  // without alpha, whose pixels do not depend on it.
  bool learn_background = false;
  // Splats drawn with the trained ones and never changed (block training: the other blocks, as they were when the
  // blocks began).
  const Gaussians<float>* context = nullptr;
};

class SplatTrainer {
 public:
  SplatTrainer(Gaussians<float> gaussians, const SplatScene& scene, const SplatTrainerOptions& options);

  // One step on the next training view (each view once per epoch, in a random order); returns its loss.
  double Step();
  // Trains on `views` from the next step on: the same views in the same order at `scale` times the size they are
  // shown at (the coarse first part of an optimisation). The splats' dilation (a pixel's footprint) is scaled with
  // them, a pixel of the shown size's, so that they learn the look they have there: with a pixel of the smaller
  // views', thin splats widened by it would be thinner, and the picture eroded, where it is shown.
  void SetViews(const std::vector<TrainView>* views, double scale);
  // Draws the next views from `views` alone (indices of the training views; those a window over the photos holds,
  // base/photo_window.h), the epoch under way going on with those of its views among them; empty: from all of them.
  void SampleFrom(const std::vector<size_t>& views);
  // The share of the run done (0..1) from the next step on; without it, step / options.steps. A run bounded by
  // time sets it from its clock, so that densification ends halfway through whatever number of steps the time
  // buys, and the Gaussians it adds are optimised before the end.
  void SetProgress(double share) { progress_ = share; }
  int step() const { return step_; }
  const Gaussians<float>& gaussians() const { return gaussians_; }
  // What the trainer draws: its splats, then the scene's context.
  Gaussians<float> Drawn() const;
  // Goes on with the splats flagged in `keep` alone (their optimiser's state with them), drawn with `context` and
  // trained on `views` from the next step on: one block of a run that was optimised whole so far (splat/blocks.h).
  void Restrict(const std::vector<bool>& keep, const Gaussians<float>* context, const std::vector<TrainView>* views);
  const std::array<float, 3>& background() const { return background_; }
  // The SH degree in use at this step.
  int ShDegree() const;

  // Everything a resumed run needs to continue as this one would (the scene excepted; options.max_gaussians
  // included: Load sets it, so that a block's part job densifies to the cap its stage chose).
  void Save(BinaryWriter* writer) const;
  void Load(BinaryReader* reader);

 private:
  std::vector<size_t> DensifyCandidates(size_t room) const;
  double StepShare() const;  // step / options.steps, at most 1
  double Progress() const;
  double PositionLearningRate() const;
  void Densify();
  void StepBackground(const std::vector<float>& d_rgb);
  void RemapAdams(const std::vector<int64_t>& sources);  // as Adam::Remap, every parameter array's
  const TrainView& NextView();

  Gaussians<float> gaussians_;
  SplatScene scene_;
  std::array<float, 3> background_;
  Adam<float> background_adam_;
  SplatTrainerOptions options_;
  static constexpr size_t kShRestArray = 5;  // sh_rest's place in Gaussians::ForEachArray's order
  std::vector<Adam<float>> adams_;           // one per parameter array, in Gaussians::ForEachArray's order
  Gaussians<float> gradients_;
  Gaussians<float> drawn_;  // the splats with the context, when there is one (kept between steps, as gradients_)
  Rasterizer<float> rasterizer_;
  SsimLoss ssim_;
  int step_ = 0;
  double progress_ = -1;   // SetProgress's share; negative: by steps
  double view_scale_ = 1;  // SetViews's scale
  std::mt19937_64 random_;
  std::vector<size_t> order_;   // this epoch's views; the next is order_.back()
  std::vector<size_t> sample_;  // SampleFrom's views; empty: all
  std::vector<float> screen_gradient_sum_;
  std::vector<uint32_t> screen_gradient_count_;
};

// `view` at half its size (odd last rows and columns dropped): each pixel the mean of four, the camera's intrinsics
// halved exactly; without pixels where it has none. For the coarse first part of an optimisation: many more steps for
// the time.
TrainView HalfSizeView(const TrainView& view);
std::vector<TrainView> HalfSizeViews(const std::vector<TrainView>& views);

// The scale that fits the longest side of the largest of `views` to `max_side` (0, or all of them smaller: 1).
double FitScale(const std::vector<TrainView>& views, int max_side);
// `view` at `scale` (FitScale's), its intrinsics scaled per axis (ResizedCamera), its pixels `pixels` (of its own size,
// or none: it has none) downsized with an area filter.
TrainView FittedView(const TrainView& view, double scale, std::vector<uint8_t> pixels);

// The Gaussians' image of `camera` over `background`: an RGB FloatImage.
FloatImage RenderSplats(const Gaussians<float>& gaussians, const PinholeCamera& camera,
                        const std::array<float, 3>& background, double near);

}  // namespace p2n

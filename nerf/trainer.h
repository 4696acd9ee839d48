#pragma once
// Trains a radiance field from posed images (docs/design.md §6): random rays across all training images, marched
// through the occupancy grid (refreshed from the field every few steps) and packed; chunks of rays run in
// parallel, each with its own gradient buffer, reduced in a fixed order (a seed gives the same run); Adam on the
// MLPs and sparse Adam on the hash grid. The number of rays per step adapts so that a step has about
// `batch_samples` samples. A step whose loss or gradient is not finite is reported and skipped.

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "base/camera.h"
#include "base/enum_names.h"
#include "base/float_image.h"
#include "base/posed_image.h"
#include "nerf/adam.h"
#include "nerf/error_map.h"
#include "nerf/nerf_model.h"
#include "nerf/renderer.h"

namespace p2n {

// The photometric loss of a ray: squared error, or Huber's (delta 0.1).
enum class PhotometricLoss { kMse, kHuber };
template <>
struct EnumNames<PhotometricLoss> {
  static constexpr std::pair<PhotometricLoss, const char*> kValues[] = {{PhotometricLoss::kMse, "mse"},
                                                                        {PhotometricLoss::kHuber, "huber"}};
};

struct TrainerOptions {
  static constexpr const char* kName = "trainer";  // checks name trainer.FIELD
  nlohmann::json field;                            // the field's config (MakeField)
  int occupancy_resolution = 128;                  // cells per axis
  int occupancy_interval = 16;                     // steps between occupancy updates
  int occupancy_warmup = 16;                       // steps before the first update (the field knows nothing before)
  double occupancy_decay = 0.95;
  double march_step = 3.4641016 / 256;  // world units: 256 samples across the scene box's diagonal
  double fine_march_step = 0;           // > 0: the spacing from step fine_march_from on
  int fine_march_from = 1000;
  SceneSpace space = SceneSpace::kBounded;  // nerf_model.h; forward: the frame is fitted to the training views
  size_t max_samples_per_ray = 1024;
  int stratified_samples = 0;              // > 0: that many stratified samples per ray, no occupancy grid (vanilla)
  size_t batch_samples = size_t{1} << 16;  // samples per step (the rays per step follow)
  size_t late_batch_samples = 0;           // > 0: samples per step in the run's second half
  int min_batch_rays = 256, max_batch_rays = 16384;
  double learning_rate = 1e-2;
  double final_learning_rate = 1e-3;  // reached at the end (exponential decay)
  PhotometricLoss loss = PhotometricLoss::kMse;
  // Weight of mip-NeRF 360's distortion loss (distortion_loss.h) per ray, in the sampler's metric; 0: off.
  double distortion_weight = 0;
  float min_transmittance = 1e-4f;
  bool random_background = false;  // RGBA images: a random background per ray (learns transparency)
  // Images without alpha: the colour behind the scene is learnt with it (a sky, a wall out of reach), starting
  // from the data's background; refused where a training image has alpha (it was composited on a known colour).
  bool learn_background = false;
  bool appearance = false;      // a colour transform per training image (appearance.h)
  bool refine_cameras = false;  // a pose correction per training image (camera_refinement.h)
  int refine_warmup = 100;      // steps before the corrections learn (a younger field's gradients mislead)
  bool error_sampling = false;  // pixels drawn by the error map (error_map.h), their losses weighted
  // Weight of the depth loss on rays through the training views' depth points (TrainView::depth_points), as
  // depth-supervised NeRF: ((rendered depth - the point's distance) / distance)^2, less for points the structure
  // from motion placed badly; 0: off.
  double depth_weight = 0;
  uint64_t seed = 0;

  // The numbers and switches, named once (base/declared_fields.h).
  template <class V>
  void Visit(V& v) {
    v("occupancy_resolution", occupancy_resolution);
    v("occupancy_interval", occupancy_interval);
    v("occupancy_warmup", occupancy_warmup);
    v("occupancy_decay", occupancy_decay);
    v("march_step", march_step);
    v("fine_march_step", fine_march_step);
    v("fine_march_from", fine_march_from);
    v("max_samples_per_ray", max_samples_per_ray);
    v("stratified_samples", stratified_samples);
    v("batch_samples", batch_samples);
    v("late_batch_samples", late_batch_samples);
    v("min_batch_rays", min_batch_rays);
    v("max_batch_rays", max_batch_rays);
    v("learning_rate", learning_rate);
    v("final_learning_rate", final_learning_rate);
    v("distortion_weight", distortion_weight);
    v("min_transmittance", min_transmittance);
    v("random_background", random_background);
    v("learn_background", learn_background);
    v("appearance", appearance);
    v("refine_cameras", refine_cameras);
    v("refine_warmup", refine_warmup);
    v("error_sampling", error_sampling);
    v("depth_weight", depth_weight);
    v("seed", seed);
  }
  // std::invalid_argument naming the field and its rule (the Trainer checks its options).
  void Check() const;
};

// A batch of world rays with their targets (RGB) and backgrounds.
struct RayBatch {
  std::vector<Ray> rays;
  std::vector<Eigen::Vector2d> near_far;
  Eigen::Matrix3Xf target, background;
  std::vector<int> views;       // each ray's training view, for its appearance (empty: none)
  std::vector<float> weights;   // each ray's loss weight (empty: all 1)
  std::vector<uint32_t> cells;  // each ray's error-map cell (empty: none), where its loss is recorded; kNoCell: none
  // Each ray's depth target: the distance along it and the depth loss's weight (empty: none; weight 0: none).
  std::vector<Eigen::Vector2f> depth;

  static constexpr uint32_t kNoCell = ~uint32_t{0};
};

struct StepResult {
  double loss = 0;        // of the batch: the photometric loss, mean over rays
  double depth_loss = 0;  // the depth loss (weighted), mean over the rays with a depth target
  size_t rays = 0;
  size_t samples = 0;       // marched and evaluated
  size_t samples_used = 0;  // before early termination (the ones with gradients)
  bool skipped = false;     // a non-finite loss or gradient: nothing was updated
  std::string problem;      // why it was skipped
};

// The photos' colour where the rendered rays end on nothing (opacity under a half): what a background must show.
struct BehindScene {
  size_t pixels = 0, evaluated = 0;  // such pixels, of all evaluated
  std::array<double, 3> colour_sum{};

  // Their mean colour; none when fewer than a hundredth of the pixels end on nothing (the background hardly shows).
  std::optional<std::array<double, 3>> MeanColour() const;
};

class Trainer {
 public:
  // `data` must outlive the trainer. Training views without pixels (not in memory, see SampleFrom) are not drawn.
  Trainer(const TrainerOptions& options, const TrainingData& data);

  // Rays are drawn from these training views only (each must have its pixels) until the next call: the ones a
  // window over photos too many for memory holds (base/photo_window.h). The error map's draws outside them are
  // drawn again (their weights then carry a common factor, the resident views' share of the two distributions).
  // The training views with pixels by default.
  void SampleFrom(std::vector<size_t> views);
  const std::vector<size_t>& sampled_views() const { return sampled_; }

  // One step at `progress` in [0, 1] of the run (for the learning-rate schedule).
  StepResult Step(double progress);
  // The step on a given batch (Step() samples one from the training views).
  StepResult StepOnBatch(const RayBatch& batch, double progress);
  RayBatch SampleBatch(int rays);

  // PSNR of each held-out view (its pixels read as it comes where the data holds none: TrainingData::read_heldout),
  // from `pixels_per_view` fixed random pixels of it (0: every pixel), rendered at the scene's default step
  // (DefaultStepScale, as render.step_scale 0 renders; the render stage may be asked for another, so both reports
  // state theirs). `on_rays_done` is called as rays finish (from worker threads; an exception it throws, e.g. on
  // Ctrl-C, stops the evaluation).
  // With `fitted`, also each view's PSNR as NeRF-W scores an image it never trained on: the colour transform
  // that best maps the render of the pixels in its left half onto the photo (least squares) applied to those in
  // its right half, scored there.
  // With `behind`, also what the held-out photos show where the rendered rays end on nothing.
  std::vector<double> HeldoutPsnr(size_t pixels_per_view, RenderStats* stats = nullptr,
                                  const std::function<void(size_t)>& on_rays_done = {},
                                  std::vector<double>* fitted = nullptr, BehindScene* behind = nullptr) const;
  // The same scores of at most `max_views` training views spread over the sampled ones (sampled_views()): how well
  // the field fits its photos, to compare with the held-out views'.
  std::vector<double> TrainingPsnr(size_t pixels_per_view, size_t max_views,
                                   const std::function<void(size_t)>& on_rays_done = {}) const;
  // Each training view's colour transform (kAppearanceParams values a view); empty without options.appearance.
  const std::vector<float>& appearance() const { return appearance_; }
  // Each training view's pose correction (kPoseParams values a view); empty without options.refine_cameras.
  const std::vector<float>& camera_corrections() const { return poses_; }

  const NerfModel& model() const { return model_; }
  NerfModel& model() { return model_; }
  // Puts `model`, trained elsewhere (a field by blocks' composite, nerf/blocked_field.h), in place of this trainer's,
  // for its evaluations and reports; no step may follow (std::logic_error).
  void AdoptModel(NerfModel model);
  int step() const { return step_; }
  int skipped_steps() const { return skipped_; }

  // The whole training state (model, optimiser moments, step, batch size); `Load` refuses a checkpoint of
  // another configuration.
  void SaveCheckpoint(BinaryWriter* writer) const;
  void LoadCheckpoint(BinaryReader* reader);

 private:
  struct Chunk;  // one chunk of a step's rays (trainer.cc)
  // View v of those scored, with its pixels (read into the scratch view given when they are not in memory).
  using ViewAt = std::function<const TrainView&(size_t v, TrainView* scratch)>;
  std::vector<double> ViewPsnrs(size_t count, const ViewAt& view_at, size_t pixels_per_view, RenderStats* stats,
                                const std::function<void(size_t)>& on_rays_done, std::vector<double>* fitted,
                                BehindScene* behind) const;
  void UpdateOccupancy();
  // A training pixel: by the error map, or uniformly over all of them (weight 1).
  ErrorMap::Draw DrawPixel(std::mt19937_64* random) const;
  double LearningRate(double progress) const;
  // The phases of StepOnBatch(): chunk c's rays marched; every sample's hash-grid encoding; a chunk's networks,
  // compositing and gradients; the pose corrections' gradients (after the hash grid's); the optimisers' steps.
  // The depth loss of a ray that renders `depth` against `target` (RayBatch::depth), added to the chunk's; returns
  // dL/d(depth) for a batch of `rays`.
  float DepthLoss(float depth, const Eigen::Vector2f& target, size_t rays, Chunk* chunk) const;
  void MarchChunk(const RayBatch& batch, const std::vector<Ray>& rays, size_t c, Chunk* chunk) const;
  Eigen::MatrixXf EncodeBatch(std::vector<Chunk>* chunks) const;
  void BackpropagateChunk(const RayBatch& batch, const std::vector<Ray>& rays, const Eigen::MatrixXf& encoded,
                          Chunk* chunk) const;
  // The chunks' losses, sample counts and gradients summed: the networks' into the first chunk's d_dense, the
  // appearance's and background's into theirs; *d_encoded_magnitude bounds the hash grid's (see trainer.cc).
  StepResult SumChunks(std::vector<Chunk>* chunks, double* d_encoded_magnitude);
  // What is not finite in a summed step ("" when all is).
  std::string GradientProblem(const StepResult& result, const std::vector<float>& d_dense,
                              double d_encoded_magnitude) const;
  // The used samples' field points and dL/d(encoding), chunk after chunk.
  void GatherUsed(const std::vector<Chunk>& chunks, Eigen::MatrixXf* positions, Eigen::MatrixXf* d_encoded) const;
  // From the first 1 / kPoseChunkShare of the chunks, given what GatherUsed() gathered.
  void AddPoseGradients(const RayBatch& batch, const std::vector<Ray>& rays, const Eigen::MatrixXf& positions,
                        const Eigen::MatrixXf& d_encoded, std::vector<Chunk>* chunks);
  void UpdateParameters(double learning_rate, const float* d_dense, bool refine);

  TrainerOptions options_;
  const TrainingData& data_;
  NerfModel model_;
  std::vector<Adam<float>> dense_adams_;
  std::unique_ptr<Adam<float>> grid_adam_;
  std::vector<float> appearance_, appearance_grads_;
  std::unique_ptr<Adam<float>> appearance_adam_;
  std::array<float, 3> background_grads_{};
  double background_seen_ = 0;  // the last step's mean final transmittance: how much of its rays ends on nothing
  std::unique_ptr<Adam<float>> background_adam_;  // with options.learn_background
  std::vector<float> poses_, pose_grads_;
  std::unique_ptr<Adam<float>> pose_adam_;
  std::vector<Eigen::Vector3d> centres_;  // the training cameras' centres, as given
  size_t dense_count_ = 0;
  int step_ = 0;
  int skipped_ = 0;
  bool adopted_ = false;                                     // AdoptModel() was called
  double samples_per_ray_ = 0;                               // running mean, for the batch size
  std::vector<size_t> sampled_;                              // the training views rays are drawn from
  std::vector<char> is_sampled_;                             // for each training view, whether it is in sampled_
  std::vector<size_t> pixel_offsets_;                        // first global pixel index of each of sampled_
  std::unique_ptr<ErrorMap> error_map_;                      // with options.error_sampling
  std::vector<std::pair<uint32_t, uint32_t>> depth_points_;  // (sampled view, its depth point), with depth_weight
};

}  // namespace p2n

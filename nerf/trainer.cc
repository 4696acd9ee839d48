#include "nerf/trainer.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <stdexcept>
#include <utility>

#include "base/declared_fields.h"
#include "nerf/appearance.h"
#include "nerf/camera_refinement.h"
#include "nerf/denormals.h"
#include "nerf/distortion_loss.h"
#include "nerf/make_field.h"
#include "nerf/random_streams.h"
#include "nerf/volume_rendering.h"

namespace p2n {
namespace {

constexpr size_t kTrainingChunkRays = 64;
constexpr float kHuberDelta = 0.1f;
// The colour transforms learn at this share of the field's rate: Adam moves every parameter by about its rate a
// step, and at the field's a photo's gain wanders by a percent a step.
constexpr double kAppearanceRateShare = 0.1;
// The camera corrections learn at this share of the field's rate (radians and world units a step).
constexpr double kPoseRateShare = 0.1;
// Their gradients come from the first 1 / kPoseChunkShare of each batch's chunks (the batch is random): the hash
// grid's gradient with respect to its input costs about as much as its backward pass, and a pose has 6 values
// where a batch has thousands of rays.
constexpr size_t kPoseChunkShare = 8;
// With a depth loss, this share of a batch's rays goes through depth points (the rest are drawn as without).
constexpr double kDepthRayShare = 0.125;
// A depth point's weight falls off with its reprojection error: 1 / (1 + (error / kDepthErrorScale)^2).
constexpr float kDepthErrorScale = 1.0f;
// A learnt background moves at the full rate once this share of a batch's light comes from behind the scene, in
// proportion below it.
constexpr double kBackgroundSeen = 0.01;

// The loss of one colour channel and its derivative.
float ChannelLoss(bool huber, float difference, float* derivative) {
  if (huber && std::abs(difference) > kHuberDelta) {
    *derivative = difference > 0 ? kHuberDelta : -kHuberDelta;
    return kHuberDelta * (std::abs(difference) - 0.5f * kHuberDelta);
  }
  if (huber) {
    *derivative = difference;
    return 0.5f * difference * difference;
  }
  *derivative = 2 * difference;
  return difference * difference;
}

// Adds `scale` x the gradient of the distortion loss of a ray's first `used` segments (in the sampler's metric) to
// d_sigma. A forward-facing scene's segment lengths are in that metric (NDC) already; its ray is mapped once.
void AddDistortionGradient(const NerfModel& model, const Ray& ray, const RaySegments<float>& segments, size_t used,
                           float scale, float* d_sigma) {
  std::vector<float> midpoints(used), lengths(used);
  const bool forward = model.space == SceneSpace::kForward;
  const ForwardRay ndc = forward ? ToForward(model.forward, ray) : ForwardRay{};
  for (size_t k = 0; k < used; ++k) {
    const double t = segments.t[k], half = 0.5 * segments.delta[k];
    if (forward) {
      midpoints[k] = static_cast<float>(ndc.valid ? ndc.NdcDistance(t) : t);
      lengths[k] = segments.delta[k];
    } else {
      midpoints[k] = static_cast<float>(SamplingDistance(model, ray, t));
      lengths[k] = static_cast<float>(SamplingDistance(model, ray, t + half) -
                                      SamplingDistance(model, ray, std::max(t - half, 0.0)));
    }
  }
  DistortionLoss(segments, used, midpoints.data(), lengths.data(), scale, d_sigma);
}

template <typename Values>
bool AllFinite(const Values& values) {
  return std::all_of(values.begin(), values.end(), [](float v) { return std::isfinite(v); });
}

}  // namespace

void TrainerOptions::Check() const {
  CheckField(*this, occupancy_resolution, occupancy_resolution >= 1 && occupancy_resolution <= 1024, "must be 1..1024");
  CheckField(*this, occupancy_interval, occupancy_interval >= 1, "must be at least 1");
  CheckField(*this, occupancy_warmup, occupancy_warmup >= 0, "must be at least 0");
  CheckField(*this, occupancy_decay, occupancy_decay > 0 && occupancy_decay <= 1, "must be in (0, 1]");
  CheckField(*this, march_step, march_step > 0 && std::isfinite(march_step), "must be positive");
  CheckField(*this, fine_march_step, fine_march_step >= 0 && std::isfinite(fine_march_step), "must be at least 0");
  CheckField(*this, fine_march_from, fine_march_from >= 0, "must be at least 0");
  CheckField(*this, max_samples_per_ray, max_samples_per_ray >= 1, "must be at least 1");
  CheckField(*this, stratified_samples, stratified_samples >= 0, "must be at least 0");
  CheckField(*this, batch_samples, batch_samples >= 1, "must be at least 1");
  CheckField(*this, min_batch_rays, min_batch_rays >= 1 && min_batch_rays <= max_batch_rays,
             "must be 1..max_batch_rays");
  CheckField(*this, learning_rate, learning_rate > 0, "must be positive");
  CheckField(*this, final_learning_rate, final_learning_rate > 0, "must be positive");
  CheckField(*this, distortion_weight, distortion_weight >= 0, "must be at least 0");
  CheckField(*this, depth_weight, depth_weight >= 0 && std::isfinite(depth_weight), "must be at least 0");
  CheckField(*this, min_transmittance, min_transmittance >= 0 && min_transmittance < 1, "must be in [0, 1)");
  CheckField(*this, refine_warmup, refine_warmup >= 0, "must be at least 0");
}

Trainer::Trainer(const TrainerOptions& options, const TrainingData& data) : options_(options), data_(data) {
  options.Check();
  if (data.train.empty()) throw std::invalid_argument("there are no training views");
  std::vector<size_t> in_memory;
  for (size_t v = 0; v < data.train.size(); ++v) {
    const TrainView& view = data.train[v];
    if (view.pixels.empty()) continue;
    if (view.pixels.size() != view.PixelBytes()) {
      throw std::invalid_argument("training view " + view.name + ": the pixels do not match its size");
    }
    in_memory.push_back(v);
  }
  model_.field = MakeField<float>(options.field, options.seed);
  model_.occupancy = OccupancyGrid(options.occupancy_resolution);
  model_.background = data.background;
  model_.march_step = options.march_step;
  model_.space = options.space;
  if (options.space == SceneSpace::kForward) {
    std::vector<PinholeCamera> cameras;
    std::vector<double> nears;
    for (const TrainView& view : data.train) {
      cameras.push_back(view.camera);
      nears.push_back(view.near);
    }
    model_.forward = FitForwardFrame(cameras, nears);
  }
  model_.stratified_samples = options.stratified_samples;
  const AdamOptions adam{options.learning_rate, 0.9, 0.99, 1e-15};
  for (const ParamBlock<float>& block : model_.field->DenseParams()) {
    dense_adams_.emplace_back(adam, block.size);
    dense_count_ += block.size;
  }
  if (Encoding<float>* grid = model_.field->TrainableEncoding()) {
    grid_adam_ = std::make_unique<Adam<float>>(adam, grid->num_params(), grid->entry_size());
  }
  if (options.learn_background) {
    if (const TrainView* view = FirstWithAlpha(data.train)) {
      throw std::invalid_argument("training view " + view->name +
                                  " has alpha: it was composited on a known background, which is not learnt");
    }
    background_adam_ = std::make_unique<Adam<float>>(adam, 3);
  }
  if (options.appearance) {
    appearance_ = IdentityAppearance(data.train.size());
    appearance_grads_.assign(appearance_.size(), 0.0f);
    appearance_adam_ = std::make_unique<Adam<float>>(adam, appearance_.size(), kAppearanceParams);
  }
  if (options.refine_cameras) {
    if (model_.field->TrainableEncoding() == nullptr) {
      throw std::invalid_argument("camera refinement needs a field with a hash grid (the ngp field)");
    }
    poses_.assign(data.train.size() * kPoseParams, 0.0f);
    pose_grads_.assign(poses_.size(), 0.0f);
    pose_adam_ = std::make_unique<Adam<float>>(adam, poses_.size(), kPoseParams);
    for (const TrainView& view : data.train) centres_.push_back(view.camera.world_from_cam.block<3, 1>(0, 3));
  }
  std::vector<std::pair<int, int>> sizes;
  for (const TrainView& view : data.train) sizes.emplace_back(view.camera.width, view.camera.height);
  if (options.error_sampling) error_map_ = std::make_unique<ErrorMap>(sizes);
  SampleFrom(std::move(in_memory));
}

void Trainer::SampleFrom(std::vector<size_t> views) {
  is_sampled_.assign(data_.train.size(), 0);
  pixel_offsets_.clear();
  depth_points_.clear();
  size_t offset = 0;
  for (const size_t v : views) {
    const TrainView& view = data_.train.at(v);
    if (view.pixels.empty()) throw std::invalid_argument("training view " + view.name + " has no pixels in memory");
    is_sampled_[v] = 1;
    pixel_offsets_.push_back(offset);
    offset += size_t(view.camera.width) * view.camera.height;
    if (options_.depth_weight == 0) continue;
    for (size_t k = 0; k < view.depth_points.size(); ++k) depth_points_.emplace_back(v, k);
  }
  pixel_offsets_.push_back(offset);
  sampled_ = std::move(views);
}

double Trainer::LearningRate(double progress) const {
  progress = std::clamp(progress, 0.0, 1.0);
  return options_.learning_rate * std::pow(options_.final_learning_rate / options_.learning_rate, progress);
}

ErrorMap::Draw Trainer::DrawPixel(std::mt19937_64* random) const {
  if (sampled_.empty()) throw std::logic_error("no training view has its pixels in memory");
  if (error_map_) {
    ErrorMap::Draw draw = error_map_->Sample(random);
    while (!is_sampled_[draw.view]) draw = error_map_->Sample(random);
    return draw;
  }
  ErrorMap::Draw draw;  // uniform over the sampled views' pixels
  const size_t global = std::uniform_int_distribution<size_t>(0, pixel_offsets_.back() - 1)(*random);
  const size_t index =
      std::upper_bound(pixel_offsets_.begin(), pixel_offsets_.end(), global) - pixel_offsets_.begin() - 1;
  draw.view = sampled_[index];
  const size_t pixel = global - pixel_offsets_[index];
  draw.x = static_cast<int>(pixel % data_.train[draw.view].camera.width);
  draw.y = static_cast<int>(pixel / data_.train[draw.view].camera.width);
  return draw;
}

RayBatch Trainer::SampleBatch(int rays) {
  RayBatch batch;
  batch.rays.resize(rays);
  batch.near_far.resize(rays);
  batch.target.resize(3, rays);
  batch.background.resize(3, rays);
  batch.views.resize(rays);
  if (error_map_) {
    batch.weights.resize(rays);
    batch.cells.resize(rays);
  }
  const int depth_rays = depth_points_.empty() ? 0 : static_cast<int>(std::ceil(kDepthRayShare * rays));
  if (depth_rays > 0) batch.depth.assign(rays, Eigen::Vector2f::Zero());
  std::mt19937_64 random(MixSeed(options_.seed, step_, 0));
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_int_distribution<size_t> any_depth_point(0, std::max<size_t>(depth_points_.size(), 1) - 1);
  for (int r = 0; r < rays; ++r) {
    ErrorMap::Draw draw;
    double u, v;
    if (r < depth_rays) {  // through a depth point, exactly where it appears
      const auto [view, k] = depth_points_[any_depth_point(random)];
      const DepthPoint& point = data_.train[view].depth_points[k];
      draw.view = view;
      draw.cell = RayBatch::kNoCell;
      u = point.u;
      v = point.v;
      draw.x = std::clamp(static_cast<int>(u), 0, data_.train[view].camera.width - 1);
      draw.y = std::clamp(static_cast<int>(v), 0, data_.train[view].camera.height - 1);
      const float ratio = point.error / kDepthErrorScale;
      batch.depth[r] = Eigen::Vector2f(point.distance, 1.0f / (1.0f + ratio * ratio));
    } else {
      draw = DrawPixel(&random);
      v = draw.y + unit(random);  // v's jitter first: the order the stream has always had them in
      u = draw.x + unit(random);
    }
    if (error_map_) {
      batch.weights[r] = draw.weight;
      batch.cells[r] = draw.cell;
    }
    const TrainView& view = data_.train[draw.view];
    const size_t pixel = size_t(draw.y) * view.camera.width + draw.x;
    batch.rays[r] = CameraRay(view.camera, u, v);
    batch.near_far[r] = Eigen::Vector2d(view.near, view.far);
    batch.views[r] = static_cast<int>(draw.view);
    for (int c = 0; c < 3; ++c) {
      const float background =
          options_.random_background && view.channels == 4 ? static_cast<float>(unit(random)) : model_.background[c];
      batch.background(c, r) = background;
      batch.target(c, r) = view.OnBackground(pixel, c, background);
    }
  }
  return batch;
}

StepResult Trainer::Step(double progress) {
  if (options_.fine_march_step > 0 && step_ == options_.fine_march_from) {
    samples_per_ray_ *= model_.march_step / options_.fine_march_step;  // the batch's rays sized for the new spacing
    model_.march_step = options_.fine_march_step;
  }
  if (options_.stratified_samples == 0 && step_ >= options_.occupancy_warmup &&
      (step_ - options_.occupancy_warmup) % options_.occupancy_interval == 0) {
    UpdateOccupancy();
  }
  const double per_ray = samples_per_ray_ > 0              ? samples_per_ray_
                         : options_.stratified_samples > 0 ? options_.stratified_samples
                                                           : 2.0 / model_.march_step;
  const size_t batch_samples =
      options_.late_batch_samples > 0 && progress >= 0.5 ? options_.late_batch_samples : options_.batch_samples;
  const int rays = static_cast<int>(std::clamp(static_cast<double>(batch_samples) / std::max(per_ray, 1.0),
                                               double(options_.min_batch_rays), double(options_.max_batch_rays)));
  return StepOnBatch(SampleBatch(rays), progress);
}

void Trainer::UpdateOccupancy() {
  const RadianceField<float>& field = *model_.field;
  const auto density = [&field](const Eigen::Matrix3Xf& points) {
    Eigen::MatrixXf values;
    field.Density(points, &values);
    return Eigen::VectorXf(values.transpose());
  };
  // A cell is occupied when one step through it would be at least 1% opaque (or above the mean, early on).
  const size_t cells = model_.occupancy.densities().size();
  model_.occupancy.Update(density, static_cast<float>(0.01 / model_.march_step),
                          static_cast<float>(options_.occupancy_decay), MixSeed(options_.seed, step_, 1),
                          step_ == options_.occupancy_warmup ? cells : std::max<size_t>(cells / 16, 1));
}

// One chunk of a step's rays, from marching to gradients.
struct Trainer::Chunk {
  size_t first = 0, count = 0;            // the batch's rays [first, first + count)
  Eigen::MatrixXf positions, directions;  // of every sample marched
  std::vector<float> t, delta;
  std::vector<size_t> offsets;    // the first sample of each ray, and one past the last
  Eigen::Index first_sample = 0;  // in the whole batch
  std::vector<float> d_dense, d_appearance, d_poses;
  std::array<float, 3> d_background{};
  double background_weight = 0;    // the rays' final transmittance summed: how much of them the background shows
  std::vector<Eigen::Index> used;  // the samples before early termination (the ones with gradients)
  Eigen::MatrixXf used_positions, d_encoded;  // of those
  double d_encoded_magnitude = 0;             // the sum of |d_encoded|
  double loss = 0;                            // weighted, summed over the rays
  double depth_loss = 0;                      // weighted, summed over the rays with a depth target
  size_t depth_rays = 0;                      // those rays
  std::vector<float> ray_losses;              // each ray's, unweighted
};

float Trainer::DepthLoss(float depth, const Eigen::Vector2f& target, size_t rays, Chunk* chunk) const {
  const float distance = target[0], weight = static_cast<float>(options_.depth_weight) * target[1];
  if (weight == 0 || !(distance > 0)) return 0.0f;
  const float relative = (depth - distance) / distance;
  chunk->depth_loss += weight * relative * relative;
  ++chunk->depth_rays;
  return 2 * weight * relative / distance / static_cast<float>(rays);
}

void Trainer::MarchChunk(const RayBatch& batch, const std::vector<Ray>& rays, size_t c, Chunk* chunk) const {
  std::mt19937_64 random(MixSeed(options_.seed, step_, 2 + c));
  chunk->first = c * kTrainingChunkRays;
  chunk->count = std::min(rays.size(), chunk->first + kTrainingChunkRays) - chunk->first;
  std::vector<std::vector<MarchSample>> samples(chunk->count);
  chunk->offsets.assign(chunk->count + 1, 0);
  for (size_t r = 0; r < chunk->count; ++r) {
    const Eigen::Vector2d& range = batch.near_far[chunk->first + r];
    samples[r] = SampleRay(model_, rays[chunk->first + r], range[0], range[1], model_.march_step,
                           options_.max_samples_per_ray, &random);
    chunk->offsets[r + 1] = chunk->offsets[r] + samples[r].size();
  }
  const size_t n = chunk->offsets.back();
  chunk->positions.resize(3, n);
  chunk->directions.resize(3, n);
  chunk->t.resize(n);
  chunk->delta.resize(n);
  for (size_t r = 0; r < chunk->count; ++r) {
    const Ray& ray = rays[chunk->first + r];
    for (size_t k = 0; k < samples[r].size(); ++k) {
      const size_t i = chunk->offsets[r] + k;
      chunk->positions.col(i) = FieldPoint(model_, ray.origin + samples[r][k].t * ray.direction).cast<float>();
      chunk->directions.col(i) = ray.direction.cast<float>();
      chunk->t[i] = static_cast<float>(samples[r][k].t);
      chunk->delta[i] = static_cast<float>(samples[r][k].delta);
    }
  }
}

Eigen::MatrixXf Trainer::EncodeBatch(std::vector<Chunk>* chunks) const {
  Eigen::Index total = 0;
  for (Chunk& chunk : *chunks) {
    chunk.first_sample = total;
    total += chunk.positions.cols();
  }
  Eigen::MatrixXf positions(3, total), encoded;
  for (const Chunk& chunk : *chunks) positions.middleCols(chunk.first_sample, chunk.positions.cols()) = chunk.positions;
  model_.field->TrainableEncoding()->Forward(positions, &encoded);
  return encoded;
}

void Trainer::BackpropagateChunk(const RayBatch& batch, const std::vector<Ray>& rays, const Eigen::MatrixXf& encoded,
                                 Chunk* chunk) const {
  const RadianceField<float>& field = *model_.field;
  const size_t n = chunk->offsets.back();
  const std::vector<size_t>& offsets = chunk->offsets;
  Eigen::MatrixXf density, colour;
  RadianceField<float>::Cache cache;
  if (n > 0) {
    Eigen::MatrixXf chunk_encoded;  // moved into the cache, not copied again
    if (encoded.size() > 0) chunk_encoded = encoded.middleCols(chunk->first_sample, n);
    field.ForwardEncoded(chunk->positions, std::move(chunk_encoded), chunk->directions, &density, &colour, &cache);
  }
  Eigen::MatrixXf d_density = Eigen::MatrixXf::Zero(1, n), d_colour = Eigen::MatrixXf::Zero(3, n);
  const float scale = 1.0f / (3.0f * static_cast<float>(rays.size()));
  const bool huber = options_.loss == PhotometricLoss::kHuber;
  const bool appearance = !appearance_.empty() && !batch.views.empty();
  if (appearance) chunk->d_appearance.assign(appearance_.size(), 0.0f);
  for (size_t r = 0; r < chunk->count; ++r) {
    const size_t o = offsets[r], b = chunk->first + r;
    const RaySegments<float> segments{density.data() + o, colour.data() + 3 * o, chunk->t.data() + o,
                                      chunk->delta.data() + o, offsets[r + 1] - o};
    const float* background = batch.background.col(b).data();
    const CompositeResult<float> result = Composite(segments, background, options_.min_transmittance);
    const size_t params = appearance ? size_t(batch.views[b]) * kAppearanceParams : 0;
    float rgb[3] = {result.rgb[0], result.rgb[1], result.rgb[2]}, d_rgb[3];
    if (appearance) ApplyAppearance(&appearance_[params], result.rgb, rgb);
    const float weight = batch.weights.empty() ? 1.0f : batch.weights[b];
    float ray_loss = 0;
    for (int ch = 0; ch < 3; ++ch) {
      ray_loss += ChannelLoss(huber, rgb[ch] - batch.target(ch, b), &d_rgb[ch]) / 3.0f;
      d_rgb[ch] *= scale * weight;
    }
    chunk->loss += weight * ray_loss;
    chunk->ray_losses.push_back(ray_loss);
    if (appearance) {
      const float d_out[3] = {d_rgb[0], d_rgb[1], d_rgb[2]};
      AppearanceBackward(&appearance_[params], result.rgb, d_out, &chunk->d_appearance[params], d_rgb);
    }
    for (int ch = 0; ch < 3; ++ch) chunk->d_background[ch] += d_rgb[ch] * result.transmittance;
    chunk->background_weight += result.transmittance;
    for (size_t k = 0; k < result.used; ++k) chunk->used.push_back(static_cast<Eigen::Index>(o + k));
    if (segments.count == 0) continue;
    const float d_depth = batch.depth.empty() ? 0.0f : DepthLoss(result.depth, batch.depth[b], rays.size(), chunk);
    CompositeBackward(segments, background, result, d_rgb, 0.0f, d_depth, d_density.data() + o,
                      d_colour.data() + 3 * o);
    if (options_.distortion_weight > 0) {
      const float distortion_scale = static_cast<float>(options_.distortion_weight / rays.size()) * weight;
      AddDistortionGradient(model_, rays[b], segments, result.used, distortion_scale, d_density.data() + o);
    }
  }
  chunk->d_dense.assign(dense_count_, 0.0f);
  if (chunk->used.empty()) return;
  // Samples behind the termination point have no gradient: neither the networks nor the hash grid need visit
  // them on the way back.
  cache.KeepColumns(chunk->used);
  Eigen::MatrixXf d_encoded;
  field.Backward(cache, d_density(Eigen::all, chunk->used), d_colour(Eigen::all, chunk->used), chunk->d_dense.data(),
                 &d_encoded);
  if (d_encoded.size() > 0) {
    chunk->used_positions = std::move(cache.positions);
    chunk->d_encoded = std::move(d_encoded);
    // In float (vectorised; in double it was a serial chain, 1% of a step): an overflow to infinity is caught as
    // the problem it is.
    chunk->d_encoded_magnitude = chunk->d_encoded.cwiseAbs().sum();
  }
}

void Trainer::GatherUsed(const std::vector<Chunk>& chunks, Eigen::MatrixXf* positions,
                         Eigen::MatrixXf* d_encoded) const {
  Eigen::Index total = 0;
  for (const Chunk& chunk : chunks) total += chunk.d_encoded.cols();
  positions->resize(3, total);
  d_encoded->resize(model_.field->TrainableEncoding()->output_dims(), total);
  Eigen::Index column = 0;
  for (const Chunk& chunk : chunks) {
    const Eigen::Index n = chunk.d_encoded.cols();
    positions->middleCols(column, n) = chunk.used_positions;
    d_encoded->middleCols(column, n) = chunk.d_encoded;
    column += n;
  }
}

void Trainer::AddPoseGradients(const RayBatch& batch, const std::vector<Ray>& rays, const Eigen::MatrixXf& positions,
                               const Eigen::MatrixXf& d_encoded, std::vector<Chunk>* chunks) {
  const size_t count = (chunks->size() + kPoseChunkShare - 1) / kPoseChunkShare;
  std::vector<Eigen::Index> first_column(count + 1, 0);
  for (size_t c = 0; c < count; ++c) first_column[c + 1] = first_column[c] + (*chunks)[c].d_encoded.cols();
  // Those chunks' samples lead the gathered columns.
  Eigen::MatrixXf d_positions;
  model_.field->TrainableEncoding()->InputGradient(positions.leftCols(first_column[count]),
                                                   d_encoded.leftCols(first_column[count]), &d_positions);
  tbb::parallel_for(size_t{0}, count, [&](size_t c) {
    Chunk& chunk = (*chunks)[c];
    chunk.d_poses.assign(poses_.size(), 0.0f);
    Eigen::Index column = first_column[c];
    size_t k = 0;  // into chunk.used
    for (size_t r = 0; r < chunk.count; ++r) {
      const Ray& ray = rays[chunk.first + r];
      Eigen::Vector3d d_origin = Eigen::Vector3d::Zero(), d_direction = Eigen::Vector3d::Zero();
      for (; k < chunk.used.size() && size_t(chunk.used[k]) < chunk.offsets[r + 1]; ++k, ++column) {
        const double t = chunk.t[size_t(chunk.used[k])];
        const Eigen::Vector3d point = ray.origin + t * ray.direction;
        const Eigen::Vector3d d_point =
            FieldPointJacobian(model_, point).transpose() * d_positions.col(column).cast<double>();
        d_origin += d_point;
        d_direction += t * d_point;
      }
      const size_t view = size_t(batch.views[chunk.first + r]) * kPoseParams;
      CorrectRayBackward(&poses_[view], ray.direction, d_origin, d_direction, &chunk.d_poses[view]);
    }
  });
  for (size_t c = 0; c < count; ++c) {
    for (size_t k = 0; k < poses_.size(); ++k) pose_grads_[k] += (*chunks)[c].d_poses[k];
  }
}

StepResult Trainer::SumChunks(std::vector<Chunk>* chunks, double* d_encoded_magnitude) {
  StepResult result;
  std::vector<float>& d_dense = chunks->front().d_dense;
  // A hash-table entry's gradient sums weight (<= 1) x dL/d(encoding) over samples, so this sum bounds them all:
  // the table's gradient is finite when the sum is, with room to spare for rounding.
  double background_weight = 0;
  size_t depth_rays = 0;
  for (size_t c = 0; c < chunks->size(); ++c) {
    const Chunk& chunk = (*chunks)[c];
    *d_encoded_magnitude += chunk.d_encoded_magnitude;
    result.rays += chunk.count;
    result.loss += chunk.loss;
    result.depth_loss += chunk.depth_loss;
    depth_rays += chunk.depth_rays;
    result.samples += chunk.offsets.back();
    result.samples_used += chunk.used.size();
    if (c > 0) {
      for (size_t k = 0; k < dense_count_; ++k) d_dense[k] += chunk.d_dense[k];
    }
    for (size_t k = 0; k < chunk.d_appearance.size(); ++k) appearance_grads_[k] += chunk.d_appearance[k];
    for (int ch = 0; ch < 3; ++ch) background_grads_[ch] += chunk.d_background[ch];
    background_weight += chunk.background_weight;
  }
  const double rays = static_cast<double>(std::max<size_t>(result.rays, 1));
  result.loss /= rays;
  result.depth_loss /= static_cast<double>(std::max<size_t>(depth_rays, 1));
  background_seen_ = background_weight / rays;
  return result;
}

std::string Trainer::GradientProblem(const StepResult& result, const std::vector<float>& d_dense,
                                     double d_encoded_magnitude) const {
  if (!std::isfinite(result.loss) || !std::isfinite(result.depth_loss)) return "the loss is not finite";
  if (!AllFinite(d_dense)) return "a network gradient is not finite";
  if (!AllFinite(appearance_grads_)) return "an appearance gradient is not finite";
  if (!AllFinite(background_grads_)) return "the background's gradient is not finite";
  if (!(d_encoded_magnitude < 0.5 * std::numeric_limits<float>::max())) return "a hash-grid gradient is not finite";
  return "";
}

void Trainer::AdoptModel(NerfModel model) {
  model_ = std::move(model);
  adopted_ = true;
}

StepResult Trainer::StepOnBatch(const RayBatch& batch, double progress) {
  if (adopted_) throw std::logic_error("Trainer: no step after AdoptModel(): its model was trained elsewhere");
  RadianceField<float>& field = *model_.field;
  // The grid's gradient is zero here: Adam zeroes the entries it used, and a skipped step writes none.
  Encoding<float>* grid = field.TrainableEncoding();
  const bool refine = !poses_.empty() && !batch.views.empty() && step_ >= options_.refine_warmup;
  std::vector<Ray> corrected;
  if (refine) {
    corrected.resize(batch.rays.size());
    for (size_t r = 0; r < corrected.size(); ++r) {
      corrected[r] = CorrectRay(&poses_[size_t(batch.views[r]) * kPoseParams], batch.rays[r]);
    }
  }
  const std::vector<Ray>& rays = refine ? corrected : batch.rays;
  std::vector<Chunk> chunks((rays.size() + kTrainingChunkRays - 1) / kTrainingChunkRays);
  // 1. March the rays through the occupancy grid; 2. the hash grid's encoding of the whole batch at once (level by
  // level: see HashGridEncoding::Forward); 3. the networks, compositing and the gradients, chunk by chunk.
  tbb::parallel_for(size_t{0}, chunks.size(), [&](size_t c) {
    FlushDenormalsOnThisThread();
    MarchChunk(batch, rays, c, &chunks[c]);
  });
  const Eigen::MatrixXf encoded = grid != nullptr ? EncodeBatch(&chunks) : Eigen::MatrixXf();
  tbb::parallel_for(size_t{0}, chunks.size(), [&](size_t c) {
    FlushDenormalsOnThisThread();
    BackpropagateChunk(batch, rays, encoded, &chunks[c]);
  });

  double d_encoded_magnitude = 0;
  StepResult result = SumChunks(&chunks, &d_encoded_magnitude);
  std::vector<float>& d_dense = chunks.front().d_dense;
  ++step_;
  result.problem = GradientProblem(result, d_dense, d_encoded_magnitude);
  if (!result.problem.empty()) {
    std::fill(appearance_grads_.begin(), appearance_grads_.end(), 0.0f);
    background_grads_.fill(0.0f);
    result.skipped = true;
    ++skipped_;
    return result;
  }
  if (grid != nullptr && result.samples_used > 0) {
    Eigen::MatrixXf positions, d_encoded;
    GatherUsed(chunks, &positions, &d_encoded);
    grid->Backward(positions, d_encoded);
    if (refine) AddPoseGradients(batch, rays, positions, d_encoded, &chunks);
  }
  UpdateParameters(LearningRate(progress), d_dense.data(), refine);
  if (error_map_ && !batch.cells.empty()) {
    for (const Chunk& chunk : chunks) {
      for (size_t r = 0; r < chunk.count; ++r) {
        const uint32_t cell = batch.cells[chunk.first + r];
        if (cell != RayBatch::kNoCell) error_map_->Record(cell, chunk.ray_losses[r]);
      }
    }
    error_map_->Rebuild();
  }
  const double per_ray = static_cast<double>(result.samples) / std::max<size_t>(rays.size(), 1);
  samples_per_ray_ = samples_per_ray_ > 0 ? 0.9 * samples_per_ray_ + 0.1 * per_ray : per_ray;
  return result;
}

void Trainer::UpdateParameters(double learning_rate, const float* d_dense, bool refine) {
  RadianceField<float>& field = *model_.field;
  size_t offset = 0;
  std::vector<ParamBlock<float>> blocks = field.DenseParams();
  for (size_t b = 0; b < blocks.size(); ++b) {
    dense_adams_[b].set_learning_rate(learning_rate);
    dense_adams_[b].Step(blocks[b].data, d_dense + offset);
    offset += blocks[b].size;
  }
  if (Encoding<float>* grid = field.TrainableEncoding()) {
    grid_adam_->set_learning_rate(learning_rate);
    grid_adam_->StepSparse(grid->params(), grid->grads(), grid->touched());
  }
  if (appearance_adam_) {  // views without rays in this batch keep their moments
    appearance_adam_->set_learning_rate(kAppearanceRateShare * learning_rate);
    appearance_adam_->StepSparse(appearance_.data(), appearance_grads_.data());
    CentreAppearance(&appearance_);
  }
  // The background keeps the first rate throughout: three values with a clean gradient, and a field that would
  // otherwise learn the sky as haze in front of it while the background catches up. But it moves only as far as
  // the rays show it: Adam's steps are as long for a gradient of noise as for a clean one, and a background that
  // no ray reaches (a field gone to fog) would drift while the field paints the true colour in front of it.
  if (background_adam_) {
    background_adam_->set_learning_rate(options_.learning_rate * std::min(1.0, background_seen_ / kBackgroundSeen));
    background_adam_->Step(model_.background.data(), background_grads_.data());
    for (float& value : model_.background) value = std::clamp(value, 0.0f, 1.0f);
  }
  background_grads_.fill(0.0f);
  if (refine && AllFinite(pose_grads_)) {
    pose_adam_->set_learning_rate(kPoseRateShare * learning_rate);
    pose_adam_->StepSparse(poses_.data(), pose_grads_.data());
    RemoveCommonMotion(centres_, &poses_);
  }
  std::fill(pose_grads_.begin(), pose_grads_.end(), 0.0f);
}

}  // namespace p2n

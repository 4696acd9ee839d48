#include "nerf/trainer.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <stdexcept>
#include <utility>

#include "nerf/appearance.h"
#include "nerf/denormals.h"
#include "nerf/distortion_loss.h"
#include "nerf/volume_rendering.h"

namespace p2n {
namespace {

constexpr size_t kChunkRays = 64;
constexpr char kCheckpointMagic[] = "P2NCKPT1";
constexpr float kHuberDelta = 0.1f;
// The colour transforms learn at this share of the field's rate: Adam moves every parameter by about its rate a
// step, and at the field's a photo's gain wanders by a percent a step.
constexpr double kAppearanceRateShare = 0.1;

// A seed for (run seed, step, stream): streams of one step never share random numbers.
uint64_t MixSeed(uint64_t seed, uint64_t step, uint64_t stream) {
  uint64_t x = seed * 0x9E3779B97F4A7C15ull ^ (step + 0x632BE59BD9B4E019ull) * 0xBF58476D1CE4E5B9ull ^
               (stream + 1) * 0x94D049BB133111EBull;
  x ^= x >> 31;
  return x * 0xD6E8FEB86659FD93ull;
}

// The options that must match for a checkpoint to be resumed.
nlohmann::json CheckpointIdentity(const TrainerOptions& options) {
  return {{"field", options.field},
          {"occupancy_resolution", options.occupancy_resolution},
          {"march_step", options.march_step},
          {"space", SceneSpaceName(options.space)},
          {"stratified_samples", options.stratified_samples},
          {"appearance", options.appearance},
          {"seed", options.seed}};
}

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

Trainer::Trainer(const TrainerOptions& options, const TrainingData& data) : options_(options), data_(data) {
  if (data.train.empty()) throw std::invalid_argument("there are no training views");
  for (const TrainView& view : data.train) {
    if (view.pixels.size() != size_t(view.camera.width) * view.camera.height * view.channels) {
      throw std::invalid_argument("training view " + view.name + ": the pixels do not match its size");
    }
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
  if (options.appearance) {
    appearance_ = IdentityAppearance(data.train.size());
    appearance_grads_.assign(appearance_.size(), 0.0f);
    appearance_adam_ = std::make_unique<Adam<float>>(adam, appearance_.size(), kAppearanceParams);
  }
  size_t offset = 0;
  for (const TrainView& view : data.train) {
    pixel_offsets_.push_back(offset);
    offset += size_t(view.camera.width) * view.camera.height;
  }
  pixel_offsets_.push_back(offset);
}

double Trainer::LearningRate(double progress) const {
  progress = std::clamp(progress, 0.0, 1.0);
  return options_.learning_rate * std::pow(options_.final_learning_rate / options_.learning_rate, progress);
}

RayBatch Trainer::SampleBatch(int rays) {
  RayBatch batch;
  batch.rays.resize(rays);
  batch.near_far.resize(rays);
  batch.target.resize(3, rays);
  batch.background.resize(3, rays);
  batch.views.resize(rays);
  std::mt19937_64 random(MixSeed(options_.seed, step_, 0));
  std::uniform_int_distribution<size_t> pick(0, pixel_offsets_.back() - 1);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int r = 0; r < rays; ++r) {
    const size_t global = pick(random);
    const size_t v = std::upper_bound(pixel_offsets_.begin(), pixel_offsets_.end(), global) - pixel_offsets_.begin() - 1;
    const TrainView& view = data_.train[v];
    const size_t pixel = global - pixel_offsets_[v];
    const int x = static_cast<int>(pixel % view.camera.width), y = static_cast<int>(pixel / view.camera.width);
    batch.rays[r] = CameraRay(view.camera, x + unit(random), y + unit(random));
    batch.near_far[r] = Eigen::Vector2d(view.near, view.far);
    batch.views[r] = static_cast<int>(v);
    const uint8_t* value = view.pixels.data() + pixel * view.channels;
    const float alpha = view.channels == 4 ? value[3] / 255.0f : 1.0f;
    for (int c = 0; c < 3; ++c) {
      const float background = options_.random_background && view.channels == 4 ? static_cast<float>(unit(random))
                                                                                : data_.background[c];
      batch.background(c, r) = background;
      batch.target(c, r) = alpha * (value[c] / 255.0f) + (1 - alpha) * background;
    }
  }
  return batch;
}

StepResult Trainer::Step(double progress) {
  if (options_.stratified_samples == 0 && step_ >= options_.occupancy_warmup && (step_ - options_.occupancy_warmup) % options_.occupancy_interval == 0) {
    UpdateOccupancy();
  }
  const double per_ray = samples_per_ray_ > 0           ? samples_per_ray_
                         : options_.stratified_samples > 0 ? options_.stratified_samples
                                                           : 2.0 / options_.march_step;
  const int rays = static_cast<int>(std::clamp(static_cast<double>(options_.batch_samples) / std::max(per_ray, 1.0),
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
  model_.occupancy.Update(density, static_cast<float>(0.01 / options_.march_step),
                          static_cast<float>(options_.occupancy_decay), MixSeed(options_.seed, step_, 1),
                          step_ == options_.occupancy_warmup ? cells : std::max<size_t>(cells / 16, 1));
}

StepResult Trainer::StepOnBatch(const RayBatch& batch, double progress) {
  RadianceField<float>& field = *model_.field;
  // The grid's gradient is zero here: Adam zeroes the entries it used, and a skipped step writes none.
  Encoding<float>* grid = field.TrainableEncoding();
  const size_t rays = batch.rays.size();
  struct Chunk {
    Eigen::MatrixXf positions, directions;  // of every sample marched
    std::vector<float> t, delta;
    std::vector<size_t> offsets;            // the first sample of each ray
    Eigen::Index first_sample = 0;          // in the whole batch
    std::vector<float> d_dense, d_appearance;
    Eigen::MatrixXf used_positions, d_encoded;  // of the samples before early termination only
    double d_encoded_magnitude = 0;             // the sum of |d_encoded|
    double loss = 0;
    size_t samples = 0, used = 0;
  };
  std::vector<Chunk> chunks((rays + kChunkRays - 1) / kChunkRays);
  // 1. March the rays through the occupancy grid.
  tbb::parallel_for(size_t{0}, chunks.size(), [&](size_t c) {
    FlushDenormalsOnThisThread();
    Chunk& chunk = chunks[c];
    const size_t first = c * kChunkRays, count = std::min(rays, first + kChunkRays) - first;
    std::mt19937_64 random(MixSeed(options_.seed, step_, 2 + c));
    std::vector<std::vector<MarchSample>> samples(count);
    chunk.offsets.assign(count + 1, 0);
    for (size_t r = 0; r < count; ++r) {
      const Eigen::Vector2d& range = batch.near_far[first + r];
      samples[r] = SampleRay(model_, batch.rays[first + r], range[0], range[1], options_.march_step,
                             options_.max_samples_per_ray, &random);
      chunk.offsets[r + 1] = chunk.offsets[r] + samples[r].size();
    }
    const size_t n = chunk.offsets[count];
    chunk.samples = n;
    chunk.positions.resize(3, n);
    chunk.directions.resize(3, n);
    chunk.t.resize(n);
    chunk.delta.resize(n);
    for (size_t r = 0; r < count; ++r) {
      for (size_t k = 0; k < samples[r].size(); ++k) {
        const size_t i = chunk.offsets[r] + k;
        const Ray& ray = batch.rays[first + r];
        chunk.positions.col(i) = FieldPoint(model_, ray.origin + samples[r][k].t * ray.direction).cast<float>();
        chunk.directions.col(i) = ray.direction.cast<float>();
        chunk.t[i] = static_cast<float>(samples[r][k].t);
        chunk.delta[i] = static_cast<float>(samples[r][k].delta);
      }
    }
  });
  // 2. The hash grid's encoding of the whole batch at once (level by level: see HashGridEncoding::Forward).
  Eigen::MatrixXf encoded;
  if (grid != nullptr) {
    Eigen::Index total = 0;
    for (Chunk& chunk : chunks) {
      chunk.first_sample = total;
      total += chunk.positions.cols();
    }
    Eigen::MatrixXf positions(3, total);
    for (const Chunk& chunk : chunks) positions.middleCols(chunk.first_sample, chunk.positions.cols()) = chunk.positions;
    grid->Forward(positions, &encoded);
  }
  // 3. The networks, compositing and the gradients, chunk by chunk.
  tbb::parallel_for(size_t{0}, chunks.size(), [&](size_t c) {
    FlushDenormalsOnThisThread();
    Chunk& chunk = chunks[c];
    const size_t first = c * kChunkRays, count = chunk.offsets.size() - 1, n = chunk.samples;
    const std::vector<size_t>& offsets = chunk.offsets;
    const std::vector<float>& t = chunk.t;
    const std::vector<float>& delta = chunk.delta;
    Eigen::MatrixXf density, colour;
    RadianceField<float>::Cache cache;
    if (n > 0) {
      Eigen::MatrixXf chunk_encoded;  // moved into the cache, not copied again
      if (grid != nullptr) chunk_encoded = encoded.middleCols(chunk.first_sample, n);
      field.ForwardEncoded(chunk.positions, std::move(chunk_encoded), chunk.directions, &density, &colour, &cache);
    }
    Eigen::MatrixXf d_density = Eigen::MatrixXf::Zero(1, n), d_colour = Eigen::MatrixXf::Zero(3, n);
    std::vector<Eigen::Index> used;  // samples that got a gradient
    const float scale = 1.0f / (3.0f * static_cast<float>(rays));
    const bool huber = options_.loss == "huber";
    const bool appearance = !appearance_.empty() && !batch.views.empty();
    if (appearance) chunk.d_appearance.assign(appearance_.size(), 0.0f);
    for (size_t r = 0; r < count; ++r) {
      const size_t o = offsets[r];
      const RaySegments<float> segments{density.data() + o, colour.data() + 3 * o, t.data() + o, delta.data() + o,
                                        offsets[r + 1] - o};
      const float* background = batch.background.col(first + r).data();
      const CompositeResult<float> result = Composite(segments, background, options_.min_transmittance);
      const size_t params = appearance ? size_t(batch.views[first + r]) * kAppearanceParams : 0;
      float rgb[3] = {result.rgb[0], result.rgb[1], result.rgb[2]}, d_rgb[3];
      if (appearance) ApplyAppearance(&appearance_[params], result.rgb, rgb);
      for (int ch = 0; ch < 3; ++ch) {
        chunk.loss += ChannelLoss(huber, rgb[ch] - batch.target(ch, first + r), &d_rgb[ch]) / 3.0;
        d_rgb[ch] *= scale;
      }
      if (appearance) {
        const float d_out[3] = {d_rgb[0], d_rgb[1], d_rgb[2]};
        AppearanceBackward(&appearance_[params], result.rgb, d_out, &chunk.d_appearance[params], d_rgb);
      }
      for (size_t k = 0; k < result.used; ++k) used.push_back(static_cast<Eigen::Index>(o + k));
      if (segments.count > 0) {
        CompositeBackward(segments, background, result, d_rgb, 0.0f, 0.0f, d_density.data() + o,
                          d_colour.data() + 3 * o);
        if (options_.distortion_weight > 0) {
          const float distortion_scale = static_cast<float>(options_.distortion_weight / rays);
          AddDistortionGradient(model_, batch.rays[first + r], segments, result.used, distortion_scale,
                                d_density.data() + o);
        }
      }
    }
    chunk.d_dense.assign(dense_count_, 0.0f);
    chunk.used = used.size();
    if (!used.empty()) {
      // Samples behind the termination point have no gradient: neither the networks nor the hash grid need
      // visit them on the way back.
      cache.KeepColumns(used);
      Eigen::MatrixXf d_encoded;
      field.Backward(cache, d_density(Eigen::all, used), d_colour(Eigen::all, used), chunk.d_dense.data(),
                     &d_encoded);
      if (d_encoded.size() > 0) {
        chunk.used_positions = std::move(cache.positions);
        chunk.d_encoded = std::move(d_encoded);
        chunk.d_encoded_magnitude = chunk.d_encoded.cwiseAbs().cast<double>().sum();
      }
    }
  });

  StepResult result;
  result.rays = rays;
  std::vector<float>& d_dense = chunks.front().d_dense;
  // A hash-table entry's gradient sums weight (<= 1) x dL/d(encoding) over samples, so this sum bounds them all:
  // the table's gradient is finite when the sum is, with room to spare for rounding.
  double d_encoded_magnitude = 0;
  for (size_t c = 0; c < chunks.size(); ++c) {
    d_encoded_magnitude += chunks[c].d_encoded_magnitude;
    result.loss += chunks[c].loss;
    result.samples += chunks[c].samples;
    result.samples_used += chunks[c].used;
    if (c > 0) {
      for (size_t k = 0; k < dense_count_; ++k) d_dense[k] += chunks[c].d_dense[k];
    }
    for (size_t k = 0; k < chunks[c].d_appearance.size(); ++k) appearance_grads_[k] += chunks[c].d_appearance[k];
  }
  result.loss /= static_cast<double>(std::max<size_t>(rays, 1));
  ++step_;
  if (!std::isfinite(result.loss)) {
    result.problem = "the loss is not finite";
  } else if (!AllFinite(d_dense)) {
    result.problem = "a network gradient is not finite";
  } else if (!AllFinite(appearance_grads_)) {
    result.problem = "an appearance gradient is not finite";
  } else if (!(d_encoded_magnitude < 0.5 * std::numeric_limits<float>::max())) {
    result.problem = "a hash-grid gradient is not finite";
  }
  if (!result.problem.empty()) {
    std::fill(appearance_grads_.begin(), appearance_grads_.end(), 0.0f);
    result.skipped = true;
    ++skipped_;
    return result;
  }
  if (grid != nullptr && result.samples_used > 0) {
    Eigen::MatrixXf positions(3, result.samples_used), d_encoded(grid->output_dims(), result.samples_used);
    Eigen::Index column = 0;
    for (const Chunk& chunk : chunks) {
      if (chunk.used == 0) continue;
      positions.middleCols(column, chunk.used) = chunk.used_positions;
      d_encoded.middleCols(column, chunk.used) = chunk.d_encoded;
      column += chunk.used;
    }
    grid->Backward(positions, d_encoded);
  }
  const double learning_rate = LearningRate(progress);
  size_t offset = 0;
  std::vector<ParamBlock<float>> blocks = field.DenseParams();
  for (size_t b = 0; b < blocks.size(); ++b) {
    dense_adams_[b].set_learning_rate(learning_rate);
    dense_adams_[b].Step(blocks[b].data, d_dense.data() + offset);
    offset += blocks[b].size;
  }
  if (grid != nullptr) {
    grid_adam_->set_learning_rate(learning_rate);
    grid_adam_->StepSparse(grid->params(), grid->grads());
  }
  if (appearance_adam_) {  // views without rays in this batch keep their moments
    appearance_adam_->set_learning_rate(kAppearanceRateShare * learning_rate);
    appearance_adam_->StepSparse(appearance_.data(), appearance_grads_.data());
    CentreAppearance(&appearance_);
  }
  const double per_ray = static_cast<double>(result.samples) / std::max<size_t>(rays, 1);
  samples_per_ray_ = samples_per_ray_ > 0 ? 0.9 * samples_per_ray_ + 0.1 * per_ray : per_ray;
  return result;
}

FloatImage PhotoOnBackground(const TrainView& view, const std::array<float, 3>& background) {
  FloatImage image{view.camera.width, view.camera.height, 3, {}};
  const size_t pixels = size_t(image.width) * image.height;
  image.pixels.resize(3 * pixels);
  for (size_t i = 0; i < pixels; ++i) {
    const uint8_t* value = &view.pixels[i * view.channels];
    const float alpha = view.channels == 4 ? value[3] / 255.0f : 1.0f;
    for (int c = 0; c < 3; ++c) image.pixels[3 * i + c] = alpha * (value[c] / 255.0f) + (1 - alpha) * background[c];
  }
  return image;
}

namespace {

// n colours as an image one pixel high.
FloatImage Row(std::vector<float> rgb) { return {static_cast<int>(rgb.size() / 3), 1, 3, std::move(rgb)}; }

// NeRF-W's score of an unseen image: fit the colour transform on the pixels left of the middle, score the rest.
double FittedPsnr(const TrainView& view, const std::vector<size_t>& pixels, const std::vector<float>& rgb,
                  const std::vector<float>& target) {
  std::vector<float> fit_rendered, fit_target, score_rendered, score_target;
  for (size_t i = 0; i < pixels.size(); ++i) {
    const bool left = int(pixels[i] % view.camera.width) < view.camera.width / 2;
    std::vector<float>& rendered_half = left ? fit_rendered : score_rendered;
    std::vector<float>& target_half = left ? fit_target : score_target;
    rendered_half.insert(rendered_half.end(), &rgb[3 * i], &rgb[3 * i + 3]);
    target_half.insert(target_half.end(), &target[3 * i], &target[3 * i + 3]);
  }
  const std::vector<float> transform = FitAppearance(fit_rendered.data(), fit_target.data(), fit_rendered.size() / 3);
  for (size_t i = 0; i < score_rendered.size(); i += 3) {
    const float in[3] = {score_rendered[i], score_rendered[i + 1], score_rendered[i + 2]};
    ApplyAppearance(transform.data(), in, &score_rendered[i]);
  }
  return Psnr(Row(std::move(score_rendered)), Row(std::move(score_target)));
}

}  // namespace

std::vector<double> Trainer::HeldoutPsnr(size_t pixels_per_view, RenderStats* stats,
                                         const std::function<void(size_t)>& on_rays_done,
                                         std::vector<double>* fitted) const {
  std::vector<double> psnrs;
  if (fitted != nullptr) fitted->clear();
  RenderOptions render;
  render.on_rays_done = on_rays_done;
  render.min_transmittance = options_.min_transmittance;
  for (size_t v = 0; v < data_.heldout.size(); ++v) {
    const TrainView& view = data_.heldout[v];
    const size_t total = size_t(view.camera.width) * view.camera.height;
    std::vector<size_t> pixels;
    if (pixels_per_view == 0 || pixels_per_view >= total) {
      pixels.resize(total);
      for (size_t i = 0; i < total; ++i) pixels[i] = i;
    } else {
      std::mt19937_64 random(MixSeed(options_.seed, v, 3));
      std::uniform_int_distribution<size_t> pick(0, total - 1);
      for (size_t i = 0; i < pixels_per_view; ++i) pixels.push_back(pick(random));
    }
    std::vector<Ray> rays(pixels.size());
    std::vector<Eigen::Vector2d> near_far(pixels.size(), Eigen::Vector2d(view.near, view.far));
    for (size_t i = 0; i < pixels.size(); ++i) {
      rays[i] = CameraRay(view.camera, pixels[i] % view.camera.width + 0.5, pixels[i] / view.camera.width + 0.5);
    }
    std::vector<float> rgb(3 * pixels.size()), depth(pixels.size()), opacity(pixels.size()), target(3 * pixels.size());
    RenderRays(model_, rays, near_far, render, rgb.data(), depth.data(), opacity.data(), stats);
    for (size_t i = 0; i < pixels.size(); ++i) {
      const uint8_t* value = view.pixels.data() + pixels[i] * view.channels;
      const float alpha = view.channels == 4 ? value[3] / 255.0f : 1.0f;
      for (int c = 0; c < 3; ++c) target[3 * i + c] = alpha * (value[c] / 255.0f) + (1 - alpha) * model_.background[c];
    }
    if (fitted != nullptr) fitted->push_back(FittedPsnr(view, pixels, rgb, target));
    psnrs.push_back(Psnr(Row(std::move(rgb)), Row(std::move(target))));
  }
  return psnrs;
}

void Trainer::SaveCheckpoint(BinaryWriter* writer) const {
  writer->PutBytes(kCheckpointMagic, 8);
  writer->PutString(CheckpointIdentity(options_).dump());
  WriteModel(model_, writer);
  writer->Put<int32_t>(step_);
  writer->Put<int32_t>(skipped_);
  writer->Put<double>(samples_per_ray_);
  writer->Put<uint64_t>(model_.occupancy.cursor());
  for (const Adam<float>& adam : dense_adams_) adam.Save(writer);
  if (grid_adam_) grid_adam_->Save(writer);
  if (appearance_adam_) {
    writer->PutVector(appearance_);
    appearance_adam_->Save(writer);
  }
}

void Trainer::LoadCheckpoint(BinaryReader* reader) {
  reader->ExpectMagic(kCheckpointMagic, "a photo2nerf training checkpoint");
  if (reader->GetString() != CheckpointIdentity(options_).dump()) {
    reader->Fail("it was written by a training run with other options");
  }
  NerfModel model = ReadModel(reader);
  const int step = reader->Get<int32_t>(), skipped = reader->Get<int32_t>();
  const double samples_per_ray = reader->Get<double>();
  model.occupancy.set_cursor(reader->Get<uint64_t>());
  for (Adam<float>& adam : dense_adams_) adam.Load(reader);
  if (grid_adam_) grid_adam_->Load(reader);
  std::vector<float> appearance;
  if (appearance_adam_) {
    appearance = reader->GetVector<float>(appearance_.size());
    appearance_adam_->Load(reader);
  }
  if (!reader->AtEnd()) reader->Fail("there are bytes after the checkpoint");
  appearance_ = std::move(appearance);
  model_ = std::move(model);
  step_ = step;
  skipped_ = skipped;
  samples_per_ray_ = samples_per_ray;
}

}  // namespace p2n

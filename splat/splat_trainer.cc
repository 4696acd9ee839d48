#include "splat/splat_trainer.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>

#include <opencv2/imgproc.hpp>

#include "base/camera.h"
#include "base/declared_fields.h"

namespace p2n {

void SplatTrainerOptions::Check() const {
  CheckField(*this, steps, steps >= 0, "must be at least 0");
  for (const double* rate : {&position_lr, &final_position_lr, &colour_lr, &opacity_lr, &scale_lr, &rotation_lr}) {
    CheckField(*this, *rate, *rate > 0 && std::isfinite(*rate), "must be positive");
  }
  CheckField(*this, sh_interval, sh_interval > 0, "must be positive");
  CheckField(*this, densify_interval, densify_interval > 0, "must be positive");
  CheckField(*this, densify_until, densify_until >= 0 && densify_until <= 1, "must be in [0, 1]");
  CheckField(*this, densify_gradient, densify_gradient > 0, "must be positive");
  CheckField(*this, prune_opacity, prune_opacity >= 0 && prune_opacity < 1, "must be in [0, 1)");
  CheckField(*this, ssim_weight, ssim_weight >= 0 && ssim_weight <= 1, "must be in [0, 1]");
}

SplatTrainer::SplatTrainer(Gaussians<float> gaussians, const SplatScene& scene, const SplatTrainerOptions& options)
    : gaussians_(std::move(gaussians)),
      scene_(scene),
      background_(scene.background),
      background_adam_(AdamOptions{options.colour_lr, 0.9, 0.999, 1e-15}, 3),
      options_(options),
      random_(options.seed) {
  options_.Check();
  if (scene_.views == nullptr || scene_.views->empty()) throw std::invalid_argument("SplatTrainer: no training views");
  if (scene_.learn_background) {
    if (const TrainView* view = FirstWithAlpha(*scene_.views)) {
      throw std::invalid_argument("SplatTrainer: a background learnt behind photos with alpha (" + view->name + ")");
    }
  }
  if (scene_.context != nullptr && scene_.context->sh_degree != gaussians_.sh_degree)
    throw std::invalid_argument("SplatTrainer: the context's SH degree is not the splats'");
  gaussians_.ForEachArray([&](const std::vector<float>& values, int per) {
    adams_.emplace_back(AdamOptions{1e-3, 0.9, 0.999, 1e-15}, values.size(), std::max(per, 1));
  });
  screen_gradient_sum_.assign(gaussians_.size(), 0);
  screen_gradient_count_.assign(gaussians_.size(), 0);
}

Gaussians<float> SplatTrainer::Drawn() const {
  Gaussians<float> drawn = gaussians_;
  if (scene_.context != nullptr) drawn.Append(*scene_.context);
  return drawn;
}

int SplatTrainer::ShDegree() const { return std::min(gaussians_.sh_degree, step_ / options_.sh_interval); }

double SplatTrainer::StepShare() const {
  return options_.steps > 0 ? std::min(1.0, double(step_) / options_.steps) : 1.0;
}

double SplatTrainer::Progress() const { return progress_ >= 0 ? std::min(1.0, progress_) : StepShare(); }

// By the step, not by the run's progress: a run cut short keeps the means moving (docs/benchmarks.md, splats).
double SplatTrainer::PositionLearningRate() const {
  const double t = StepShare();
  return scene_.extent * std::exp((1 - t) * std::log(options_.position_lr) + t * std::log(options_.final_position_lr));
}

void SplatTrainer::Restrict(const std::vector<bool>& keep, const Gaussians<float>* context,
                            const std::vector<TrainView>* views) {
  if (context != nullptr && context->sh_degree != gaussians_.sh_degree)
    throw std::invalid_argument("SplatTrainer::Restrict: the context's SH degree is not the splats'");
  if (views == nullptr || views->empty()) throw std::invalid_argument("SplatTrainer::Restrict: no training views");
  if (keep.size() != gaussians_.size()) throw std::invalid_argument("SplatTrainer::Restrict: one flag per splat");
  std::vector<int64_t> sources;
  std::vector<float> gradient_sum;
  std::vector<uint32_t> gradient_count;
  for (size_t i = 0; i < keep.size(); ++i) {
    if (!keep[i]) continue;
    sources.push_back(static_cast<int64_t>(i));
    gradient_sum.push_back(screen_gradient_sum_[i]);
    gradient_count.push_back(screen_gradient_count_[i]);
  }
  gaussians_.Filter(keep);
  RemapAdams(sources);
  screen_gradient_sum_ = std::move(gradient_sum);
  screen_gradient_count_ = std::move(gradient_count);
  scene_.context = context;
  scene_.views = views;
  order_.clear();  // an epoch of the new views begins
  sample_.clear();
}

void SplatTrainer::RemapAdams(const std::vector<int64_t>& sources) {
  size_t array = 0;  // an array of no values per Gaussian (SH degree 0's higher coefficients) keeps none
  gaussians_.ForEachArray([&](const std::vector<float>&, int per) {
    if (per > 0) adams_[array].Remap(sources);
    ++array;
  });
}

void SplatTrainer::SetViews(const std::vector<TrainView>* views, double scale) {
  if (views->size() != scene_.views->size()) throw std::invalid_argument("SplatTrainer::SetViews: other views");
  if (!(scale > 0 && scale <= 1)) throw std::invalid_argument("SplatTrainer::SetViews: a scale not in (0, 1]");
  scene_.views = views;
  view_scale_ = scale;
}

void SplatTrainer::SampleFrom(const std::vector<size_t>& views) {
  for (const size_t v : views) {
    if (v >= scene_.views->size()) throw std::invalid_argument("SplatTrainer::SampleFrom: a view that is not there");
  }
  sample_ = views;
  if (sample_.empty()) return;
  std::vector<bool> in(scene_.views->size(), false);
  for (const size_t v : sample_) in[v] = true;
  std::erase_if(order_, [&](size_t v) { return !in[v]; });
}

const TrainView& SplatTrainer::NextView() {
  if (order_.empty()) {
    if (sample_.empty()) {
      order_.resize(scene_.views->size());
      std::iota(order_.begin(), order_.end(), size_t{0});
    } else {
      order_ = sample_;
    }
    std::shuffle(order_.begin(), order_.end(), random_);
  }
  const size_t view = order_.back();
  order_.pop_back();
  return (*scene_.views)[view];
}

double SplatTrainer::Step() {
  const TrainView& view = NextView();
  if (view.pixels.size() != view.PixelBytes()) {
    throw std::logic_error("SplatTrainer: training view " + view.name + " has no pixels (not in the photo window)");
  }
  RasterOptions raster;
  raster.projection.near = scene_.near;
  raster.projection.sh_degree = ShDegree();
  raster.projection.dilation *= view_scale_ * view_scale_;
  for (int c = 0; c < 3; ++c) raster.background[c] = background_[c];
  const Gaussians<float>* drawn = &gaussians_;
  if (scene_.context != nullptr) {
    drawn_ = gaussians_;
    drawn_.Append(*scene_.context);
    drawn = &drawn_;
  }
  rasterizer_.Forward(*drawn, view.camera, raster);

  // (1 - w) L1 + w (1 - SSIM) against the photo on the background (w: options_.ssim_weight).
  const std::vector<float>& rgb = rasterizer_.rgb();
  std::vector<float> photo(rgb.size()), d_rgb(rgb.size());
  for (size_t i = 0; i < rgb.size() / 3; ++i) {
    for (int c = 0; c < 3; ++c) photo[3 * i + c] = view.OnBackground(i, c, background_[c]);
  }
  const float weight = static_cast<float>(options_.ssim_weight);
  double loss = 0;
  if (weight > 0) {
    loss = weight * (1 - ssim_(rgb.data(), photo.data(), view.camera.width, view.camera.height, 3, d_rgb.data()));
    for (float& d : d_rgb) d *= -weight;
  }
  const float scale = (1 - weight) / static_cast<float>(rgb.size());
  double l1 = 0;
  for (size_t i = 0; i < rgb.size(); ++i) {
    const float difference = rgb[i] - photo[i];
    l1 += std::abs(difference);
    d_rgb[i] += difference > 0 ? scale : (difference < 0 ? -scale : 0.0f);
  }
  loss += (1 - weight) * l1 / rgb.size();
  Gaussians<float>& grads = gradients_;  // kept between steps: no allocation of its tens of megabytes each step
  grads.sh_degree = gaussians_.sh_degree;
  if (grads.size() != drawn->size()) grads.Resize(drawn->size());
  grads.SetZero();
  std::vector<float> screen;
  rasterizer_.Backward(d_rgb, &grads, &screen);
  grads.Resize(gaussians_.size());  // the context's gradients go (its capacity stays for the next step)
  if (scene_.learn_background) StepBackground(d_rgb);

  // Screen-space gradients in normalised device units (as the reference's threshold is), for densification.
  const float half_width = 0.5f * view.camera.width, half_height = 0.5f * view.camera.height;
  for (size_t i = 0; i < gaussians_.size(); ++i) {
    if (!rasterizer_.IsDrawn(i)) continue;
    screen_gradient_sum_[i] += std::hypot(screen[2 * i] * half_width, screen[2 * i + 1] * half_height);
    ++screen_gradient_count_[i];
  }

  const double rates[6] = {PositionLearningRate(), options_.scale_lr,  options_.rotation_lr,
                           options_.opacity_lr,    options_.colour_lr, options_.colour_lr / 20};
  std::vector<std::vector<float>*> gradients;
  grads.ForEachArray([&](std::vector<float>& values, int) { gradients.push_back(&values); });
  size_t array = 0;
  gaussians_.ForEachArray([&](std::vector<float>& values, int) {
    Adam<float>& adam = adams_[array];
    adam.set_learning_rate(rates[array]);
    // The higher SH coefficients wait for their degree: until then their gradients are zero, and so would be
    // their updates (their moments start from zero when the first degree joins).
    if (array != kShRestArray || ShDegree() > 0) adam.Step(values.data(), gradients[array]->data());
    ++array;
  });
  ++step_;
  if (step_ >= options_.densify_from && step_ % options_.densify_interval == 0 &&
      Progress() <= options_.densify_until) {
    Densify();
  }
  return loss;
}

// The background shows through each pixel by what the splats leave of it: its gradient is the sum of the pixels'
// colour gradients times their transmittance.
void SplatTrainer::StepBackground(const std::vector<float>& d_rgb) {
  const std::vector<float>& transmittance = rasterizer_.transmittance();
  float gradient[3] = {0, 0, 0};
  for (size_t i = 0; i < transmittance.size(); ++i) {
    for (int c = 0; c < 3; ++c) gradient[c] += d_rgb[3 * i + c] * transmittance[i];
  }
  background_adam_.Step(background_.data(), gradient);
  for (float& value : background_) value = std::clamp(value, 0.0f, 1.0f);
}

// The Gaussians whose mean screen-space gradient reaches the threshold, at most `room` of them (each adds one
// Gaussian): where the cap leaves room for some only, those the loss pulls hardest. In the order of the Gaussians.
std::vector<size_t> SplatTrainer::DensifyCandidates(size_t room) const {
  std::vector<size_t> candidates;
  std::vector<float> mean(gaussians_.size(), 0);
  for (size_t i = 0; i < gaussians_.size(); ++i) {
    if (screen_gradient_count_[i] == 0) continue;
    mean[i] = screen_gradient_sum_[i] / screen_gradient_count_[i];
    if (mean[i] >= options_.densify_gradient) candidates.push_back(i);
  }
  if (candidates.size() > room) {
    std::nth_element(candidates.begin(), candidates.begin() + room, candidates.end(),
                     [&](size_t a, size_t b) { return mean[a] > mean[b] || (mean[a] == mean[b] && a < b); });
    candidates.resize(room);
    std::sort(candidates.begin(), candidates.end());
  }
  return candidates;
}

void SplatTrainer::Densify() {
  const size_t n = gaussians_.size();
  const double dense_scale = options_.dense_fraction * scene_.extent;
  std::normal_distribution<float> normal;
  Gaussians<float> added;
  added.sh_degree = gaussians_.sh_degree;
  std::vector<bool> keep(n, true);
  for (const size_t i : DensifyCandidates(options_.max_gaussians > n ? options_.max_gaussians - n : 0)) {
    const float* log_scale = &gaussians_.log_scales[3 * i];
    const float largest = std::exp(std::max({log_scale[0], log_scale[1], log_scale[2]}));
    if (largest <= dense_scale) {  // small: a copy, which the next steps pull apart
      added.Append(gaussians_, i);
      continue;
    }
    // Large: two Gaussians drawn from it, each 1/1.6 of its size; the original goes.
    const float* q = &gaussians_.rotations[4 * i];
    Eigen::Quaternionf rotation(q[0], q[1], q[2], q[3]);
    if (!(rotation.norm() > 0)) rotation = Eigen::Quaternionf::Identity();
    const Eigen::Matrix3f r = rotation.normalized().toRotationMatrix();
    for (int child = 0; child < 2; ++child) {
      added.Append(gaussians_, i);
      const size_t k = added.size() - 1;
      const Eigen::Vector3f offset(std::exp(log_scale[0]) * normal(random_), std::exp(log_scale[1]) * normal(random_),
                                   std::exp(log_scale[2]) * normal(random_));
      const Eigen::Vector3f shift = r * offset;
      for (int a = 0; a < 3; ++a) {
        added.positions[3 * k + a] += shift[a];
        added.log_scales[3 * k + a] -= std::log(1.6f);
      }
    }
    keep[i] = false;
  }
  for (size_t i = 0; i < n; ++i) {
    if (Sigmoid(gaussians_.opacity_logits[i]) < options_.prune_opacity) keep[i] = false;
  }
  std::vector<int64_t> sources;
  for (size_t i = 0; i < n; ++i) {
    if (keep[i]) sources.push_back(static_cast<int64_t>(i));
  }
  sources.resize(sources.size() + added.size(), -1);
  gaussians_.Filter(keep);
  for (size_t k = 0; k < added.size(); ++k) gaussians_.Append(added, k);
  RemapAdams(sources);
  screen_gradient_sum_.assign(gaussians_.size(), 0);
  screen_gradient_count_.assign(gaussians_.size(), 0);
}

void SplatTrainer::Save(BinaryWriter* writer) const {
  writer->Put<int32_t>(step_);
  writer->Put<int32_t>(gaussians_.sh_degree);
  gaussians_.ForEachArray([&](const std::vector<float>& values, int) { writer->PutVector(values); });
  for (const Adam<float>& adam : adams_) adam.Save(writer);
  writer->PutVector(std::vector<float>(background_.begin(), background_.end()));
  background_adam_.Save(writer);
  writer->PutVector(screen_gradient_sum_);
  writer->PutVector(screen_gradient_count_);
  std::vector<uint64_t> order(order_.begin(), order_.end());
  writer->PutVector(order);
  std::ostringstream state;
  state << random_;
  writer->PutString(state.str());
  writer->Put<uint64_t>(options_.max_gaussians);
}

void SplatTrainer::Load(BinaryReader* reader) {
  step_ = reader->Get<int32_t>();
  gaussians_.sh_degree = reader->Get<int32_t>();
  if (gaussians_.sh_degree < 0 || gaussians_.sh_degree > kMaxShDegree) {
    throw std::runtime_error("a splat checkpoint's SH degree is not 0..3");
  }
  size_t count = SIZE_MAX;
  gaussians_.ForEachArray([&](std::vector<float>& values, int per) {
    values = reader->GetVector<float>(count == SIZE_MAX ? SIZE_MAX : count * per);
    if (count == SIZE_MAX) count = values.size() / per;
    if (values.size() != count * per) throw std::runtime_error("a splat checkpoint's arrays disagree in length");
  });
  adams_.clear();
  gaussians_.ForEachArray([&](const std::vector<float>& values, int per) {
    adams_.emplace_back(AdamOptions{1e-3, 0.9, 0.999, 1e-15}, values.size(), std::max(per, 1));
    adams_.back().Load(reader);
  });
  const std::vector<float> background = reader->GetVector<float>(3);
  std::copy(background.begin(), background.end(), background_.begin());
  background_adam_.Load(reader);
  screen_gradient_sum_ = reader->GetVector<float>(count);
  screen_gradient_count_ = reader->GetVector<uint32_t>(count);
  const std::vector<uint64_t> order = reader->GetVector<uint64_t>();
  for (const uint64_t v : order) {
    if (v >= scene_.views->size()) throw std::runtime_error("a splat checkpoint names a view that is not there");
  }
  order_.assign(order.begin(), order.end());
  std::istringstream state(reader->GetString());
  state >> random_;
  if (state.fail()) throw std::runtime_error("a splat checkpoint's random state cannot be read");
  options_.max_gaussians = reader->Get<uint64_t>();
}

FloatImage RenderSplats(const Gaussians<float>& gaussians, const PinholeCamera& camera,
                        const std::array<float, 3>& background, double near) {
  RasterOptions options;
  options.projection.near = near;
  for (int c = 0; c < 3; ++c) options.background[c] = background[c];
  Rasterizer<float> rasterizer;
  rasterizer.Forward(gaussians, camera, options);
  return FloatImage{camera.width, camera.height, 3, rasterizer.rgb()};
}

TrainView HalfSizeView(const TrainView& view) {
  const int w = view.camera.width / 2, ht = view.camera.height / 2, c = view.channels;
  if (w < 1 || ht < 1)
    throw std::invalid_argument("HalfSizeViews: a view of " + std::to_string(view.camera.width) + "x" +
                                std::to_string(view.camera.height) + " pixels");
  TrainView h{view.camera, view.near, view.far, c, {}, view.name, {}};
  h.camera.width = w, h.camera.height = ht;
  h.camera.fx /= 2, h.camera.fy /= 2, h.camera.cx /= 2, h.camera.cy /= 2;
  if (view.pixels.empty()) return h;
  h.pixels.assign(size_t(w) * ht * c, 0);
  for (int y = 0; y < ht; ++y) {
    for (int x = 0; x < w; ++x) {
      for (int k = 0; k < c; ++k) {
        int sum = 2;  // rounds
        for (int dy = 0; dy < 2; ++dy) {
          for (int dx = 0; dx < 2; ++dx)
            sum += view.pixels[(size_t(2 * y + dy) * view.camera.width + 2 * x + dx) * c + k];
        }
        h.pixels[(size_t(y) * w + x) * c + k] = static_cast<uint8_t>(sum / 4);
      }
    }
  }
  return h;
}

std::vector<TrainView> HalfSizeViews(const std::vector<TrainView>& views) {
  std::vector<TrainView> half;
  for (const TrainView& view : views) half.push_back(HalfSizeView(view));
  return half;
}

double FitScale(const std::vector<TrainView>& views, int max_side) {
  int longest = 0;
  for (const TrainView& view : views) longest = std::max({longest, view.camera.width, view.camera.height});
  return max_side <= 0 || longest <= max_side ? 1.0 : static_cast<double>(max_side) / longest;
}

TrainView FittedView(const TrainView& view, double scale, std::vector<uint8_t> pixels) {
  if (!pixels.empty() && pixels.size() != view.PixelBytes())
    throw std::invalid_argument("FittedView: " + view.name + "'s pixels are not of its size");
  if (scale == 1) {
    TrainView same = WithoutPixels(view);
    same.pixels = std::move(pixels);
    return same;
  }
  const int width = std::max(1, static_cast<int>(std::lround(view.camera.width * scale)));
  const int height = std::max(1, static_cast<int>(std::lround(view.camera.height * scale)));
  TrainView small{ResizedCamera(view.camera, width, height), view.near, view.far, view.channels, {}, view.name, {}};
  if (pixels.empty()) return small;
  small.pixels.resize(size_t(width) * height * view.channels);
  const cv::Mat source(view.camera.height, view.camera.width, CV_8UC(view.channels), pixels.data());
  cv::Mat target(height, width, CV_8UC(view.channels), small.pixels.data());
  cv::resize(source, target, target.size(), 0, 0, cv::INTER_AREA);
  return small;
}

}  // namespace p2n

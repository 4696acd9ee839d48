// The trainer's evaluations (trainer.h: HeldoutPsnr, TrainingPsnr) and the photos they compare with.

#include <random>

#include "nerf/appearance.h"
#include "nerf/random_streams.h"
#include "nerf/trainer.h"

namespace p2n {

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

std::optional<std::array<double, 3>> BehindScene::MeanColour() const {
  if (pixels == 0 || pixels * 100 < evaluated) return std::nullopt;
  return std::array<double, 3>{colour_sum[0] / pixels, colour_sum[1] / pixels, colour_sum[2] / pixels};
}

std::vector<double> Trainer::HeldoutPsnr(size_t pixels_per_view, RenderStats* stats,
                                         const std::function<void(size_t)>& on_rays_done, std::vector<double>* fitted,
                                         BehindScene* behind) const {
  const auto view = [this](size_t v, TrainView* scratch) -> const TrainView& { return HeldoutView(data_, v, scratch); };
  return ViewPsnrs(data_.heldout.size(), view, pixels_per_view, stats, on_rays_done, fitted, behind);
}

std::vector<double> Trainer::TrainingPsnr(size_t pixels_per_view, size_t max_views,
                                          const std::function<void(size_t)>& on_rays_done) const {
  const size_t count = std::min(max_views, sampled_.size());
  const auto view = [&](size_t i, TrainView*) -> const TrainView& {
    return data_.train[sampled_[i * sampled_.size() / count]];
  };
  return ViewPsnrs(count, view, pixels_per_view, nullptr, on_rays_done, nullptr, nullptr);
}

std::vector<double> Trainer::ViewPsnrs(size_t count, const ViewAt& view_at, size_t pixels_per_view, RenderStats* stats,
                                       const std::function<void(size_t)>& on_rays_done, std::vector<double>* fitted,
                                       BehindScene* behind) const {
  std::vector<double> psnrs;
  if (fitted != nullptr) fitted->clear();
  RenderOptions render;
  render.on_rays_done = on_rays_done;
  render.min_transmittance = options_.min_transmittance;
  for (size_t v = 0; v < count; ++v) {
    TrainView scratch;
    const TrainView& view = view_at(v, &scratch);
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
      for (int c = 0; c < 3; ++c) target[3 * i + c] = view.OnBackground(pixels[i], c, model_.background[c]);
      if (behind == nullptr) continue;
      ++behind->evaluated;
      if (opacity[i] >= 0.5f) continue;
      ++behind->pixels;
      for (int c = 0; c < 3; ++c) behind->colour_sum[c] += target[3 * i + c];
    }
    if (fitted != nullptr) fitted->push_back(FittedPsnr(view, pixels, rgb, target));
    psnrs.push_back(Psnr(Row(std::move(rgb)), Row(std::move(target))));
  }
  return psnrs;
}

}  // namespace p2n

#include "splat/splat_schedule.h"

namespace p2n {

// 40 passes: by then the splats have learnt what the half size shows, and a long run's rest is better spent at full
// size.
bool InCoarsePart(double coarse_share, double progress, int steps, size_t train_views) {
  constexpr int kCoarsePasses = 40;
  return progress < coarse_share && static_cast<size_t>(steps) < kCoarsePasses * train_views;
}

SplatSchedule::SplatSchedule(SplatTrainer* trainer, const std::vector<TrainView>* views, PhotoWindow* window,
                             double coarse_share, size_t train_views)
    : trainer_(trainer), views_(views), window_(window), coarse_share_(coarse_share), train_views_(train_views) {
  if (coarse_share_ > 0) coarse_ = HalfSizeViews(*views_);
}

std::optional<double> SplatSchedule::Step(double progress) {
  const bool in_coarse = !coarse_.empty() && InCoarsePart(coarse_share_, progress, trainer_->step(), train_views_);
  trainer_->SetViews(in_coarse ? &coarse_ : views_, in_coarse ? 0.5 : 1.0);
  if (!in_coarse) std::vector<TrainView>().swap(coarse_);  // the coarse part is over for good
  if (window_ && window_->MoveTo(trainer_->step())) {
    trainer_->SampleFrom(window_->resident());
    if (!coarse_.empty()) FollowWindow();
  }
  trainer_->SetProgress(progress);
  return trainer_->Step();
}

void SplatSchedule::FollowWindow() {
  for (size_t v = 0; v < views_->size(); ++v) {
    if ((*views_)[v].pixels.empty()) {
      std::vector<uint8_t>().swap(coarse_[v].pixels);
    } else if (coarse_[v].pixels.empty()) {
      coarse_[v] = HalfSizeView((*views_)[v]);
    }
  }
}

}  // namespace p2n

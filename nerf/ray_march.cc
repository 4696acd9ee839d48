#include "nerf/ray_march.h"

#include <algorithm>
#include <limits>

namespace p2n {
namespace {

constexpr double kUnboundedFar = 1e3;  // world units: the contracted distance there is within 0.1% of the limit
// The smallest share of a forward ray's NDC segment left before its point at infinity: no sample beyond.
constexpr double kForwardEnd = 1 - 1e-6;

}  // namespace

RayMarch::RayMarch(const NerfModel& model, const Ray& ray, double near, double far, double step,
                   std::mt19937_64* jitter)
    : model_(&model), step_(step) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double offset = jitter != nullptr ? unit(*jitter) : 0.5;
  const bool limited = near >= 0 && far >= 0;
  if (limited && !(far > near)) return;  // an empty segment
  switch (model.space) {
    case SceneSpace::kUnbounded: {
      kind_ = Kind::kUnbounded;
      ray_ = ray;
      position_ = limited ? near : 0.0;
      end_ = limited ? far : kUnboundedFar;
      position_ += offset * step * std::max(1.0, 0.5 * position_);
      return;
    }
    case SceneSpace::kForward: {
      forward_ = ToForward(model.forward, ray);
      if (!forward_.valid) return;
      const Eigen::Vector3d start = 0.5 * (forward_.start + Eigen::Vector3d::Ones());
      const Eigen::Vector3d along = 0.5 * (forward_.end - forward_.start);
      forward_length_ = along.norm();
      if (!(forward_length_ > 0)) return;
      const double begin = limited && near > forward_.t0 ? forward_length_ * forward_.Fraction(near) : 0.0;
      kind_ = Kind::kForward;
      StartInCube({start, along / forward_length_}, begin, kForwardEnd * forward_length_, offset, jitter);
      return;
    }
    case SceneSpace::kBounded:
      // Distances in the field's cube are half the world's.
      kind_ = Kind::kBounded;
      StartInCube({FieldPoint(model, ray.origin), ray.direction}, limited ? 0.5 * near : 0.0,
                  limited ? 0.5 * far : std::numeric_limits<double>::infinity(), offset, jitter);
      return;
  }
}

void RayMarch::StartInCube(const Ray& cube_ray, double begin, double end, double offset, std::mt19937_64* jitter) {
  const auto box = IntersectBox(cube_ray, Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones());
  begin = box ? std::max(begin, box->first) : 0.0;
  end = box ? std::min(end, box->second) : 0.0;
  if (!(end > begin)) {
    kind_ = Kind::kNothing;
    return;
  }
  ray_ = cube_ray;
  step_ *= 0.5;
  position_ = begin + offset * step_;
  end_ = end;
  const int bins = model_->stratified_samples;
  if (bins == 0) return;
  // Stratified (vanilla): every sample now, in world units.
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double width = (end - begin) / bins;
  const Kind kind = kind_;
  kind_ = Kind::kStratified;
  for (int i = 0; i < bins; ++i) {
    const MarchSample cube{begin + (i + (jitter != nullptr ? unit(*jitter) : 0.5)) * width, width};
    stratified_.push_back(kind == Kind::kForward
                              ? MarchSample{forward_.Distance(cube.t / forward_length_), 2 * cube.delta}
                              : MarchSample{2 * cube.t, 2 * cube.delta});
  }
}

size_t RayMarch::Next(size_t count, std::vector<MarchSample>* out) {
  switch (kind_) {
    case Kind::kNothing:
      return 0;
    case Kind::kStratified: {
      const size_t n = std::min(count, stratified_.size() - taken_);
      out->insert(out->end(), stratified_.begin() + taken_, stratified_.begin() + taken_ + n);
      taken_ += n;
      return n;
    }
    case Kind::kUnbounded:
      return NextUnbounded(count, out);
    case Kind::kBounded:
    case Kind::kForward:
      return NextInCube(count, out);
  }
  return 0;
}

size_t RayMarch::NextUnbounded(size_t count, std::vector<MarchSample>* out) {
  const OccupancyGrid& occupancy = model_->occupancy;
  const Eigen::Vector3d origin = ray_.origin, direction = ray_.direction;
  size_t added = 0;
  while (position_ < end_ && added < count) {
    // The step grows with the distance beyond the unit box, so that contracted space is sampled about evenly.
    const double dt = std::min(step_ * std::max(1.0, 0.5 * position_), end_ - position_);
    const double middle = position_ + 0.5 * dt;
    if (occupancy.Occupied(UnboundedFieldPoint(origin + middle * direction))) {
      out->push_back({middle, dt});
      ++added;
    }
    position_ += dt;
  }
  return added;
}

size_t RayMarch::NextInCube(size_t count, std::vector<MarchSample>* out) {
  if (!(position_ < end_)) return 0;
  const size_t first = out->size();
  std::vector<MarchSample> cube = model_->occupancy.March(ray_, position_, end_, step_, count, &position_);
  for (const MarchSample& s : cube) {
    out->push_back(kind_ == Kind::kForward ? MarchSample{forward_.Distance(s.t / forward_length_), 2 * s.delta}
                                           : MarchSample{2 * s.t, 2 * s.delta});
  }
  return out->size() - first;
}

}  // namespace p2n

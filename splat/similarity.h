#pragma once
// Splats moved into another frame.

#include <Eigen/Core>

#include "splat/gaussians.h"

namespace p2n {

// Moves Gaussians by the similarity x -> linear x + translation (linear: a rotation times a positive scale):
// means, scales, rotations and the higher SH coefficients (turned with the directions they are seen along, so that
// each Gaussian shows the same colour to a camera moved with it); std::invalid_argument when `linear` is not a
// similarity of positive determinant.
void ApplySimilarity(const Eigen::Matrix3d& linear, const Eigen::Vector3d& translation, Gaussians<float>* gaussians);

}  // namespace p2n

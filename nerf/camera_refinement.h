#pragma once
// Camera refinement (as nerfacto and BARF do it): each training view's pose gets a small rigid correction learnt
// with the field, six values a view: a rotation about the camera's centre as a rotation vector in world axes
// (radians), then a shift of the centre (world units). The photometric loss reaches them through the positions
// of the samples along the view's rays (the view direction's effect on colour is left out).
//
// The corrections are known only up to one similarity of all cameras alike (the field can move with them), and
// the held-out cameras are not refined: RemoveCommonMotion takes that common part out, so that the refined
// cameras stay in the frame the held-out ones are in.

#include <Eigen/Core>

#include <vector>

#include "base/camera.h"
#include "nerf/rays.h"

namespace p2n {

inline constexpr int kPoseParams = 6;  // rotation vector (3), then shift (3)

// The ray after `correction` (its origin is the camera's centre).
Ray CorrectRay(const float* correction, const Ray& ray);
// Adds dL/d(correction) to `d_correction` given dL/d(origin) and dL/d(direction) of the corrected ray, whose
// direction is `corrected_direction`.
void CorrectRayBackward(const float* correction, const Eigen::Vector3d& corrected_direction,
                        const Eigen::Vector3d& d_origin, const Eigen::Vector3d& d_direction, float* d_correction);
// The camera after `correction`: the pose that casts CorrectRay()'s rays.
PinholeCamera CorrectedCamera(const PinholeCamera& camera, const float* correction);

// Takes out of `corrections` (kPoseParams a view) the similarity of the whole set (a rotation about the origin, a
// scale and a shift) that best explains them (least squares; rotations weighted by the cameras' RMS distance
// from the origin). `centres`: the cameras' uncorrected centres, one a view.
void RemoveCommonMotion(const std::vector<Eigen::Vector3d>& centres, std::vector<float>* corrections);

// How far a correction turns the camera (degrees) and moves its centre (world units).
double CorrectionDegrees(const float* correction);
double CorrectionShift(const float* correction);

}  // namespace p2n

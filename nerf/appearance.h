#pragma once
// Per-image appearance: photos of one scene differ in exposure and white balance. Each training image gets an
// affine colour transform c' = M c + b (M 3 x 3, b 3), learnt with the field, applied to the rendered colour of
// its rays before the loss; the field learns the scene as the average photo shows it (the transforms are kept
// centred on the identity), and novel views show that. (A colour transform rather than NeRF-W's latent code:
// it can change only what a camera changes, never the scene, and an image that was never trained on is fitted
// in closed form, by least squares.)

#include <cstddef>
#include <vector>

namespace p2n {

inline constexpr int kAppearanceParams = 12;  // M row-major, then b

// The parameters of `views` identity transforms.
std::vector<float> IdentityAppearance(size_t views);

// Shifts every transform by the same amount so that their mean is the identity. The scene's colours and the
// transforms are only known up to a transform of all photos alike; this keeps the field's colours those of the
// average photo, which novel views show.
void CentreAppearance(std::vector<float>* params);

// out = M in + b for the transform at `params` (12 values).
void ApplyAppearance(const float* params, const float in[3], float out[3]);

// Given dL/d(out) at `in`: adds dL/dM and dL/db to `grads` (12 values) and writes dL/d(in) = M^T dL/d(out).
void AppearanceBackward(const float* params, const float in[3], const float d_out[3], float* grads, float d_in[3]);

// The transform (12 values) that best maps `rendered` onto `target` (n RGB triples each) in least squares,
// pulled weakly towards the identity: where the pixels leave a direction open (too few, or all grey) it keeps
// the identity's.
std::vector<float> FitAppearance(const float* rendered, const float* target, size_t n);

// The gain of a transform: what it makes of white, averaged over the channels (1 for the identity).
double AppearanceGain(const float* params);

}  // namespace p2n

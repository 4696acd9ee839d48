#pragma once
// A cloud of 3D Gaussians (3D Gaussian Splatting, Kerbl et al. 2023), one array per parameter so that each has
// its own Adam and a gradient of the same shape. The parameters are those of the standard splat PLY: a mean, a
// per-axis natural-log scale, a rotation quaternion (w, x, y, z; normalised where it is used), an opacity logit
// and the colour's spherical-harmonics coefficients (RGB per coefficient; colour = 0.5 + Σ coefficient · basis),
// the degree-0 one apart from the others (they learn at different rates).

#include <Eigen/Core>

#include <cstddef>
#include <vector>

namespace p2n {

// Coefficients per colour channel of spherical harmonics up to `degree` (0..3): (degree + 1)².
constexpr int ShCoefficients(int degree) { return (degree + 1) * (degree + 1); }
inline constexpr int kMaxShDegree = 3;
inline constexpr double kShC0 = 0.28209479177387814;  // the degree-0 basis function, 1 / (2 sqrt(pi))

template <typename T>
struct Gaussians {
  int sh_degree = kMaxShDegree;
  std::vector<T> positions;       // 3 per Gaussian
  std::vector<T> log_scales;      // 3
  std::vector<T> rotations;       // 4: w, x, y, z
  std::vector<T> opacity_logits;  // 1
  std::vector<T> sh_dc;           // 3: the degree-0 coefficient's R, G, B
  std::vector<T> sh_rest;         // 3 · (ShCoefficients(sh_degree) - 1): coefficient 1's R, G, B, then 2's, ...

  size_t size() const { return opacity_logits.size(); }
  int coefficients() const { return ShCoefficients(sh_degree); }
  // Every array sized for `count` Gaussians (new ones zero: a zero rotation renders as the identity).
  void Resize(size_t count);
  // Sets every value to zero (a gradient before accumulation).
  void SetZero();
  // Appends Gaussian `index` of `other` (same sh_degree).
  void Append(const Gaussians& other, size_t index);
  // Appends every Gaussian of `other` (same sh_degree).
  void Append(const Gaussians& other);
  // Keeps the Gaussians whose `keep` is true, in order.
  void Filter(const std::vector<bool>& keep);

  // Calls visit(values, per_gaussian) for each parameter array, in a fixed order.
  template <class Visit>
  void ForEachArray(Visit&& visit) {
    ForEachArrayOf(*this, visit);
  }
  template <class Visit>
  void ForEachArray(Visit&& visit) const {
    ForEachArrayOf(*this, visit);
  }

 private:
  template <class Self, class Visit>
  static void ForEachArrayOf(Self& self, Visit& visit) {
    visit(self.positions, 3);
    visit(self.log_scales, 3);
    visit(self.rotations, 4);
    visit(self.opacity_logits, 1);
    visit(self.sh_dc, 3);
    visit(self.sh_rest, 3 * (self.coefficients() - 1));
  }
};

template <typename T>
T Sigmoid(T x);
template <typename T>
T Logit(T p);

extern template struct Gaussians<float>;
extern template struct Gaussians<double>;

}  // namespace p2n

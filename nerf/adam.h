#pragma once
// Adam (Kingma & Ba) for dense parameter vectors, and a sparse variant for hash tables that updates only the
// entries that received a gradient, each with its own step count (as tiny-cuda-nn does): an entry that is
// seldom touched is not decayed by steps it took no part in.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "nerf/binary_io.h"

namespace p2n {

struct AdamOptions {
  double learning_rate = 1e-2;
  double beta1 = 0.9;
  double beta2 = 0.999;
  double epsilon = 1e-8;
};

template <typename T>
class Adam {
 public:
  // `entry_size` values share one step count (a hash-table entry's features); 1 for dense use.
  Adam(AdamOptions options, size_t num_params, int entry_size = 1);

  void set_learning_rate(double learning_rate) { options_.learning_rate = learning_rate; }
  const AdamOptions& options() const { return options_; }

  // Updates every parameter from `grads` (num_params values).
  void Step(T* params, const T* grads);
  // Updates only the listed entries (indices of entries, not of values); `grads` is indexed like `params`.
  void StepSparse(T* params, const T* grads, const std::vector<uint32_t>& entries);

  // The moments and step counts, for checkpoints (Load() checks the sizes).
  void Save(BinaryWriter* writer) const;
  void Load(BinaryReader* reader);

 private:
  // Updates values [begin, end) as at step `step` (1-based).
  void UpdateRange(T* params, const T* grads, size_t begin, size_t end, uint32_t step);

  AdamOptions options_;
  int entry_size_;
  std::vector<T> first_moment_, second_moment_;
  std::vector<uint32_t> entry_steps_;
  std::vector<double> beta1_powers_{1.0}, beta2_powers_{1.0};  // beta^t, grown on demand
  uint32_t dense_step_ = 0;
  uint32_t sparse_calls_ = 0;  // StepSparse() calls: a bound on every entry's step
};

extern template class Adam<float>;
extern template class Adam<double>;

}  // namespace p2n

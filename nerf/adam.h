#pragma once
// Adam (Kingma & Ba) for dense parameter vectors, and a sparse variant for hash tables that updates only the
// entries that received a gradient, each with its own step count (as tiny-cuda-nn does): an entry that is
// seldom touched is not decayed by steps it took no part in. As in tiny-cuda-nn, an entry took part in a step
// when its gradient is not exactly zero; the sparse step sweeps the table in order (sequential memory access)
// and zeroes the gradients it used, so the table's gradient is zero for the next. Given the gradient's touch
// marks, it reads only the groups of entries marked, and clears the marks.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "base/binary_io.h"
#include "nerf/touch_marks.h"

namespace p2n {

struct AdamOptions {
  static constexpr const char* kName = "adam";  // checks name adam.FIELD
  double learning_rate = 1e-2;
  double beta1 = 0.9;
  double beta2 = 0.999;
  double epsilon = 1e-8;

  template <class V>
  void Visit(V& v) {
    v("learning_rate", learning_rate);
    v("beta1", beta1);
    v("beta2", beta2);
    v("epsilon", epsilon);
  }

  // std::invalid_argument naming the field and its rule (Adam checks its options).
  void Check() const;
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
  // Updates only the entries whose gradient is not all zero, and zeroes their gradient; `grads` is indexed
  // like `params`. With `marks` (one entry of them per Adam entry), only the marked groups are read.
  void StepSparse(T* params, T* grads, TouchMarks* marks = nullptr);

  // Rebuilds the moments for a new list of entries: entry k takes those of old entry sources[k], or zeros when it
  // is -1 (entries added or removed between steps, as splat densification does). Dense use only.
  void Remap(const std::vector<int64_t>& sources);

  // The moments and step counts, for checkpoints (Load() checks the sizes).
  void Save(BinaryWriter* writer) const;
  void Load(BinaryReader* reader);

 private:
  // Grows the bias-correction tables to step `step`.
  void GrowTables(uint32_t step);

  AdamOptions options_;
  int entry_size_;
  std::vector<T> first_moment_, second_moment_;
  std::vector<uint32_t> entry_steps_;
  // Bias corrections of step t (1-based, grown on demand): 1 / (1 - beta1^t) and 1 / sqrt(1 - beta2^t).
  std::vector<T> correction1_{T(0)}, correction2_{T(0)};
  double beta1_power_ = 1, beta2_power_ = 1;  // of the last step in the tables
  uint32_t dense_step_ = 0;
  uint32_t sparse_calls_ = 0;  // StepSparse() calls: a bound on every entry's step
};

extern template class Adam<float>;
extern template class Adam<double>;

}  // namespace p2n

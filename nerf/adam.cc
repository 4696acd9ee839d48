#include "nerf/adam.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace p2n {

template <typename T>
Adam<T>::Adam(AdamOptions options, size_t num_params, int entry_size)
    : options_(options),
      entry_size_(entry_size),
      first_moment_(num_params, T(0)),
      second_moment_(num_params, T(0)),
      entry_steps_(num_params / entry_size, 0) {
  if (entry_size <= 0 || num_params % entry_size != 0) {
    throw std::invalid_argument("Adam: the parameter count must be a multiple of the entry size");
  }
}

template <typename T>
void Adam<T>::GrowTables(uint32_t step) {
  while (correction1_.size() <= step) {
    beta1_power_ *= options_.beta1;
    beta2_power_ *= options_.beta2;
    correction1_.push_back(static_cast<T>(1 / (1 - beta1_power_)));
    correction2_.push_back(static_cast<T>(1 / std::sqrt(1 - beta2_power_)));
  }
}

namespace {

// One Adam update of `count` values at bias corrections c1 = 1 / (1 - beta1^t), c2 = 1 / sqrt(1 - beta2^t):
// p -= lr * m_hat / (sqrt(v_hat) + eps), with m_hat = m c1 and sqrt(v_hat) = sqrt(v) c2.
template <typename T>
void Update(const AdamOptions& options, T c1, T c2, size_t count, T* params, const T* grads, T* m, T* v) {
  const T beta1 = static_cast<T>(options.beta1), beta2 = static_cast<T>(options.beta2);
  const T epsilon = static_cast<T>(options.epsilon), step_size = static_cast<T>(options.learning_rate) * c1;
  for (size_t k = 0; k < count; ++k) {
    const T g = grads[k];
    m[k] = beta1 * m[k] + (1 - beta1) * g;
    v[k] = beta2 * v[k] + (1 - beta2) * g * g;
    params[k] -= step_size * m[k] / (std::sqrt(v[k]) * c2 + epsilon);
  }
}

}  // namespace

template <typename T>
void Adam<T>::Step(T* params, const T* grads) {
  GrowTables(++dense_step_);
  Update(options_, correction1_[dense_step_], correction2_[dense_step_], first_moment_.size(), params, grads,
         first_moment_.data(), second_moment_.data());
}

template <typename T>
void Adam<T>::StepSparse(T* params, T* grads) {
  // No entry can be past step `sparse_calls_` (one step per call at most): grow the tables that far first, then
  // sweep the entries in parallel ranges.
  GrowTables(++sparse_calls_);
  const size_t n = entry_size_;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, entry_steps_.size(), 16384), [&](const tbb::blocked_range<size_t>& range) {
    for (size_t entry = range.begin(); entry < range.end(); ++entry) {
      T* g = grads + entry * n;
      if (std::all_of(g, g + n, [](T value) { return value == T(0); })) continue;
      const uint32_t step = ++entry_steps_[entry];
      Update(options_, correction1_[step], correction2_[step], n, params + entry * n, g,
             first_moment_.data() + entry * n, second_moment_.data() + entry * n);
      std::fill(g, g + n, T(0));
    }
  });
}

template <typename T>
void Adam<T>::Save(BinaryWriter* writer) const {
  writer->PutVector(first_moment_);
  writer->PutVector(second_moment_);
  writer->PutVector(entry_steps_);
  writer->Put<uint32_t>(dense_step_);
}

template <typename T>
void Adam<T>::Load(BinaryReader* reader) {
  first_moment_ = reader->GetVector<T>(first_moment_.size());
  second_moment_ = reader->GetVector<T>(second_moment_.size());
  entry_steps_ = reader->GetVector<uint32_t>(entry_steps_.size());
  dense_step_ = reader->Get<uint32_t>();
  sparse_calls_ = 0;
  for (const uint32_t step : entry_steps_) sparse_calls_ = std::max(sparse_calls_, step);
}

template class Adam<float>;
template class Adam<double>;

}  // namespace p2n

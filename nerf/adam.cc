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
void Adam<T>::UpdateRange(T* params, const T* grads, size_t begin, size_t end, uint32_t step) {
  while (beta1_powers_.size() <= step) {
    beta1_powers_.push_back(beta1_powers_.back() * options_.beta1);
    beta2_powers_.push_back(beta2_powers_.back() * options_.beta2);
  }
  // p -= lr * m_hat / (sqrt(v_hat) + eps), with m_hat = m / (1 - beta1^t) and v_hat = v / (1 - beta2^t).
  const T step_size = static_cast<T>(options_.learning_rate / (1 - beta1_powers_[step]));
  const T inv_sqrt_correction2 = static_cast<T>(1 / std::sqrt(1 - beta2_powers_[step]));
  const T beta1 = static_cast<T>(options_.beta1), beta2 = static_cast<T>(options_.beta2);
  const T epsilon = static_cast<T>(options_.epsilon);
  for (size_t k = begin; k < end; ++k) {
    const T g = grads[k];
    first_moment_[k] = beta1 * first_moment_[k] + (1 - beta1) * g;
    second_moment_[k] = beta2 * second_moment_[k] + (1 - beta2) * g * g;
    params[k] -= step_size * first_moment_[k] / (std::sqrt(second_moment_[k]) * inv_sqrt_correction2 + epsilon);
  }
}

template <typename T>
void Adam<T>::Step(T* params, const T* grads) {
  UpdateRange(params, grads, 0, first_moment_.size(), ++dense_step_);
}

template <typename T>
void Adam<T>::StepSparse(T* params, const T* grads, const std::vector<uint32_t>& entries) {
  // No entry can be past step `sparse_calls_` (one step per call at most): grow the bias-correction tables
  // that far first, then update the entries in parallel (each appears once, so no two tasks share one).
  ++sparse_calls_;
  while (beta1_powers_.size() <= sparse_calls_) {
    beta1_powers_.push_back(beta1_powers_.back() * options_.beta1);
    beta2_powers_.push_back(beta2_powers_.back() * options_.beta2);
  }
  const T beta1 = static_cast<T>(options_.beta1), beta2 = static_cast<T>(options_.beta2);
  const T epsilon = static_cast<T>(options_.epsilon);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, entries.size(), 4096), [&](const tbb::blocked_range<size_t>& range) {
    for (size_t k = range.begin(); k < range.end(); ++k) {
      const uint32_t entry = entries[k];
      const uint32_t step = ++entry_steps_[entry];
      const T step_size = static_cast<T>(options_.learning_rate / (1 - beta1_powers_[step]));
      const T inv_sqrt_correction2 = static_cast<T>(1 / std::sqrt(1 - beta2_powers_[step]));
      for (size_t i = size_t{entry} * entry_size_; i < size_t{entry + 1} * entry_size_; ++i) {
        const T g = grads[i];
        first_moment_[i] = beta1 * first_moment_[i] + (1 - beta1) * g;
        second_moment_[i] = beta2 * second_moment_[i] + (1 - beta2) * g * g;
        params[i] -= step_size * first_moment_[i] / (std::sqrt(second_moment_[i]) * inv_sqrt_correction2 + epsilon);
      }
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

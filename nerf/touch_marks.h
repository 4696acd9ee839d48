#pragma once
// Which groups of a sparse gradient's entries may be non-zero: one flag per kGroupEntries entries, set by whoever
// adds to the gradient (from any thread: the flags are atomic bytes, and a group may straddle two hash-grid levels
// that two threads fill), cleared by the sparse Adam step. A clear flag promises that the group's gradient is zero,
// so the step skips it without reading it.

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>

namespace p2n {

class TouchMarks {
 public:
  static constexpr size_t kGroupEntries = 8;  // one 64-byte cache line of two-float entries

  explicit TouchMarks(size_t entries)
      : groups_((entries + kGroupEntries - 1) / kGroupEntries), flags_(new std::atomic<uint8_t>[groups_]) {
    ClearAll();
  }

  size_t groups() const { return groups_; }
  void Mark(size_t entry) {
    std::atomic<uint8_t>& flag = flags_[entry / kGroupEntries];
    if (flag.load(std::memory_order_relaxed) == 0) flag.store(1, std::memory_order_relaxed);  // a read is cheaper
  }
  bool marked(size_t group) const { return flags_[group].load(std::memory_order_relaxed) != 0; }
  void Clear(size_t group) { flags_[group].store(0, std::memory_order_relaxed); }
  void ClearAll() {
    for (size_t g = 0; g < groups_; ++g) Clear(g);
  }

 private:
  size_t groups_;
  std::unique_ptr<std::atomic<uint8_t>[]> flags_;
};

}  // namespace p2n

#pragma once
// Training and rendering allocate and free matrices of a few MB in every step. By default glibc maps each from the
// kernel and returns it when freed, so every step faults its pages in again (a tenth of a training step on fox, half
// of throughput_bench's whole field): keep such blocks in the heap (up to the largest threshold glibc allows) and
// keep freed memory. Every program that trains or renders calls this first, the test programs too.

#include <malloc.h>

namespace p2n {

inline void KeepFreedBlocksInHeap() {
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 512 << 20);
}

}  // namespace p2n

#pragma once
// Seeds of the trainer's random streams: a run is reproducible for a given seed, whatever order its streams are
// drawn in.

#include <cstdint>

namespace p2n {

// A seed for (run seed, step, stream): streams of one step never share random numbers.
inline uint64_t MixSeed(uint64_t seed, uint64_t step, uint64_t stream) {
  uint64_t x = seed * 0x9E3779B97F4A7C15ull ^ (step + 0x632BE59BD9B4E019ull) * 0xBF58476D1CE4E5B9ull ^
               (stream + 1) * 0x94D049BB133111EBull;
  x ^= x >> 31;
  return x * 0xD6E8FEB86659FD93ull;
}

}  // namespace p2n

#pragma once
// Denormal floats make some operations a hundred times slower, and training produces them as errors shrink.
// docs/design.md §6: flush them to zero (MXCSR FTZ and DAZ) in every thread that computes; -ffast-math as a whole
// stays off because it breaks the non-finite checks. Setting the bits is cheap and idempotent, so parallel
// bodies call this at their start.

#if defined(__SSE__) || defined(__x86_64__)
#include <pmmintrin.h>
#include <xmmintrin.h>
#endif

namespace p2n {

inline void FlushDenormalsOnThisThread() {
#if defined(__SSE__) || defined(__x86_64__)
  _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
  _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
#endif
}

}  // namespace p2n

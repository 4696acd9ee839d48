#include "pipeline/run_options.h"

#include "base/format.h"

namespace p2n {

void RunOptions::Check() const {
  CheckField(*this, threads, threads >= 0, format("must be 0 (every core) or more, not {}", threads));
}

}  // namespace p2n

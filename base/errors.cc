#include "base/errors.h"

namespace p2n {

void ThrowInternalError(const char* file, int line, const std::string& message) {
  throw InternalError(std::string(file) + ":" + std::to_string(line) + ": " + message);
}

}  // namespace p2n

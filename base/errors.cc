#include "base/errors.h"

#include "base/format.h"

namespace p2n {

void ThrowInternalError(const char* file, int line, const std::string& message) {
  throw InternalError(std::string(file) + ":" + std::to_string(line) + ": " + message);
}

void ThrowBadField(const std::filesystem::path& file, const std::string& field, const std::string& problem) {
  throw UserError(format("'{}': {} {}", file.string(), field, problem));
}

}  // namespace p2n

#pragma once
// Integers read from JSON documents a user or a damaged file may have written. nlohmann's get<int>() casts a
// floating-point value (1e30) or an out-of-range integer without a check, which is undefined behaviour; the
// readers take integers through JsonInteger instead and refuse what it does not return.

#include <nlohmann/json.hpp>

#include <cstdint>
#include <limits>
#include <optional>
#include <type_traits>

namespace p2n {

// `value` as a T when it is a JSON integer (not a float, not a string) that T holds; otherwise nothing.
template <class T>
std::optional<T> JsonInteger(const nlohmann::json& value) {
  static_assert(std::is_integral_v<T> && sizeof(T) <= sizeof(int64_t));
  if (value.is_number_unsigned()) {
    const uint64_t n = value.get<uint64_t>();
    if (n > static_cast<uint64_t>(std::numeric_limits<T>::max())) return std::nullopt;
    return static_cast<T>(n);
  }
  if (!value.is_number_integer()) return std::nullopt;
  const int64_t n = value.get<int64_t>();
  if constexpr (std::is_signed_v<T>) {
    if (n < std::numeric_limits<T>::min() || n > std::numeric_limits<T>::max()) return std::nullopt;
  } else {
    if (n < 0 || static_cast<uint64_t>(n) > std::numeric_limits<T>::max()) return std::nullopt;
  }
  return static_cast<T>(n);
}

}  // namespace p2n

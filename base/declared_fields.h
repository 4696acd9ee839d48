#pragma once
// Structs that declare their fields once: a member template Visit(v) calls v("name", field, ...) for each field
// (the pipeline's options pass their help, unit and kind after it, pipeline/options.h; the engine's configs and
// options the name alone). From that one declaration come a field's name wherever a message needs it
// (FieldName), the checks that name the field (CheckField), and a config's JSON (FieldsToJson, ReadFields).
//
//   struct HashGridConfig {
//     static constexpr const char* kName = "hash_grid";  // messages say hash_grid.levels
//     int levels = 16;
//     template <class V> void Visit(V& v) { v("levels", levels); }
//     void Check() const { CheckField(*this, levels, levels >= 1, "must be at least 1"); }
//   };

#include <nlohmann/json.hpp>

#include <algorithm>
#include <initializer_list>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "base/json_number.h"

namespace p2n {
namespace internal {

// Finds the name Visit() gives the field at `target`.
struct FieldNameFinder {
  const void* target;
  const char* found = nullptr;
  template <class T, class... Rest>
  void operator()(const char* name, const T& field, const Rest&...) {
    if (static_cast<const void*>(&field) == target) found = name;
  }
  // The pipeline's options end with their choices, given as a braced list (pipeline/options.h).
  template <class T, class Kind>
  void operator()(const char* name, const T& field, const char*, const char*, Kind, const std::vector<std::string>&) {
    if (static_cast<const void*>(&field) == target) found = name;
  }
};

}  // namespace internal

// The name `s`'s Visit() gives its member `field`; nullptr when it declares no such field.
template <class S, class T>
const char* FieldName(const S& s, const T& field) {
  internal::FieldNameFinder finder{&field};
  const_cast<S&>(s).Visit(finder);  // a visit that only reads
  return finder.found;
}

// How a failed CheckField on a struct of type S is told: std::invalid_argument "KNAME.FIELD RULE, not VALUE" for the
// engine's configs; the pipeline's options (those with a kSection) tell the user instead (pipeline/options.h).
template <class S>
struct FieldCheckFailure {
  template <class T>
  [[noreturn]] static void Throw(const char* name, const T& value, std::string_view rule) {
    std::ostringstream message;
    message << S::kName << "." << (name ? name : "?") << " " << rule << ", not ";
    if constexpr (requires { value.transpose(); }) {
      message << value.transpose();  // an Eigen vector on one line
    } else {
      message << value;
    }
    throw std::invalid_argument(message.str());
  }
};

// Reports `field` of `s` as breaking `rule` ("must be at least 1") unless `ok` (FieldCheckFailure): for the Check()s of
// every struct that declares its fields, which name the field and never spell it.
template <class S, class T>
void CheckField(const S& s, const T& field, bool ok, std::string_view rule) {
  if (!ok) FieldCheckFailure<S>::Throw(FieldName(s, field), field, rule);
}

// Every field `s` declares, as a JSON object {name: value}.
template <class S>
nlohmann::json FieldsToJson(const S& s) {
  nlohmann::json json = nlohmann::json::object();
  const auto write = [&json](const char* name, const auto& field, const auto&...) { json[name] = field; };
  const_cast<S&>(s).Visit(write);
  return json;
}

// Reads the integer fields `s` declares (the field configs') from the JSON object `json` (a field it lacks keeps
// its value). A key that is neither a field nor in `other_keys` is refused, as is a value that is not an integer the
// field holds: std::invalid_argument naming `what` and the key (a config's reader reads every key its writer writes;
// a misspelt one must not be ignored).
template <class S>
void ReadFields(const nlohmann::json& json, S* s, std::initializer_list<const char*> other_keys,
                const std::string& what) {
  if (!json.is_object()) throw std::invalid_argument(what + " is not a JSON object");
  for (const auto& [key, value] : json.items()) {
    bool read = false;
    const auto read_field = [&, &key = key, &value = value](const char* name, auto& field, const auto&...) {
      if (key != name) return;
      using T = std::remove_reference_t<decltype(field)>;
      static_assert(std::is_integral_v<T> && !std::is_same_v<T, bool>, "ReadFields reads integer fields");
      const std::optional<T> number = JsonInteger<T>(value);
      if (!number) throw std::invalid_argument(what + ": '" + key + "' must be an integer, not " + value.dump());
      field = *number;
      read = true;
    };
    s->Visit(read_field);
    const auto is_key = [&key = key](const char* k) { return key == k; };
    if (!read && std::none_of(other_keys.begin(), other_keys.end(), is_key)) {
      throw std::invalid_argument(what + ": unknown key '" + key + "'");
    }
  }
}

// A config's writer also writes keys derived from its fields, for the reader (a network's shape). Its reader
// accepts them only as the writer writes them: throws std::invalid_argument naming the first that differs.
inline void CheckDerivedKeys(const nlohmann::json& json, const nlohmann::json& written,
                             std::initializer_list<const char*> derived, const std::string& what) {
  for (const char* key : derived) {
    if (json.contains(key) && json.at(key) != written.at(key)) {
      throw std::invalid_argument(what + ": '" + key + "' follows from the other fields (" + written.at(key).dump() +
                                  ") and cannot be set");
    }
  }
}

}  // namespace p2n

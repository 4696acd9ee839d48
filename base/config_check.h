#pragma once
// Checks of the engine's option structs (TrainerOptions::Check() and the like): each names the field and the
// rule it breaks, as the pipeline's options do, but with std::invalid_argument (nerf/ knows nothing of the
// pipeline's error types; the stages turn it into a user error).

#include <nlohmann/json.hpp>

#include <algorithm>
#include <initializer_list>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

#include "base/json_number.h"

namespace p2n {

// Throws std::invalid_argument "WHAT.FIELD must RULE, not VALUE" unless `ok`.
template <class Value>
void CheckField(bool ok, const char* what, const char* field, const char* rule, const Value& value) {
  if (ok) return;
  std::ostringstream message;
  message << what << "." << field << " must " << rule << ", not " << value;
  throw std::invalid_argument(message.str());
}

// Reads a config's integer fields from the JSON object `json` (a field it lacks keeps its value). A key that is
// neither a field nor in `other_keys` is refused, as is a value of the wrong type: std::invalid_argument
// naming `what` and the key (a config's FromJson() reads every key its ToJson() writes; a misspelt one must not
// be ignored).
inline void ReadIntFields(const nlohmann::json& json, std::initializer_list<std::pair<const char*, int*>> fields,
                          std::initializer_list<const char*> other_keys, const std::string& what) {
  if (!json.is_object()) throw std::invalid_argument(what + " is not a JSON object");
  for (const auto& [key, value] : json.items()) {
    const auto is_key = [&key = key](const char* k) { return key == k; };
    const auto field = std::find_if(fields.begin(), fields.end(), [&](const auto& f) { return is_key(f.first); });
    if (field == fields.end()) {
      if (std::none_of(other_keys.begin(), other_keys.end(), is_key)) {
        throw std::invalid_argument(what + ": unknown key '" + key + "'");
      }
    } else if (const std::optional<int> n = JsonInteger<int>(value)) {
      *field->second = *n;
    } else {
      throw std::invalid_argument(what + ": '" + key + "' must be an integer, not " + value.dump());
    }
  }
}

// A config's ToJson() also writes keys derived from its fields, for the reader (a network's shape). FromJson()
// accepts them only as ToJson() writes them: throws std::invalid_argument naming the first that differs.
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

#include "pipeline/options.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>

#include "base/errors.h"
#include "base/format.h"

namespace p2n {
namespace {

size_t EditDistance(std::string_view a, std::string_view b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diagonal = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t substitution = diagonal + (a[i - 1] == b[j - 1] ? 0 : 1);
      diagonal = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, substitution});
    }
  }
  return row[b.size()];
}

std::string TypeName(const nlohmann::json& value) {
  if (value.is_boolean()) return "true or false";
  if (value.is_number_integer()) return "an integer";
  if (value.is_number()) return "a number";
  return "a string";
}

template <class T>
bool ParseNumber(std::string_view text, T* value) {
  const char* end = text.data() + text.size();
  auto [ptr, error] = std::from_chars(text.data(), end, *value);
  return error == std::errc() && ptr == end;
}

std::string UnknownKeyMessage(const OptionRegistry& registry, std::string_view key, std::string_view origin) {
  std::string message = format("unknown option '{}' (from {})", key, origin);
  const std::string suggestion = registry.Suggest(key);
  if (!suggestion.empty()) message += format("; did you mean '{}'?", suggestion);
  return message + "; `photo2nerf run --help` lists every option";
}

}  // namespace

void OptionRegistry::Add(OptionSpec spec) {
  P2N_CHECK(spec.key.find('.') != std::string::npos, "option key without a section: " + spec.key);
  P2N_CHECK(Find(spec.key) == nullptr, "option registered twice: " + spec.key);
  specs_.push_back(std::move(spec));
}

const OptionSpec* OptionRegistry::Find(std::string_view key) const {
  for (const OptionSpec& spec : specs_) {
    if (spec.key == key) return &spec;
  }
  return nullptr;
}

std::string OptionRegistry::Suggest(std::string_view key) const {
  std::string best;
  size_t best_distance = std::max<size_t>(3, key.size() / 3) + 1;
  for (const OptionSpec& spec : specs_) {
    const size_t distance = EditDistance(key, spec.key);
    if (distance < best_distance) {
      best_distance = distance;
      best = spec.key;
    }
  }
  return best;
}

Config::Config(const OptionRegistry& registry) : registry_(&registry), values_(nlohmann::json::object()) {
  for (const OptionSpec& spec : registry.specs()) values_[spec.key] = spec.default_value;
}

void Config::Set(std::string_view key, const nlohmann::json& value, std::string_view origin) {
  const OptionSpec* spec = registry_->Find(key);
  if (spec == nullptr) throw UserError(UnknownKeyMessage(*registry_, key, origin));
  const nlohmann::json& expected = spec->default_value;
  if (expected.is_boolean() && value.is_string()) {  // "on" in a config file, as on a command line
    return SetFromText(key, value.get<std::string>(), origin);
  }
  const bool type_ok = (expected.is_boolean() && value.is_boolean()) ||
                       (expected.is_number_integer() && value.is_number_integer()) ||
                       (expected.is_number_float() && value.is_number()) || (expected.is_string() && value.is_string());
  if (!type_ok) {
    throw UserError(format("option '{}' (from {}) must be {}, not {}", key, origin, TypeName(expected), value.dump()));
  }
  if (!spec->choices.empty() &&
      std::find(spec->choices.begin(), spec->choices.end(), value.get<std::string>()) == spec->choices.end()) {
    std::string allowed;
    for (const std::string& choice : spec->choices) allowed += (allowed.empty() ? "" : ", ") + choice;
    throw UserError(
        format("option '{}' (from {}) must be one of: {}; got '{}'", key, origin, allowed, value.get<std::string>()));
  }
  origins_[std::string(key)] = origin;
  values_[std::string(key)] = expected.is_number_float() ? nlohmann::json(value.get<double>()) : value;
}

void Config::Unset(std::string_view key) {
  const OptionSpec* spec = registry_->Find(key);
  if (spec == nullptr) throw InternalError(format("Config::Unset: no option {}", key));
  values_[spec->key] = spec->default_value;
  origins_.erase(spec->key);
}

std::string Config::Origin(std::string_view key) const {
  const auto found = origins_.find(key);
  return found == origins_.end() ? std::string() : found->second;
}

void Config::SetFromText(std::string_view key, std::string_view text, std::string_view origin) {
  const OptionSpec* spec = registry_->Find(key);
  if (spec == nullptr) throw UserError(UnknownKeyMessage(*registry_, key, origin));
  const nlohmann::json& expected = spec->default_value;
  const auto bad_value = [&] {
    return UserError(format("option '{}' (from {}) must be {}, not '{}'", key, origin, TypeName(expected), text));
  };
  if (expected.is_boolean()) {
    if (text == "true" || text == "1" || text == "yes" || text == "on") return Set(key, true, origin);
    if (text == "false" || text == "0" || text == "no" || text == "off") return Set(key, false, origin);
    throw bad_value();
  }
  if (expected.is_number_integer()) {
    int64_t value = 0;
    if (!ParseNumber(text, &value)) throw bad_value();
    return Set(key, value, origin);
  }
  if (expected.is_number_float()) {
    double value = 0;
    if (!ParseNumber(text, &value) || !std::isfinite(value)) throw bad_value();
    return Set(key, value, origin);
  }
  Set(key, std::string(text), origin);
}

void Config::Merge(const nlohmann::json& object, std::string_view origin,
                   const std::function<void(const UserError&)>& refused) {
  if (!object.is_object()) throw UserError(format("{}: expected a JSON object of options", origin));
  const auto set = [&](const std::string& key, const nlohmann::json& value) {
    try {
      Set(key, value, origin);
    } catch (const UserError& e) {
      if (!refused) throw;
      refused(e);
    }
  };
  for (const auto& [name, value] : object.items()) {
    if (!value.is_object()) {
      set(name, value);
      continue;
    }
    for (const auto& [sub_name, sub_value] : value.items()) {
      if (sub_value.is_object()) {
        throw UserError(format("{}: option '{}.{}' is nested too deeply", origin, name, sub_name));
      }
      set(name + "." + sub_name, sub_value);
    }
  }
}

void Config::MergeFile(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw UserError(format("cannot read config file '{}'", path.string()));
  nlohmann::json object;
  try {
    object = nlohmann::json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    throw UserError(format("config file '{}' is not valid JSON: {}", path.string(), e.what()));
  }
  Merge(object, path.string());
}

const nlohmann::json& Config::Get(std::string_view key) const {
  const auto it = values_.find(std::string(key));
  P2N_CHECK(it != values_.end(), "option not registered: " + std::string(key));
  return *it;
}

nlohmann::json Config::ResultOptions(std::string_view section) const {
  nlohmann::json result = nlohmann::json::object();
  const std::string prefix = std::string(section) + ".";
  for (const OptionSpec& spec : registry_->specs()) {
    if (spec.kind != OptionKind::kResult || spec.key.rfind(prefix, 0) != 0) continue;
    if (Get(spec.key) != spec.default_value) result[spec.key] = Get(spec.key);
  }
  return result;
}

nlohmann::json Config::ToJson() const {
  nlohmann::json nested = nlohmann::json::object();
  for (const OptionSpec& spec : registry_->specs()) {
    const size_t dot = spec.key.find('.');
    nested[spec.key.substr(0, dot)][spec.key.substr(dot + 1)] = Get(spec.key);
  }
  return nested;
}

nlohmann::json Config::ExplicitResultOptions() const {
  nlohmann::json nested = nlohmann::json::object();
  for (const auto& [key, origin] : origins_) {
    if (registry_->Find(key)->kind == OptionKind::kRuntime) continue;
    const size_t dot = key.find('.');
    nested[key.substr(0, dot)][key.substr(dot + 1)] = Get(key);
  }
  return nested;
}

bool ParseAutoOrNumber(const std::string& text, std::optional<double>* value) {
  value->reset();
  if (text == "auto") return true;
  try {
    size_t end = 0;
    const double number = std::stod(text, &end);
    if (end != text.size() || !std::isfinite(number)) return false;
    *value = number;
    return true;
  } catch (const std::exception&) {  // not a number, or out of range
    return false;
  }
}

std::string AutoOrNumberText(const AutoOrNumber& option) {
  return option.value ? nlohmann::json(*option.value).dump() : "auto";
}

std::string OptionKeyOf(std::string_view section, const char* name) {
  if (name == nullptr) throw InternalError(format("OptionKey: a field that is not one of the {} options", section));
  return std::string(section).append(".").append(name);
}

OptionError::OptionError(std::string_view key, std::string_view rule)
    : UserError(format("option {} {}", key, rule)), key_(key), rule_(rule) {}

void FailOption(std::string_view key, std::string_view rule) { throw OptionError(key, rule); }

}  // namespace p2n

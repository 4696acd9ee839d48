#pragma once
// Options addressable by dotted keys (`ingest.max_image_size`), from the command line and from JSON config
// files (docs/design.md §4). Each configurable unit keeps one plain XxxOptions struct with a default and a comment
// on every field, and a member template Visit() that names its fields once:
//
//   struct IngestOptions {
//     static constexpr const char* kSection = "ingest";  // its options are ingest.NAME
//     int max_image_size = 0;  // Longest side in pixels after downscaling; 0 keeps the full size.
//     template <class V> void Visit(V& v) {
//       v("max_image_size", max_image_size, "longest image side after downscaling; 0 keeps it", "px");
//     }
//     void Check() const;  // CheckField(*this, max_image_size, rule holds, "must ..."): UserError naming the key
//   };
//
// A field is a bool, a number, a string, an enum with EnumNames (base/enum_names.h: its names are the option's
// choices) or an AutoOrNumber. RegisterOptions<IngestOptions>(registry, "ingest") declares the keys with the
// struct's defaults; ReadOptions<IngestOptions>(config) fills a struct from a resolved Config and checks it;
// OptionKey names a field's key wherever a message needs it.

#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "base/declared_fields.h"
#include "base/enum_names.h"
#include "base/errors.h"

namespace p2n {

// kResult options change a stage's output: the cache key holds those set to other than their defaults (so an
// option added later does not make old results stale; a stage whose output changes with a default bumps its
// format version). kCheck options are pass/fail thresholds on a result (ingest.min_images): remembered in the
// workspace, never in a key, applied to fresh results too (Stage::CheckResult). kRuntime ones (threads, log
// level, progress display) change nothing in any result and are not remembered.
enum class OptionKind { kResult, kCheck, kRuntime };
template <>
struct EnumNames<OptionKind> {
  static constexpr std::pair<OptionKind, const char*> kValues[] = {
      {OptionKind::kResult, "result"}, {OptionKind::kCheck, "check"}, {OptionKind::kRuntime, "runtime"}};
};

struct OptionSpec {
  std::string key;               // dotted: "section.name"
  nlohmann::json default_value;  // its JSON type is the option's type (integer, number, boolean, string)
  std::string help;              // one line
  std::string unit;              // "px", "s", "images", or empty
  OptionKind kind = OptionKind::kResult;
  std::vector<std::string> choices;  // allowed values of a string option; empty means any
};

class OptionRegistry {
 public:
  // Throws InternalError on a duplicate key or a key without a section.
  void Add(OptionSpec spec);
  const OptionSpec* Find(std::string_view key) const;
  const std::vector<OptionSpec>& specs() const { return specs_; }
  // The registered key closest to `key` (for "did you mean"), or "" when none is close.
  std::string Suggest(std::string_view key) const;

 private:
  std::vector<OptionSpec> specs_;
};

// A resolved configuration: every registered key with its value (defaults until set).
class Config {
 public:
  explicit Config(const OptionRegistry& registry);

  // Sets one option. `origin` names where the value came from ("--ingest.max_image_size", "cfg.json").
  // Throws UserError for an unknown key (with a suggestion), a wrong type or a value outside the choices.
  void Set(std::string_view key, const nlohmann::json& value, std::string_view origin);
  // Parses `text` as the option's type (as typed on a command line) and sets it.
  void SetFromText(std::string_view key, std::string_view text, std::string_view origin);
  // Merges a JSON object, nested ({"ingest": {"max_image_size": 800}}) or flat ("ingest.max_image_size"). An
  // option Set refuses (an unknown key, a wrong type or choice) throws its UserError, or with `refused` is left out
  // and passed to it.
  void Merge(const nlohmann::json& object, std::string_view origin,
             const std::function<void(const UserError&)>& refused = nullptr);
  // Merges a JSON config file; UserError naming the file on a parse error or an unknown key.
  void MergeFile(const std::filesystem::path& path);

  // Puts an option back to its default, as if it had not been set.
  void Unset(std::string_view key);
  // Where an option's value came from (Set's `origin`); empty for a default.
  std::string Origin(std::string_view key) const;

  const nlohmann::json& Get(std::string_view key) const;
  template <class T>
  T Get(std::string_view key) const {
    return Get(key).get<T>();
  }

  // Flat {"section.name": value} of the section's kResult options not at their defaults (what a cache key holds).
  nlohmann::json ResultOptions(std::string_view section) const;
  // Nested {"section": {"name": value}} of every option (the resolved config written beside results).
  nlohmann::json ToJson() const;
  // Nested, the kResult and kCheck options that were set (not left at their defaults): what a workspace remembers.
  nlohmann::json ExplicitResultOptions() const;
  const OptionRegistry& registry() const { return *registry_; }

 private:
  const OptionRegistry* registry_;
  nlohmann::json values_;                                    // flat: dotted key -> value
  std::map<std::string, std::string, std::less<>> origins_;  // of the options set: explicit
};

// An option that is "auto" or a number (train.distortion, render.elevation): the number, or nothing for auto.
// Given as text ("auto", "0.01"); reading it refuses other text, naming the key.
struct AutoOrNumber {
  std::optional<double> value;
};

// An "auto or a number" option's text: *value is nothing for "auto", else the number the whole text is. False when
// it is neither.
bool ParseAutoOrNumber(const std::string& text, std::optional<double>* value);
std::string AutoOrNumberText(const AutoOrNumber& option);
// A value an option's rule refuses ("option KEY RULE"), with its key and rule apart: whoever resolved the
// configuration knows where the value came from (Config::Origin) and can say so.
class OptionError : public UserError {
 public:
  OptionError(std::string_view key, std::string_view rule);
  const std::string& key() const { return key_; }
  const std::string& rule() const { return rule_; }

 private:
  std::string key_, rule_;
};
// Throws OptionError.
[[noreturn]] void FailOption(std::string_view key, std::string_view rule);

namespace internal {

struct RegisterVisitor {
  OptionRegistry& registry;
  std::string_view section;
  template <class T>
  void operator()(const char* name, const T& field, const char* help, const char* unit = "",
                  OptionKind kind = OptionKind::kResult, std::vector<std::string> choices = {}) {
    std::string key = std::string(section).append(".").append(name);
    if constexpr (std::is_enum_v<T>) {
      registry.Add({std::move(key), EnumName(field), help, unit, kind, EnumNameList<T>()});
    } else if constexpr (std::is_same_v<T, AutoOrNumber>) {
      registry.Add({std::move(key), AutoOrNumberText(field), help, unit, kind, std::move(choices)});
    } else {
      registry.Add({std::move(key), nlohmann::json(field), help, unit, kind, std::move(choices)});
    }
  }
};

struct ReadVisitor {
  const Config& config;
  std::string_view section;
  template <class T>
  void operator()(const char* name, T& field, const char*, const char* = "", OptionKind = OptionKind::kResult,
                  const std::vector<std::string>& = {}) {
    const std::string key = std::string(section).append(".").append(name);
    if constexpr (std::is_enum_v<T>) {
      field = *EnumFromName<T>(config.Get<std::string>(key));  // Config::Set allows the names alone
    } else if constexpr (std::is_same_v<T, AutoOrNumber>) {
      const std::string text = config.Get<std::string>(key);
      if (!ParseAutoOrNumber(text, &field.value)) {
        FailOption(key, std::string("must be auto or a number, not '").append(text).append("'"));
      }
    } else {
      field = config.Get<T>(key);
    }
  }
};

}  // namespace internal

template <class Options>
void RegisterOptions(OptionRegistry& registry, std::string_view section) {
  Options defaults;
  internal::RegisterVisitor visitor{registry, section};
  defaults.Visit(visitor);
}

template <class Options>
Options ReadOptions(const Config& config, std::string_view section) {
  Options options;
  internal::ReadVisitor visitor{config, section};
  options.Visit(visitor);
  options.Check();
  return options;
}

template <class Options>
Options ReadOptions(const Config& config) {
  return ReadOptions<Options>(config, Options::kSection);
}

// The dotted key of `field`, a member of `options`, from the struct's declaration: in TrainOptions::Check(),
// OptionKey(*this, steps) is "train.steps". InternalError when `field` is not one of its options.
std::string OptionKeyOf(std::string_view section, const char* name);
template <class Options, class T>
std::string OptionKey(const Options& options, const T& field) {
  return OptionKeyOf(Options::kSection, FieldName(options, field));
}
// The key of a member: OptionKey(&SfmOptions::colmap) is "sfm.colmap".
template <class Options, class T>
std::string OptionKey(T Options::*member) {
  Options options;
  return OptionKey(options, options.*member);
}

// A failed CheckField (base/declared_fields.h) on options: OptionError "option KEY RULE", a user's error.
template <class Options>
requires requires { Options::kSection; }
struct FieldCheckFailure<Options> {
  template <class T>
  [[noreturn]] static void Throw(const char* name, const T&, std::string_view rule) {
    FailOption(OptionKeyOf(Options::kSection, name), rule);
  }
};

}  // namespace p2n

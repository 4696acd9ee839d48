#pragma once
// Options addressable by dotted keys (`ingest.max_image_size`), from the command line and from JSON config
// files (DESIGN.md §4). Each configurable unit keeps one plain XxxOptions struct with a default and a comment
// on every field, and a member template Visit() that names its fields once:
//
//   struct IngestOptions {
//     int max_image_size = 0;  // Longest side in pixels after downscaling; 0 keeps the full size.
//     template <class V> void Visit(V& v) {
//       v("max_image_size", max_image_size, "longest image side after downscaling; 0 keeps it", "px");
//     }
//     void Check() const;  // throws UserError naming the field and the rule
//   };
//
// RegisterOptions<IngestOptions>(registry, "ingest") declares the keys with the struct's defaults;
// ReadOptions<IngestOptions>(config, "ingest") fills a struct from a resolved Config and checks it. A struct that
// names its section (static constexpr const char* kSection = "ingest") is read with ReadOptions<IngestOptions>(config).

#include <nlohmann/json.hpp>

#include <filesystem>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

namespace p2n {

// kResult options change a stage's output: the cache key holds those set to other than their defaults (so an
// option added later does not make old results stale; a stage whose output changes with a default bumps its
// format version). kCheck options are pass/fail thresholds on a result (ingest.min_images): remembered in the
// workspace, never in a key, applied to fresh results too (Stage::CheckResult). kRuntime ones (threads, log
// level, progress display) change nothing in any result and are not remembered.
enum class OptionKind { kResult, kCheck, kRuntime };

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
  // Merges a JSON object, nested ({"ingest": {"max_image_size": 800}}) or flat ("ingest.max_image_size").
  void Merge(const nlohmann::json& object, std::string_view origin);
  // Merges a JSON config file; UserError naming the file on a parse error or an unknown key.
  void MergeFile(const std::filesystem::path& path);

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
  nlohmann::json values_;  // flat: dotted key -> value
  std::set<std::string> explicit_keys_;
};

namespace internal {

struct RegisterVisitor {
  OptionRegistry& registry;
  std::string_view section;
  template <class T>
  void operator()(const char* name, const T& field, const char* help, const char* unit = "",
                  OptionKind kind = OptionKind::kResult, std::vector<std::string> choices = {}) {
    registry.Add({std::string(section) + "." + name, nlohmann::json(field), help, unit, kind, std::move(choices)});
  }
};

struct ReadVisitor {
  const Config& config;
  std::string_view section;
  template <class T>
  void operator()(const char* name, T& field, const char*, const char* = "", OptionKind = OptionKind::kResult,
                  const std::vector<std::string>& = {}) {
    field = config.Get<T>(std::string(section) + "." + name);
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

// An "auto or a number" option's text (train.distortion, render.elevation): *value is nothing for "auto", else the
// number the whole text is. False when it is neither.
bool ParseAutoOrNumber(const std::string& text, std::optional<double>* value);

// Throws UserError "option KEY RULE" when `condition` is false; for XxxOptions::Check().
void CheckOption(bool condition, std::string_view key, std::string_view rule);

}  // namespace p2n

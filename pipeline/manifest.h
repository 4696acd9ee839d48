#pragma once
// The cache key of a stage and the manifest that records it (docs/design.md §2: by content, never by existence).

#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace p2n {

// Everything a stage's result depends on.
struct KeyInputs {
  std::string stage;
  int format_version = 0;
  nlohmann::json options = nlohmann::json::object();  // {"section.name": value} of the result options
  std::map<std::string, std::string> upstream_keys;   // upstream stage -> its key
  std::map<std::string, std::string> inputs;          // external input label -> fingerprint

  // A stable SHA-1 over all fields (options as canonical JSON: sorted keys, round-trip doubles).
  std::string Key() const;
};

// Why a result made from `before` is not valid for `now`, in words ("option ingest.max_image_size changed
// (0 -> 800)", "upstream ingest changed", "input image 0042.jpg changed", "format version 1 -> 2").
std::vector<std::string> DescribeChanges(const KeyInputs& before, const KeyInputs& now);

struct OutputFile {
  std::string path;  // relative to the stage folder, '/'-separated
  uint64_t size = 0;
  std::string sha1;
};

struct Manifest {
  KeyInputs inputs;
  std::string key;
  std::string photo2nerf_version;
  std::string finished_utc;
  double wall_seconds = 0;
  nlohmann::json summary = nlohmann::json::object();
  std::vector<OutputFile> outputs;
  // Upstream stage -> OutputsDigest of the result it read. A stage rerun alone (`train --force`) keeps its key
  // but may make another result (a time budget); what read the old one is stale then. Empty in manifests
  // written before this was recorded: their upstream results are not checked.
  std::map<std::string, std::string> upstream_results;

  nlohmann::json ToJson() const;
  // UserError naming `source` when a field is missing or of the wrong type.
  static Manifest FromJson(const nlohmann::json& json, const std::string& source);
};

inline constexpr const char* kManifestName = "manifest.json";
inline constexpr const char* kConfigName = "config.json";  // the whole configuration a stage ran with

// A SHA-1 over the listed files' paths, sizes and SHA-1s but the configuration's: equal for equal results, whatever
// runtime options (threads, logging) they were made with.
std::string OutputsDigest(const std::vector<OutputFile>& outputs);

// Every file below `folder` (but the manifest), sorted, with sizes and SHA-1s (hashed in parallel).
std::vector<OutputFile> ListOutputs(const std::filesystem::path& folder);
// The outputs that are missing or whose size differs (a cheap check; contents are not re-hashed).
std::vector<std::string> ChangedOutputs(const std::filesystem::path& folder, const std::vector<OutputFile>& outputs);

}  // namespace p2n

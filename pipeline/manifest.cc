#include "pipeline/manifest.h"

#include <algorithm>
#include <optional>
#include <set>

#include "base/errors.h"
#include "base/format.h"
#include "base/json_number.h"
#include "pipeline/hash.h"

namespace p2n {
namespace fs = std::filesystem;
namespace {

std::string Short(const nlohmann::json& value) {
  std::string text = value.dump();
  return text.size() > 40 ? text.substr(0, 37) + "..." : text;
}

// Reports added, removed and changed entries of two maps with the given noun ("input", "upstream").
template <class Map, class Describe>
void CompareMaps(const Map& before, const Map& now, const std::string& noun, Describe describe_change,
                 std::vector<std::string>* reasons) {
  for (const auto& [label, value] : now) {
    const auto it = before.find(label);
    if (it == before.end()) {
      reasons->push_back(format("{} {} added", noun, label));
    } else if (it->second != value) {
      reasons->push_back(describe_change(label, it->second, value));
    }
  }
  for (const auto& [label, value] : before) {
    if (now.find(label) == now.end()) reasons->push_back(format("{} {} removed", noun, label));
  }
}

[[noreturn]] void Damaged(const std::string& source, const std::string& what) {
  throw UserError(format("manifest '{}' is damaged ({}); rerun the stage with --force", source, what));
}

template <class T>
T Integer(const nlohmann::json& value, const char* field, const std::string& source) {
  const std::optional<T> n = JsonInteger<T>(value);
  if (!n) Damaged(source, format("{} is not a whole number in range: {}", field, Short(value)));
  return *n;
}

}  // namespace

std::string KeyInputs::Key() const {
  Hasher hasher;
  hasher.Field("photo2nerf stage key v1").Field(stage).Field(int64_t{format_version}).Field(options.dump());
  hasher.Field(static_cast<int64_t>(upstream_keys.size()));
  for (const auto& [name, key] : upstream_keys) hasher.Field(name).Field(key);
  hasher.Field(static_cast<int64_t>(inputs.size()));
  for (const auto& [label, fingerprint] : inputs) hasher.Field(label).Field(fingerprint);
  return hasher.HexDigest();
}

std::vector<std::string> DescribeChanges(const KeyInputs& before, const KeyInputs& now) {
  std::vector<std::string> reasons;
  if (before.format_version != now.format_version) {
    reasons.push_back(format("format version {} -> {}", before.format_version, now.format_version));
  }
  // The key holds only options set to other than their defaults: one missing on a side is at its default there.
  std::set<std::string> keys;
  for (const auto& [key, value] : before.options.items()) keys.insert(key);
  for (const auto& [key, value] : now.options.items()) keys.insert(key);
  const auto value_text = [](const nlohmann::json& options, const std::string& key) {
    return options.contains(key) ? Short(options[key]) : std::string("default");
  };
  for (const std::string& key : keys) {
    if (before.options.value(key, nlohmann::json()) == now.options.value(key, nlohmann::json())) continue;
    reasons.push_back(
        format("option {} changed ({} -> {})", key, value_text(before.options, key), value_text(now.options, key)));
  }
  CompareMaps(
      before.upstream_keys, now.upstream_keys, "upstream",
      [](const std::string& name, const std::string&, const std::string&) {
        return format("upstream {} changed", name);
      },
      &reasons);
  CompareMaps(
      before.inputs, now.inputs, "input",
      [](const std::string& label, const std::string&, const std::string&) {
        return format("input {} changed", label);
      },
      &reasons);
  return reasons;
}

nlohmann::json Manifest::ToJson() const {
  nlohmann::json files = nlohmann::json::array();
  for (const OutputFile& file : outputs)
    files.push_back({{"path", file.path}, {"size", file.size}, {"sha1", file.sha1}});
  return {{"stage", inputs.stage},
          {"format_version", inputs.format_version},
          {"key", key},
          {"options", inputs.options},
          {"upstream", inputs.upstream_keys},
          {"inputs", inputs.inputs},
          {"photo2nerf_version", photo2nerf_version},
          {"finished_utc", finished_utc},
          {"wall_seconds", wall_seconds},
          {"summary", summary},
          {"outputs", files},
          {"upstream_results", upstream_results}};
}

Manifest Manifest::FromJson(const nlohmann::json& json, const std::string& source) {
  Manifest manifest;
  try {
    manifest.inputs.stage = json.at("stage").get<std::string>();
    manifest.inputs.format_version = Integer<int>(json.at("format_version"), "format_version", source);
    manifest.inputs.options = json.at("options");
    manifest.inputs.upstream_keys = json.at("upstream").get<std::map<std::string, std::string>>();
    manifest.inputs.inputs = json.at("inputs").get<std::map<std::string, std::string>>();
    manifest.key = json.at("key").get<std::string>();
    manifest.photo2nerf_version = json.value("photo2nerf_version", "");
    manifest.finished_utc = json.value("finished_utc", "");
    manifest.wall_seconds = json.value("wall_seconds", 0.0);
    manifest.summary = json.value("summary", nlohmann::json::object());
    if (json.contains("upstream_results"))
      manifest.upstream_results = json.at("upstream_results").get<std::map<std::string, std::string>>();
    for (const nlohmann::json& file : json.at("outputs")) {
      manifest.outputs.push_back({file.at("path").get<std::string>(),
                                  Integer<uint64_t>(file.at("size"), "outputs[].size", source),
                                  file.at("sha1").get<std::string>()});
    }
  } catch (const nlohmann::json::exception& e) {
    Damaged(source, e.what());
  }
  if (!manifest.inputs.options.is_object()) Damaged(source, "options is not an object");
  return manifest;
}

std::vector<OutputFile> ListOutputs(const fs::path& folder) {
  std::vector<OutputFile> outputs;
  for (const fs::directory_entry& entry : fs::recursive_directory_iterator(folder)) {
    if (!entry.is_regular_file()) continue;
    const std::string relative = fs::relative(entry.path(), folder).generic_string();
    if (relative == kManifestName) continue;
    outputs.push_back({relative, entry.file_size(), ""});
  }
  std::sort(outputs.begin(), outputs.end(), [](const OutputFile& a, const OutputFile& b) { return a.path < b.path; });
  std::vector<std::filesystem::path> paths;
  for (const OutputFile& file : outputs) paths.push_back(folder / file.path);
  const std::vector<std::string> digests = Sha1OfFiles(paths);
  for (size_t i = 0; i < outputs.size(); ++i) outputs[i].sha1 = digests[i];
  return outputs;
}

std::string OutputsDigest(const std::vector<OutputFile>& outputs) {
  Hasher hasher;
  hasher.Field("photo2nerf outputs v1");
  for (const OutputFile& file : outputs) {
    if (file.path != kConfigName) hasher.Field(file.path).Field(static_cast<int64_t>(file.size)).Field(file.sha1);
  }
  return hasher.HexDigest();
}

std::vector<std::string> ChangedOutputs(const fs::path& folder, const std::vector<OutputFile>& outputs) {
  std::vector<std::string> changed;
  for (const OutputFile& file : outputs) {
    std::error_code error;
    const uintmax_t size = fs::file_size(folder / file.path, error);
    if (error || size != file.size) changed.push_back(file.path);
  }
  return changed;
}

}  // namespace p2n

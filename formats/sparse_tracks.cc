#include "formats/sparse_tracks.h"

#include <cmath>
#include <set>

#include <nlohmann/json.hpp>

#include "base/errors.h"
#include "base/file_util.h"
#include "base/format.h"

namespace p2n {
namespace fs = std::filesystem;
namespace {

[[noreturn]] void BadTracks(const fs::path& file, const std::string& field, const std::string& problem) {
  ThrowBadField(file, field, problem + "; rerun the poses stage");
}

}  // namespace

void SparseTracks::Write(const fs::path& path) const {
  nlohmann::json json;
  json["errors"] = errors;
  json["views"] = nlohmann::json::array();
  for (const SparseTrackView& view : views)
    json["views"].push_back({{"file_path", view.file_path}, {"points", view.points}});
  WriteJsonAtomic(path, json);
}

SparseTracks SparseTracks::Read(const fs::path& path) {
  const nlohmann::json json = ReadJsonFile(path);
  SparseTracks tracks;
  try {
    if (!json.is_object()) BadTracks(path, "the file", "must be a JSON object");
    if (!json.contains("errors") || !json["errors"].is_array()) BadTracks(path, "errors", "must be an array of pixels");
    for (const nlohmann::json& error : json["errors"]) {
      if (!error.is_number() || !(error.get<double>() >= 0) || !std::isfinite(error.get<double>()))
        BadTracks(path, format("errors[{}]", tracks.errors.size()), "must be a finite number of pixels, at least 0");
      tracks.errors.push_back(error.get<float>());
    }
    if (!json.contains("views") || !json["views"].is_array()) BadTracks(path, "views", "must be an array");
    std::set<std::string> seen;
    for (const nlohmann::json& entry : json["views"]) {
      const std::string field = format("views[{}]", tracks.views.size());
      if (!entry.is_object() || !entry.contains("file_path") || !entry["file_path"].is_string())
        BadTracks(path, field, "must have a file_path");
      SparseTrackView view;
      view.file_path = entry["file_path"].get<std::string>();
      if (!seen.insert(view.file_path).second)
        BadTracks(path, field, format("names '{}' a second time", view.file_path));
      if (!entry.contains("points") || !entry["points"].is_array())
        BadTracks(path, field + ".points", "must be an array");
      for (const nlohmann::json& point : entry["points"]) {
        if (!point.is_number_unsigned() || point.get<uint64_t>() >= tracks.errors.size())
          BadTracks(path, field + ".points", format("must hold indices below the {} points", tracks.errors.size()));
        view.points.push_back(point.get<uint32_t>());
      }
      tracks.views.push_back(std::move(view));
    }
  } catch (const nlohmann::json::exception& e) {
    BadTracks(path, "the file", format("does not have the expected layout: {}", e.what()));
  }
  return tracks;
}

const std::vector<uint32_t>& SparseTracks::PointsOf(const std::string& file_path) const {
  static const std::vector<uint32_t> kNone;
  for (const SparseTrackView& view : views) {
    if (view.file_path == file_path) return view.points;
  }
  return kNone;
}

}  // namespace p2n

#pragma once
// sparse_tracks.json beside sparse_points.ply: which views see each sparse point, and how well the structure from
// motion placed it. Free depth for those views' pixels (the train stage's depth loss, docs/design.md §6).
//
//   {"errors": [px, ...],                                    one per point of sparse_points.ply, in its order
//    "views": [{"file_path": "...", "points": [i, ...]}, ...]}  transforms.json's views, each with the points it sees

#include <filesystem>
#include <string>
#include <vector>

namespace p2n {

struct SparseTrackView {
  std::string file_path;         // as transforms.json names the view
  std::vector<uint32_t> points;  // indices into sparse_points.ply
};

struct SparseTracks {
  std::vector<float> errors;  // each point's mean reprojection error, pixels
  std::vector<SparseTrackView> views;

  // Throws UserError naming the file when it cannot be written.
  void Write(const std::filesystem::path& path) const;
  // UserError naming the file and the field: malformed, a negative or non-finite error, a point index past the
  // errors, a view twice.
  static SparseTracks Read(const std::filesystem::path& path);
  // The points `file_path` sees; empty when no view has that path.
  const std::vector<uint32_t>& PointsOf(const std::string& file_path) const;
};

}  // namespace p2n

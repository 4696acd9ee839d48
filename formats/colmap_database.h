#pragma once
// COLMAP's database (database.db, SQLite): the images' names and SIFT descriptors read, raw feature matches
// written, in COLMAP's layout (docs/design.md §7), so that COLMAP's own matchers find the matches there and only verify
// them. Errors name the database and the record and are ExternalToolError: COLMAP wrote the file.

#include <Eigen/Core>

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

struct sqlite3;

namespace p2n {

// One descriptor a column: COLMAP stores a feature's 128 bytes in a row, which is this matrix's column.
using SiftDescriptors = Eigen::Matrix<uint8_t, 128, Eigen::Dynamic>;

// (feature index in the first image, feature index in the second).
using FeatureMatches = std::vector<std::pair<uint32_t, uint32_t>>;

struct ColmapDatabaseImage {
  uint32_t id = 0;
  std::string name;
};

// A pair COLMAP's geometric verification kept, with its number of inlier matches.
struct VerifiedPair {
  uint32_t image_id1 = 0, image_id2 = 0;
  size_t inliers = 0;
};

class ColmapDatabase {
 public:
  // Opens an existing database for reading and writing, or for reading alone (while others read it too);
  // ExternalToolError when it cannot.
  explicit ColmapDatabase(const std::filesystem::path& path, bool read_only = false);
  ~ColmapDatabase();
  ColmapDatabase(const ColmapDatabase&) = delete;
  ColmapDatabase& operator=(const ColmapDatabase&) = delete;

  // Every image, by name.
  std::vector<ColmapDatabaseImage> Images() const;
  // An image's descriptors (none when it has no row); ExternalToolError when the row is not rows x 128 bytes.
  SiftDescriptors Descriptors(uint32_t image_id) const;
  // Each image's number of features, by image id (none for an image without a row).
  std::map<uint32_t, size_t> FeatureCounts() const;
  // The pairs with inlier matches after geometric verification.
  std::vector<VerifiedPair> VerifiedPairs() const;
  // Whether the pair has a row of raw matches (in either order).
  bool HasMatches(uint32_t image_id1, uint32_t image_id2) const;
  // Appends the images of the database `other` as COLMAP's feature_extractor wrote it (cameras, images, keypoints,
  // descriptors: matches are not copied), their ids after this one's, in their order: with their own cameras, or
  // all on this database's `camera` when given. Returns the id of the first camera they were given. Written for
  // the blocks of photos extracted apart (sfm stage): a block of a shared camera's photos makes a camera of the same
  // size as the others' blocks, and the first block's stands for all, as one extraction would make.
  uint32_t AppendImages(const std::filesystem::path& other, std::optional<uint32_t> camera);
  // Appends the raw matches of the database `other` and COLMAP's verification of them (a block of pairs of the
  // same images matched and verified apart, CreateBlock).
  void AppendMatches(const std::filesystem::path& other);
  // A new database at `path` with the tables of `database` (COLMAP's, whatever its version), its cameras, its
  // images named by their ids, and the keypoints of the images `image_ids`: what COLMAP needs to verify matches of
  // those images made apart and written there (AppendMatches), listed by the ids (which hold no spaces).
  static void CreateBlock(const std::filesystem::path& database, const std::filesystem::path& path,
                          const std::vector<uint32_t>& image_ids);
  // Writes the pairs' raw matches (COLMAP's pair id and order: the smaller image id first) in one transaction.
  void WriteMatches(const std::vector<std::pair<std::pair<uint32_t, uint32_t>, FeatureMatches>>& pairs);

 private:
  // Attaches the database `other` as "part".
  void Attach(const std::filesystem::path& other);

  std::filesystem::path path_;
  sqlite3* db_ = nullptr;
};

// COLMAP's id of an unordered image pair.
uint64_t ColmapPairId(uint32_t image_id1, uint32_t image_id2);

}  // namespace p2n

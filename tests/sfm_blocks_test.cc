// Feature extraction and matching in blocks (the sfm stage's parts under a scheduler): the blocks' plan, and their
// databases merged into what one extraction, or one matching and verification, writes, with COLMAP itself.

#include <sqlite3.h>

#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdlib>
#include <functional>
#include <map>
#include <set>

#include "base/file_util.h"
#include "base/format.h"
#include "examples/synthetic_scene.h"
#include "stages/sfm/feature_matching.h"
#include "stages/sfm/sfm_blocks.h"
#include "tests/test_util.h"

namespace p2n::testing {
namespace fs = std::filesystem;
namespace {

std::vector<std::string> PhotoNames(size_t count, const std::string& prefix) {
  std::vector<std::string> names;
  for (size_t i = 0; i < count; ++i) names.push_back(prefix + std::to_string(100 + i) + ".png");
  return names;
}

// Calls `row` with each row of `sql`'s answer from `database` (read only).
void ForEachRow(const fs::path& database, const char* sql, const std::function<void(sqlite3_stmt*)>& row) {
  sqlite3* db = nullptr;
  REQUIRE(sqlite3_open_v2(database.c_str(), &db, SQLITE_OPEN_READONLY, nullptr) == SQLITE_OK);
  sqlite3_stmt* statement = nullptr;
  REQUIRE(sqlite3_prepare_v2(db, sql, -1, &statement, nullptr) == SQLITE_OK);
  while (sqlite3_step(statement) == SQLITE_ROW) row(statement);
  sqlite3_finalize(statement);
  sqlite3_close(db);
}

// What an extraction wrote of each image, by name: its camera's id, model, size and parameters, its keypoints' and
// descriptors' bytes.
struct Extracted {
  std::string camera;
  std::string keypoints, descriptors;
  bool operator==(const Extracted&) const = default;
};
std::map<std::string, Extracted> ByName(const fs::path& database) {
  const char* sql =
      "SELECT name, cameras.camera_id, model, width, height, params, keypoints.data, descriptors.data FROM images "
      "JOIN cameras USING (camera_id) JOIN keypoints USING (image_id) JOIN descriptors USING (image_id)";
  std::map<std::string, Extracted> images;
  ForEachRow(database, sql, [&](sqlite3_stmt* statement) {
    const auto blob = [&](int c) {
      return std::string(static_cast<const char*>(sqlite3_column_blob(statement, c)),
                         sqlite3_column_bytes(statement, c));
    };
    images[reinterpret_cast<const char*>(sqlite3_column_text(statement, 0))] = {
        format("{} {} {}x{} ", sqlite3_column_int(statement, 1), sqlite3_column_int(statement, 2),
               sqlite3_column_int(statement, 3), sqlite3_column_int(statement, 4)) +
            blob(5),
        blob(6), blob(7)};
  });
  return images;
}

// The number of bytes in which `a` and `b` (of one size) differ.
size_t BytesApart(const std::string& a, const std::string& b) {
  size_t apart = 0;
  for (size_t i = 0; i < a.size(); ++i) apart += a[i] != b[i];
  return apart;
}

// COLMAP's extraction of the photos in `images` listed in `list` into `database`, one camera for them.
void Extract(const fs::path& images, const fs::path& list, const fs::path& database) {
  std::string output;
  const int code =
      RunCommand({"colmap", "feature_extractor", "--database_path", database.string(), "--image_path", images.string(),
                  "--image_list_path", list.string(), "--ImageReader.single_camera", "1", "--SiftExtraction.use_gpu",
                  "0", "--SiftExtraction.num_threads", "2", "--SiftExtraction.max_num_features", "500"},
                 &output);
  INFO(output);
  REQUIRE(code == 0);
}

// COLMAP's `matcher` ("exhaustive_matcher", or "matches_importer" with `extra` its list) on `database`, which holds
// our raw matches: COLMAP verifies them.
void Verify(const fs::path& database, const std::string& matcher, const std::vector<std::string>& extra = {}) {
  std::vector<std::string> command = {"colmap",
                                      matcher,
                                      "--database_path",
                                      database.string(),
                                      "--SiftMatching.use_gpu",
                                      "0",
                                      "--SiftMatching.num_threads",
                                      "2"};
  command.insert(command.end(), extra.begin(), extra.end());
  std::string output;
  const int code = RunCommand(command, &output);
  INFO(output);
  REQUIRE(code == 0);
}

// Each pair's raw matches, inlier matches and configuration after COLMAP's verification, by pair id.
struct Verified {
  int matches = 0, inliers = 0, config = 0;
};
std::map<int64_t, Verified> VerifiedByPair(const fs::path& database) {
  const char* sql =
      "SELECT pair_id, matches.rows, two_view_geometries.rows, config FROM matches JOIN two_view_geometries "
      "USING (pair_id)";
  std::map<int64_t, Verified> pairs;
  ForEachRow(database, sql, [&](sqlite3_stmt* statement) {
    pairs[sqlite3_column_int64(statement, 0)] = {sqlite3_column_int(statement, 1), sqlite3_column_int(statement, 2),
                                                 sqlite3_column_int(statement, 3)};
  });
  return pairs;
}

bool HaveColmap() {
  if (std::system("colmap help > /dev/null 2>&1") == 0) return true;
  WARN("COLMAP is not installed (scripts/install_deps.sh installs it): skipping");
  return false;
}

// The synthetic scene's 10 views in `dir`, their names in order.
std::vector<std::string> WriteTenViews(const fs::path& dir) {
  SyntheticSceneOptions scene;
  scene.num_views = 10;
  scene.supersampling = 1;
  WriteSyntheticScene(scene, dir);
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.path().extension() == ".png") names.push_back(entry.path().filename().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

}  // namespace

TEST_CASE("extraction blocks: each group's photos in order, in as few even blocks as fit the limit", "[sfm_blocks]") {
  const std::vector<CameraGroup> groups = {
      {"a", PhotoNames(10, "a")}, {"b", PhotoNames(3, "b")}, {"c", PhotoNames(8, "c")}};
  const std::vector<ExtractionBlock> blocks = PlanExtractionBlocks(groups, 4);
  std::vector<size_t> sizes, group_of;
  std::vector<std::string> order;
  for (const ExtractionBlock& block : blocks) {
    sizes.push_back(block.images.size());
    group_of.push_back(block.group);
    order.insert(order.end(), block.images.begin(), block.images.end());
  }
  CHECK(sizes == std::vector<size_t>{3, 3, 4, 3, 4, 4});
  CHECK(group_of == std::vector<size_t>{0, 0, 0, 1, 2, 2});
  std::vector<std::string> all = groups[0].images;
  for (size_t g = 1; g < groups.size(); ++g) all.insert(all.end(), groups[g].images.begin(), groups[g].images.end());
  CHECK(order == all);
  CHECK(PlanExtractionBlocks(groups, 100).size() == 3);

  TempDir dir;
  CHECK(WriteExtractionBlocks(blocks, dir / "x") == std::vector<int>{1, 2, 3, 4, 5, 6});
  CHECK(ReadTextFile(ExtractionBlockList(dir / "x", 4)) == "b100.png\nb101.png\nb102.png\n");
}

// Two camera groups (as photos of two cameras), each extracted in two blocks into databases of their own and merged:
// the same cameras, images, ids, keypoints and descriptors as the per-group extractions into one database.
TEST_CASE("extraction blocks: the merged databases are what one extraction writes", "[sfm_blocks][colmap]") {
  if (!HaveColmap()) return;
  TempDir dir;
  const std::vector<std::string> names = WriteTenViews(dir / "photos");
  REQUIRE(names.size() == 10);
  const std::vector<CameraGroup> groups = {{"first", {names.begin(), names.begin() + 6}},
                                           {"second", {names.begin() + 6, names.end()}}};
  // One extraction a group into one database, as the stage does without a scheduler.
  for (size_t g = 0; g < groups.size(); ++g) {
    std::string lines;
    for (const std::string& name : groups[g].images) lines += name + "\n";
    WriteText(dir / "group.txt", lines);
    Extract(dir / "photos", dir / "group.txt", dir / "whole.db");
  }
  const std::vector<ExtractionBlock> blocks = PlanExtractionBlocks(groups, 3);
  REQUIRE(blocks.size() == 4);
  const std::vector<int> parts = WriteExtractionBlocks(blocks, dir / "blocks");
  for (const int part : parts) {
    Extract(dir / "photos", ExtractionBlockList(dir / "blocks", part), ExtractionBlockDatabase(dir / "blocks", part));
  }
  MergeExtractionBlocks(blocks, dir / "blocks", dir / "merged.db", /*shared_camera=*/true);
  // The same images on the same cameras with the same keypoints. COLMAP numbers the images as its threads finish
  // them, and two of its own extractions differ in some descriptors (about 100 of an image's 100,000 bytes in a
  // few images): the descriptors agree to 1% of their bytes.
  const std::map<std::string, Extracted> whole = ByName(dir / "whole.db"), merged = ByName(dir / "merged.db");
  REQUIRE(merged.size() == names.size());
  REQUIRE(whole.size() == names.size());
  std::set<std::string> cameras;
  for (const auto& [name, image] : whole) {
    INFO(name);
    const Extracted& block = merged.at(name);
    CHECK(block.camera == image.camera);
    CHECK(block.keypoints == image.keypoints);
    REQUIRE(block.descriptors.size() == image.descriptors.size());
    CHECK(BytesApart(block.descriptors, image.descriptors) < image.descriptors.size() / 100);
    cameras.insert(block.camera);
  }
  CHECK(cameras.size() == 2);

  // Without a shared camera each block keeps its own: four cameras, one for each block's images.
  for (const int part : parts) {
    Extract(dir / "photos", ExtractionBlockList(dir / "blocks", part), ExtractionBlockDatabase(dir / "blocks", part));
  }
  MergeExtractionBlocks(blocks, dir / "blocks", dir / "own.db", /*shared_camera=*/false);
  const std::map<std::string, Extracted> own = ByName(dir / "own.db");
  for (size_t k = 0; k < blocks.size(); ++k) {
    for (const std::string& name : blocks[k].images) {
      INFO(name);
      CHECK(own.at(name).camera.substr(0, 2) == format("{} ", k + 1));
      CHECK(own.at(name).keypoints == whole.at(name).keypoints);
    }
  }
}

// The pairs of 10 photos matched in three blocks, each verified by COLMAP in the block's own database and merged:
// every pair with the raw matches and, within RANSAC's spread, the verified geometry of matching and verifying them
// all in the one database.
TEST_CASE("matching blocks: verified apart by COLMAP, merged, as one verification does", "[sfm_blocks][colmap]") {
  if (!HaveColmap()) return;
  TempDir dir;
  const std::vector<std::string> names = WriteTenViews(dir / "photos");
  std::string lines;
  for (const std::string& name : names) lines += name + "\n";
  WriteText(dir / "all.txt", lines);
  Extract(dir / "photos", dir / "all.txt", dir / "whole.db");
  fs::copy_file(dir / "whole.db", dir / "blocks.db");
  const std::vector<std::pair<size_t, size_t>> pairs = ExhaustivePairs(names.size());
  MatchIntoDatabase(dir / "whole.db", pairs);
  Verify(dir / "whole.db", "exhaustive_matcher");

  const std::vector<int> parts = WriteMatchingBlocks(pairs, 3, dir / "matching");
  for (const int part : parts) {
    MatchBlock(dir / "blocks.db", dir / "matching", part);
    Verify(MatchingBlockDatabase(dir / "matching", part), "matches_importer",
           {"--match_list_path", MatchingBlockNames(dir / "matching", part).string(), "--match_type", "pairs"});
  }
  MergeMatchingBlocks(dir / "matching", parts, dir / "blocks.db");

  const std::map<int64_t, Verified> whole = VerifiedByPair(dir / "whole.db"),
                                    blocks = VerifiedByPair(dir / "blocks.db");
  CHECK(whole.size() == pairs.size());
  REQUIRE(blocks.size() == whole.size());
  size_t verified = 0;
  for (const auto& [pair, expected] : whole) {
    INFO("pair " << pair);
    REQUIRE(blocks.count(pair));
    const Verified& got = blocks.at(pair);
    CHECK(got.matches == expected.matches);
    CHECK(got.config == expected.config);
    CHECK(std::abs(got.inliers - expected.inliers) <= std::max(5, expected.inliers / 10));
    verified += got.inliers > 0;
  }
  CHECK(verified >= names.size() - 1);  // at least as many as neighbours on the orbit
}

}  // namespace p2n::testing

// Our SIFT matching against a literal transcription of COLMAP's brute-force rule, its pair choices, and COLMAP's
// database layout (descriptors read, matches written in its pair order).

#include <sqlite3.h>

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>

#include "base/errors.h"
#include "base/file_util.h"
#include "base/format.h"
#include "formats/colmap_database.h"
#include "stages/sfm/descriptor_similarity.h"
#include "stages/sfm/feature_matching.h"
#include "stages/sfm/sfm_blocks.h"
#include "tests/test_util.h"

using namespace p2n;
using p2n::testing::TempDir;
using p2n::testing::WriteText;
namespace fs = std::filesystem;

namespace {

// Random SIFT-like descriptors: non-negative, length about 512, as bytes.
SiftDescriptors RandomDescriptors(int count, std::mt19937* rng) {
  std::gamma_distribution<double> value(0.5, 1.0);
  SiftDescriptors descriptors(128, count);
  for (int k = 0; k < count; ++k) {
    Eigen::Matrix<double, 128, 1> d;
    for (int i = 0; i < 128; ++i) d[i] = value(*rng);
    d *= 512 / d.norm();
    descriptors.col(k) = d.cwiseMin(255).array().round().cast<uint8_t>();
  }
  return descriptors;
}

// b's descriptors are a's, shuffled and moved by noise, after `extra` unrelated ones; permutation[i] is where a's
// i-th went.
SiftDescriptors Shuffled(const SiftDescriptors& a, int extra, double noise, std::vector<int>* permutation,
                         std::mt19937* rng) {
  const int n = static_cast<int>(a.cols());
  permutation->resize(n);
  for (int i = 0; i < n; ++i) (*permutation)[i] = extra + i;
  std::shuffle(permutation->begin(), permutation->end(), *rng);
  SiftDescriptors b(128, n + extra);
  b.leftCols(extra) = RandomDescriptors(extra, rng);
  std::normal_distribution<double> jitter(0.0, noise);
  for (int i = 0; i < n; ++i) {
    for (int r = 0; r < 128; ++r) {
      b(r, (*permutation)[i]) = static_cast<uint8_t>(std::clamp(std::round(a(r, i) + jitter(*rng)), 0.0, 255.0));
    }
  }
  return b;
}

// COLMAP 3.8's FindBestMatchesOneWayBruteForce and cross check, transcribed: integer dot products, the first of
// equal bests.
FeatureMatches ReferenceMatches(const SiftDescriptors& a, const SiftDescriptors& b, const SiftMatchRules& rules) {
  const Eigen::MatrixXi dots = a.cast<int>().transpose() * b.cast<int>();
  const auto one_way = [&](const Eigen::MatrixXi& d) {
    std::vector<int> match(d.rows(), -1);
    for (int i = 0; i < d.rows(); ++i) {
      int best_j = -1, best = 0, second = 0;
      for (int j = 0; j < d.cols(); ++j) {
        if (d(i, j) > best) {
          best_j = j;
          second = best;
          best = d(i, j);
        } else if (d(i, j) > second) {
          second = d(i, j);
        }
      }
      if (best_j < 0) continue;
      const float norm = 1.0f / (512.0f * 512.0f);
      const float angle = std::acos(std::min(norm * best, 1.0f));
      const float second_angle = std::acos(std::min(norm * second, 1.0f));
      if (angle > rules.max_distance || angle >= rules.max_ratio * second_angle) continue;
      match[i] = best_j;
    }
    return match;
  };
  const std::vector<int> forward = one_way(dots), backward = one_way(dots.transpose());
  FeatureMatches matches;
  for (int i = 0; i < dots.rows(); ++i) {
    if (forward[i] >= 0 && (!rules.cross_check || backward[forward[i]] == i)) matches.emplace_back(i, forward[i]);
  }
  return matches;
}

// The tables and columns of COLMAP's database that photo2nerf reads and writes.
void CreateColmapSchema(const std::filesystem::path& path) {
  sqlite3* db = nullptr;
  REQUIRE(sqlite3_open(path.c_str(), &db) == SQLITE_OK);
  REQUIRE(sqlite3_exec(db,
                       "CREATE TABLE images (image_id INTEGER PRIMARY KEY NOT NULL, name TEXT NOT NULL UNIQUE, "
                       "camera_id INTEGER NOT NULL);"
                       "CREATE TABLE descriptors (image_id INTEGER PRIMARY KEY NOT NULL, rows INTEGER NOT NULL, "
                       "cols INTEGER NOT NULL, data BLOB);"
                       "CREATE TABLE matches (pair_id INTEGER PRIMARY KEY NOT NULL, rows INTEGER NOT NULL, "
                       "cols INTEGER NOT NULL, data BLOB);"
                       // What the blocks' databases copy (ColmapDatabase::CreateBlock, AppendMatches).
                       "CREATE TABLE cameras (camera_id INTEGER PRIMARY KEY NOT NULL);"
                       "CREATE TABLE keypoints (image_id INTEGER PRIMARY KEY NOT NULL, data BLOB);"
                       "CREATE TABLE two_view_geometries (pair_id INTEGER PRIMARY KEY NOT NULL, rows INTEGER);",
                       nullptr, nullptr, nullptr) == SQLITE_OK);
  sqlite3_close(db);
}

void AddImage(const std::filesystem::path& path, int id, const std::string& name, const SiftDescriptors& d,
              int64_t stated_rows = -1) {
  sqlite3* db = nullptr;
  REQUIRE(sqlite3_open(path.c_str(), &db) == SQLITE_OK);
  sqlite3_stmt* statement = nullptr;
  REQUIRE(sqlite3_prepare_v2(db, "INSERT INTO images VALUES(?, ?, 1)", -1, &statement, nullptr) == SQLITE_OK);
  sqlite3_bind_int(statement, 1, id);
  sqlite3_bind_text(statement, 2, name.c_str(), -1, SQLITE_TRANSIENT);
  REQUIRE(sqlite3_step(statement) == SQLITE_DONE);
  sqlite3_finalize(statement);
  REQUIRE(sqlite3_prepare_v2(db, "INSERT INTO descriptors VALUES(?, ?, 128, ?)", -1, &statement, nullptr) == SQLITE_OK);
  sqlite3_bind_int(statement, 1, id);
  sqlite3_bind_int64(statement, 2, stated_rows >= 0 ? stated_rows : d.cols());
  sqlite3_bind_blob(statement, 3, d.data(), static_cast<int>(d.size()), SQLITE_TRANSIENT);
  REQUIRE(sqlite3_step(statement) == SQLITE_DONE);
  sqlite3_finalize(statement);
  sqlite3_close(db);
}

// The raw matches stored for a pair id: (rows, values in stored order).
std::pair<int64_t, std::vector<uint32_t>> StoredMatches(const std::filesystem::path& path, uint64_t pair_id) {
  sqlite3* db = nullptr;
  REQUIRE(sqlite3_open(path.c_str(), &db) == SQLITE_OK);
  sqlite3_stmt* statement = nullptr;
  REQUIRE(sqlite3_prepare_v2(db, "SELECT rows, data FROM matches WHERE pair_id = ?", -1, &statement, nullptr) ==
          SQLITE_OK);
  sqlite3_bind_int64(statement, 1, static_cast<sqlite3_int64>(pair_id));
  REQUIRE(sqlite3_step(statement) == SQLITE_ROW);
  const int64_t rows = sqlite3_column_int64(statement, 0);
  const auto* data = static_cast<const uint32_t*>(sqlite3_column_blob(statement, 1));
  std::vector<uint32_t> values(data, data + sqlite3_column_bytes(statement, 1) / sizeof(uint32_t));
  sqlite3_finalize(statement);
  sqlite3_close(db);
  return {rows, values};
}

}  // namespace

TEST_CASE("SIFT matching finds shuffled, noisy copies and rejects the rest, as COLMAP's rule does",
          "[feature_matching]") {
  std::mt19937 rng(7);
  const SiftDescriptors a = RandomDescriptors(300, &rng);
  std::vector<int> permutation;
  // Noise of 6 per byte moves a descriptor by about 0.13 rad; unrelated ones are about 0.9 rad apart.
  const SiftDescriptors b = Shuffled(a, 1100, 6.0, &permutation, &rng);  // b spans many column blocks, the last partial
  const FeatureMatches matches = MatchSiftDescriptors(a, b);
  CHECK(matches.size() >= 295);
  for (const auto& [i, j] : matches) CHECK(int(j) == permutation[i]);
  CHECK(matches == ReferenceMatches(a, b, {}));

  SECTION("a feature with two equal candidates fails the ratio test") {
    const auto [first, its_match] = matches.front();
    SiftDescriptors twin(128, b.cols() + 1);
    twin << b, b.col(its_match);
    const FeatureMatches with_twin = MatchSiftDescriptors(a, twin);
    for (const auto& [i, j] : with_twin) CHECK(i != first);
    CHECK(with_twin.size() == matches.size() - 1);
  }
  SECTION("other rules and no cross check agree with COLMAP's too") {
    const SiftMatchRules loose{0.95f, 1.2f, false};
    const SiftDescriptors noisy = Shuffled(a, 200, 20.0, &permutation, &rng);
    CHECK(MatchSiftDescriptors(a, noisy, loose) == ReferenceMatches(a, noisy, loose));
    CHECK(MatchSiftDescriptors(a, noisy) == ReferenceMatches(a, noisy, {}));
  }
  SECTION("no features, no matches") {
    CHECK(MatchSiftDescriptors(SiftDescriptors(128, 0), b).empty());
    CHECK(MatchSiftDescriptors(a, SiftDescriptors(128, 0)).empty());
  }
}

TEST_CASE("descriptor similarities are the exact integer dot products, at any size and byte value",
          "[feature_matching]") {
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> byte(0, 255);
  INFO("instructions: " << DescriptorSimilarity::Instructions());
  for (const int rows : {1, 63, 64, 65, 130}) {
    SiftDescriptors a(128, rows), b(128, 17);
    for (uint8_t& value : a.reshaped()) value = static_cast<uint8_t>(byte(rng));
    for (uint8_t& value : b.reshaped()) value = static_cast<uint8_t>(byte(rng));
    a.col(0).setConstant(255);  // the largest product sum: 128 * 255 * 255
    b.col(1).setConstant(255);
    b.col(2).setZero();
    const Eigen::MatrixXi exact = a.cast<int>().transpose() * b.cast<int>();
    const DescriptorSimilarity similarity(a);
    REQUIRE(similarity.stride() >= rows);
    for (const auto& [first, width] : {std::pair<int, int>{0, 17}, {3, 7}, {16, 1}}) {
      std::vector<float> out(static_cast<size_t>(similarity.stride()) * width);
      similarity.Block(b, first, width, out.data());
      for (int j = 0; j < width; ++j) {
        for (int i = 0; i < rows; ++i) {
          INFO("rows " << rows << ", column " << first + j << ", row " << i);
          CHECK(out[size_t(j) * similarity.stride() + i] == static_cast<float>(exact(i, first + j)));
        }
      }
    }
  }
}

TEST_CASE("pairs as COLMAP's exhaustive and sequential (quadratic overlap) matchers choose them",
          "[feature_matching]") {
  using Pairs = std::vector<std::pair<size_t, size_t>>;
  CHECK(ExhaustivePairs(4) == Pairs{{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}});
  CHECK(ExhaustivePairs(1).empty());
  // overlap 3: the next 2 photos and those 1, 2 and 4 after.
  CHECK(SequentialPairs(6, 3) ==
        Pairs{{0, 1}, {0, 2}, {0, 4}, {1, 2}, {1, 3}, {1, 5}, {2, 3}, {2, 4}, {3, 4}, {3, 5}, {4, 5}});
  CHECK(SequentialPairs(3, 1) == Pairs{{0, 1}, {1, 2}});
}

TEST_CASE("loop pairs: every two keyframes the sequential pairs leave apart", "[feature_matching]") {
  using Pairs = std::vector<std::pair<size_t, size_t>>;
  // Keyframes 0, 3, 6, 9; sequential overlap 2 pairs photos 1 and 2 apart only.
  CHECK(LoopPairs(10, 2, 3) == Pairs{{0, 3}, {0, 6}, {0, 9}, {3, 6}, {3, 9}, {6, 9}});
  // Keyframes 0, 2, 4, 6, 8; overlap 3 pairs photos 1, 2 and 4 apart, so 6 and 8 apart are left.
  CHECK(LoopPairs(9, 3, 2) == Pairs{{0, 6}, {0, 8}, {2, 8}});
  // A 300-frame orbit: its first frame meets its last keyframe, and the pairs grow with the keyframes' square.
  const Pairs orbit = LoopPairs(300, 12, 6);
  CHECK(std::find(orbit.begin(), orbit.end(), std::pair<size_t, size_t>{0, 294}) != orbit.end());
  CHECK(orbit.size() == 50 * 49 / 2 - 49);  // less the pairs 6 apart, which are sequential
  CHECK(LoopPairs(5, 1, 0) == Pairs{{0, 2}, {0, 3}, {0, 4}, {1, 3}, {1, 4}, {2, 4}});  // stride 0 read as 1
}

TEST_CASE("COLMAP's database: descriptors read, matches written in its pair order, damage named",
          "[feature_matching]") {
  TempDir dir;
  const auto path = dir / "database.db";
  CreateColmapSchema(path);
  std::mt19937 rng(3);
  const SiftDescriptors a = RandomDescriptors(50, &rng);
  std::vector<int> permutation;
  const SiftDescriptors b = Shuffled(a, 10, 3.0, &permutation, &rng);
  // Ids against name order: "b.png" (id 1) sorts after "a.png" (id 2).
  AddImage(path, 2, "a.png", a);
  AddImage(path, 1, "b.png", b);
  AddImage(path, 3, "c.png", SiftDescriptors(128, 0));
  {
    ColmapDatabase db(path);
    const std::vector<ColmapDatabaseImage> images = db.Images();
    REQUIRE(images.size() == 3);
    CHECK(images[0].name == "a.png");
    CHECK(images[0].id == 2);
    CHECK(db.Descriptors(2) == a);
    CHECK(db.Descriptors(3).cols() == 0);
    CHECK(db.Descriptors(9).cols() == 0);
  }
  CHECK(MatchIntoDatabase(path, ExhaustivePairs(3)) == 3);
  // Pair (a, b) is stored as (image 1, image 2): b's feature first.
  const auto [rows, values] = StoredMatches(path, ColmapPairId(2, 1));
  CHECK(ColmapPairId(2, 1) == 2147483647ull + 2);
  CHECK(rows >= 45);
  for (int64_t m = 0; m < rows; ++m) CHECK(int(values[2 * m]) == permutation[values[2 * m + 1]]);
  CHECK(StoredMatches(path, ColmapPairId(2, 3)).first == 0);  // no features: an empty row, as COLMAP writes
  CHECK(ColmapDatabase(path).HasMatches(1, 2));
  CHECK(ColmapDatabase(path).HasMatches(3, 1));
  CHECK(MatchIntoDatabase(path, ExhaustivePairs(3)) == 0);  // nothing matched twice

  AddImage(path, 4, "d.png", a, /*stated_rows=*/51);
  try {
    MatchIntoDatabase(path, ExhaustivePairs(4));
    FAIL("damaged descriptors were read");
  } catch (const ExternalToolError& e) {
    CHECK_THAT(e.what(), Catch::Contains(path.string()) && Catch::Contains("image 4"));
  }
}

// The sfm stage's matching under a scheduler: the pairs cut into blocks, each matched from the database (read only)
// into a database of its own, the blocks' matches appended: the same matches as matching them all at once.
TEST_CASE("descriptor matching in blocks of pairs, merged, stores what matching at once does", "[feature_matching]") {
  TempDir dir;
  const auto whole = dir / "whole.db", blocks = dir / "blocks.db";
  CreateColmapSchema(whole);
  std::mt19937 rng(5);
  const SiftDescriptors base = RandomDescriptors(40, &rng);
  for (int k = 0; k < 6; ++k) {
    std::vector<int> permutation;
    AddImage(whole, 6 - k, format("{}.png", k), Shuffled(base, 5 * k, 2.0, &permutation, &rng));
  }
  fs::copy_file(whole, blocks);
  const std::vector<std::pair<size_t, size_t>> pairs = ExhaustivePairs(6);
  CHECK(MatchIntoDatabase(whole, pairs) == 15);

  const std::vector<int> parts = WriteMatchingBlocks(pairs, 4, dir / "matching");
  REQUIRE(parts == std::vector<int>{1, 2, 3, 4});
  CHECK(ReadTextFile(MatchingBlockPairs(dir / "matching", 1)) == "0 1\n0 2\n0 3\n");
  size_t listed = 0;
  for (const int part : parts) {
    const std::string lines = ReadTextFile(MatchingBlockPairs(dir / "matching", part));
    listed += std::count(lines.begin(), lines.end(), '\n');
    MatchBlock(blocks, dir / "matching", part);
  }
  CHECK(listed == pairs.size());
  // Each block's pairs by name, for COLMAP's verification in the block's database.
  CHECK(ReadTextFile(MatchingBlockNames(dir / "matching", 1)) == "6 5\n6 4\n6 3\n");  // ids: k.png is 6 - k
  CHECK(!ColmapDatabase(blocks).HasMatches(1, 2));  // the blocks' own databases hold them so far
  MergeMatchingBlocks(dir / "matching", parts, blocks);
  for (const auto& [i, j] : pairs) {
    const uint64_t pair = ColmapPairId(static_cast<uint32_t>(6 - i), static_cast<uint32_t>(6 - j));
    INFO(i << " " << j);
    CHECK(StoredMatches(blocks, pair) == StoredMatches(whole, pair));
    CHECK(StoredMatches(whole, pair).first >= 30);
  }

  // A damaged list of pairs is named.
  WriteText(MatchingBlockPairs(dir / "matching", 2), "0 x\n");
  CHECK_THROWS_WITH(MatchBlock(blocks, dir / "matching", 2), Catch::Contains("pairs.txt"));
}

// The photos cut into clusters for mapping apart: where they share least, each grown by its strongest neighbours.

#include <catch2/catch.hpp>

#include <algorithm>
#include <numeric>
#include <set>

#include "stages/mapper_clusters.h"

namespace p2n::testing {
namespace {

std::vector<uint32_t> Ids(uint32_t first, uint32_t last) {
  std::vector<uint32_t> ids(last - first + 1);
  std::iota(ids.begin(), ids.end(), first);
  return ids;
}

// Every pair of `ids` with `inliers`.
void AddClique(const std::vector<uint32_t>& ids, size_t inliers, std::vector<VerifiedPair>* pairs) {
  for (size_t i = 0; i < ids.size(); ++i) {
    for (size_t j = i + 1; j < ids.size(); ++j) pairs->push_back({ids[i], ids[j], inliers});
  }
}

bool Contains(const std::vector<uint32_t>& cluster, const std::vector<uint32_t>& ids) {
  return std::includes(cluster.begin(), cluster.end(), ids.begin(), ids.end());
}

}  // namespace

TEST_CASE("mapper clusters: two groups of photos part where they share least, each grown by its neighbours", "[sfm]") {
  std::vector<VerifiedPair> pairs;
  AddClique(Ids(1, 30), 100, &pairs);
  AddClique(Ids(31, 60), 100, &pairs);
  pairs.push_back({30, 31, 40});  // the groups touch through a few photos
  pairs.push_back({29, 32, 20});
  pairs.push_back({28, 33, 10});
  std::vector<uint32_t> images = Ids(1, 60);
  images.push_back(61);  // a photo nothing matched

  const std::vector<std::vector<uint32_t>> clusters = ClusterImages(images, pairs, 31, 2);
  REQUIRE(clusters.size() == 2);
  const bool first_has_one = Contains(clusters[0], {1});
  const std::vector<uint32_t>& a = clusters[first_has_one ? 0 : 1];
  const std::vector<uint32_t>& b = clusters[first_has_one ? 1 : 0];
  CHECK(Contains(a, Ids(1, 30)));
  CHECK(Contains(b, Ids(31, 60)));
  // Grown by the two outside photos sharing the most inliers with them: 31 (40) and 32 (20) for the first group.
  CHECK(Contains(a, {31, 32}));
  CHECK_FALSE(Contains(a, {33}));
  CHECK(Contains(b, {29, 30}));
  CHECK_FALSE(Contains(b, {28}));
  CHECK(a.size() + b.size() == 61 + 4);  // the lone photo in one of them
  CHECK(std::is_sorted(a.begin(), a.end()));
}

TEST_CASE("mapper clusters: a sequence of photos cut into runs of at most the size asked for", "[sfm]") {
  std::vector<VerifiedPair> pairs;
  for (uint32_t i = 1; i < 100; ++i) {
    pairs.push_back({i, i + 1, 200});
    if (i + 2 <= 100) pairs.push_back({i, i + 2, 100});
  }
  const std::vector<std::vector<uint32_t>> clusters = ClusterImages(Ids(1, 100), pairs, 25, 6);
  REQUIRE(clusters.size() == 4);
  std::set<uint32_t> covered;
  for (const std::vector<uint32_t>& cluster : clusters) {
    CHECK(cluster.size() <= 26 + 6);
    // A run of the sequence, grown at its ends: consecutive ids.
    CHECK(cluster.back() - cluster.front() + 1 == cluster.size());
    covered.insert(cluster.begin(), cluster.end());
  }
  CHECK(covered.size() == 100);
}

TEST_CASE("mapper clusters: as many photos as a cluster holds stay one cluster", "[sfm]") {
  const std::vector<std::vector<uint32_t>> clusters = ClusterImages({5, 3, 9}, {{3, 5, 50}}, 3, 1);
  REQUIRE(clusters.size() == 1);
  CHECK(clusters[0] == std::vector<uint32_t>{3, 5, 9});
  CHECK_THROWS_AS(ClusterImages({1}, {}, 0, 0), std::invalid_argument);
}

}  // namespace p2n::testing

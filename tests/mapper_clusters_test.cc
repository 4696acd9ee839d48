// The photos cut into clusters for mapping apart: where they share least, each grown by its strongest neighbours;
// the clusters' models merged by the photos they share.

#include <catch2/catch.hpp>

#include <algorithm>
#include <numeric>
#include <set>

#include "base/file_util.h"
#include "formats/colmap_model.h"
#include "stages/sfm/cluster_mapping.h"
#include "stages/sfm/mapper_clusters.h"
#include "tests/test_util.h"

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

// A model of the photos `names` (one camera, no points) in `folder`.
void WriteModel(const std::vector<std::string>& names, const std::filesystem::path& folder) {
  ColmapModel model;
  model.cameras[1] = {1, "SIMPLE_PINHOLE", 320, 240, {300, 160, 120}};
  uint32_t id = 0;
  for (const std::string& name : names) {
    ColmapImage image;
    image.id = ++id;
    image.camera_id = 1;
    image.name = name;
    model.images[id] = image;
  }
  std::filesystem::create_directories(folder);
  WriteColmapModelBinary(model, folder);
}

std::set<std::string> NamesIn(const std::filesystem::path& folder) {
  std::set<std::string> names;
  for (const auto& [id, image] : ReadColmapModel(folder).images) names.insert(image.name);
  return names;
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

// Clusters: 1 the largest, 2 sharing 3 photos with it, 3 sharing 2 with them, 4 inside the merged model, 5 without a
// model, 6 sharing 3 but not aligning (the merger leaves the first model as it was, as model_merger does).
TEST_CASE("mapper clusters: the models merged from the largest by the photos they share and the rest kept apart",
          "[sfm]") {
  TempDir dir;
  const std::filesystem::path clusters = dir / "clusters", output = dir / "sparse";
  const std::vector<std::vector<std::string>> photos = {{"p1", "p2", "p3", "p4", "p5", "p6"},
                                                        {"p4", "p5", "p6", "p7", "p8"},
                                                        {"p7", "p8", "p9", "p10"},
                                                        {"p1", "p2"},
                                                        {"p12"},
                                                        {"p1", "p2", "p3", "p11"}};
  for (size_t k = 0; k < photos.size(); ++k) {
    const int part = static_cast<int>(k) + 1;
    std::filesystem::create_directories(ClusterModels(clusters, part));
    WriteFileAtomic(ClusterImageList(clusters, part), "");
    if (part != 5) WriteModel(photos[k], ClusterModels(clusters, part) / "0");
  }
  WriteModel({"p9"}, ClusterModels(clusters, 3) / "1");  // a smaller second model of cluster 3: not merged
  std::vector<std::pair<std::set<std::string>, std::set<std::string>>> merges;
  MergeClusterModels(clusters, output, [&](const auto& first, const auto& second, const auto& into) {
    merges.push_back({NamesIn(first), NamesIn(second)});
    std::set<std::string> names = NamesIn(first);
    if (!NamesIn(second).contains("p11")) names.merge(NamesIn(second));
    WriteModel(std::vector<std::string>(names.begin(), names.end()), into);
  });
  REQUIRE(merges.size() == 2);
  CHECK(merges[0].second.contains("p7"));   // cluster 2 first: it shares 3 photos, as 6 does, and is larger
  CHECK(merges[1].second.contains("p11"));  // then 6, which does not align
  CHECK(NamesIn(output / "0") == std::set<std::string>{"p1", "p2", "p3", "p4", "p5", "p6", "p7", "p8"});
  CHECK(NamesIn(output / "1") == std::set<std::string>{"p1", "p2", "p3", "p11"});
  CHECK(NamesIn(output / "2") == std::set<std::string>{"p10", "p7", "p8", "p9"});
  CHECK(!std::filesystem::exists(output / "3"));
}

}  // namespace p2n::testing

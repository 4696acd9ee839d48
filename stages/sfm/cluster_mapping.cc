// The photos mapped in clusters that a scheduler runs as jobs of their own (cluster_mapping.h).

#include "stages/sfm/cluster_mapping.h"

#include <algorithm>
#include <map>
#include <optional>
#include <set>
#include <string>

#include "base/file_util.h"
#include "base/format.h"
#include "formats/colmap_database.h"
#include "formats/colmap_model.h"
#include "pipeline/log.h"
#include "stages/sfm/mapper_clusters.h"

namespace p2n {
namespace fs = std::filesystem;
namespace {

// Models must share this many photos to be aligned (COLMAP's own minimum for merging).
constexpr size_t kMinSharedImages = 3;

struct ClusterModel {
  fs::path folder;
  std::set<std::string> images;  // their names
};

std::set<std::string> ImageNamesOf(const fs::path& folder) {
  std::set<std::string> names;
  for (const auto& [id, image] : ReadColmapModel(folder).images) names.insert(image.name);
  return names;
}

// The model with the most photos that cluster `part` made, if any.
std::optional<ClusterModel> LargestModel(const fs::path& dir, int part) {
  std::optional<ClusterModel> largest;
  const fs::path models = ClusterModels(dir, part);
  if (!fs::is_directory(models)) return largest;
  for (const fs::directory_entry& entry : fs::directory_iterator(models)) {
    if (!fs::exists(entry.path() / "images.bin")) continue;
    ClusterModel model{entry.path(), ImageNamesOf(entry.path())};
    if (!largest || model.images.size() > largest->images.size()) largest = std::move(model);
  }
  return largest;
}

size_t Shared(const std::set<std::string>& a, const std::set<std::string>& b) {
  return std::count_if(b.begin(), b.end(), [&](const std::string& name) { return a.contains(name); });
}

}  // namespace

std::vector<int> PlanClusters(const fs::path& database, const fs::path& dir, size_t max_images, size_t overlap) {
  const ColmapDatabase db(database);
  std::map<uint32_t, std::string> names;
  std::vector<uint32_t> ids;
  for (const ColmapDatabaseImage& image : db.Images()) {
    names[image.id] = image.name;
    ids.push_back(image.id);
  }
  const std::vector<std::vector<uint32_t>> clusters = ClusterImages(ids, db.VerifiedPairs(), max_images, overlap);
  std::vector<int> parts;
  for (size_t k = 0; k < clusters.size(); ++k) {
    const int part = static_cast<int>(k) + 1;
    std::string lines;
    for (const uint32_t id : clusters[k]) lines += names.at(id) + "\n";
    fs::create_directories(ClusterModels(dir, part));
    WriteFileAtomic(ClusterImageList(dir, part), lines);
    parts.push_back(part);
  }
  return parts;
}

fs::path ClusterImageList(const fs::path& dir, int part) { return dir / std::to_string(part) / "images.txt"; }

fs::path ClusterModels(const fs::path& dir, int part) { return dir / std::to_string(part) / "models"; }

void MergeClusterModels(const fs::path& dir, const fs::path& output, const ModelMerger& merge) {
  std::vector<ClusterModel> left;
  for (int part = 1; fs::exists(ClusterImageList(dir, part)); ++part) {
    if (std::optional<ClusterModel> model = LargestModel(dir, part)) {
      left.push_back(std::move(*model));
    } else {
      LogWarning(format("sfm: cluster {} of the photos made no model (its log: mapping_cluster_{}.log)", part, part));
    }
  }
  if (left.empty()) return;
  std::stable_sort(left.begin(), left.end(),
                   [](const ClusterModel& a, const ClusterModel& b) { return a.images.size() > b.images.size(); });
  ClusterModel merged = left.front();
  left.erase(left.begin());
  std::vector<ClusterModel> apart;
  for (int merges = 1; !left.empty(); ++merges) {
    const auto next = std::max_element(left.begin(), left.end(), [&](const ClusterModel& a, const ClusterModel& b) {
      return Shared(merged.images, a.images) < Shared(merged.images, b.images);
    });
    ClusterModel cluster = std::move(*next);
    left.erase(next);
    const size_t shared = Shared(merged.images, cluster.images);
    if (shared == cluster.images.size()) continue;  // nothing to add
    if (shared < kMinSharedImages) {
      apart.push_back(std::move(cluster));
      continue;
    }
    const fs::path into = dir / format("merged_{}", merges);
    fs::create_directories(into);
    merge(merged.folder, cluster.folder, into);
    std::set<std::string> images = ImageNamesOf(into);
    if (images.size() > merged.images.size()) {
      merged = {into, std::move(images)};
    } else {
      LogWarning(format("sfm: the model of {} photos from {} did not align with the merged model of {}",
                        cluster.images.size(), cluster.folder.string(), merged.images.size()));
      apart.push_back(std::move(cluster));
    }
  }
  fs::create_directories(output);
  fs::rename(merged.folder, output / "0");
  for (size_t i = 0; i < apart.size(); ++i) fs::rename(apart[i].folder, output / std::to_string(i + 1));
}

}  // namespace p2n

// The photos cut into clusters for mapping apart (mapper_clusters.h).

#include "stages/sfm/mapper_clusters.h"

#include <metis.h>

#include <algorithm>
#include <map>
#include <stdexcept>
#include <unordered_map>

#include "base/format.h"

namespace p2n {
namespace {

// Each image's neighbours (indices into the image list) with the inliers they share.
using Neighbours = std::vector<std::map<size_t, size_t>>;

Neighbours NeighboursOf(const std::vector<uint32_t>& images, const std::vector<VerifiedPair>& pairs) {
  std::unordered_map<uint32_t, size_t> index;
  for (size_t i = 0; i < images.size(); ++i) index[images[i]] = i;
  Neighbours neighbours(images.size());
  for (const VerifiedPair& pair : pairs) {
    const auto a = index.find(pair.image_id1), b = index.find(pair.image_id2);
    if (a == index.end() || b == index.end() || a->second == b->second || pair.inliers == 0) continue;
    neighbours[a->second][b->second] += pair.inliers;
    neighbours[b->second][a->second] += pair.inliers;
  }
  return neighbours;
}

// METIS's partition of the graph into `parts` (each image's part).
std::vector<idx_t> Partition(const Neighbours& neighbours, idx_t parts) {
  std::vector<idx_t> offsets{0}, adjacent, weights;
  for (const std::map<size_t, size_t>& around : neighbours) {
    for (const auto& [j, inliers] : around) {
      adjacent.push_back(static_cast<idx_t>(j));
      weights.push_back(static_cast<idx_t>(std::min<size_t>(inliers, 1u << 30)));
    }
    offsets.push_back(static_cast<idx_t>(adjacent.size()));
  }
  idx_t vertices = static_cast<idx_t>(neighbours.size()), constraints = 1, cut = 0;
  idx_t options[METIS_NOPTIONS];
  METIS_SetDefaultOptions(options);
  options[METIS_OPTION_SEED] = 0;
  std::vector<idx_t> part(neighbours.size(), 0);
  const int status = METIS_PartGraphKway(&vertices, &constraints, offsets.data(), adjacent.data(), nullptr, nullptr,
                                         weights.data(), &parts, nullptr, nullptr, options, &cut, part.data());
  if (status != METIS_OK) throw std::runtime_error(format("METIS could not cut the photos' graph (status {})", status));
  return part;
}

// The `overlap` images outside `members` that share the most inliers with them (none that share nothing).
std::vector<size_t> Grown(const std::vector<size_t>& members, const Neighbours& neighbours, size_t overlap) {
  std::vector<bool> inside(neighbours.size(), false);
  for (const size_t i : members) inside[i] = true;
  std::map<size_t, size_t> shared;  // outside image -> inliers with the members
  for (const size_t i : members) {
    for (const auto& [j, inliers] : neighbours[i]) {
      if (!inside[j]) shared[j] += inliers;
    }
  }
  std::vector<std::pair<size_t, size_t>> ranked(shared.begin(), shared.end());
  std::stable_sort(ranked.begin(), ranked.end(), [](const auto& a, const auto& b) { return a.second > b.second; });
  ranked.resize(std::min(ranked.size(), overlap));
  std::vector<size_t> grown;
  for (const auto& [j, inliers] : ranked) grown.push_back(j);
  return grown;
}

}  // namespace

std::vector<std::vector<uint32_t>> ClusterImages(const std::vector<uint32_t>& images,
                                                 const std::vector<VerifiedPair>& pairs, size_t max_images,
                                                 size_t overlap) {
  if (max_images == 0) throw std::invalid_argument("clusters of at most 0 images");
  if (images.size() <= max_images) {
    std::vector<uint32_t> all(images);
    std::sort(all.begin(), all.end());
    return {all};
  }
  const Neighbours neighbours = NeighboursOf(images, pairs);
  const idx_t parts = static_cast<idx_t>((images.size() + max_images - 1) / max_images);
  const std::vector<idx_t> part = Partition(neighbours, parts);
  std::vector<std::vector<size_t>> members(parts);
  for (size_t i = 0; i < images.size(); ++i) members[part[i]].push_back(i);
  std::vector<std::vector<uint32_t>> clusters;
  for (const std::vector<size_t>& cluster : members) {
    if (cluster.empty()) continue;
    std::vector<uint32_t> ids;
    for (const size_t i : cluster) ids.push_back(images[i]);
    for (const size_t j : Grown(cluster, neighbours, overlap)) ids.push_back(images[j]);
    std::sort(ids.begin(), ids.end());
    clusters.push_back(std::move(ids));
  }
  return clusters;
}

}  // namespace p2n

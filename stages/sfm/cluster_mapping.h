#pragma once
// The photos mapped in clusters that a scheduler runs as jobs of their own (the sfm stage's parts): COLMAP's
// hierarchical mapper spread over machines. The stage's job cuts the photos into clusters (mapper_clusters.h) and
// writes each one's photo list; each part runs COLMAP's incremental mapper on its list; the stage's job merges the
// clusters' models (COLMAP's model_merger aligns them on the photos they share), then triangulates and adjusts the
// merged model as after the hierarchical mapper (docs/design.md §7).

#include <cstddef>
#include <filesystem>
#include <functional>
#include <vector>

namespace p2n {

// The kind of the sfm stage's parts that map clusters (StageContext::RunParts).
inline constexpr const char* kClusterWork = "cluster";

// Cuts the photos of COLMAP's `database` into clusters of at most `max_images`, each grown by up to `overlap` of
// its neighbours (ClusterImages), and writes cluster k's photo names to ClusterImageList(dir, k), k from 1. Returns
// the clusters' numbers.
std::vector<int> PlanClusters(const std::filesystem::path& database, const std::filesystem::path& dir,
                              size_t max_images, size_t overlap);

// Cluster `part`'s photo list (COLMAP's --image_list_path), and the folder its mapper writes its models into.
std::filesystem::path ClusterImageList(const std::filesystem::path& dir, int part);
std::filesystem::path ClusterModels(const std::filesystem::path& dir, int part);

// Merges `first` and `second` into `output` (COLMAP's model_merger, which writes `first` unchanged when they do not
// align).
using ModelMerger = std::function<void(const std::filesystem::path& first, const std::filesystem::path& second,
                                       const std::filesystem::path& output)>;

// The largest model of each cluster in `dir`, merged by `merge` from the largest on, each time with the cluster that
// shares the most photos with what is merged so far; the merged model goes to `output`/0 and a cluster's model that
// shares fewer than 3 photos with it or does not align to `output`/1, 2, ... (as COLMAP's mappers write separate
// models). Clusters without a model are left out; none at all: nothing is written.
void MergeClusterModels(const std::filesystem::path& dir, const std::filesystem::path& output,
                        const ModelMerger& merge);

}  // namespace p2n

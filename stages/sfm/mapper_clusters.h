#pragma once
// The photos cut into clusters for mapping apart (each a job of its own on a scheduler), by the matches COLMAP's
// geometric verification kept: METIS's cut of the graph whose edges are the verified pairs, weighted by their
// inlier matches, so that the clusters part where the photos share least. Each cluster is then grown by the photos
// outside it that share the most matches with it: the overlap the merge aligns the clusters' models on.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "formats/colmap_database.h"

namespace p2n {

// `images` (database ids) in clusters of at most about `max_images` (METIS balances them within 3%), each grown by
// up to `overlap` photos of its neighbours. Every image is in at least one cluster, an image without verified pairs
// in one of them; one cluster when `images` has at most `max_images`. Each cluster's ids ascending.
std::vector<std::vector<uint32_t>> ClusterImages(const std::vector<uint32_t>& images,
                                                 const std::vector<VerifiedPair>& pairs, size_t max_images,
                                                 size_t overlap);

}  // namespace p2n

#pragma once
// SIFT descriptors matched in-process, for COLMAP to verify. COLMAP 3.8's CPU matcher finds each feature's two
// nearest neighbours with a FLANN kd-tree that it builds again for every pair: on the demo's photos 95% of its
// matching time, with geometric verification the rest. Here every pair's similarities are one exact matrix
// product of the bytes (DescriptorSimilarity: byte products with AVX-512 VNNI), judged by COLMAP's rules: the
// angle between descriptors at most max_distance, below max_ratio of the second best's, and the best both ways.
// The raw matches go into COLMAP's database, where its exhaustive and sequential matchers find them and only
// verify them (docs/design.md §7).

#include <cstddef>
#include <filesystem>
#include <utility>
#include <vector>

#include "formats/colmap_database.h"

namespace p2n {

// COLMAP's SiftMatching defaults (max_ratio, max_distance in radians, cross_check).
struct SiftMatchRules {
  float max_ratio = 0.8f;
  float max_distance = 0.7f;
  bool cross_check = true;
};

// The features of `a` and `b` (one descriptor a column) that are each other's match under `rules`; exact
// nearest neighbours, ties to the first as COLMAP's brute-force matcher.
FeatureMatches MatchSiftDescriptors(const SiftDescriptors& a, const SiftDescriptors& b,
                                    const SiftMatchRules& rules = {});

// The pairs (i < j) of `images` photos in name order that COLMAP's exhaustive matcher matches: all of them.
std::vector<std::pair<size_t, size_t>> ExhaustivePairs(size_t images);
// ... and its sequential matcher with `overlap` and quadratic overlap (its default): each photo with the next
// overlap - 1 and with those 2^k after it for k < overlap.
std::vector<std::pair<size_t, size_t>> SequentialPairs(size_t images, int overlap);
// The pairs that close a walk's loops, which sequential pairs miss (a full orbit comes back to its first frames
// hundreds of frames later): every two keyframes, every `stride`-th photo, that SequentialPairs(images, overlap)
// does not pair. Any photo is within stride / 2 of a keyframe, so wherever the walk passes a place again, two
// keyframes about as far apart as sequential neighbours see it.
std::vector<std::pair<size_t, size_t>> LoopPairs(size_t images, int overlap, size_t stride);

// Matches the pairs (indices into the database's images in name order) that have no raw matches yet and writes
// their matches, into `database` or, when given, into `into` (CreateMatchesDatabase: `database` is then only read);
// returns how many pairs it matched. Progress as "sfm: matching descriptors"; Ctrl-C stops it.
size_t MatchIntoDatabase(const std::filesystem::path& database, const std::vector<std::pair<size_t, size_t>>& pairs,
                         const std::filesystem::path& into = {});

}  // namespace p2n

#pragma once
// Image retrieval for the vocab_tree matcher: COLMAP's vocab_tree_retriever finds each photo's most similar photos
// in a vocabulary tree; the pairs it names are matched by our descriptor matching (feature_matching.h, about 11 ms
// a pair and core against COLMAP's CPU matcher's 250 ms: matcher_choice.h) and verified by COLMAP, in blocks under a
// scheduler as the other matchers' pairs (sfm_blocks.h).

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "formats/colmap_database.h"

namespace p2n {

// Which of the photos retrieved for a photo, most similar first, it is paired with: the `nearest` first, and `spread`
// more at even steps through the rest of the list. On a dense capture (a walk, a video, an orbit of hundreds) the most
// similar photos are the next few along the path, with too little parallax between them to place points, and
// clusters of them mapped apart share too little to be merged; the less similar ones further down the list are
// farther along it.
struct RetrievalPicks {
  size_t nearest = 0, spread = 0;
  // The photos to retrieve for each (itself first, as COLMAP lists it): the nearest and four times as many more to
  // spread the others over.
  size_t Candidates() const { return 1 + nearest + 4 * nearest; }
};

// The vocabulary tree retrieval searches, built from the photos themselves (COLMAP's pretrained trees are a download
// away): its words, and the photos whose features it is clustered from.
struct VocabularyTreeSize {
  size_t words = 0, photos = 0;
};
// The tree for `photos` photos of at most `features` features each. Below 2,000 photos a word per 64 features, at most
// 999 (FLANN, which COLMAP searches the words with, tunes an index of 1,000 words or more by trial searches that
// cost more than the rest of such a retrieval); from 2,000, 2.4 words a photo, at most 9,600: each query scores the
// photos that share its words, so with a fixed vocabulary the retrieval grows with the square of the photos
// (docs/benchmarks.md, "The vocabulary tree's words" and "Retrieval at 3,000 photos"). Clustered from 30 photos.
VocabularyTreeSize TreeSizeFor(size_t photos, size_t features);

// The pairs in COLMAP's vocab_tree_retriever's printed answer: for each "Querying for image NAME [i/n]" line, the
// lines "  image_id=ID, image_name=..., score=..." of the photos retrieved for it, those `picks` takes. As indices
// into `images` (a database's, in name order: ColmapDatabase::Images), the smaller first, each pair once in the order
// first named, none of a photo with itself. ExternalToolError when a line names a photo the database lacks, or
// retrieved photos come before any query.
std::vector<std::pair<size_t, size_t>> RetrievedPairs(const std::string& answer,
                                                      const std::vector<ColmapDatabaseImage>& images,
                                                      const RetrievalPicks& picks);

}  // namespace p2n

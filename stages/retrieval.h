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

// The pairs in COLMAP's vocab_tree_retriever's printed answer: for each "Querying for image NAME [i/n]" line, the
// lines "  image_id=ID, image_name=..., score=..." of the photos retrieved for it. As indices into `images` (a
// database's, in name order: ColmapDatabase::Images), the smaller first, each pair once in the order first named,
// none of a photo with itself. ExternalToolError when a line names a photo the database lacks, or retrieved photos
// come before any query.
std::vector<std::pair<size_t, size_t>> RetrievedPairs(const std::string& answer,
                                                      const std::vector<ColmapDatabaseImage>& images);

}  // namespace p2n

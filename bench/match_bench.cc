// Descriptor matching speed on a COLMAP database's features: matches every pair of the first IMAGES photos (all by
// default) as the sfm stage does, without writing, and prints the seconds, pairs per second and matches found.
// Usage: match_bench DATABASE [IMAGES]

#include <tbb/parallel_for.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>

#include "stages/sfm/descriptor_similarity.h"
#include "stages/sfm/feature_matching.h"

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: match_bench DATABASE [IMAGES]\n");
    return 1;
  }
  const p2n::ColmapDatabase db(argv[1]);
  std::vector<p2n::ColmapDatabaseImage> images = db.Images();
  if (argc > 2 && static_cast<size_t>(std::atoi(argv[2])) < images.size()) images.resize(std::atoi(argv[2]));
  std::vector<p2n::SiftDescriptors> descriptors;
  size_t features = 0;
  for (const p2n::ColmapDatabaseImage& image : images) {
    descriptors.push_back(db.Descriptors(image.id));
    features += descriptors.back().cols();
  }
  const auto pairs = p2n::ExhaustivePairs(images.size());
  std::vector<size_t> found(pairs.size());
  const auto start = std::chrono::steady_clock::now();
  tbb::parallel_for(size_t{0}, pairs.size(), [&](size_t p) {
    found[p] = p2n::MatchSiftDescriptors(descriptors[pairs[p].first], descriptors[pairs[p].second]).size();
  });
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  size_t matches = 0;
  for (const size_t n : found) matches += n;
  std::printf("%zu images (%.0f features each), %zu pairs in %.2f s: %.1f pairs/s, %zu matches (%s)\n", images.size(),
              double(features) / images.size(), pairs.size(), seconds, pairs.size() / seconds, matches,
              p2n::DescriptorSimilarity::Instructions());
  return 0;
}

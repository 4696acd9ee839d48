#include "stages/sfm/feature_matching.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "pipeline/cancel.h"
#include "pipeline/progress.h"
#include "stages/sfm/descriptor_similarity.h"

namespace p2n {
namespace {

constexpr float kSimilarityNorm = 1.0f / (512.0f * 512.0f);  // COLMAP scales descriptors to a length of 512
constexpr Eigen::Index kBlockColumns = 96;  // similarities computed a block of b at a time (in the cache)

// The best and second best similarity of one feature, as COLMAP's brute-force matcher keeps them: the best is
// the first of equals, and a similarity must exceed 0 to count.
struct BestTwo {
  float best = 0, second = 0;
  int index = -1;
  // Whether the values pass the distance and the ratio test.
  bool Passes(const SiftMatchRules& rules) const {
    const float angle = std::acos(std::min(kSimilarityNorm * best, 1.0f));
    if (angle > rules.max_distance) return false;
    const float second_angle = std::acos(std::min(kSimilarityNorm * second, 1.0f));
    return angle < rules.max_ratio * second_angle;
  }
  // The index of the match, or -1 when there is none or a test rejects it.
  int Match(const SiftMatchRules& rules) const { return index >= 0 && Passes(rules) ? index : -1; }
};

// Adds a similarity to the best two so far (the second counts a value equal to the best).
void AddToBestTwo(float value, float* best, float* second) {
  *second = std::max(*second, std::min(value, *best));
  *best = std::max(*best, value);
}

// The best two of a column of n similarities: in 16 lanes first (vector instructions), then across the lanes;
// the best's index (the first of equals) only when the values pass `rules`, else -1.
BestTwo BestOfColumn(const float* column, Eigen::Index n, const SiftMatchRules& rules) {
  using Lanes = Eigen::Array<float, 16, 1>;
  Lanes best = Lanes::Zero(), second = Lanes::Zero();
  Eigen::Index i = 0;
  for (; i + Lanes::SizeAtCompileTime <= n; i += Lanes::SizeAtCompileTime) {
    const Eigen::Map<const Lanes> values(column + i);
    second = second.max(values.min(best));
    best = best.max(values);
  }
  BestTwo result;
  for (int l = 0; l < Lanes::SizeAtCompileTime; ++l) {
    AddToBestTwo(best[l], &result.best, &result.second);
    AddToBestTwo(second[l], &result.best, &result.second);
  }
  for (; i < n; ++i) AddToBestTwo(column[i], &result.best, &result.second);
  if (!(result.best > 0) || !result.Passes(rules)) return {};
  result.index = static_cast<int>(std::find(column, column + n, result.best) - column);
  return result;
}

// Every row's best two over the columns seen so far, updated a column at a time without branches (the same
// result as BestTwo's rule taken in column order), so that the loop over rows vectorises.
struct RowBests {
  std::vector<float> best, second;
  std::vector<int> index;
  explicit RowBests(Eigen::Index rows) : best(rows, 0.0f), second(rows, 0.0f), index(rows, -1) {}
  void Add(const float* column, int j) {
    const size_t rows = best.size();
    float* __restrict b = best.data();
    float* __restrict s = second.data();
    int* __restrict k = index.data();
    for (size_t i = 0; i < rows; ++i) {
      const float value = column[i];
      s[i] = std::max(s[i], std::min(value, b[i]));
      k[i] = value > b[i] ? j : k[i];
      b[i] = std::max(b[i], value);
    }
  }
  BestTwo operator[](size_t i) const { return {best[i], second[i], index[i]}; }
};

}  // namespace

FeatureMatches MatchSiftDescriptors(const SiftDescriptors& a, const SiftDescriptors& b, const SiftMatchRules& rules) {
  const Eigen::Index n1 = a.cols(), n2 = b.cols();
  if (n1 == 0 || n2 == 0) return {};
  const DescriptorSimilarity similarities(a);
  const Eigen::Index stride = similarities.stride();
  RowBests best12(n1);
  std::vector<BestTwo> best21(n2);
  std::vector<float> block(static_cast<size_t>(stride) * std::min(kBlockColumns, n2));
  for (Eigen::Index j0 = 0; j0 < n2; j0 += kBlockColumns) {
    const Eigen::Index width = std::min(kBlockColumns, n2 - j0);
    similarities.Block(b, j0, width, block.data());
    for (Eigen::Index j = 0; j < width; ++j) {
      const float* column = block.data() + j * stride;
      best12.Add(column, static_cast<int>(j0 + j));
      best21[j0 + j] = BestOfColumn(column, n1, rules);
    }
  }
  FeatureMatches matches;
  for (Eigen::Index i = 0; i < n1; ++i) {
    const int j = best12[i].Match(rules);
    if (j < 0) continue;
    if (rules.cross_check && best21[j].Match(rules) != i) continue;
    matches.emplace_back(static_cast<uint32_t>(i), static_cast<uint32_t>(j));
  }
  return matches;
}

std::vector<std::pair<size_t, size_t>> ExhaustivePairs(size_t images) {
  std::vector<std::pair<size_t, size_t>> pairs;
  for (size_t i = 0; i < images; ++i) {
    for (size_t j = i + 1; j < images; ++j) pairs.emplace_back(i, j);
  }
  return pairs;
}

std::vector<std::pair<size_t, size_t>> SequentialPairs(size_t images, int overlap) {
  std::set<size_t> offsets;
  for (int k = 0; k < overlap; ++k) {
    if (k > 0) offsets.insert(k);
    if (k < 62) offsets.insert(size_t{1} << k);
  }
  std::vector<std::pair<size_t, size_t>> pairs;
  for (size_t i = 0; i < images; ++i) {
    for (const size_t offset : offsets) {
      if (offset < images - i) pairs.emplace_back(i, i + offset);
    }
  }
  return pairs;
}

std::vector<std::pair<size_t, size_t>> LoopPairs(size_t images, int overlap, size_t stride) {
  const std::vector<std::pair<size_t, size_t>> sequential = SequentialPairs(images, overlap);
  const std::set<std::pair<size_t, size_t>> paired(sequential.begin(), sequential.end());
  stride = std::max<size_t>(stride, 1);
  std::vector<std::pair<size_t, size_t>> pairs;
  for (size_t i = 0; i < images; i += stride) {
    for (size_t j = i + stride; j < images; j += stride) {
      if (!paired.count({i, j})) pairs.emplace_back(i, j);
    }
  }
  return pairs;
}

size_t MatchIntoDatabase(const std::filesystem::path& database, const std::vector<std::pair<size_t, size_t>>& pairs,
                         const std::filesystem::path& into) {
  ColmapDatabase db(database, /*read_only=*/!into.empty());
  const std::vector<ColmapDatabaseImage> images = db.Images();
  std::vector<std::pair<size_t, size_t>> todo;
  for (const auto& [i, j] : pairs) {
    if (i < images.size() && j < images.size() && !db.HasMatches(images[i].id, images[j].id)) todo.emplace_back(i, j);
  }
  std::map<size_t, SiftDescriptors> descriptors;
  for (const auto& [i, j] : todo) {
    for (const size_t k : {i, j}) {
      if (!descriptors.count(k)) descriptors[k] = db.Descriptors(images[k].id);
    }
  }
  std::vector<std::pair<std::pair<uint32_t, uint32_t>, FeatureMatches>> results(todo.size());
  Progress progress("sfm: matching descriptors", static_cast<int64_t>(todo.size()), "pairs");
  tbb::parallel_for(size_t{0}, todo.size(), [&](size_t p) {
    ThrowIfCancelled();
    const auto [i, j] = todo[p];
    results[p] = {{images[i].id, images[j].id}, MatchSiftDescriptors(descriptors.at(i), descriptors.at(j))};
    progress.Add();
  });
  if (into.empty()) {
    db.WriteMatches(results);
  } else {
    ColmapDatabase(into).WriteMatches(results);
  }
  return todo.size();
}

}  // namespace p2n

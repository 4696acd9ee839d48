#include "stages/sfm/retrieval.h"

#include <algorithm>
#include <charconv>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <string_view>

#include "base/errors.h"
#include "base/format.h"

namespace p2n {
namespace {

constexpr std::string_view kQuery = "Querying for image ", kRetrieved = "  image_id=";

// The vocabulary tree's sizes (TreeSizeFor).
constexpr size_t kFeaturesPerWord = 64, kMinWords = 256, kMaxLinearWords = 999;
constexpr size_t kLargeTreePhotos = 2'000, kLargeTreeMaxWords = 9'600, kTreePhotos = 30;

[[noreturn]] void Unreadable(const std::string& line) {
  throw ExternalToolError(format("COLMAP's retrieval: '{}' names no photo of the database", line));
}

// The photo a query line names ("Querying for image NAME [i/n] in 0.012s": the name may hold " [" itself, the
// count comes last).
size_t QueriedPhoto(const std::string& line, const std::map<std::string, size_t>& by_name) {
  const size_t end = line.rfind(" [");
  if (end == std::string::npos || end < kQuery.size()) Unreadable(line);
  const auto found = by_name.find(line.substr(kQuery.size(), end - kQuery.size()));
  if (found == by_name.end()) Unreadable(line);
  return found->second;
}

// The photo a line of retrieved photos names by its database id.
size_t RetrievedPhoto(const std::string& line, const std::map<uint32_t, size_t>& by_id) {
  uint32_t id = 0;
  const char* digits = line.data() + kRetrieved.size();
  if (std::from_chars(digits, line.data() + line.size(), id).ec != std::errc()) Unreadable(line);
  const auto found = by_id.find(id);
  if (found == by_id.end()) Unreadable(line);
  return found->second;
}

// The ranks (0: the most similar other photo) `picks` takes of a list of `count`.
std::vector<size_t> PickedRanks(const RetrievalPicks& picks, size_t count) {
  std::vector<size_t> ranks;
  for (size_t r = 0; r < std::min(picks.nearest, count); ++r) ranks.push_back(r);
  if (count <= picks.nearest) return ranks;
  const size_t rest = count - picks.nearest;
  const size_t spread = std::min(picks.spread, rest);
  for (size_t j = 0; j < spread; ++j) ranks.push_back(picks.nearest + (2 * j + 1) * rest / (2 * spread));
  return ranks;
}

// Adds the pairs of `query` with the photos `retrieved` for it (most similar first) that `picks` takes.
void AddPicked(size_t query, const std::vector<size_t>& retrieved, const RetrievalPicks& picks,
               std::set<std::pair<size_t, size_t>>* seen, std::vector<std::pair<size_t, size_t>>* pairs) {
  for (const size_t rank : PickedRanks(picks, retrieved.size())) {
    const std::pair<size_t, size_t> pair(std::min(query, retrieved[rank]), std::max(query, retrieved[rank]));
    if (seen->insert(pair).second) pairs->push_back(pair);
  }
}

}  // namespace

VocabularyTreeSize TreeSizeFor(size_t photos, size_t features) {
  const size_t words = photos < kLargeTreePhotos
                           ? std::clamp<size_t>(photos * features / kFeaturesPerWord, kMinWords, kMaxLinearWords)
                           : std::min<size_t>(photos * 12 / 5, kLargeTreeMaxWords);
  return {words, std::min(photos, kTreePhotos)};  // COLMAP aborts when asked for more photos than there are
}

std::vector<std::pair<size_t, size_t>> RetrievedPairs(const std::string& answer,
                                                      const std::vector<ColmapDatabaseImage>& images,
                                                      const RetrievalPicks& picks) {
  std::map<std::string, size_t> by_name;
  std::map<uint32_t, size_t> by_id;
  for (size_t i = 0; i < images.size(); ++i) {
    by_name[images[i].name] = i;
    by_id[images[i].id] = i;
  }
  std::vector<std::pair<size_t, size_t>> pairs;
  std::set<std::pair<size_t, size_t>> seen;
  std::optional<size_t> query;
  std::vector<size_t> retrieved;  // for `query`, itself left out
  std::istringstream lines(answer);
  for (std::string line; std::getline(lines, line);) {
    if (line.starts_with(kQuery)) {
      if (query) AddPicked(*query, retrieved, picks, &seen, &pairs);
      query = QueriedPhoto(line, by_name);
      retrieved.clear();
    } else if (line.starts_with(kRetrieved)) {
      if (!query) Unreadable(line);
      const size_t photo = RetrievedPhoto(line, by_id);
      if (photo != *query) retrieved.push_back(photo);
    }
  }
  if (query) AddPicked(*query, retrieved, picks, &seen, &pairs);
  return pairs;
}

}  // namespace p2n

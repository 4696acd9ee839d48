#include "stages/retrieval.h"

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

}  // namespace

std::vector<std::pair<size_t, size_t>> RetrievedPairs(const std::string& answer,
                                                      const std::vector<ColmapDatabaseImage>& images) {
  std::map<std::string, size_t> by_name;
  std::map<uint32_t, size_t> by_id;
  for (size_t i = 0; i < images.size(); ++i) {
    by_name[images[i].name] = i;
    by_id[images[i].id] = i;
  }
  std::vector<std::pair<size_t, size_t>> pairs;
  std::set<std::pair<size_t, size_t>> seen;
  std::optional<size_t> query;
  std::istringstream lines(answer);
  for (std::string line; std::getline(lines, line);) {
    if (line.starts_with(kQuery)) {
      query = QueriedPhoto(line, by_name);
    } else if (line.starts_with(kRetrieved)) {
      if (!query) Unreadable(line);
      const size_t retrieved = RetrievedPhoto(line, by_id);
      const std::pair<size_t, size_t> pair(std::min(*query, retrieved), std::max(*query, retrieved));
      if (pair.first != pair.second && seen.insert(pair).second) pairs.push_back(pair);
    }
  }
  return pairs;
}

}  // namespace p2n

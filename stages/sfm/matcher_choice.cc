#include "stages/sfm/matcher_choice.h"

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>

namespace p2n {
namespace {

constexpr double kMinNumbered = 0.9;    // share of names that must end in a number after the common prefix
constexpr uint64_t kMaxMedianStep = 2;  // the median step between sorted numbers, in commonest steps
constexpr size_t kMaxDigits = 18;       // longer digit runs are not counters

struct Numbered {
  std::string prefix;
  uint64_t number = 0;
};

// "IMG_0412.JPG" -> {"IMG_", 412}; none when the stem does not end in digits.
std::optional<Numbered> SplitNumber(const std::string& name) {
  const std::string stem = std::filesystem::path(name).stem().string();
  size_t start = stem.size();
  while (start > 0 && std::isdigit(static_cast<unsigned char>(stem[start - 1]))) --start;
  if (start == stem.size() || stem.size() - start > kMaxDigits) return std::nullopt;
  return Numbered{stem.substr(0, start), std::stoull(stem.substr(start))};
}

}  // namespace

bool LooksLikeFrameSequence(const std::vector<std::string>& names) {
  if (names.size() < 3) return true;  // nothing to get wrong
  std::map<std::string, std::vector<uint64_t>> by_prefix;
  for (const std::string& name : names) {
    if (const std::optional<Numbered> split = SplitNumber(name)) by_prefix[split->prefix].push_back(split->number);
  }
  const auto largest = std::max_element(by_prefix.begin(), by_prefix.end(),
                                        [](const auto& a, const auto& b) { return a.second.size() < b.second.size(); });
  if (largest == by_prefix.end() || largest->second.size() < kMinNumbered * names.size()) return false;
  std::vector<uint64_t> numbers = largest->second;
  std::sort(numbers.begin(), numbers.end());
  std::vector<uint64_t> steps;
  std::map<uint64_t, size_t> counts;
  for (size_t i = 1; i < numbers.size(); ++i) {
    steps.push_back(numbers[i] - numbers[i - 1]);
    ++counts[steps.back()];
  }
  // The commonest step (the smallest of equals) is the sequence's own; frames left out (blurred, deleted) make
  // some steps longer, but the median stays within a few of it. Numbers with no relation step anyhow.
  const uint64_t commonest = std::max_element(counts.begin(), counts.end(), [](const auto& a, const auto& b) {
                               return a.second < b.second;
                             })->first;
  std::nth_element(steps.begin(), steps.begin() + steps.size() / 2, steps.end());
  return commonest > 0 && steps[steps.size() / 2] <= kMaxMedianStep * commonest;
}

namespace {

Matcher Unordered(size_t photos) {
  return static_cast<int>(photos) <= kRetrievalMinImages ? Matcher::kExhaustive : Matcher::kVocabTree;
}

}  // namespace

Matcher AutoMatcher(const std::vector<std::string>& names, int exhaustive_max_images, bool one_video) {
  const int exhaustive_limit = one_video ? kVideoExhaustiveFactor * exhaustive_max_images : exhaustive_max_images;
  if (static_cast<int>(names.size()) <= exhaustive_limit) return Matcher::kExhaustive;
  return one_video || LooksLikeFrameSequence(names) ? Matcher::kSequential : Unordered(names.size());
}

std::optional<Matcher> RetryMatcher(Matcher first, size_t photos) {
  if (first == Matcher::kExhaustive) return std::nullopt;
  return first == Matcher::kSequential ? Unordered(photos) : Matcher::kSequential;
}

}  // namespace p2n

// sfm.matcher auto: numbered sequences are matched sequentially, anything else by retrieval, small sets
// exhaustively; and the matcher a failed first try adds.

#include <catch2/catch.hpp>

#include <algorithm>
#include <random>

#include "base/format.h"
#include "stages/matcher_choice.h"

namespace p2n::testing {
namespace {

std::vector<std::string> Names(const std::string& pattern, int first, int count, int step = 1) {
  std::vector<std::string> names;
  for (int i = 0; i < count; ++i) names.push_back(format(pattern, first + i * step));
  return names;
}

}  // namespace

TEST_CASE("matcher choice: numbered sequences are sequential, unordered names are not", "[sfm]") {
  CHECK(LooksLikeFrameSequence(Names("{:04d}.jpg", 1, 50)));
  // fox's photos: frames of a video with the blurred ones left out (steps of 1 to 4, once 18)
  std::vector<std::string> fox;
  for (int frame :
       {1,  2,  3,  4,  6,  7,  8,  9,  12, 14, 18, 19, 21, 22, 25, 26, 27, 29, 30, 31,  33,  34,  35,  39,  42,
        44, 45, 46, 49, 52, 54, 72, 73, 74, 76, 77, 78, 81, 84, 85, 89, 90, 94, 97, 103, 105, 107, 108, 110, 115}) {
    fox.push_back(format("{:04d}.jpg", frame));
  }
  CHECK(LooksLikeFrameSequence(fox));
  CHECK(LooksLikeFrameSequence(Names("frame_{:05d}.png", 0, 120, 5)));  // every 5th video frame
  std::vector<std::string> phone = Names("IMG_{:04d}.JPG", 412, 60);
  phone.erase(phone.begin() + 10, phone.begin() + 14);  // a few deleted shots
  phone.push_back("notes.txt.jpg");                     // and one stray file
  CHECK(LooksLikeFrameSequence(phone));

  std::mt19937 random(5);
  std::vector<std::string> hex, numbers, words;
  for (int i = 0; i < 60; ++i) {
    hex.push_back(format("{:08x}.jpg", random()));
    numbers.push_back(format("{}.jpg", random() % 100000000));  // digits, but no regular step
    words.push_back(format("photo by {} {}.jpg", i % 3 ? "ann" : "bob", static_cast<char>('a' + i % 26)));
  }
  CHECK_FALSE(LooksLikeFrameSequence(hex));
  CHECK_FALSE(LooksLikeFrameSequence(numbers));
  CHECK_FALSE(LooksLikeFrameSequence(words));

  CHECK(AutoMatcher(fox, 40) == Matcher::kSequential);
  CHECK(AutoMatcher(std::vector<std::string>(hex.begin(), hex.begin() + 40), 40) == Matcher::kExhaustive);
  CHECK(AutoMatcher(hex, 40) == Matcher::kExhaustive);  // 60 unordered: as cheap as retrieval
  std::vector<std::string> many = hex;
  for (int i = 0; i < 60; ++i) many.push_back(format("{:08x}.png", random()));
  CHECK(AutoMatcher(many, 40) == Matcher::kVocabTree);

  // A video's frames as ingest takes them, the sharpest of each stretch of motion: steps of 2 to 9 frames, the
  // commonest 2.
  const int steps[] = {2, 2, 6, 8, 7, 9};
  std::vector<std::string> frames;
  for (int i = 0, frame = 0; i < 120; frame += steps[i % 6], ++i) frames.push_back(format("clip_{:05d}.jpg", frame));
  CHECK_FALSE(LooksLikeFrameSequence(frames));
  CHECK(AutoMatcher(frames, 100) == Matcher::kVocabTree);
  CHECK(AutoMatcher(frames, 100, /*one_video=*/true) == Matcher::kExhaustive);  // 120 frames: pairs cost less
  CHECK(AutoMatcher(frames, 50, /*one_video=*/true) == Matcher::kSequential);
}

TEST_CASE("matcher choice: a failed first matching adds the other kind once", "[sfm]") {
  CHECK(RetryMatcher(Matcher::kSequential, 60) == Matcher::kExhaustive);
  CHECK(RetryMatcher(Matcher::kSequential, 150) == Matcher::kVocabTree);
  CHECK(RetryMatcher(Matcher::kVocabTree, 150) == Matcher::kSequential);
  CHECK_FALSE(RetryMatcher(Matcher::kExhaustive, 30));  // its pairs contain every other matcher's
}

}  // namespace p2n::testing

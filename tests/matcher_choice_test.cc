// sfm.matcher auto: numbered sequences are matched sequentially, anything else by retrieval, small sets
// exhaustively; the matcher a failed first try adds; retrieval's answer read as pairs.

#include <catch2/catch.hpp>

#include <algorithm>
#include <random>

#include "base/errors.h"
#include "base/format.h"
#include "stages/sfm/matcher_choice.h"
#include "stages/sfm/retrieval.h"

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

// COLMAP's vocab_tree_retriever's printed answer (3.8's format) as pairs of photos in name order: the photo itself
// and pairs named twice left out, a name holding " [" read whole, ids against name order (ids 3, 1, 2 for a, b, c).
TEST_CASE("retrieval: COLMAP's answer read as pairs of photos in name order", "[sfm]") {
  const std::vector<ColmapDatabaseImage> images = {{3, "a.jpg"}, {1, "b [2].jpg"}, {2, "c.jpg"}, {4, "d.jpg"}};
  const std::string answer =
      "$ colmap vocab_tree_retriever --database_path db\n"
      "Indexing image [1/4] in 0.010s\n"
      "Querying for image b [2].jpg [1/4] in 0.002s\n"
      "  image_id=1, image_name=b [2].jpg, score=0.9\n"
      "  image_id=3, image_name=a.jpg, score=0.5\n"
      "  image_id=2, image_name=c.jpg, score=0.1\n"
      "Querying for image a.jpg [2/4] in 0.002s\n"
      "  image_id=3, image_name=a.jpg, score=0.9\n"
      "  image_id=1, image_name=b [2].jpg, score=0.5\n"
      "  image_id=4, image_name=d.jpg, score=0.4\n"
      "Querying for image d.jpg [3/4] in 0.002s\n";
  using Pairs = std::vector<std::pair<size_t, size_t>>;
  const RetrievalPicks all{10, 0};
  CHECK(RetrievedPairs(answer, images, all) == Pairs{{0, 1}, {1, 2}, {0, 3}});
  CHECK(RetrievedPairs("", images, all).empty());
  // The nearest one of each and none spread: the second of each (c for b, d for a) is left out.
  CHECK(RetrievedPairs(answer, images, {1, 0}) == Pairs{{0, 1}});

  // An answer about other photos is refused, naming the line.
  CHECK_THROWS_AS(RetrievedPairs("Querying for image e.jpg [1/1] in 0.1s\n", images, all), ExternalToolError);
  CHECK_THROWS_WITH(
      RetrievedPairs("Querying for image a.jpg [1/4]\n  image_id=9, image_name=x, score=1\n", images, all),
      Catch::Contains("image_id=9"));
  CHECK_THROWS_AS(RetrievedPairs("  image_id=1, image_name=b [2].jpg, score=1\n", images, all), ExternalToolError);
  CHECK_THROWS_AS(RetrievedPairs("Querying for image a.jpg [1/4]\n  image_id=x\n", images, all), ExternalToolError);
}

// Photo 0's list of the other twelve, most similar first: the two nearest, then three at even steps through the
// other ten (ranks 2 + 1, 2 + 5 and 2 + 8 of 0..11).
TEST_CASE("retrieval: the nearest photos retrieved, and more spread through the rest of the list", "[sfm]") {
  std::vector<ColmapDatabaseImage> images;
  std::string answer = "Querying for image p00.jpg [1/13] in 0.002s\n";
  for (uint32_t i = 0; i < 13; ++i) {
    images.push_back({i + 1, format("p{:02}.jpg", i)});
    answer += format("  image_id={}, image_name=p{:02}.jpg, score=0.5\n", i + 1, i);  // itself first
  }
  using Pairs = std::vector<std::pair<size_t, size_t>>;
  CHECK(RetrievedPairs(answer, images, {2, 3}) == Pairs{{0, 1}, {0, 2}, {0, 4}, {0, 8}, {0, 11}});
  CHECK(RetrievalPicks{2, 3}.Candidates() == 11);
  // A list shorter than the picks: every photo of it, once.
  CHECK(RetrievedPairs(answer, images, {2, 20}).size() == 12);
  CHECK(RetrievedPairs(answer, images, {20, 5}).size() == 12);
}

TEST_CASE("retrieval: the vocabulary tree's words grow with the photos from 2,000", "[sfm]") {
  using Size = std::pair<size_t, size_t>;
  const auto size = [](size_t photos, size_t features) {
    const VocabularyTreeSize tree = TreeSizeFor(photos, features);
    return Size{tree.words, tree.photos};
  };
  CHECK(size(5, 1'000) == Size{256, 5});         // 78 by the features, at least 256; the photos there are
  CHECK(size(20, 2'048) == Size{640, 20});       // a word per 64 features
  CHECK(size(300, 2'048) == Size{999, 30});      // below FLANN's tuned index
  CHECK(size(1'999, 2'048) == Size{999, 30});    // the last below 2,000 photos
  CHECK(size(2'000, 2'048) == Size{4'800, 30});  // 2.4 a photo
  CHECK(size(3'000, 512) == Size{7'200, 30});    // whatever the features
  CHECK(size(4'000, 2'048) == Size{9'600, 30});  // at most 9,600
  CHECK(size(20'000, 2'048) == Size{9'600, 30});
}

}  // namespace p2n::testing

// The window over training photos too many for memory (base/photo_window.h).

#include <catch2/catch.hpp>

#include <atomic>
#include <set>
#include <stdexcept>

#include "base/decoded_photos.h"
#include "base/photo_window.h"
#include "test_util.h"

namespace p2n::testing {
namespace {

constexpr int kWidth = 8, kHeight = 6;
constexpr size_t kViewBytes = kWidth * kHeight * 3;

std::vector<TrainView> ViewsWithoutPixels(size_t count) {
  std::vector<TrainView> views(count);
  for (size_t v = 0; v < count; ++v) {
    views[v].camera.width = kWidth;
    views[v].camera.height = kHeight;
    views[v].name = "view_" + std::to_string(v);
  }
  return views;
}

// Every pixel of view v holds v; counts the reads.
PhotoWindow::Loader CountingLoader(std::atomic<int>* reads) {
  return [reads](size_t v) {
    ++*reads;
    return std::vector<uint8_t>(kViewBytes, static_cast<uint8_t>(v));
  };
}

}  // namespace

TEST_CASE("photo window: within its budget it moves through every photo, each read once a pass", "[photo_window]") {
  std::vector<TrainView> views = ViewsWithoutPixels(10);
  std::atomic<int> reads{0};
  const double budget = 6 * kViewBytes + 10;  // six photos: a window of four and one being read
  PhotoWindow window(&views, CountingLoader(&reads), budget, 7);
  CHECK(window.size() == 4);
  CHECK(window.stride() == 1);
  CHECK(reads == 0);  // nothing before the first move

  std::set<size_t> seen;
  const int moves = 10;  // a whole pass: ten photos, one more a move
  for (int step = 0; step < moves * PhotoWindow::kStepsPerMove; ++step) {
    CHECK(window.MoveTo(step) == (step % PhotoWindow::kStepsPerMove == 0));
    const std::vector<size_t>& resident = window.resident();
    REQUIRE(resident.size() == 4);
    size_t bytes = 0;
    for (size_t v = 0; v < views.size(); ++v) {
      const bool in = std::find(resident.begin(), resident.end(), v) != resident.end();
      CHECK(views[v].pixels.empty() != in);
      bytes += views[v].pixels.size();
      if (in) CHECK(views[v].pixels == std::vector<uint8_t>(kViewBytes, static_cast<uint8_t>(v)));
    }
    CHECK(bytes + kViewBytes <= budget);  // with the photo being read ahead
    seen.insert(resident.begin(), resident.end());
  }
  CHECK(seen.size() == views.size());
  // The first window, then one photo a move, and the next move's read ahead: none twice.
  CHECK(reads <= 4 + (moves - 1) + 1);
  CHECK(reads >= 4 + (moves - 1));

  SECTION("a window that starts at a later step (a resumed run) holds the same photos there") {
    std::vector<TrainView> resumed_views = ViewsWithoutPixels(10);
    std::atomic<int> resumed_reads{0};
    PhotoWindow resumed(&resumed_views, CountingLoader(&resumed_reads), budget, 7);
    const int step = moves * PhotoWindow::kStepsPerMove - 1;
    CHECK(resumed.MoveTo(step));
    CHECK(resumed.resident() == window.resident());
  }
  SECTION("another seed shuffles the photos otherwise") {
    std::vector<TrainView> other_views = ViewsWithoutPixels(10);
    PhotoWindow other(&other_views, CountingLoader(&reads), budget, 8);
    std::vector<size_t> first, other_first;
    for (int move = 0; move < 3; ++move) {
      window.MoveTo(move * PhotoWindow::kStepsPerMove);
      other.MoveTo(move * PhotoWindow::kStepsPerMove);
      first.insert(first.end(), window.resident().begin(), window.resident().end());
      other_first.insert(other_first.end(), other.resident().begin(), other.resident().end());
    }
    CHECK(first != other_first);
  }
}

TEST_CASE("photo window: a budget of fewer than five photos, and a photo that cannot be read, are errors",
          "[photo_window]") {
  std::vector<TrainView> views = ViewsWithoutPixels(10);
  std::atomic<int> reads{0};
  CHECK_THROWS_WITH(PhotoWindow(&views, CountingLoader(&reads), 5 * kViewBytes - 1, 0),
                    Catch::Contains("a window needs 5"));

  // The window of the second move reads a photo that fails: the error reaches the training loop there.
  PhotoWindow probe(&views, CountingLoader(&reads), 6 * kViewBytes, 0);
  probe.MoveTo(0);
  const std::vector<size_t> first = probe.resident();
  probe.MoveTo(PhotoWindow::kStepsPerMove);
  size_t added = 0;
  for (const size_t v : probe.resident()) {
    if (std::find(first.begin(), first.end(), v) == first.end()) added = v;
  }
  std::vector<TrainView> failing_views = ViewsWithoutPixels(10);
  PhotoWindow failing(
      &failing_views,
      [added](size_t v) {
        if (v == added) throw std::runtime_error("cannot read " + std::to_string(v));
        return std::vector<uint8_t>(kViewBytes, 1);
      },
      6 * kViewBytes, 0);
  CHECK(failing.MoveTo(0));
  CHECK_THROWS_WITH(failing.MoveTo(PhotoWindow::kStepsPerMove), "cannot read " + std::to_string(added));
}

}  // namespace p2n::testing

namespace p2n::testing {

TEST_CASE("held-out views: their own pixels, else a copy with them read, else an error", "[photo_window]") {
  TrainingData data;
  data.heldout = ViewsWithoutPixels(3);
  data.heldout[1].pixels.assign(kViewBytes, 9);
  TrainView scratch;
  CHECK(&HeldoutView(data, 1, &scratch) == &data.heldout[1]);
  CHECK_THROWS_AS(HeldoutView(data, 0, &scratch), std::logic_error);
  std::atomic<int> reads{0};
  data.read_heldout = CountingLoader(&reads);
  const TrainView& read = HeldoutView(data, 2, &scratch);
  CHECK(&read == &scratch);
  CHECK(read.name == "view_2");
  CHECK(read.pixels == std::vector<uint8_t>(kViewBytes, 2));
  CHECK(data.heldout[2].pixels.empty());  // nothing kept
  CHECK(&HeldoutView(data, 1, &scratch) == &data.heldout[1]);
  CHECK(reads == 1);
}

TEST_CASE("decoded photos: each read back as decoded, from a file with no name left in its folder", "[photo_window]") {
  TempDir dir;
  const std::vector<size_t> sizes = {10, 0, 300, 7};
  const DecodedPhotos photos(dir.path(), sizes, [&](size_t i) {
    std::vector<uint8_t> pixels(sizes[i]);
    for (size_t k = 0; k < pixels.size(); ++k) pixels[k] = static_cast<uint8_t>(i * 31 + k);
    return pixels;
  });
  CHECK(std::filesystem::is_empty(dir.path()));
  for (size_t i = 0; i < sizes.size(); ++i) {
    const std::vector<uint8_t> pixels = photos.Read(i);
    REQUIRE(pixels.size() == sizes[i]);
    for (size_t k = 0; k < pixels.size(); ++k) CHECK(pixels[k] == static_cast<uint8_t>(i * 31 + k));
  }
  CHECK_THROWS_WITH(DecodedPhotos(dir.path() / "missing", sizes, [](size_t) { return std::vector<uint8_t>(); }),
                    Catch::Contains("missing") && Catch::Contains("cannot make a file"));
}

}  // namespace p2n::testing

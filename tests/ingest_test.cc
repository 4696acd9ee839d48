// The ingest stage on small images made here: bad files, EXIF orientation, fingerprints, downsizing.

#include <catch2/catch.hpp>
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>

#include <fstream>

#include "nerf/image_io.h"
#include "pipeline/errors.h"
#include "pipeline/file_util.h"
#include "stages/ingest_stage.h"
#include "stages/stages.h"
#include "tests/test_util.h"

namespace p2n::testing {
namespace fs = std::filesystem;
namespace {

// A w x h RGB image: left half red, right half blue, with a seed-dependent grey square.
OIIO::ImageBuf MakeImage(int width, int height, int seed) {
  OIIO::ImageBuf image(OIIO::ImageSpec(width, height, 3, OIIO::TypeDesc::UINT8));
  OIIO::ImageBufAlgo::fill(image, {1.0f, 0.0f, 0.0f}, OIIO::ROI(0, width / 2, 0, height));
  OIIO::ImageBufAlgo::fill(image, {0.0f, 0.0f, 1.0f}, OIIO::ROI(width / 2, width, 0, height));
  OIIO::ImageBufAlgo::fill(image, {0.5f, 0.5f, 0.5f}, OIIO::ROI(seed % 4, seed % 4 + 2, 0, 2));
  return image;
}

void Write(const OIIO::ImageBuf& image, const fs::path& path, int orientation = 1) {
  OIIO::ImageBuf copy;
  copy.copy(image);
  if (orientation != 1) copy.specmod().attribute("Orientation", orientation);
  REQUIRE(copy.write(path.string()));
}

struct IngestFixture {
  TempDir dir;
  fs::path photos = dir / "photos";
  OptionRegistry registry = AllOptions();
  Config config{registry};
  Workspace workspace = Workspace::Open(dir / "ws", true);
  Runner runner = MakeRunner();

  IngestFixture() {
    fs::create_directories(photos);
    workspace.SetInput(photos);
  }
  nlohmann::json Run() {
    RunRequest request;
    request.until = "ingest";
    runner.Run(workspace, config, request);
    return ReadJsonFile(workspace.StageDir("00_ingest") / "ingest_report.json");
  }
  StageStatus Status() { return runner.Status(workspace, config).at(0); }
};

std::string SkipReason(const nlohmann::json& report, const std::string& file) {
  for (const auto& skipped : report["skipped"]) {
    if (skipped["file"] == file) return skipped["reason"];
  }
  return "(not skipped)";
}

}  // namespace

TEST_CASE("ingest skips files that are not decodable images, naming the reason", "[ingest]") {
  IngestFixture f;
  for (int i = 0; i < 3; ++i) Write(MakeImage(40, 20, i), f.photos / ("good" + std::to_string(i) + ".jpg"));
  Write(MakeImage(40, 20, 7), f.dir / "whole.jpg");
  const std::string whole = ReadText(f.dir / "whole.jpg");
  WriteText(f.photos / "truncated.jpg", whole.substr(0, whole.size() / 2));
  WriteText(f.photos / "text.JPG", "this is not an image\n");
  WriteText(f.photos / "zero.png", "");
  WriteText(f.photos / "notes.txt", "ignored: not an image by name");

  const nlohmann::json report = f.Run();
  CHECK(report["images"].size() == 3);
  CHECK(report["skipped"].size() == 3);
  CHECK_THAT(SkipReason(report, "truncated.jpg"), Catch::Contains("Premature end of JPEG file"));
  CHECK_THAT(SkipReason(report, "text.JPG"), Catch::Contains("not a readable image"));
  CHECK_THAT(SkipReason(report, "zero.png"), Catch::Contains("empty file"));
  CHECK(fs::exists(f.workspace.StageDir("00_ingest") / "images" / "good0.jpg"));
  CHECK_FALSE(fs::exists(f.workspace.StageDir("00_ingest") / "images" / "truncated.jpg"));
}

TEST_CASE("ingest applies EXIF orientation", "[ingest]") {
  IngestFixture f;
  for (int i = 0; i < 2; ++i) Write(MakeImage(40, 20, i), f.photos / ("plain" + std::to_string(i) + ".png"));
  // Orientation 6: the stored image must be turned 90 degrees clockwise, so its left (red) half becomes the top.
  Write(MakeImage(40, 20, 0), f.photos / "rotated.jpg", 6);
  const nlohmann::json report = f.Run();
  const nlohmann::json& rotated = report["images"][2];
  REQUIRE(rotated["source"] == "rotated.jpg");
  CHECK(rotated["exif_orientation"] == 6);
  CHECK(rotated["width"] == 20);
  CHECK(rotated["height"] == 40);
  const ReadImageResult upright = ReadImage(f.workspace.StageDir("00_ingest") / "images" / rotated["name"].get<std::string>());
  REQUIRE(upright.ok());
  CHECK(upright.orientation == 1);
  float top[3], bottom[3];
  upright.image.getpixel(10, 5, top);
  upright.image.getpixel(10, 35, bottom);
  CHECK(top[0] > 0.8f);
  CHECK(top[2] < 0.2f);
  CHECK(bottom[2] > 0.8f);
  CHECK(bottom[0] < 0.2f);
}

TEST_CASE("fingerprints follow the pixels, not the file's time stamp", "[ingest]") {
  IngestFixture f;
  for (int i = 0; i < 3; ++i) Write(MakeImage(16, 16, i), f.photos / ("img" + std::to_string(i) + ".png"));
  const nlohmann::json first = f.Run();
  const std::string fingerprint = first["images"][1]["fingerprint"];

  const fs::path file = f.photos / "img1.png";
  fs::last_write_time(file, fs::last_write_time(file) + std::chrono::hours(2));
  CHECK(f.Status().state == StageState::kFresh);

  OIIO::ImageBuf changed = MakeImage(16, 16, 1);
  const float pixel[3] = {0.0f, 1.0f, 0.0f};
  changed.setpixel(15, 15, pixel);
  Write(changed, file);
  const StageStatus status = f.Status();
  CHECK(status.state == StageState::kStale);
  CHECK(status.reasons == std::vector<std::string>{"input image img1.png changed"});
  const nlohmann::json second = f.Run();
  CHECK(second["images"][1]["fingerprint"] != fingerprint);
  CHECK(second["images"][0]["fingerprint"] == first["images"][0]["fingerprint"]);
}

TEST_CASE("ingest downsizes to ingest.max_image_size with an area filter", "[ingest]") {
  IngestFixture f;
  for (int i = 0; i < 3; ++i) Write(MakeImage(64, 32, i), f.photos / ("img" + std::to_string(i) + ".png"));
  f.config.Set("ingest.max_image_size", 32, "test");
  const nlohmann::json report = f.Run();
  CHECK(report["images"][0]["width"] == 32);
  CHECK(report["images"][0]["height"] == 16);
  CHECK(report["images"][0]["source_width"] == 64);
  const ReadImageResult small = ReadImage(f.workspace.StageDir("00_ingest") / "images" / "img0.png");
  REQUIRE(small.ok());
  float left[3], right[3];
  small.image.getpixel(4, 8, left);
  small.image.getpixel(28, 8, right);
  CHECK(left[0] == Approx(1.0f));
  CHECK(right[2] == Approx(1.0f));
}

TEST_CASE("too few usable images, a missing or empty folder are user errors", "[ingest]") {
  IngestFixture f;
  CHECK_THROWS_WITH(f.Run(), Catch::Contains("no photos in") && Catch::Contains(f.photos.string()));
  Write(MakeImage(16, 16, 0), f.photos / "a.png");
  WriteText(f.photos / "b.png", "broken");
  CHECK_THROWS_WITH(f.Run(), Catch::Contains("only 1 usable images") && Catch::Contains("ingest.min_images"));
  CHECK(f.Status().state == StageState::kIncomplete);
  fs::remove_all(f.photos);
  CHECK_THROWS_WITH(f.Run(), Catch::Contains("does not exist"));
  CHECK_THROWS_WITH(ListPhotos(f.dir / "ws" / "workspace.json"), Catch::Contains("is a file, not a folder"));
}

TEST_CASE("absurd declared image sizes are refused before allocating", "[ingest]") {
  TempDir dir;
  // A PNG that declares 100000 x 100000 pixels (IHDR) and has an empty IDAT.
  const unsigned char header[] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n', 0, 0, 0, 13, 'I', 'H', 'D', 'R',
                                  0, 1, 0x86, 0xa0, 0, 1, 0x86, 0xa0, 8, 2, 0, 0, 0, 0x27, 0x30, 0x9c, 0x9f,
                                  0, 0, 0, 0, 'I', 'D', 'A', 'T', 0x35, 0xaf, 0x06, 0x1e};
  std::ofstream(dir / "huge.png", std::ios::binary).write(reinterpret_cast<const char*>(header), sizeof(header));
  const ReadImageResult result = ReadImage(dir / "huge.png");
  CHECK_FALSE(result.ok());
  CHECK_THAT(result.error, Catch::Contains("100000x100000"));
}

}  // namespace p2n::testing

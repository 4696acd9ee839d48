// Videos in: which frames are chosen (windows of equal motion, the sharpest of each, repeats left out), ingest of a
// video beside photos, a phone's rotation honoured, and the bad videos (cut short, empty, only sound, not a video),
// each a clear error naming the file that keeps the last result.

#include <catch2/catch.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <fstream>
#include <set>

#include "base/errors.h"
#include "base/file_util.h"
#include "base/format.h"
#include "base/image_io.h"
#include "stages/ingest/frame_choice.h"
#include "tests/stage_fixtures.h"
#include "tests/test_util.h"

namespace p2n::testing {
namespace fs = std::filesystem;
namespace {

// A scan whose frame i has thumbnail value travelled[i] everywhere, so that ThumbnailDifference of two frames is
// the motion between them: `motion[i]` from frame i - 1 to i, `sharpness` as given.
VideoScan ScanOf(const std::vector<double>& motion, const std::vector<double>& sharpness) {
  VideoScan scan;
  scan.fps = 10;
  scan.thumbnail_height = 1;
  double travelled = 0;
  for (size_t i = 0; i < motion.size(); ++i) {
    travelled += i ? motion[i] : 0;
    scan.times.push_back(i / scan.fps);
    scan.motion.push_back(i ? motion[i] : 0);
    scan.sharpness.push_back(sharpness[i]);
    scan.thumbnails.push_back(std::vector<uint8_t>(kThumbnailWidth, static_cast<uint8_t>(travelled)));
  }
  return scan;
}

// A textured frame of a scene panned `shift` pixels to the left; blurred when `blurred`.
cv::Mat PannedFrame(int width, int height, int shift, bool blurred) {
  cv::Mat frame(height, width, CV_8UC3);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const int u = x + shift;
      const uint8_t value = ((u / 6 + y / 6) % 2) ? 220 : 30;
      frame.at<cv::Vec3b>(y, x) = {value, static_cast<uint8_t>((u * 7 + y * 3) % 256),
                                   static_cast<uint8_t>(255 - value)};
    }
  }
  if (blurred) cv::GaussianBlur(frame, frame, cv::Size(0, 0), 3.0);
  return frame;
}

// A 96 x 64 motion-JPEG AVI at 10 frames a second: a pan of 2 pixels a frame, still for frames 20 to 29, frames in
// `blurred` blurred.
void WritePanVideo(const fs::path& path, int frames, const std::set<int>& blurred) {
  cv::VideoWriter writer(path.string(), cv::CAP_FFMPEG, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 10.0,
                         cv::Size(96, 64));
  REQUIRE(writer.isOpened());
  for (int i = 0; i < frames; ++i) {
    const int shift = 2 * (i < 20 ? i : i < 30 ? 19 : i - 10);
    writer.write(PannedFrame(96, 64, shift, blurred.count(i) > 0));
  }
}

// Five frames of a 96 x 64 MPEG-4 video, grey with a red square at the top left, whose track says to show it turned
// 90 degrees clockwise, as a phone held upright records it (the matrix of its track header: 0 1 0, -1 0 0).
void WritePortraitPhoneVideo(const fs::path& path) {
  {
    cv::VideoWriter writer(path.string(), cv::CAP_FFMPEG, cv::VideoWriter::fourcc('m', 'p', '4', 'v'), 10.0,
                           cv::Size(96, 64));
    REQUIRE(writer.isOpened());
    cv::Mat frame(64, 96, CV_8UC3, cv::Scalar(40, 40, 40));
    cv::rectangle(frame, cv::Rect(0, 0, 16, 16), cv::Scalar(0, 0, 255), cv::FILLED);
    for (int i = 0; i < 5; ++i) writer.write(frame);
  }
  std::string bytes = ReadTextFile(path);
  const size_t header = bytes.find("tkhd");
  REQUIRE(header != std::string::npos);
  REQUIRE(bytes[header + 4] == 0);    // version 0: 32-bit times
  const size_t matrix = header + 44;  // after version, flags, 5 fields of 4 bytes, 8 reserved, 4 of 2
  const int32_t turned[9] = {0, 0x10000, 0, -0x10000, 0, 0, 0, 0, 0x40000000};
  for (int i = 0; i < 9; ++i) {
    for (int b = 0; b < 4; ++b)
      bytes[matrix + 4 * i + b] = static_cast<char>((uint32_t(turned[i]) >> (24 - 8 * b)) & 0xff);
  }
  WriteFileAtomic(path, bytes);
}

// A tenth of a second of silence as a WAV file: sound, no picture.
void WriteSilence(const fs::path& path) {
  const uint32_t samples = 800, bytes = 2 * samples, rate = 8000;
  std::string wav = "RIFF";
  auto put = [&wav](uint32_t value, int size) {
    for (int i = 0; i < size; ++i) wav += static_cast<char>((value >> (8 * i)) & 0xff);
  };
  put(36 + bytes, 4);
  wav += "WAVEfmt ";
  put(16, 4), put(1, 2), put(1, 2), put(rate, 4), put(2 * rate, 4), put(2, 2), put(16, 2);
  wav += "data";
  put(bytes, 4);
  wav.append(bytes, '\0');
  WriteFileAtomic(path, wav);
}

// Keeps the first `share` of the file's bytes.
void CutShort(const fs::path& path, double share) {
  fs::resize_file(path, static_cast<uintmax_t>(share * fs::file_size(path)));
}

}  // namespace

TEST_CASE("frame choice: a frame per window of equal motion, the sharpest of each, none from a camera standing still",
          "[ingest][video]") {
  // Frames 50 to 79 stand still; 2 grey levels of motion a frame elsewhere: 138 in all, ten windows of 13.8.
  std::vector<double> motion(100, 2.0), sharpness(100, 1.0);
  std::fill(motion.begin() + 50, motion.begin() + 80, 0.0);
  for (int sharp : {3, 10, 45, 60}) sharpness[sharp] = 5;  // in windows 0, 1, 6 and 7 (frames 49 to 85)
  const FrameChoice choice = ChooseFrames(ScanOf(motion, sharpness), 10);
  CHECK(choice.taken.size() == 10);
  CHECK(std::is_sorted(choice.taken.begin(), choice.taken.end()));
  for (size_t sharp : {3, 10, 45, 60}) CHECK(std::count(choice.taken.begin(), choice.taken.end(), sharp) == 1);
  CHECK(std::count_if(choice.taken.begin(), choice.taken.end(), [](size_t i) { return i >= 49 && i < 80; }) == 1);
  CHECK(choice.repeats.empty());

  SECTION("a video that never moves gives its sharpest frame") {
    std::vector<double> sharpness(30, 1.0);
    sharpness[17] = 3;
    const FrameChoice still = ChooseFrames(ScanOf(std::vector<double>(30, 0.0), sharpness), 10);
    CHECK(still.taken == std::vector<size_t>{17});
  }
  SECTION("of two neighbouring frames taken from neighbouring windows, the second is a repeat") {
    // One grey level a frame, four windows of 4.75: frames 0-4, 5-9, 10-14, 15-19; steps 1, 7, 5 between the
    // sharpest (4, 5, 12, 17): under a quarter of the median 5 is a repeat.
    std::vector<double> sharpness(20, 1.0);
    for (int sharp : {4, 5, 12, 17}) sharpness[sharp] = 5;
    const FrameChoice paired = ChooseFrames(ScanOf(std::vector<double>(20, 1.0), sharpness), 4);
    CHECK(paired.taken == std::vector<size_t>{4, 12, 17});
    REQUIRE(paired.repeats.size() == 1);
    CHECK(paired.repeats[0] == std::pair<size_t, size_t>{5, 4});
  }
}

TEST_CASE("frame choice: auto takes five frames a second, 100 to 300, never more than the video has",
          "[ingest][video]") {
  CHECK(AutoFrameCount(23.5, 706) == 118);
  CHECK(AutoFrameCount(5.0, 150) == 100);
  CHECK(AutoFrameCount(5.0, 60) == 60);
  CHECK(AutoFrameCount(600.0, 18000) == 300);
}

TEST_CASE("ingest: a video beside photos gives its sharpest frames in order, each with its time", "[ingest][video]") {
  IngestFixture f;
  for (int i = 0; i < 3; ++i)
    REQUIRE(cv::imwrite((f.photos / format("photo{}.png", i)).string(), PannedFrame(96, 64, 7 * i + 1, false)));
  const std::set<int> blurred = {3, 4, 13, 33, 34};
  WritePanVideo(f.photos / "clip.avi", 40, blurred);
  f.config.Set("ingest.video_frames", "8", "test");
  const nlohmann::json report = f.Run();

  REQUIRE(report["videos"].size() == 1);
  const nlohmann::json& video = report["videos"][0];
  CHECK(video["file"] == "clip.avi");
  CHECK(video["frames"] == 40);
  CHECK(video["width"] == 96);
  CHECK(video["height"] == 64);
  CHECK(video["sharpness"].size() == 40);
  const size_t taken = video["taken"].size();
  CHECK(taken >= 6);
  CHECK(taken <= 8);
  CHECK(report["images"].size() == 3 + taken);
  int still = 0;
  for (const nlohmann::json& frame : video["taken"]) {
    const int index = frame["index"];
    INFO("frame " << index);
    CHECK(blurred.count(index) == 0);
    still += index >= 20 && index < 30;  // the same picture as frame 19
    CHECK(frame["time"].get<double>() == Approx(index / 10.0).margin(1e-3));
    CHECK(fs::exists(f.workspace.StageDir("00_ingest") / "images" / frame["image"].get<std::string>()));
  }
  CHECK(still == 0);
  const nlohmann::json& first_frame = report["images"][3];
  CHECK(first_frame["source"] == "clip.avi");
  CHECK(first_frame["name"] == format("clip_{:05d}.jpg", video["taken"][0]["index"].get<int>()));
  CHECK(first_frame["frame"] == video["taken"][0]["index"]);
}

TEST_CASE("ingest: a video a phone recorded upright gives upright frames", "[ingest][video]") {
  IngestFixture f;
  fs::remove_all(f.photos);
  WritePortraitPhoneVideo(f.dir / "portrait.mp4");
  f.workspace.SetInput(f.dir / "portrait.mp4");
  f.config.Set("ingest.min_images", 1, "test");
  const nlohmann::json report = f.Run();
  REQUIRE(report["images"].size() >= 1);
  CHECK(report["input_folder"] == (f.dir / "portrait.mp4").string());
  const ReadImageResult frame =
      ReadImage(f.workspace.StageDir("00_ingest") / "images" / report["images"][0]["name"].get<std::string>());
  REQUIRE(frame.ok());
  REQUIRE(frame.image.spec().width == 64);
  REQUIRE(frame.image.spec().height == 96);
  // Turned clockwise, the top left corner is now the top right.
  std::array<float, 3> top_right{}, bottom_left{};
  frame.image.getpixel(60, 3, top_right.data(), 3);
  frame.image.getpixel(3, 92, bottom_left.data(), 3);
  CHECK(top_right[0] > 0.8f);
  CHECK(top_right[2] < 0.2f);
  CHECK(bottom_left[0] < 0.3f);
}

TEST_CASE(
    "ingest: a video cut short, empty, of sound only or no video at all is an error naming it, and the last "
    "result stays",
    "[ingest][video][bad_input]") {
  IngestFixture f;
  for (int i = 0; i < 3; ++i)
    REQUIRE(cv::imwrite((f.photos / format("photo{}.png", i)).string(), PannedFrame(96, 64, 7 * i + 1, false)));
  f.Run();
  const fs::path images = f.workspace.StageDir("00_ingest") / "images";
  struct Bad {
    std::string file, says;
    std::function<void(const fs::path&)> write;
  };
  const std::vector<Bad> table = {
      {"cut.avi", "ends after",
       [](const fs::path& path) {
         WritePanVideo(path, 40, {});
         CutShort(path, 0.5);
       }},
      {"cut.mp4", "cannot open",
       [](const fs::path& path) {
         cv::VideoWriter writer(path.string(), cv::CAP_FFMPEG, cv::VideoWriter::fourcc('m', 'p', '4', 'v'), 10.0,
                                cv::Size(96, 64));
         for (int i = 0; i < 20; ++i) writer.write(PannedFrame(96, 64, i, false));
         writer.release();
         CutShort(path, 0.6);
       }},
      {"empty.avi", "", [](const fs::path& path) { WritePanVideo(path, 0, {}); }},
      {"sound.mp4", "holds only sound", WriteSilence},
      {"text.mov", "cannot open", [](const fs::path& path) { WriteFileAtomic(path, "not a video at all\n"); }},
  };
  for (const Bad& bad : table) {
    INFO(bad.file);
    bad.write(f.photos / bad.file);
    CHECK_THROWS_WITH(f.Run(),
                      Catch::Contains("'" + (f.photos / bad.file).string() + "'") && Catch::Contains(bad.says));
    fs::remove(f.photos / bad.file);
    CHECK(std::distance(fs::directory_iterator(images), fs::directory_iterator()) == 3);
    CHECK(f.Status().state == StageState::kIncomplete);  // the failed run's output, never read as a result
  }
}

}  // namespace p2n::testing

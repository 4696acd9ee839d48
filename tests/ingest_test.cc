// The ingest stage on small images made here: the table of unusual and bad photos (16-bit, grey, alpha, CMYK,
// HDR, EXIF-rotated, non-ASCII names, copies, broken and absurd files), fingerprints, downsizing, too few photos.

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <catch2/catch.hpp>

#include <cstdio>
#include <fstream>
#include <functional>

#include <jpeglib.h>

#include "base/errors.h"
#include "base/file_util.h"
#include "base/image_io.h"
#include "formats/dataset_import.h"
#include "stages/ingest/ingest_stage.h"
#include "stages/sfm/sfm_stage.h"
#include "stages/stages.h"
#include "stages/training_data.h"
#include "tests/stage_fixtures.h"
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

// A PNG that declares 100000 x 100000 pixels (IHDR) and has an empty IDAT.
void WriteHugePng(const fs::path& path) {
  const unsigned char header[] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n', 0,    0, 0,    13,
                                  'I',  'H', 'D', 'R', 0,    1,    0x86, 0xa0, 0,    1, 0x86, 0xa0,
                                  8,    2,   0,   0,   0,    0x27, 0x30, 0x9c, 0x9f, 0, 0,    0,
                                  0,    'I', 'D', 'A', 'T',  0x35, 0xaf, 0x06, 0x1e};
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(header), sizeof(header));
}

// A 40 x 20 red CMYK JPEG as Photoshop writes them (libjpeg's Adobe marker, inverted values: 255 is no ink).
void WriteRedCmykJpeg(const fs::path& path) {
  FILE* file = std::fopen(path.c_str(), "wb");
  REQUIRE(file != nullptr);
  jpeg_compress_struct info;
  jpeg_error_mgr errors;
  info.err = jpeg_std_error(&errors);
  jpeg_create_compress(&info);
  jpeg_stdio_dest(&info, file);
  info.image_width = 40;
  info.image_height = 20;
  info.input_components = 4;
  info.in_color_space = JCS_CMYK;
  jpeg_set_defaults(&info);
  jpeg_start_compress(&info, TRUE);
  std::vector<unsigned char> row;
  for (int x = 0; x < 40; ++x) row.insert(row.end(), {255, 0, 0, 255});  // no cyan, full magenta and yellow, no black
  while (info.next_scanline < info.image_height) {
    JSAMPROW pointer = row.data();
    jpeg_write_scanlines(&info, &pointer, 1);
  }
  jpeg_finish_compress(&info);
  jpeg_destroy_compress(&info);
  std::fclose(file);
}

std::string SkipReason(const nlohmann::json& report, const std::string& file) {
  for (const auto& skipped : report["skipped"]) {
    if (skipped["file"] == file) return skipped["reason"];
  }
  return "(not skipped)";
}

}  // namespace

// The table of unusual and bad photos (issue 7): for each, whether ingest keeps it (and what training then sees)
// or skips it with a reason that names what is wrong. All go into one folder with three ordinary photos.
namespace {

// A photo of the table: its file, how it is written, and the reason ingest skips it or what it keeps.
struct PhotoRow {
  std::string file;                                                               // its name in the photo folder
  std::function<void(const fs::path&)> make;                                      // writes it
  std::string skip_reason;                                                        // empty: kept
  std::function<void(const nlohmann::json& entry, const TrainView& view)> check;  // for kept files
};

// Writes the test image of `seed`.
constexpr auto TablePhoto = [](int seed) {
  return [seed](const fs::path& path) { Write(MakeImage(40, 20, seed), path); };
};
constexpr auto SolidPhoto = [](int channels, OIIO::TypeDesc type, std::vector<float> value) {
  return [=](const fs::path& path) {
    OIIO::ImageSpec spec(40, 20, channels, type);
    spec.attribute("oiio:UnassociatedAlpha", 1);  // the values as they are, as photos store them
    OIIO::ImageBuf buffer(spec);
    OIIO::ImageBufAlgo::fill(buffer, value);
    REQUIRE(buffer.write(path.string()));
  };
};
constexpr auto CheckPixelNear = [](const TrainView& view, int x, int y, std::vector<int> expected, int tolerance) {
  for (int c = 0; c < view.channels; ++c) {
    CHECK(std::abs(view.pixels[(size_t(y) * view.camera.width + x) * view.channels + c] - expected[c]) <= tolerance);
  }
};

// Photos ingest must skip, each with its reason.
std::vector<PhotoRow> SkippedPhotos() {
  return {

      {"huge.png", WriteHugePng, "declared size 100000x100000x3 is beyond what photo2nerf reads", nullptr},
      {"truncated.jpg",
       [](const fs::path& path) {
         Write(MakeImage(40, 20, 7), path);
         const std::string whole = ReadText(path);
         WriteText(path, whole.substr(0, whole.size() / 2));
       },
       "Premature end of JPEG file", nullptr},
      {"text.JPG", [](const fs::path& path) { WriteText(path, "this is not an image\n"); }, "not a readable image",
       nullptr},
      {"zero.png", [](const fs::path& path) { WriteText(path, ""); }, "empty file (0 bytes)", nullptr},
      {"bomb.exr",  // found by fuzzing: 217 bytes that made OpenEXR take 2 GB before refusing them
       [](const fs::path& path) {
         const int32_t size = 1953458498;
         WriteText(path, std::string("\x76\x2f\x31\x01\x02\0\0\0Exif:ImageHistory\0string\0", 33) +
                             std::string(reinterpret_cast<const char*>(&size), 4) + "only a few bytes");
       },
       "damaged EXR header: attribute 'Exif:ImageHistory' declares 1953458498 bytes in a file of 53", nullptr},
      {"bomb.png",  // found by fuzzing: 320 bytes that made libpng take 2 GB before refusing them
       [](const fs::path& path) {
         WriteHugePng(path);
         WriteText(path, ReadText(path).substr(0, 33) + std::string("\x74\x6f\x6f\x42tEXtonly a few bytes", 24));
       },
       "damaged PNG: chunk 'tEXt' declares 1953460034 bytes in a file of 57", nullptr},
      {"zz_copy.png", TablePhoto(0), "the same pixels as base0.png", nullptr},
  };
}

// Photos kept in another encoding than 8-bit RGB: 16 bits, grey, alpha.
std::vector<PhotoRow> KeptEncodings() {
  return {
      {"sixteen_bit.png", SolidPhoto(3, OIIO::TypeDesc::UINT16, {1.0f, 0.5f, 0.0f}), "",
       [](const nlohmann::json&, const TrainView& view) {
         CHECK(view.channels == 3);
         CheckPixelNear(view, 5, 5, {255, 128, 0}, 0);
       }},
      {"grey.jpg", SolidPhoto(1, OIIO::TypeDesc::UINT8, {0.6f}), "",
       [](const nlohmann::json& entry, const TrainView& view) {
         CHECK(entry["channels"] == 1);
         CHECK(view.channels == 3);
         CheckPixelNear(view, 5, 5, {153, 153, 153}, 2);
       }},
      {"grey_alpha.png", SolidPhoto(2, OIIO::TypeDesc::UINT8, {0.6f, 0.2f}), "",
       [](const nlohmann::json&, const TrainView& view) {
         CHECK(view.channels == 4);
         CheckPixelNear(view, 5, 5, {153, 153, 153, 51}, 0);
       }},
      {"alpha.png",
       [](const fs::path& path) {
         OIIO::ImageBuf buffer(OIIO::ImageSpec(40, 20, 4, OIIO::TypeDesc::UINT8));
         OIIO::ImageBufAlgo::fill(buffer, {0.0f, 1.0f, 0.0f, 0.0f}, OIIO::ROI(0, 20, 0, 20));
         OIIO::ImageBufAlgo::fill(buffer, {0.0f, 0.0f, 1.0f, 1.0f}, OIIO::ROI(20, 40, 0, 20));
         REQUIRE(buffer.write(path.string()));
       },
       "",
       [](const nlohmann::json&, const TrainView& view) {
         CHECK(view.channels == 4);
         CheckPixelNear(view, 5, 5, {0, 255, 0, 0}, 0);  // straight alpha: a transparent pixel keeps its colour
         CheckPixelNear(view, 30, 5, {0, 0, 255, 255}, 0);
       }},
  };
}

// Photos kept from CMYK, linear light, EXIF rotation and a non-ASCII name.
std::vector<PhotoRow> KeptConversions() {
  return {
      {"cmyk.jpg", WriteRedCmykJpeg, "",
       [](const nlohmann::json& entry, const TrainView& view) {
         CHECK(entry["from_cmyk"] == true);
         CHECK(entry["name"] == "cmyk_jpg.png");  // re-encoded as RGB: COLMAP never sees the CMYK file
         CHECK(view.channels == 3);
         CheckPixelNear(view, 5, 5, {255, 0, 0}, 8);
       }},
      {"cmyk.tif",
       [](const fs::path& path) {
         OIIO::ImageSpec spec(40, 20, 4, OIIO::TypeDesc::UINT8);
         spec.channelnames = {"C", "M", "Y", "K"};
         spec.alpha_channel = -1;
         spec.attribute("tiff:ColorSpace", "CMYK");
         OIIO::ImageBuf buffer(spec);
         OIIO::ImageBufAlgo::fill(buffer, {1.0f, 0.0f, 1.0f, 0.0f});  // cyan and yellow ink: green
         REQUIRE(buffer.write(path.string()));
       },
       "",
       [](const nlohmann::json& entry, const TrainView& view) {
         CHECK(entry["from_cmyk"] == true);
         CheckPixelNear(view, 5, 5, {0, 255, 0}, 0);
       }},
      {"linear.exr", SolidPhoto(3, OIIO::TypeDesc::HALF, {0.214f, 0.214f, 0.214f}), "",
       [](const nlohmann::json& entry, const TrainView& view) {
         CHECK(entry["name"] == "linear_exr.png");
         CheckPixelNear(view, 5, 5, {128, 128, 128}, 1);  // linear 0.214 is sRGB 0.5
       }},
      {"rotated.jpg", [](const fs::path& path) { Write(MakeImage(40, 20, 5), path, 6); }, "",
       [](const nlohmann::json& entry, const TrainView& view) {
         // Orientation 6: turned 90 degrees clockwise, so the stored left (red) half becomes the top.
         CHECK(entry["exif_orientation"] == 6);
         REQUIRE(view.camera.width == 20);
         REQUIRE(view.camera.height == 40);
         CheckPixelNear(view, 10, 5, {255, 0, 0}, 40);
         CheckPixelNear(view, 10, 35, {0, 0, 255}, 40);
       }},
      {"vue n°1 été.png", TablePhoto(3), "",
       [](const nlohmann::json& entry, const TrainView& view) {
         CHECK(entry["name"] == "vue n°1 été.png");
         CheckPixelNear(view, 5, 5, {255, 0, 0}, 0);
       }},
  };
}

}  // namespace

TEST_CASE("ingest: a table of unusual and bad photos, each kept as training expects or skipped with its reason",
          "[ingest][bad_input]") {
  std::vector<PhotoRow> rows = SkippedPhotos();
  for (std::vector<PhotoRow> more : {KeptEncodings(), KeptConversions()})
    rows.insert(rows.end(), more.begin(), more.end());
  IngestFixture f;
  for (int i = 0; i < 3; ++i) TablePhoto(i)(f.photos / ("base" + std::to_string(i) + ".png"));
  for (const PhotoRow& row : rows) row.make(f.photos / row.file);
  fs::create_directories(f.photos / "folder.jpg");  // not a file: ignored
  TablePhoto(9)(f.photos / ".hidden.png");          // hidden: ignored
  const nlohmann::json report = f.Run();

  size_t kept = 3;
  for (const PhotoRow& row : rows) {
    INFO("photo " << row.file);
    if (!row.skip_reason.empty()) {
      CHECK_THAT(SkipReason(report, row.file), Catch::Contains(row.skip_reason));
      continue;
    }
    ++kept;
    const auto entry = std::find_if(report["images"].begin(), report["images"].end(),
                                    [&](const nlohmann::json& e) { return e["source"] == row.file; });
    REQUIRE(entry != report["images"].end());
    ImportedView imported;
    imported.view.camera.width = (*entry)["width"];
    imported.view.camera.height = (*entry)["height"];
    imported.source = f.workspace.StageDir("00_ingest") / "images" / (*entry)["name"].get<std::string>();
    row.check(*entry, LoadTrainView(imported));
    // COLMAP reads these files: 8 bits (it does not register 16-bit PNGs), RGB or grey, with or without alpha.
    CHECK(ReadImage(imported.source).image.spec().format == OIIO::TypeDesc::UINT8);
  }
  CHECK(report["images"].size() == kept);
  CHECK(report["skipped"].size() == rows.size() + 3 - kept);
  CHECK_FALSE(fs::exists(f.workspace.StageDir("00_ingest") / "images" / "zz_copy.png"));
  CHECK_FALSE(fs::exists(f.workspace.StageDir("00_ingest") / "images" / "truncated.jpg"));
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

TEST_CASE("ingest: too few photos, all photos the same, a missing or empty folder are user errors naming it",
          "[ingest][bad_input]") {
  IngestFixture f;
  CHECK_THROWS_WITH(f.Run(), Catch::Contains("no photos or videos in") && Catch::Contains(f.photos.string()));
  Write(MakeImage(16, 16, 0), f.photos / "a.png");
  CHECK_THROWS_WITH(f.Run(), Catch::Contains("only 1 usable images") && Catch::Contains("ingest.min_images"));
  CHECK(f.Status().state == StageState::kIncomplete);
  Write(MakeImage(16, 16, 1), f.photos / "b.png");
  CHECK_THROWS_WITH(f.Run(), Catch::Contains("only 2 usable images"));
  for (const char* copy : {"c.png", "d.png", "e.png"}) Write(MakeImage(16, 16, 0), f.photos / copy);
  CHECK_THROWS_WITH(f.Run(), Catch::Contains("only 2 usable images") &&
                                 Catch::Contains("3 skipped, 3 of them copies of another photo"));
  fs::remove_all(f.photos);
  CHECK_THROWS_WITH(f.Run(), Catch::Contains("does not exist"));
  CHECK_THROWS_WITH(ListInputs(f.dir / "ws" / "workspace.json"), Catch::Contains("is a file, not a folder or a video"));
}

TEST_CASE("ingest reads the camera each photo's EXIF names, and sfm groups the photos by it and by size",
          "[ingest][sfm]") {
  IngestFixture f;
  auto write = [&](const std::string& name, int seed, const std::string& make, const std::string& model, float focal) {
    OIIO::ImageBuf image = MakeImage(32, 24, seed);
    OIIO::ImageBufAlgo::fill(image, {0.2f, 0.9f, 0.1f}, OIIO::ROI(4 * seed, 4 * seed + 3, 10, 13));  // distinct
    if (!make.empty()) image.specmod().attribute("Make", make);
    if (!model.empty()) image.specmod().attribute("Model", model);
    if (focal > 0) image.specmod().attribute("Exif:FocalLength", focal);
    REQUIRE(image.write((f.photos / name).string()));
  };
  write("a.jpg", 0, "Apple", "iPhone 12", 4.2f);
  write("b.jpg", 1, "Apple", "iPhone 12", 4.2f);
  write("c.jpg", 2, "Apple", "iPhone 12", 6.0f);  // the same phone zoomed: another camera
  write("d.jpg", 3, "Google", "Pixel 7", 0);
  write("e.jpg", 4, "", "", 0);
  write("f.jpg", 5, "", "", 0);
  const nlohmann::json report = f.Run();
  std::map<std::string, std::string> camera;
  for (const nlohmann::json& image : report["images"]) camera[image["name"]] = image["camera"];
  CHECK(camera["a.jpg"] == "Apple, iPhone 12, 4.2 mm");
  CHECK(camera["c.jpg"] == "Apple, iPhone 12, 6 mm");
  CHECK(camera["d.jpg"] == "Google, Pixel 7");
  CHECK(camera["e.jpg"].empty());

  const std::vector<CameraGroup> groups =
      CameraGroups(IngestReport::Read(f.workspace.StageDir("00_ingest") / "ingest_report.json"));
  std::map<std::string, std::vector<std::string>> by_label;
  for (const CameraGroup& group : groups) by_label[group.label] = group.images;
  CHECK(by_label.size() == 4);
  CHECK(by_label["Apple, iPhone 12, 4.2 mm, 32x24"] == std::vector<std::string>{"a.jpg", "b.jpg"});
  CHECK(by_label["Apple, iPhone 12, 6 mm, 32x24"] == std::vector<std::string>{"c.jpg"});
  CHECK(by_label["Google, Pixel 7, 32x24"] == std::vector<std::string>{"d.jpg"});
  CHECK(by_label["32x24"] == std::vector<std::string>{"e.jpg", "f.jpg"});
}

TEST_CASE(
    "ingest: the photo folder's masks/ (or one beside images/) written as the images, at their size and orientation",
    "[ingest]") {
  IngestFixture f;
  fs::create_directories(f.photos / "masks");
  // A mask whose left `left` columns of `width` x `height` leave the photo out.
  const auto mask = [](int width, int height, int left) {
    OIIO::ImageBuf image(OIIO::ImageSpec(width, height, 1, OIIO::TypeDesc::UINT8));
    OIIO::ImageBufAlgo::fill(image, {1.0f}, OIIO::ROI(left, width, 0, height, 0, 1, 0, 1));
    return image;
  };
  Write(MakeImage(64, 32, 0), f.photos / "a.png");
  Write(mask(32, 16, 8), f.photos / "masks" / "a_mask.png");  // half size: resized
  Write(MakeImage(64, 32, 1), f.photos / "b.jpg", 6);         // shown turned a quarter: 32 x 64 upright
  Write(mask(64, 32, 16), f.photos / "masks" / "b.jpg.png");  // drawn on the stored pixels: turned with them
  Write(MakeImage(64, 32, 2), f.photos / "c.tif");
  Write(mask(64, 32, 32), f.photos / "masks" / "c.png");
  const nlohmann::json report = f.Run();
  REQUIRE(report["images"].size() == 3);
  const fs::path masks = f.workspace.StageDir("00_ingest") / "masks";
  const auto alpha = [&](const std::string& name, int x, int y) {
    const ReadImageResult read = ReadImage(masks / name);
    REQUIRE(read.ok());
    return read.image.getchannel(x, y, 0, 0);
  };
  CHECK(alpha("a.png", 13, 10) == 0.0f);  // the edge at 16, blurred a little by the resize
  CHECK(alpha("a.png", 19, 10) == 1.0f);
  CHECK(alpha("c_tif.png", 31, 10) == 0.0f);
  CHECK(alpha("c_tif.png", 32, 10) == 1.0f);
  // b.jpg's stored left columns are its upright top rows (orientation 6 turns it clockwise).
  const ReadImageResult b = ReadImage(masks / "b_jpg.png");
  REQUIRE(b.ok());
  CHECK(b.image.spec().width == 32);
  CHECK(b.image.spec().height == 64);
  CHECK(b.image.getchannel(10, 15, 0, 0) == 0.0f);
  CHECK(b.image.getchannel(10, 17, 0, 0) == 1.0f);

  CHECK(f.Status().state == StageState::kFresh);
  Write(mask(64, 32, 20), f.photos / "masks" / "c.png");  // another mask: the images' alpha changes
  CHECK(f.Status().state == StageState::kStale);
  fs::remove(f.photos / "masks" / "c.png");
  CHECK_THROWS_WITH(f.Run(), Catch::Contains("has no mask for 1 of the 3 photos (the first: 'c.tif')"));

  // A dataset's layout: the photos in images/, the masks beside it.
  fs::rename(f.photos / "masks", f.dir / "masks");
  fs::rename(f.photos, f.dir / "images");
  f.workspace.SetInput(f.dir / "images");
  Write(mask(64, 32, 32), f.dir / "masks" / "c.png");
  REQUIRE(f.Run()["images"].size() == 3);
  CHECK(alpha("c_tif.png", 31, 10) == 0.0f);
  CHECK(alpha("c_tif.png", 32, 10) == 1.0f);
}

}  // namespace p2n::testing

// COLMAP models: binary and text agree; damaged and hostile files give clear errors; flags follow the version.

#include <catch2/catch.hpp>

#include <cstring>
#include <fstream>

#include "base/errors.h"
#include "formats/colmap_model.h"
#include "formats/npy.h"
#include "stages/sfm/colmap_flags.h"
#include "tests/test_util.h"

namespace p2n::testing {
namespace fs = std::filesystem;
namespace {

ColmapModel SmallModel() {
  ColmapModel model;
  model.cameras[1] = {1, "PINHOLE", 640, 480, {500.5, 501.25, 320.1, 239.9}};
  model.cameras[2] = {2, "OPENCV", 800, 600, {700, 710, 400, 300, 0.01, -0.002, 0.0003, -0.0004}};
  for (uint32_t i = 1; i <= 3; ++i) {
    ColmapImage image;
    image.id = i;
    image.cam_from_world_rotation =
        Eigen::Quaterniond(Eigen::AngleAxisd(0.3 * i, Eigen::Vector3d(1, 2, 3).normalized()));
    image.cam_from_world_translation = Eigen::Vector3d(0.1 * i, -0.2, 1.5);
    image.camera_id = i == 3 ? 2 : 1;
    image.name = "img " + std::to_string(i) + ".jpg";
    image.points2d = {{10.5, 20.25}, {30.0, 40.0}};
    image.point3d_ids = {i, kNoPoint3D};
    model.images[i] = image;
  }
  for (uint64_t p = 1; p <= 3; ++p) {
    model.points[p] = {p,
                       Eigen::Vector3d(0.5 * p, -1.0, 2.0 + p),
                       {10, 200, static_cast<uint8_t>(30 * p)},
                       0.75,
                       {{static_cast<uint32_t>(p), 0}}};
  }
  return model;
}

void CheckSame(const ColmapModel& a, const ColmapModel& b) {
  REQUIRE(a.cameras.size() == b.cameras.size());
  for (const auto& [id, camera] : a.cameras) {
    CHECK(b.cameras.at(id).model == camera.model);
    CHECK(b.cameras.at(id).width == camera.width);
    CHECK(b.cameras.at(id).params == camera.params);
  }
  REQUIRE(a.images.size() == b.images.size());
  for (const auto& [id, image] : a.images) {
    const ColmapImage& other = b.images.at(id);
    CHECK(other.name == image.name);
    CHECK(other.camera_id == image.camera_id);
    CHECK(other.cam_from_world_rotation.coeffs().isApprox(image.cam_from_world_rotation.coeffs(), 1e-15));
    CHECK(other.cam_from_world_translation == image.cam_from_world_translation);
    CHECK(other.points2d == image.points2d);
    CHECK(other.point3d_ids == image.point3d_ids);
  }
  REQUIRE(a.points.size() == b.points.size());
  for (const auto& [id, point] : a.points) {
    CHECK(b.points.at(id).xyz == point.xyz);
    CHECK(b.points.at(id).rgb == point.rgb);
    CHECK(b.points.at(id).track == point.track);
  }
}

std::string Bytes(const fs::path& path) { return ReadText(path); }
void PutBytes(const fs::path& path, const std::string& bytes) { std::ofstream(path, std::ios::binary) << bytes; }

}  // namespace

TEST_CASE("COLMAP models: binary and text of the same model read the same", "[colmap]") {
  TempDir dir;
  const ColmapModel model = SmallModel();
  WriteColmapModelBinary(model, dir / "bin");
  WriteColmapModelText(model, dir / "txt");
  const ColmapModel from_binary = ReadColmapModel(dir / "bin");
  const ColmapModel from_text = ReadColmapModel(dir / "txt");
  CheckSame(model, from_binary);
  CheckSame(from_binary, from_text);
}

TEST_CASE("COLMAP models: damaged and hostile files are refused with the file named", "[colmap]") {
  TempDir dir;
  WriteColmapModelBinary(SmallModel(), dir / "m");
  const fs::path cameras = dir / "m" / "cameras.bin", images = dir / "m" / "images.bin";
  const std::string good_cameras = Bytes(cameras), good_images = Bytes(images);

  SECTION("truncated") {
    PutBytes(cameras, good_cameras.substr(0, good_cameras.size() - 5));
    CHECK_THROWS_WITH(ReadColmapModel(dir / "m"), Catch::Contains("cameras.bin") && Catch::Contains("ends early"));
  }
  SECTION("an absurd count is refused before allocating") {
    std::string hostile = good_images;
    const uint64_t huge = uint64_t{1} << 60;
    std::memcpy(hostile.data(), &huge, sizeof(huge));
    PutBytes(images, hostile);
    CHECK_THROWS_WITH(ReadColmapModel(dir / "m"), Catch::Contains("images.bin") && Catch::Contains("cannot fit"));
  }
  SECTION("an unknown camera model id") {
    std::string hostile = good_cameras;
    const int32_t model_id = 99;
    std::memcpy(hostile.data() + 8 + 4, &model_id, sizeof(model_id));
    PutBytes(cameras, hostile);
    CHECK_THROWS_WITH(ReadColmapModel(dir / "m"), Catch::Contains("unknown model id 99"));
  }
  SECTION("NaN, a zero quaternion, a missing camera, an unknown model name in text") {
    ColmapModel model = SmallModel();
    model.cameras[1].params[0] = std::nan("");
    WriteColmapModelText(model, dir / "t1");
    CHECK_THROWS_WITH(ReadColmapModel(dir / "t1"), Catch::Contains("cameras.txt") && Catch::Contains("line 2"));
    model = SmallModel();
    model.images[2].cam_from_world_rotation = Eigen::Quaterniond(0, 0, 0, 0);
    WriteColmapModelBinary(model, dir / "t2");
    CHECK_THROWS_WITH(ReadColmapModel(dir / "t2"), Catch::Contains("image 2") && Catch::Contains("norm"));
    model = SmallModel();
    model.images[3].camera_id = 7;
    WriteColmapModelText(model, dir / "t3");
    CHECK_THROWS_WITH(ReadColmapModel(dir / "t3"), Catch::Contains("refers to camera 7"));
    model = SmallModel();
    model.cameras[1].model = "BANANA";
    WriteColmapModelText(model, dir / "t4");
    CHECK_THROWS_WITH(ReadColmapModel(dir / "t4"), Catch::Contains("unknown camera model 'BANANA'"));
  }
  SECTION("a folder without a model") {
    CHECK_THROWS_WITH(ReadColmapModel(dir.path()), Catch::Contains("holds no COLMAP model"));
  }
}

TEST_CASE("NumPy arrays: damaged headers are user errors (found by fuzzing)", "[colmap]") {
  const std::string header = "{'descr': '<f8', 'fortran_order': False, 'shape': (2, x), }";
  std::string bytes = std::string("\x93NUMPY\x01\x00", 8) + std::string(1, static_cast<char>(header.size())) +
                      std::string(1, '\0') + header;
  CHECK_THROWS_WITH(ParseNpy(bytes, "bad.npy"), Catch::Contains("bad.npy") && Catch::Contains("shape"));
  const std::string good = "{'descr': '<f8', 'fortran_order': False, 'shape': (2,), }";
  bytes = std::string("\x93NUMPY\x01\x00", 8) + std::string(1, static_cast<char>(good.size())) + std::string(1, '\0') +
          good + std::string(16, '\0');
  CHECK(ParseNpy(bytes, "good.npy").shape == std::vector<size_t>{2});
  CHECK_THROWS_WITH(ParseNpy(bytes.substr(0, bytes.size() - 3), "short.npy"), Catch::Contains("truncated"));
}

TEST_CASE("an .npz that declares gigabytes from a few bytes is refused before allocating (found by fuzzing)",
          "[colmap]") {
  const fs::path path = fs::path(P2N_SOURCE_DIR) / "tests" / "data" / "npz_declares_2600_mb.npz";
  CHECK_THROWS_WITH(ReadNpz(path), Catch::Contains("declares") && Catch::Contains("compressed"));
  // A ZIP64 record longer than the extra field it is in (a heap overflow before the fix).
  CHECK_THROWS_AS(ReadNpz(fs::path(P2N_SOURCE_DIR) / "tests" / "data" / "npz_extra_field_overflow.npz"), UserError);
}

TEST_CASE("COLMAP flags are built from the version the program reports", "[colmap]") {
  CHECK(ParseColmapVersion("COLMAP 3.8 -- Structure-from-Motion and Multi-View Stereo\n(Commit Unknown on Unknown "
                           "without CUDA)")
            .ToString() == "3.8");
  CHECK(ParseColmapVersion("COLMAP 3.14.0.dev0 -- Structure-from-Motion").ToString() == "3.14");
  CHECK_THROWS_WITH(ParseColmapVersion("bash: colmap: command not found"), Catch::Contains("is this COLMAP?"));
  const ColmapFlags v38 = ColmapFlagsFor({3, 8});
  CHECK(v38.extraction_use_gpu == "--SiftExtraction.use_gpu");
  CHECK(v38.matching_use_gpu == "--SiftMatching.use_gpu");
  CHECK(v38.extraction_max_image_size == "--SiftExtraction.max_image_size");
  const ColmapFlags v312 = ColmapFlagsFor({3, 12});
  CHECK(v312.extraction_use_gpu == "--SiftExtraction.use_gpu");
  CHECK(v312.matching_num_threads == "--SiftMatching.num_threads");
  for (const ColmapVersion version : {ColmapVersion{3, 13}, ColmapVersion{4, 0}}) {
    const ColmapFlags flags = ColmapFlagsFor(version);
    CHECK(flags.extraction_use_gpu == "--FeatureExtraction.use_gpu");
    CHECK(flags.extraction_num_threads == "--FeatureExtraction.num_threads");
    CHECK(flags.matching_use_gpu == "--FeatureMatching.use_gpu");
    CHECK(flags.extraction_max_num_features == "--SiftExtraction.max_num_features");
  }
}

}  // namespace p2n::testing

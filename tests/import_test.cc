// Importers of datasets with cameras: the shared datasets (skipped when absent), geometry kept up to a
// similarity, and validation of hostile or broken files.

#include <catch2/catch.hpp>

#include <OpenImageIO/imagebuf.h>
#include <Eigen/Geometry>
#include <Eigen/LU>

#include "base/errors.h"
#include "base/file_util.h"
#include "examples/synthetic_scene.h"
#include "formats/colmap_model.h"
#include "formats/dataset_import.h"
#include "formats/ply.h"
#include "formats/sparse_tracks.h"
#include "nerf/rays.h"
#include "stages/stages.h"
#include "stages/training_data.h"
#include "tests/test_util.h"

namespace p2n::testing {
namespace fs = std::filesystem;
namespace {

const fs::path kData = P2N_DATA_DIR;  // the shared scenes (tests/CMakeLists.txt)

// Runs the import stage on `input` (images at most `max_image_size` on their longest side, transparent ones shown on
// `background`); returns the written transforms.json.
nlohmann::json Import(const fs::path& input, const fs::path& workspace_path, int max_image_size = 0,
                      const std::string& background = "white", bool masks = true) {
  const OptionRegistry registry = AllOptions();
  Config config(registry);
  config.Set("run.progress", "none", "test");
  if (max_image_size > 0) config.Set("poses.max_image_size", max_image_size, "test");
  config.Set("import.background", background, "test");
  config.Set("poses.masks", masks, "test");
  Workspace workspace = Workspace::Open(workspace_path, true);
  workspace.SetInput(input);
  RunRequest request;
  request.until = "poses";
  MakeRunner(input).Run(workspace, config, request);
  return ReadJsonFile(workspace_path / "20_poses" / "transforms.json");
}

Eigen::Matrix4d ReadMatrix(const nlohmann::json& rows) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) m(r, c) = rows[r][c].get<double>();
  }
  return m;
}

// The largest rotation difference (degrees) between two pose lists after the best similarity alignment.
double WorstRotationAfterAlignment(const std::vector<Eigen::Matrix4d>& a, const std::vector<Eigen::Matrix4d>& b) {
  Eigen::Matrix3Xd pa(3, a.size()), pb(3, b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    pa.col(i) = a[i].topRightCorner<3, 1>();
    pb.col(i) = b[i].topRightCorner<3, 1>();
  }
  const Eigen::Matrix4d alignment = Eigen::umeyama(pa, pb, true);
  const Eigen::Matrix3d rotation =
      alignment.topLeftCorner<3, 3>() / std::cbrt(alignment.topLeftCorner<3, 3>().determinant());
  double worst = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    const Eigen::Matrix3d d = b[i].topLeftCorner<3, 3>().transpose() * rotation * a[i].topLeftCorner<3, 3>();
    worst = std::max(worst, Eigen::AngleAxisd(d).angle() * 180 / M_PI);
  }
  return worst;
}

// A small synthetic scene: `views` views of 64 x 48.
SyntheticSceneOptions SmallScene(int views) {
  SyntheticSceneOptions scene;
  scene.num_views = views;
  scene.width = 64;
  scene.height = 48;
  return scene;
}

// A transforms.json dataset of the small synthetic scene's `views` views in `folder`; its transforms.json.
nlohmann::json WriteSmallDataset(int views, const fs::path& folder) {
  WriteSyntheticScene(SmallScene(views), folder);
  fs::rename(folder / "ground_truth_cameras.json", folder / "transforms.json");
  return ReadJsonFile(folder / "transforms.json");
}

}  // namespace

TEST_CASE("import: a transforms.json dataset keeps its cameras up to a similarity", "[import]") {
  TempDir dir;
  const nlohmann::json truth = WriteSmallDataset(6, dir / "data");
  CHECK(DetectDataset(dir / "data") == DatasetKind::kTransformsJson);
  const nlohmann::json transforms = Import(dir / "data", dir / "ws");
  REQUIRE(transforms["frames"].size() == 6);
  std::vector<Eigen::Matrix4d> ours, theirs;
  for (size_t i = 0; i < 6; ++i) {
    ours.push_back(ReadMatrix(transforms["frames"][i]["transform_matrix"]));
    theirs.push_back(ReadMatrix(truth["frames"][i]["transform_matrix"]));
    CHECK(fs::exists(dir / "ws" / "20_poses" / transforms["frames"][i]["file_path"].get<std::string>()));
  }
  CHECK(WorstRotationAfterAlignment(ours, theirs) < 1e-6);
  // One of six held out (as every 8th would), inside the span of the others: the middle of the sequence.
  for (size_t i = 0; i < 6; ++i) CHECK(transforms["frames"][i]["split"] == (i == 3 ? "val" : "train"));
  CHECK_THAT(transforms["heldout_rule"].get<std::string>(), Catch::Contains("1 of 6 views"));
  CHECK(transforms["fl_x"].get<double>() == Approx(truth["fl_x"].get<double>()));
}

TEST_CASE("import: images larger than poses.max_image_size are downsized, their intrinsics with them", "[import]") {
  TempDir dir;
  const nlohmann::json truth = WriteSmallDataset(3, dir / "data");
  const nlohmann::json transforms = Import(dir / "data", dir / "ws", 32);  // 64 x 48 -> 32 x 24
  CHECK(transforms["w"] == 32);
  CHECK(transforms["h"] == 24);
  for (const char* key : {"fl_x", "fl_y", "cx", "cy"})
    CHECK(transforms[key].get<double>() == Approx(truth[key].get<double>() / 2));
  for (size_t i = 0; i < 3; ++i) {
    const std::string file = transforms["frames"][i]["file_path"];
    const OIIO::ImageBuf small((dir / "ws" / "20_poses" / file).string());
    const OIIO::ImageBuf full((dir / "data" / truth["frames"][i]["file_path"].get<std::string>()).string());
    REQUIRE(small.spec().width == 32);
    REQUIRE(small.spec().height == 24);
    // Each pixel the mean of the 2 x 2 it covers (an area filter), within 8-bit rounding.
    for (const auto& [x, y] : {std::pair{0, 0}, std::pair{13, 7}, std::pair{31, 23}}) {
      for (int c = 0; c < 3; ++c) {
        float mean = 0;
        for (int d = 0; d < 4; ++d) mean += full.getchannel(2 * x + d % 2, 2 * y + d / 2, 0, c) / 4;
        CHECK(small.getchannel(x, y, 0, c) == Approx(mean).margin(1.0 / 255));
      }
    }
  }
  // The default keeps images of up to 1920 pixels as they are.
  CHECK(Import(dir / "data", dir / "ws_default")["w"] == 64);
}

TEST_CASE("import: transparent images keep their alpha, and import.background is the colour they are shown on",
          "[import]") {
  TempDir dir;
  const nlohmann::json truth = WriteSmallDataset(3, dir / "data");
  for (const nlohmann::json& frame : truth["frames"]) {  // the left half transparent
    const fs::path file = dir / "data" / frame["file_path"].get<std::string>();
    const OIIO::ImageBuf rgb(file.string());
    OIIO::ImageBuf rgba(OIIO::ImageSpec(64, 48, 4, OIIO::TypeDesc::UINT8));
    for (OIIO::ImageBuf::Iterator<unsigned char, float> p(rgba); !p.done(); ++p) {
      for (int c = 0; c < 3; ++c) p[c] = rgb.getchannel(p.x(), p.y(), 0, c);
      p[3] = p.x() < 32 ? 0.0f : 1.0f;
    }
    REQUIRE(rgba.write(file.string()));
  }
  const nlohmann::json white = Import(dir / "data", dir / "white");
  CHECK(white["background"] == nlohmann::json::array({1.0, 1.0, 1.0}));
  const OIIO::ImageBuf imported(
      (dir / "white" / "20_poses" / white["frames"][0]["file_path"].get<std::string>()).string());
  REQUIRE(imported.spec().nchannels == 4);
  CHECK(imported.getchannel(3, 3, 0, 3) == 0.0f);
  CHECK(imported.getchannel(40, 3, 0, 3) == 1.0f);
  CHECK(Import(dir / "data", dir / "black", 0, "black")["background"] == nlohmann::json::array({0.0, 0.0, 0.0}));
  CHECK_FALSE(Import(dir / "data", dir / "keep", 0, "keep").contains("background"));
}

TEST_CASE("import: a masks/ folder in the dataset gives the photos their alpha, and a photo without one is named",
          "[import]") {
  TempDir dir;
  const nlohmann::json truth = WriteSmallDataset(3, dir / "data");
  fs::create_directories(dir / "data" / "masks");
  std::vector<fs::path> masks;
  for (const nlohmann::json& frame : truth["frames"]) {  // half size, the left half left out
    const fs::path photo = frame["file_path"].get<std::string>();
    OIIO::ImageBuf mask(OIIO::ImageSpec(32, 24, 1, OIIO::TypeDesc::UINT8));
    for (OIIO::ImageBuf::Iterator<unsigned char, float> p(mask); !p.done(); ++p) p[0] = p.x() < 16 ? 0.0f : 1.0f;
    masks.push_back(dir / "data" / "masks" / (photo.stem().string() + "_mask.png"));
    REQUIRE(mask.write(masks.back().string()));
  }
  const nlohmann::json masked = Import(dir / "data", dir / "masked");
  CHECK(masked["background"] == nlohmann::json::array({1.0, 1.0, 1.0}));
  const fs::path first_photo = dir / "data" / truth["frames"][0]["file_path"].get<std::string>();
  const OIIO::ImageBuf photo(first_photo.string());
  const OIIO::ImageBuf imported(
      (dir / "masked" / "20_poses" / masked["frames"][0]["file_path"].get<std::string>()).string());
  REQUIRE(imported.spec().nchannels == 4);
  CHECK(imported.getchannel(3, 3, 0, 3) == 0.0f);
  CHECK(imported.getchannel(40, 3, 0, 3) == 1.0f);
  for (int c = 0; c < 3; ++c) CHECK(imported.getchannel(40, 3, 0, c) == photo.getchannel(40, 3, 0, c));

  const nlohmann::json opaque = Import(dir / "data", dir / "opaque", 0, "white", false);
  CHECK_FALSE(opaque.contains("background"));
  const OIIO::ImageBuf kept(
      (dir / "opaque" / "20_poses" / opaque["frames"][0]["file_path"].get<std::string>()).string());
  CHECK(kept.spec().nchannels == 3);

  fs::rename(masks[0], dir / "data" / "masks" / "other.png");
  CHECK_THROWS_WITH(Import(dir / "data", dir / "missing"), Catch::Contains("has no mask for 1 of the 3 photos") &&
                                                               Catch::Contains(first_photo.filename().string()) &&
                                                               Catch::Contains("--poses.masks false"));
  OIIO::ImageBuf narrow(OIIO::ImageSpec(16, 24, 1, OIIO::TypeDesc::UINT8));
  REQUIRE(narrow.write(masks[0].string()));
  CHECK_THROWS_WITH(Import(dir / "data", dir / "narrow"), Catch::Contains("is 16x24 but its photo"));
}

TEST_CASE("import: a COLMAP project folder (images/ + sparse/0) keeps its cameras and points", "[import]") {
  TempDir dir;
  const SyntheticSceneOptions scene = SmallScene(5);
  WriteSyntheticScene(scene, dir / "data" / "images");
  fs::remove(dir / "data" / "images" / "ground_truth_cameras.json");
  const std::vector<PinholeCamera> cameras = SyntheticCameras(scene);
  ColmapModel model;
  model.cameras[1] = {1, "PINHOLE", 64, 48, {cameras[0].fx, cameras[0].fy, cameras[0].cx, cameras[0].cy}};
  for (uint32_t i = 0; i < 5; ++i) {
    ColmapImage image;
    image.id = i + 1;
    image.camera_id = 1;
    image.name = "view_00" + std::to_string(i) + ".png";
    OpenCvCamFromWorld(cameras[i].world_from_cam, &image.cam_from_world_rotation, &image.cam_from_world_translation);
    model.images[image.id] = image;
  }
  // Points near the middle of the scene, seen by images 1 and 3 (the first and third views).
  for (uint64_t p = 1; p <= 20; ++p)
    model.points[p] = {p, Eigen::Vector3d(0.01 * p, 0.02, -0.01), {1, 2, 3}, 0.1 * p, {{1, 0}, {3, 0}}};
  WriteColmapModelBinary(model, dir / "data" / "sparse" / "0");
  CHECK(DetectDataset(dir / "data") == DatasetKind::kColmap);
  const nlohmann::json transforms = Import(dir / "data", dir / "ws");
  REQUIRE(transforms["frames"].size() == 5);
  std::vector<Eigen::Matrix4d> ours, truth;
  for (size_t i = 0; i < 5; ++i) {
    ours.push_back(ReadMatrix(transforms["frames"][i]["transform_matrix"]));
    truth.push_back(cameras[i].world_from_cam);
  }
  CHECK(WorstRotationAfterAlignment(ours, truth) < 1e-6);
  CHECK(fs::exists(dir / "ws" / "20_poses" / "sparse_points.ply"));

  // The tracks: each view's points and each point's error, and the depth points training reads from them: where
  // the ray through each meets its point.
  const SparseTracks tracks = SparseTracks::Read(dir / "ws" / "20_poses" / "sparse_tracks.json");
  REQUIRE(tracks.errors.size() == 20);
  CHECK(tracks.errors[19] == Approx(2.0));
  REQUIRE(tracks.views.size() == 5);
  for (size_t i = 0; i < 5; ++i) CHECK(tracks.views[i].points.size() == (i == 0 || i == 2 ? 20u : 0u));
  const ImportedDataset poses = LoadTransformsJson(dir / "ws" / "20_poses" / "transforms.json", dir / "ws");
  const TrainingData data = LoadTrainingData(poses, true);
  const std::vector<ColouredPoint> points = ReadPly(dir / "ws" / "20_poses" / "sparse_points.ply");
  size_t depth_points = 0;
  for (const TrainView& view : data.train) {
    for (const DepthPoint& point : view.depth_points) {
      const Ray ray = CameraRay(view.camera, point.u, point.v);
      const Eigen::Vector3d end = ray.origin + point.distance * ray.direction;
      double nearest = 1e9;
      for (const ColouredPoint& p : points) nearest = std::min(nearest, (p.position.cast<double>() - end).norm());
      CHECK(nearest < 1e-4);
      ++depth_points;
    }
  }
  CHECK(depth_points > 0);
}

TEST_CASE("poses.train_views keeps that many training views, spread evenly, and the held-out views stay", "[import]") {
  std::vector<CameraView> views(20);
  AssignHoldout(&views, 8, false);
  KeepTrainingViews(&views, 5);
  std::vector<size_t> kept;
  for (size_t i = 0; i < views.size(); ++i) {
    if (views[i].split == ViewSplit::kTrain) kept.push_back(i);
    CHECK(views[i].split == (i % 8 == 0 ? ViewSplit::kVal : views[i].split));
  }
  // The 17 training views are 1-7, 9-15, 17-19: the 1st, 5th, 9th, 13th and 17th of them.
  CHECK(kept == std::vector<size_t>{1, 5, 10, 14, 19});
  KeepTrainingViews(&views, 0);
  CHECK(std::count_if(views.begin(), views.end(), [](const CameraView& v) { return v.split == ViewSplit::kTrain; }) ==
        5);
  KeepTrainingViews(&views, 1);
  CHECK(std::count_if(views.begin(), views.end(), [](const CameraView& v) { return v.split == ViewSplit::kTrain; }) ==
        1);
}

TEST_CASE("sparse_tracks.json reads back what was written, and broken ones are refused by field", "[import]") {
  TempDir dir;
  const fs::path file = dir / "sparse_tracks.json";
  SparseTracks tracks{{0.5f, 1.5f, 0.0f}, {{"images/a.png", {0, 2}}, {"images/b.png", {}}}};
  tracks.Write(file);
  const SparseTracks read = SparseTracks::Read(file);
  CHECK(read.errors == tracks.errors);
  CHECK(read.PointsOf("images/a.png") == std::vector<uint32_t>{0, 2});
  CHECK(read.PointsOf("images/b.png").empty());
  CHECK(read.PointsOf("images/c.png").empty());
  const auto refused = [&](const std::string& text, const std::string& field) {
    WriteFileAtomic(file, text);
    CHECK_THROWS_WITH(SparseTracks::Read(file), Catch::Contains(field) && Catch::Contains("sparse_tracks.json"));
  };
  refused(R"({"errors": [1], "views": [{"file_path": "a", "points": [1]}]})", "views[0].points");
  refused(R"({"errors": [-1], "views": []})", "errors[0]");
  refused(R"({"errors": [1], "views": [{"file_path": "a", "points": []}, {"file_path": "a", "points": []}]})",
          "views[1]");
  refused(R"({"views": []})", "errors");
  refused(R"({"errors": [1], "views": [{"points": []}]})", "views[0]");
  refused(R"([1, 2])", "the file");
  refused(R"({"errors": [1], "views": [{"file_path": 3, "points": []}]})", "views[0]");
}

TEST_CASE("transforms.json reads back exactly what was written: cameras, bounds, normalisation, meta", "[import]") {
  TempDir dir;
  OIIO::ImageBuf image(OIIO::ImageSpec(8, 6, 3, OIIO::TypeDesc::UINT8));
  fs::create_directories(dir / "images");
  for (const char* name : {"a.png", "b.png"}) REQUIRE(image.write((dir / "images" / name).string()));
  TransformsFile written;
  for (int i = 0; i < 2; ++i) {
    CameraView& view = written.views.emplace_back();
    view.file_path = i == 0 ? "images/a.png" : "images/b.png";
    view.camera.width = 8;
    view.camera.height = 6;
    view.camera.fx = 10.25;
    view.camera.fy = 10.5;
    view.camera.cx = 4.125;
    view.camera.cy = 2.875;
    view.camera.world_from_cam.topLeftCorner<3, 3>() =
        Eigen::AngleAxisd(0.3 * i + 0.1, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    view.camera.world_from_cam.topRightCorner<3, 1>() = Eigen::Vector3d(0.5, -1.25, 2.0 + i);
    view.split = i == 0 ? ViewSplit::kTrain : ViewSplit::kVal;
    view.near = 0.125 + i;
    view.far = 4.5 + i;
  }
  written.views[1].distortion = {0.01, -0.002, 0.0005, 0};
  TransformsMeta& meta = written.meta;
  meta.normalization.normalized_from_world.topRows<3>() << 0, -0.5, 0, 1, 0.5, 0, 0, 2, 0, 0, 0.5, 3;
  meta.normalization.scale = 0.5;
  meta.normalization.centre_from = "focus point";
  meta.normalization.up_from = "camera up vectors";
  meta.dataset_kind = DatasetKind::kLlff;
  meta.dataset_path = "/data/fern";
  meta.background = {0.0f, 0.25f, 1.0f};
  meta.frame = "frame: source";
  meta.cameras_refined = true;

  const auto check_same = [&](const TransformsFile& read) {
    REQUIRE(read.views.size() == 2);
    for (size_t i = 0; i < 2; ++i) {
      const CameraView &a = written.views[i], &b = read.views[i];
      CHECK(b.file_path == a.file_path);
      CHECK(b.split == a.split);
      CHECK((b.near == a.near && b.far == a.far));
      CHECK(b.distortion == a.distortion);
      CHECK((b.camera.width == a.camera.width && b.camera.height == a.camera.height));
      CHECK((b.camera.fx == a.camera.fx && b.camera.fy == a.camera.fy && b.camera.cx == a.camera.cx &&
             b.camera.cy == a.camera.cy));
      CHECK(b.camera.world_from_cam == a.camera.world_from_cam);
    }
    CHECK(read.meta.normalization.normalized_from_world == meta.normalization.normalized_from_world);
    CHECK(read.meta.normalization.scale == meta.normalization.scale);
    CHECK(read.meta.normalization.centre_from == meta.normalization.centre_from);
    CHECK(read.meta.normalization.up_from == meta.normalization.up_from);
    CHECK((read.meta.dataset_kind == meta.dataset_kind && read.meta.dataset_path == meta.dataset_path));
    CHECK(read.meta.Background() == *meta.background);
    CHECK((read.meta.frame == meta.frame && read.meta.cameras_refined == meta.cameras_refined));
  };
  written.Write(dir / "transforms.json");
  check_same(TransformsFile::Read(dir / "transforms.json", dir.path()));
  // Intrinsics per frame when the views differ.
  written.views[1].camera.fx = 11;
  written.Write(dir / "transforms.json");
  check_same(TransformsFile::Read(dir / "transforms.json", dir.path()));
  CHECK(ReadJsonFile(dir / "transforms.json")["frames"][1]["fl_x"] == 11.0);

  // A file without our fields (instant-ngp's): no dataset, white, the identity.
  WriteText(dir / "transforms.json", R"({"fl_x": 10, "w": 8, "h": 6, "frames": [{"file_path": "images/a.png",
      "transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0]]}]})");
  const TransformsFile plain = TransformsFile::Read(dir / "transforms.json", dir.path(), ViewSplit::kTest);
  CHECK_FALSE(plain.meta.dataset_kind);
  CHECK_FALSE(plain.meta.background.has_value());
  CHECK(plain.meta.Background() == std::array<float, 3>{1, 1, 1});
  CHECK(plain.meta.normalization.normalized_from_world == Eigen::Matrix4d::Identity());
  CHECK(plain.views.at(0).split == ViewSplit::kTest);
  CHECK((plain.views[0].near < 0 && plain.views[0].far < 0));
  WriteText(dir / "transforms.json", R"({"fl_x": 10, "w": 8, "h": 6, "background": [1, 1], "frames": []})");
  CHECK_THROWS_WITH(TransformsFile::Read(dir / "transforms.json", dir.path()),
                    Catch::Contains("transforms.json': background must be three numbers"));
  // A split of no kind we know is named, with the kinds there are.
  WriteText(dir / "transforms.json", R"({"fl_x": 10, "w": 8, "h": 6, "frames": [{"file_path": "images/a.png",
      "split": "holdout", "transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0]]}]})");
  CHECK_THROWS_WITH(TransformsFile::Read(dir / "transforms.json", dir.path()),
                    Catch::Contains("frames[0].split must be one of train, val, test or unused"));
}

TEST_CASE("import: broken and hostile datasets are refused, naming the file and field", "[import]") {
  TempDir dir;
  fs::create_directories(dir / "data");
  OIIO::ImageBuf image(OIIO::ImageSpec(8, 6, 3, OIIO::TypeDesc::UINT8));
  REQUIRE(image.write((dir / "data" / "a.png").string()));
  const auto write = [&](const std::string& matrix, const std::string& path, const std::string& focal = "10") {
    WriteText(dir / "data" / "transforms.json", R"({"fl_x": )" + focal +
                                                    R"(, "w": 8, "h": 6, "frames": [{"file_path": ")" + path +
                                                    R"(", "transform_matrix": )" + matrix + "}]}");
  };
  const std::string identity = "[[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]";
  write(identity, "../../etc/passwd");
  CHECK_THROWS_WITH(LoadDataset(dir / "data"),
                    Catch::Contains("frames[0].file_path") && Catch::Contains("outside the dataset"));
  write(identity, "/etc/passwd");
  CHECK_THROWS_WITH(LoadDataset(dir / "data"), Catch::Contains("outside the dataset"));
  write("[[2,0,0,0],[0,2,0,0],[0,0,2,0],[0,0,0,1]]", "a.png");
  CHECK_THROWS_WITH(LoadDataset(dir / "data"), Catch::Contains("not orthonormal"));
  write("[[1,0,0,0],[0,1,0,0],[0,0,1,0]]", "a.png", "-5");
  CHECK_THROWS_WITH(LoadDataset(dir / "data"), Catch::Contains("focal length"));
  write("[[1,0,0,\"x\"],[0,1,0,0],[0,0,1,0]]", "a.png");
  CHECK_THROWS_WITH(LoadDataset(dir / "data"), Catch::Contains("not a number"));
  WriteText(dir / "data" / "transforms.json", R"({"fl_x": "long", "w": 8, "h": 6, "frames": [{"file_path": "a.png",
      "transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0]]}]})");
  CHECK_THROWS_WITH(LoadDataset(dir / "data"), Catch::Contains("transforms.json' has a value of the wrong type"));
  WriteText(dir / "data" / "transforms.json", R"({"fl_x": 10, "w": 1e30, "h": 6, "frames": [{"file_path": "a.png",
      "transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0]]}]})");
  CHECK_THROWS_WITH(LoadDataset(dir / "data"),
                    Catch::Contains("frames[0].w must be a whole number of pixels") && Catch::Contains("1e+30"));
  // instant-ngp writes sizes as 8.0: read as 8.
  WriteText(dir / "data" / "transforms.json", R"({"fl_x": 10, "w": 8.0, "h": 6.0, "frames": [{"file_path": "a.png",
      "transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0]]}]})");
  CHECK(LoadDataset(dir / "data").views.at(0).view.camera.width == 8);
  write(identity, "missing.png");
  CHECK_THROWS_WITH(LoadDataset(dir / "data"), Catch::Contains("no usable view"));
  // Declared 8x6, but the image is 8x6... declare another size: refused when the images are read.
  WriteText(
      dir / "data" / "transforms.json",
      R"({"fl_x": 10, "w": 16, "h": 6, "frames": [{"file_path": "a.png", "transform_matrix": )" + identity + "}]}");
  CHECK_THROWS_WITH(Import(dir / "data", dir / "ws"), Catch::Contains("a.png' is 8x6 but the dataset declares 16x6"));

  // A COLMAP project whose image name climbs out of the project.
  fs::remove(dir / "data" / "transforms.json");
  ColmapModel model;
  model.cameras[1] = {1, "PINHOLE", 8, 6, {10, 10, 4, 3}};
  ColmapImage outside;
  outside.id = outside.camera_id = 1;
  outside.name = "../../secret.png";
  model.images[1] = outside;
  WriteColmapModelBinary(model, dir / "data" / "sparse" / "0");
  fs::create_directories(dir / "data" / "images");
  CHECK_THROWS_WITH(LoadDataset(dir / "data"),
                    Catch::Contains("images/../../secret.png") && Catch::Contains("outside the dataset"));
}

TEST_CASE("import: the shared datasets (fox, lego, lego_200, fern)", "[import][data]") {
  if (!fs::exists(kData / "lego")) {
    WARN(kData.string() << " is absent: skipping the shared-dataset importer test");
    return;
  }
  TempDir dir;
  SECTION("instant-ngp fox: frames without images are left out; distorted images are undistorted") {
    const ImportedDataset fox = LoadDataset(kData / "fox");
    CHECK(fox.kind == DatasetKind::kTransformsJson);
    CHECK(fox.views.size() == 50);
    CHECK(fox.views[0].view.distortion[0] != 0.0);
    CHECK(fox.warnings.size() == 1);
  }
  SECTION("Blender lego: the three splits") {
    const ImportedDataset lego = LoadDataset(kData / "lego");
    CHECK(lego.kind == DatasetKind::kBlender);
    std::map<std::string, int> splits;
    for (const ImportedView& view : lego.views) ++splits[EnumName(view.view.split)];
    CHECK(splits == std::map<std::string, int>{{"test", 25}, {"train", 100}, {"val", 10}});
    CHECK(lego.views[0].view.camera.fx == Approx(1111.111).epsilon(1e-3));  // 400 / tan(camera_angle_x / 2)
  }
  SECTION("the course's lego_200 .npz: train and val with their pixels, the same cameras as Blender's lego") {
    const ImportedDataset npz = LoadDataset(kData / "lego_200" / "lego_200x200.npz");
    CHECK(npz.kind == DatasetKind::kNpz);
    CHECK(npz.views.size() == 110);
    CHECK(npz.views[0].pixels.spec().width == 200);
    CHECK(npz.views[0].view.camera.fx == Approx(277.7778).epsilon(1e-4));
    const nlohmann::json transforms = Import(kData / "lego_200" / "lego_200x200.npz", dir / "ws");
    CHECK(transforms["frames"].size() == 110);
    // Rendered on white: every image's border says so, and training keeps it fixed.
    CHECK(transforms["background"] == nlohmann::json::array({1.0, 1.0, 1.0}));
    CHECK(fs::exists(dir / "ws" / "20_poses" / "images" / "val_009.png"));
  }
  SECTION("LLFF fern: poses_bounds rows with their near and far") {
    const ImportedDataset fern = LoadDataset(kData / "fern");
    CHECK(fern.kind == DatasetKind::kLlff);
    REQUIRE(fern.views.size() == 20);
    CHECK(fern.views[0].view.near > 10);
    CHECK(fern.views[0].view.camera.width == 1008);
    CHECK(fern.views[0].view.camera.fx == Approx(3260.526 / 4).epsilon(1e-4));
    // Photos: no plain background to keep; the NeRF paper's held-out views (every 8th from the first) though
    // fewer than 20.
    const nlohmann::json transforms = Import(kData / "fern", dir / "ws");
    CHECK_FALSE(transforms.contains("background"));
    CHECK(transforms["heldout_rule"] == "every 8th view from the first");
    for (size_t i = 0; i < 20; ++i) CHECK(transforms["frames"][i]["split"] == (i % 8 == 0 ? "val" : "train"));
    // Its sparse points with their tracks (points3D.bin without images.bin): image ids in the views' order, and
    // nearly every observation inside its view (else the tracks would have been dropped).
    CHECK(fern.points.size() == 10091);
    REQUIRE(fern.view_points.size() == 20);
    for (const std::vector<uint32_t>& seen : fern.view_points) CHECK(seen.size() > 1000);
    CHECK(fern.warnings.empty());
  }
}

}  // namespace p2n::testing

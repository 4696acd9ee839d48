// The render and export stages on a small trained scene: held-out PSNR agrees with training's own evaluation,
// the path's frames, depth and video are there and readable, a path written out renders the same when read
// back, and the mesh and point cloud open in an independent reader (Assimp) in both coordinate frames.

#include <catch2/catch.hpp>

#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <Eigen/Geometry>
#include <assimp/Importer.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include <bit>
#include <cmath>
#include <map>

#include "base/file_util.h"
#include "base/float_image.h"
#include "base/format.h"
#include "base/image_io.h"
#include "formats/dataset_import.h"
#include "formats/mesh_io.h"
#include "formats/ply.h"
#include "nerf/camera_refinement.h"
#include "pipeline/hash.h"
#include "splat/gaussians.h"
#include "splat/similarity.h"
#include "splat/splat_ply.h"
#include "stage_fixtures.h"
#include "stages/camera_corrections.h"
#include "stages/outputs/export_stage.h"
#include "stages/outputs/render_stage.h"
#include "stages/outputs/view_renderer.h"
#include "stages/stage_io.h"
#include "stages/stage_reports.h"
#include "stages/training_data.h"
#include "stages/view_renders.h"
#include "test_camera.h"

namespace p2n::testing {
namespace fs = std::filesystem;
namespace {

// The scene's meshes as Assimp reads them (no post-processing that could hide defects).
const aiScene* ReadWithAssimp(Assimp::Importer& importer, const fs::path& file) {
  const aiScene* scene = importer.ReadFile(file.string(), 0);
  INFO(importer.GetErrorString());
  REQUIRE(scene != nullptr);
  return scene;
}

// The mean depth (normalised units) over the pixels of path frame `f` that the render stage gave one.
double MeanDepth(const fs::path& out, int f) {
  const cv::Mat depth = cv::imread((out / "depth" / format("{:04d}.png", f)).string(), cv::IMREAD_UNCHANGED);
  REQUIRE(depth.depth() == CV_16U);
  const double depth_max = ReadJsonFile(out / "render_report.json")["path"]["depth_png_max"];
  double sum = 0, count = 0;
  for (auto d = depth.begin<uint16_t>(); d != depth.end<uint16_t>(); ++d) {
    if (*d > 0) sum += *d / 65535.0 * depth_max, ++count;
  }
  REQUIRE(count > 0);
  return sum / count;
}

}  // namespace

TEST_CASE("render stage: held-out PSNR and SSIM, path frames, depth, video, a written path renders the same",
          "[render]") {
  StageWorkspace setup;
  Config config = SmallStageConfig(60);
  config.Set("train.final_eval_pixels", 0, "test");  // every pixel, as the render stage
  config.Set("render.source", "field", "test");
  setup.runner.Run(setup.workspace, config, Until("render"));
  const fs::path out = setup.dir / "ws" / "40_render";

  const nlohmann::json eval = ReadJsonFile(out / "eval.json");
  const nlohmann::json train = ReadJsonFile(setup.dir / "ws" / "30_train" / "train_report.json");
  REQUIRE(eval["views"].size() == 2);
  // The same model, cameras and pixels as training's final evaluation: the same PSNR (tiles reassembled right).
  CHECK(eval["psnr"].get<double>() == Approx(train["heldout_psnr"].get<double>()).margin(0.01));
  CHECK(eval["step_scale"] == train["heldout_step_scale"]);
  CHECK(eval["ssim"].get<double>() > 0.2);
  CHECK(eval["ssim"].get<double>() <= 1.0);
  for (const nlohmann::json& view : eval["views"]) {
    CHECK(fs::exists(out / view["render"].get<std::string>()));
    CHECK(fs::exists(out / view["error_map"].get<std::string>()));
  }

  const nlohmann::json report = ReadJsonFile(out / "render_report.json")["path"];
  CHECK(report["kind"] == "orbit");
  CHECK(report["frames"] == 6);
  CHECK(report["frames_per_second"].get<double>() > 0);
  for (int f = 0; f < 6; ++f) {
    for (const char* folder : {"frames", "depth", "opacity"}) CHECK(fs::exists(out / folder / format("{:04d}.png", f)));
  }
  cv::VideoCapture video((out / "video.mp4").string());
  REQUIRE(video.isOpened());
  CHECK(video.get(cv::CAP_PROP_FRAME_COUNT) == 6);
  CHECK(video.get(cv::CAP_PROP_FRAME_WIDTH) == 64);
  CHECK(video.get(cv::CAP_PROP_FPS) == Approx(6));
  cv::Mat frame;
  CHECK(video.read(frame));
  CHECK(cv::mean(frame)[0] > 1);  // not black

  // Fresh on a rerun; a render option makes render stale and leaves train fresh.
  CHECK(setup.Status(config, "render").state == StageState::kFresh);
  const std::string first_frame = Sha1OfFile(out / "frames" / "0001.png");
  fs::copy_file(out / "path.json", setup.dir / "path.json");
  config.Set("render.path", "file", "test");
  config.Set("render.path_file", (setup.dir / "path.json").string(), "test");
  CHECK(setup.Status(config, "render").state == StageState::kStale);
  CHECK(setup.Status(config, "train").state == StageState::kFresh);
  setup.runner.Run(setup.workspace, config, Until("render"));
  CHECK(Sha1OfFile(out / "frames" / "0001.png") == first_frame);
  // Editing the path file makes the result stale.
  WriteText(setup.dir / "path.json", ReadText(setup.dir / "path.json") + "\n");
  CHECK(setup.Status(config, "render").state == StageState::kStale);

  // A path that comes back to a camera draws it once: the same files.
  const std::vector<PinholeCamera> path = ReadCameraPath(out / "path.json", PinholeCamera{});
  WriteCameraPath(setup.dir / "path.json", {path[0], path[1], path[0], path[1]});
  setup.runner.Run(setup.workspace, config, Until("render"));
  const nlohmann::json repeated = ReadJsonFile(out / "render_report.json")["path"];
  CHECK(repeated["frames"] == 4);
  CHECK(repeated["rendered_frames"] == 2);
  CHECK(Sha1OfFile(out / "frames" / "0001.png") == first_frame);
  for (const char* folder : {"frames", "depth", "opacity"}) {
    CHECK(Sha1OfFile(out / folder / "0002.png") == Sha1OfFile(out / folder / "0000.png"));
    CHECK(Sha1OfFile(out / folder / "0003.png") == Sha1OfFile(out / folder / "0001.png"));
  }

  // The field's renders read no splats: without the splat stage's result the render stays fresh and runs alone.
  fs::remove_all(setup.dir / "ws" / "35_splat");
  CHECK(setup.Status(config, "render").state == StageState::kFresh);
  RunRequest alone;
  alone.from = alone.until = "render";
  alone.force = {"render"};
  setup.runner.Run(setup.workspace, config, alone);
  CHECK(ReadJsonFile(out / "eval.json")["splats_psnr"].is_null());
}

TEST_CASE("render stage: from the splats, with both PSNRs in eval.json, refused when there are none", "[render]") {
  StageWorkspace setup;
  Config config = SmallStageConfig(60);
  config.Set("render.source", "splats", "test");
  setup.runner.Run(setup.workspace, config, Until("render"));
  const fs::path out = setup.dir / "ws" / "40_render";
  const nlohmann::json eval = ReadJsonFile(out / "eval.json");
  const nlohmann::json splats = ReadJsonFile(setup.dir / "ws" / "35_splat" / "splat_report.json");
  const nlohmann::json train = ReadJsonFile(setup.dir / "ws" / "30_train" / "train_report.json");
  CHECK(eval["source"] == "splats");
  // The same splats, cameras, pixels and rasterizer as the splat stage's own evaluation.
  CHECK(eval["psnr"].get<double>() == Approx(splats["heldout_psnr"].get<double>()).margin(1e-3));
  CHECK(eval["splats_psnr"] == eval["psnr"]);
  CHECK(eval["field_psnr"] == train["heldout_psnr"]);
  CHECK(ReadJsonFile(out / "render_report.json")["path"]["source"] == "splats");
  for (int f = 0; f < 6; ++f) {
    for (const char* folder : {"frames", "depth", "opacity"}) CHECK(fs::exists(out / folder / format("{:04d}.png", f)));
  }
  CHECK(MeanDepth(out, 0) > 0);  // its units: the test below

  config.Set("render.source", "splats", "test");
  config.Set("splat.enabled", false, "test");
  CHECK_THROWS_WITH(setup.runner.Run(setup.workspace, config, Until("render")),
                    Catch::Contains("render.source splats") && Catch::Contains("splat.enabled"));
}

TEST_CASE("the splats' depth: the distance along each pixel's ray in normalised units, from either frame", "[render]") {
  // A wide, flat, opaque Gaussian across the view axis, 2 normalised units ahead of the camera: each pixel's
  // depth is 2 over the cosine of its ray's angle to the axis, whichever frame the splats were written in.
  TempDir dir;
  PinholeCamera camera = CentredCamera(40, 30, 30);
  for (const double scale : {1.0, 0.25}) {
    ImportedDataset poses;  // normalized = scale * rotation * source + shift
    Eigen::Matrix4d& normalized_from_source = poses.meta.normalization.normalized_from_world;
    normalized_from_source.topLeftCorner<3, 3>() =
        scale * Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    normalized_from_source.topRightCorner<3, 1>() = Eigen::Vector3d(0.3, -0.2, 0.5);
    SplatReport report;
    report.enabled = true;
    report.frame = scale == 1.0 ? FrameKind::kNormalized : FrameKind::kSource;
    Gaussians<float> splat;
    splat.sh_degree = 0;
    splat.Resize(1);
    for (int a = 0; a < 3; ++a) splat.log_scales[a] = std::log(a < 2 ? 20.0f : 1e-3f);
    splat.rotations[0] = 1;
    splat.opacity_logits[0] = 12;
    // At (0, 0, 0) in the normalised frame (the camera stands 2 behind it), written in the report's frame.
    const Eigen::Matrix4d written_from_normalized =
        scale == 1.0 ? Eigen::Matrix4d::Identity() : Eigen::Matrix4d(normalized_from_source.inverse());
    ApplySimilarity(written_from_normalized.topLeftCorner<3, 3>(), written_from_normalized.topRightCorner<3, 1>(),
                    &splat);
    camera.world_from_cam = Eigen::Matrix4d::Identity();
    camera.world_from_cam(2, 3) = 2;  // OpenGL axes: the camera looks down -z
    WriteSplatPly(dir.path() / "splats.ply", splat);
    WriteJsonAtomic(dir.path() / "splat_report.json", report.ToJson());
    const RenderedView view = SplatRenderer(SplatResult{dir.path()}, report, poses, true).render(camera, 0.1, 10, {});
    for (int y = 0; y < camera.height; ++y) {
      for (int x = 0; x < camera.width; ++x) {
        const double u = (x + 0.5 - camera.cx) / camera.fx, v = (y + 0.5 - camera.cy) / camera.fy;
        const size_t i = size_t(y) * camera.width + x;
        INFO("scale " << scale << ", pixel " << x << ", " << y);
        REQUIRE(view.opacity.pixels[i] > 0.98f);
        REQUIRE(view.depth.pixels[i] == Approx(2 * std::sqrt(1 + u * u + v * v)).epsilon(1e-4));
      }
    }
  }
}

TEST_CASE("render stage: a camera path file is read back as written, bad ones are refused by name", "[render]") {
  TempDir dir;
  PinholeCamera camera = CentredCamera(40, 30, 35);
  camera.world_from_cam.block<3, 1>(0, 3) = Eigen::Vector3d(1, 2, 3);
  WriteCameraPath(dir / "path.json", {camera, camera});
  const std::vector<PinholeCamera> read = ReadCameraPath(dir / "path.json", PinholeCamera{});
  REQUIRE(read.size() == 2);
  CHECK(read[1].width == 40);
  CHECK(read[1].fx == 35);
  CHECK(read[1].world_from_cam.isApprox(camera.world_from_cam));

  WriteText(dir / "bad.json", R"({"frames": [{"transform_matrix": [[1, 0, 0, 0], [0, 2, 0, 0], [0, 0, 1, 0]]}]})");
  CHECK_THROWS_WITH(ReadCameraPath(dir / "bad.json", camera),
                    Catch::Contains("bad.json") && Catch::Contains("orthonormal"));
  WriteText(dir / "bad.json",
            R"({"w": -3, "frames": [{"transform_matrix": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]]}]})");
  CHECK_THROWS_WITH(ReadCameraPath(dir / "bad.json", camera), Catch::Contains("\"w\""));
  WriteText(dir / "bad.json", R"({"cameras": []})");
  CHECK_THROWS_WITH(ReadCameraPath(dir / "bad.json", camera), Catch::Contains("frames"));
}

// The export's mesh.ply and mesh.obj (every vertex finite and inside the region of `centre` and `half_size`, the
// report's triangles), its textured mesh.glb and its point cloud, as Assimp reads them; the mesh's vertices.
std::vector<aiVector3D> CheckMeshFiles(const fs::path& out, const nlohmann::json& report, const Eigen::Vector3d& centre,
                                       double half_size) {
  std::vector<aiVector3D> normalized;
  for (const char* file : {"mesh.ply", "mesh.obj"}) {
    Assimp::Importer importer;
    const aiScene* scene = ReadWithAssimp(importer, out / file);
    REQUIRE(scene->mNumMeshes == 1);
    const aiMesh* mesh = scene->mMeshes[0];
    CHECK(mesh->mNumFaces == report["mesh"]["triangles"].get<size_t>());
    CHECK(mesh->HasNormals());
    for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
      const aiVector3D& p = mesh->mVertices[v];
      REQUIRE((std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)));
      CHECK((Eigen::Vector3d(p.x, p.y, p.z) - centre).cwiseAbs().maxCoeff() <= half_size + 1e-5);  // in the region
    }
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) REQUIRE(mesh->mFaces[f].mNumIndices == 3);
    if (normalized.empty()) normalized.assign(mesh->mVertices, mesh->mVertices + mesh->mNumVertices);
  }
  {
    // The textured mesh: mesh.glb with its texture inside, mesh.obj with mesh.mtl naming the texture beside it.
    CHECK(report["mesh"]["marched_triangles"].get<size_t>() >= report["mesh"]["triangles"].get<size_t>());
    CHECK(report["textured"]["bytes"].get<size_t>() == fs::file_size(out / "mesh.glb"));
    Assimp::Importer importer;
    const aiScene* scene = ReadWithAssimp(importer, out / "mesh.glb");
    REQUIRE(scene->mNumMeshes == 1);
    CHECK(scene->mMeshes[0]->mNumFaces == report["mesh"]["triangles"].get<size_t>());
    CHECK(scene->mMeshes[0]->HasTextureCoords(0));
    CHECK(scene->mNumTextures == 1);
    CHECK(ReadText(out / "mesh.obj").find("mtllib mesh.mtl") != std::string::npos);
    CHECK(ReadText(out / "mesh.mtl").find("map_Kd mesh_texture.jpg") != std::string::npos);
    CHECK(ReadImage(out / "mesh_texture.jpg").ok());
  }
  {
    Assimp::Importer importer;
    const aiScene* scene = ReadWithAssimp(importer, out / "points.ply");
    CHECK(scene->mMeshes[0]->mNumVertices == report["points"]["count"].get<size_t>());
    CHECK(scene->mMeshes[0]->HasVertexColors(0));
  }

  return normalized;
}

TEST_CASE("export stage: mesh and point cloud open in Assimp, finite, in the source or the normalised frame",
          "[export]") {
  StageWorkspace setup;
  Config config = SmallStageConfig(150);
  config.Set("export.obj", true, "test");
  config.Set("export.frame", "normalized", "test");
  config.Set("export.threshold", 2.0, "test");       // a young field's densities are low
  config.Set("export.points_opacity", 0.5, "test");  // and so are its opacities
  setup.runner.Run(setup.workspace, config, Until("export"));
  const fs::path out = setup.dir / "ws" / "50_export";
  const nlohmann::json report = ReadJsonFile(out / "export_report.json");
  REQUIRE(report["mesh"]["triangles"].get<size_t>() > 100);
  // Every training view's depths (fewer than 200 of them).
  const nlohmann::json poses = ReadJsonFile(setup.dir / "ws" / "20_poses" / "transforms.json");
  size_t training_views = 0;
  for (const nlohmann::json& frame : poses["frames"]) training_views += frame["split"] == "train";
  CHECK(report["depth_views"].get<size_t>() == training_views);
  // The small scene is unbounded (a transforms.json dataset): the mesh covers the cube the views look at, inside
  // the scene box.
  const nlohmann::json& region = report["mesh"]["region"];
  CHECK(region["kind"] == "focus");
  const double half_size = region["half_size"].get<double>();
  CHECK((half_size > 0.05 && half_size <= 1.0));
  const Eigen::Vector3d centre(region["centre"][0].get<double>(), region["centre"][1].get<double>(),
                               region["centre"][2].get<double>());
  CHECK(centre.cwiseAbs().maxCoeff() + half_size <= 1.0 + 1e-9);

  const std::vector<aiVector3D> normalized = CheckMeshFiles(out, report, centre, half_size);

  // In the source frame, applying applied_transform gives back the normalised vertices.
  config.Set("export.frame", "source", "test");
  setup.runner.Run(setup.workspace, config, Until("export"));
  const nlohmann::json transforms = ReadJsonFile(setup.dir / "ws" / "20_poses" / "transforms.json");
  Eigen::Matrix<double, 3, 4> normalized_from_source;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) normalized_from_source(r, c) = transforms["applied_transform"][r][c].get<double>();
  }
  Assimp::Importer importer;
  const aiMesh* mesh = ReadWithAssimp(importer, out / "mesh.ply")->mMeshes[0];
  REQUIRE(mesh->mNumVertices == normalized.size());
  for (unsigned v = 97; v < mesh->mNumVertices; v += 97) {  // the first vertices may trade places (LeadingRecord)
    const Eigen::Vector3d source(mesh->mVertices[v].x, mesh->mVertices[v].y, mesh->mVertices[v].z);
    const Eigen::Vector3d back = normalized_from_source * source.homogeneous();
    CHECK((back - Eigen::Vector3d(normalized[v].x, normalized[v].y, normalized[v].z)).norm() < 1e-4);
  }

  // export.region box: the whole scene box.
  config.Set("export.region", "box", "test");
  setup.runner.Run(setup.workspace, config, Until("export"));
  const nlohmann::json box = ReadJsonFile(out / "export_report.json")["mesh"]["region"];
  CHECK(box["kind"] == "box");
  CHECK(box["half_size"] == 1.0);
}

TEST_CASE("export stage: a texture with no room for the mesh's charts leaves the textured files out, with a warning",
          "[export]") {
  StageWorkspace setup;
  Config config = SmallStageConfig(150);
  config.Set("export.threshold", 2.0, "test");  // a young field's densities are low
  config.Set("export.max_triangles", 0, "test");
  config.Set("export.texture_size", 64, "test");  // 4,096 texels: a few hundred charts at most
  setup.runner.Run(setup.workspace, config, Until("export"));
  const fs::path out = setup.dir / "ws" / "50_export";
  const nlohmann::json report = ReadJsonFile(out / "export_report.json");
  REQUIRE(report["mesh"]["triangles"].get<size_t>() > 1000);
  CHECK(fs::exists(out / "mesh.ply"));
  CHECK_FALSE(fs::exists(out / "mesh.glb"));
  CHECK(report["textured"]["file"] == "");
}

TEST_CASE("mesh.ply and points.ply read right in Assimp when the first vertex's first byte is a line end", "[export]") {
  // Assimp skips such a byte after the header (its issue #5341) and reads the rest one byte off; the writers put
  // another vertex first.
  TempDir dir;
  const float line_end = std::bit_cast<float>(uint32_t{0x3f80000a});  // 1.0000012: first byte '\n'
  Mesh mesh;
  mesh.positions = {{line_end, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0.1f, 0.5f, 0.5f}};  // 0.1f: first byte 0xcd
  mesh.normals.assign(4, Eigen::Vector3f(0, 0, 1));
  mesh.colours = {{{10, 20, 30}}, {{40, 50, 60}}, {{70, 80, 90}}, {{100, 110, 120}}};
  mesh.triangles = {{{0, 1, 2}}, {{0, 2, 3}}, {{1, 3, 2}}};
  WriteMeshPly(dir / "mesh.ply", mesh, {});
  Assimp::Importer importer;
  const aiMesh* read = ReadWithAssimp(importer, dir / "mesh.ply")->mMeshes[0];
  REQUIRE(read->mNumVertices == 4);
  REQUIRE(read->mNumFaces == 3);
  for (unsigned f = 0; f < 3; ++f) {
    REQUIRE(read->mFaces[f].mNumIndices == 3);
    for (int k = 0; k < 3; ++k) {
      const aiVector3D& p = read->mVertices[read->mFaces[f].mIndices[k]];
      CHECK(Eigen::Vector3f(p.x, p.y, p.z) == mesh.positions[mesh.triangles[f][k]]);
    }
  }

  std::vector<ColouredPoint> points = {{{line_end, 2, 3}, {{1, 2, 3}}}, {{0.1f, 5, 6}, {{4, 5, 6}}}};
  WritePly(dir / "points.ply", points);
  const aiMesh* cloud = ReadWithAssimp(importer, dir / "points.ply")->mMeshes[0];
  REQUIRE(cloud->mNumVertices == 2);
  std::vector<float> xs = {cloud->mVertices[0].x, cloud->mVertices[1].x};
  std::sort(xs.begin(), xs.end());
  CHECK(xs == std::vector<float>{0.1f, line_end});
  CHECK(ReadPly(dir / "points.ply").size() == 2);
}

TEST_CASE("the training views rendered small: no more pixels than points kept", "[export]") {
  PinholeCamera photo;
  photo.width = 1080;  // fox's photos: portrait
  photo.height = 1920;
  photo.fx = photo.fy = 1500;
  photo.cx = 540;
  photo.cy = 960;
  const std::vector<PinholeCamera> few(3, photo), many(43, photo);
  CHECK(SmallViewsWidth(few, 200) == 200);  // 3 x 200 x 356 pixels: all kept
  const int width = SmallViewsWidth(many, 200, 2'000'000);
  const PinholeCamera scaled = ScaledCamera(photo, width);
  const size_t pixels = 43 * size_t(scaled.width) * scaled.height;
  CHECK(pixels <= 2'000'000);
  CHECK(pixels > 1'950'000);  // no narrower than it must be
  CHECK(SmallViewsWidth(many, 200, 10) >= 1);
}

TEST_CASE("the training views rendered small: once a run for the splat and export stages, the same when run alone",
          "[export]") {
  StageWorkspace setup;
  Config config = SmallStageConfig(30);
  config.Set("splat.init_width", 32, "test");  // the export's points_width: the two stages want the same renders
  setup.runner.Run(setup.workspace, config, Until("train"));
  const fs::path ws = setup.dir / "ws", model_file = ws / "30_train" / "model.bin";
  const NerfModel model = LoadTrainedModel(model_file);
  std::vector<TrainView> views = LoadTrainingData(LoadTransformsJson(ws / "20_poses" / "transforms.json", ws)).train;
  for (TrainView& view : views) view.pixels.clear();

  RunMemo memo;
  StageContext context{setup.dir / "out", setup.workspace, config, {}, {}, "", setup.dir / "resume", nullptr, &memo};
  const auto renders = RenderViewsSmall(context, model_file, model, views, 24, "test");
  REQUIRE(renders->renders.size() == views.size());
  CHECK(renders->cameras[0].width == 24);
  CHECK(RenderViewsSmall(context, model_file, model, views, 24, "test") == renders);  // found, not rendered again
  CHECK(RenderViewsSmall(context, model_file, model, views, 16, "test") != renders);  // another width
  std::vector<TrainView> moved = views;
  moved[3].camera.world_from_cam(0, 3) += 1e-3;
  CHECK(RenderViewsSmall(context, model_file, model, moved, 24, "test") != renders);  // another camera
  context.memo = nullptr;  // a stage run alone renders them itself: the same pixels and median depths
  const auto alone = RenderViewsSmall(context, model_file, model, views, 24, "test");
  CHECK(alone != renders);
  for (size_t v = 0; v < views.size(); ++v) {
    CHECK(alone->renders[v].rgb.pixels == renders->renders[v].rgb.pixels);
    CHECK(alone->renders[v].depth.pixels == renders->renders[v].depth.pixels);
  }

  // Through the runner: the export after the splat stage in one run writes the points it writes alone.
  setup.runner.Run(setup.workspace, config, Until("export"));
  const std::string points = ReadTextFile(ws / "50_export" / "points.ply");
  RunRequest export_alone = Until("export");
  export_alone.from = "export";
  export_alone.force = {"export"};
  setup.runner.Run(setup.workspace, config, export_alone);
  CHECK(ReadTextFile(ws / "50_export" / "points.ply") == points);
}

TEST_CASE("export stage: transforms.json holds the cameras, the training ones as camera refinement moved them",
          "[export]") {
  StageWorkspace setup;
  Config config = SmallStageConfig(150);
  config.Set("train.refine_cameras", "on", "test");
  config.Set("export.frame", "normalized", "test");
  config.Set("export.points", false, "test");
  config.Set("export.resolution", 8, "test");
  setup.runner.Run(setup.workspace, config, Until("export"));
  const nlohmann::json poses = ReadJsonFile(setup.dir / "ws" / "20_poses" / "transforms.json");
  const nlohmann::json exported = ReadJsonFile(setup.dir / "ws" / "50_export" / "transforms.json");
  const std::map<std::string, CameraCorrection> corrections =
      ReadTrainedField(InWorkspace<TrainResult>(setup.workspace)).corrections;
  CHECK(exported["cameras_refined"] == true);
  REQUIRE(exported["frames"].size() == poses["frames"].size());
  const auto matrix = [](const nlohmann::json& json) {
    Eigen::Matrix4d m;
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c) m(r, c) = json[r][c].get<double>();
    }
    return m;
  };
  size_t refined = 0;
  double largest_turn = 0;
  for (size_t f = 0; f < poses["frames"].size(); ++f) {
    const nlohmann::json& frame = exported["frames"][f];
    const fs::path image = frame["file_path"].get<std::string>();
    CHECK(image.is_absolute());
    CHECK(fs::exists(image));
    PinholeCamera camera;
    camera.world_from_cam = matrix(poses["frames"][f]["transform_matrix"]);
    const auto found = corrections.find(image.filename().string());
    INFO(image.filename().string());
    CHECK((found != corrections.end()) == (poses["frames"][f]["split"] == "train"));
    if (found != corrections.end()) {
      camera = CorrectedCamera(camera, found->second.data());
      largest_turn = std::max(largest_turn, CorrectionDegrees(found->second.data()));
      ++refined;
    }
    CHECK((matrix(frame["transform_matrix"]) - camera.world_from_cam).norm() < 1e-5);
  }
  CHECK(refined == corrections.size());
  CHECK(largest_turn > 0);  // 50 steps after the warm-up moved them
  CHECK(largest_turn < 2);
}

}  // namespace p2n::testing

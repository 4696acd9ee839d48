// The splat files, the textured mesh and the viewer page against independent readers: splat-transform (PlayCanvas's
// splat tool, from npm) reads our standard and compressed PLYs and our SPZ to the values we wrote, Khronos's
// glTF-Validator finds nothing wrong in the export's mesh.glb, three.js draws a textured sphere as it is, and
// headless Chromium shows
// viewer.html with Spark: the frame it draws from a camera matches our CPU rasterizer's render of that camera, a
// drag moves the view, and the page asks the network for nothing.

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>

#include "base/file_util.h"
#include "base/float_image.h"
#include "formats/gltf_io.h"
#include "mesh/mesh.h"
#include "mesh/mesh_simplify.h"
#include "mesh/texture_atlas.h"
#include "nerf/image_fit.h"
#include "splat/compressed_ply.h"
#include "splat/splat_gltf.h"
#include "splat/splat_ply.h"
#include "splat/splat_trainer.h"
#include "splat/spz.h"
#include "stage_fixtures.h"
#include "tests/random_splats.h"
#include "tests/sphere_field.h"
#include "viewer/viewer_page.h"

namespace p2n::testing {
namespace fs = std::filesystem;
namespace {

// `input` converted by splat-transform into a standard PLY, read back.
Gaussians<float> ThroughSplatTransform(const fs::path& input, const TempDir& dir) {
  const fs::path output = dir / "converted.ply";
  std::string log;
  const int status = RunCommand({P2N_NODE, P2N_NODE_DIR "/node_modules/@playcanvas/splat-transform/bin/cli.mjs",
                                 "--overwrite", input.string(), output.string()},
                                &log);
  INFO(log);
  REQUIRE(status == 0);
  return ReadSplatPly(output);
}

// The index in `g` of each splat of `h` (the compressed file reorders them), by nearest position.
std::vector<size_t> Match(const Gaussians<float>& g, const Gaussians<float>& h) {
  std::vector<size_t> match(h.size());
  for (size_t j = 0; j < h.size(); ++j) {
    float best = INFINITY;
    for (size_t i = 0; i < g.size(); ++i) {
      float d = 0;
      for (int a = 0; a < 3; ++a) d += std::pow(g.positions[3 * i + a] - h.positions[3 * j + a], 2.f);
      if (d < best) best = d, match[j] = i;
    }
  }
  return match;
}

}  // namespace

TEST_CASE("splat-transform reads our standard splat PLY to the very values we wrote", "[viewer]") {
  TempDir dir;
  const Gaussians<float> g = RandomSplats(300, 1);
  WriteSplatPly(dir / "splats.ply", g);
  const Gaussians<float> read = ThroughSplatTransform(dir / "splats.ply", dir);
  REQUIRE(read.size() == g.size());
  REQUIRE(read.sh_degree == 3);
  g.ForEachArray([&, a = 0](const std::vector<float>& values, int) mutable {
    int b = 0;
    read.ForEachArray([&](const std::vector<float>& other, int) {
      if (b++ == a) CHECK(other == values);
    });
    ++a;
  });
}

TEST_CASE("splat-transform reads our compressed splat PLY to within its quantisation", "[viewer]") {
  TempDir dir;
  const Gaussians<float> g = RandomSplats(1000, 2);  // four chunks
  const std::vector<char> bytes = CompressedSplatPlyBytes(g);
  CHECK(bytes.size() < g.size() * 62 + 1500);  // 61 bytes a splat at degree 3, 72 a chunk, and the header
  WriteFileAtomic(dir / "splats.compressed.ply", std::string_view(bytes.data(), bytes.size()));
  const Gaussians<float> read = ThroughSplatTransform(dir / "splats.compressed.ply", dir);
  REQUIRE(read.size() == g.size());
  REQUIRE(read.sh_degree == 3);
  const std::vector<size_t> match = Match(g, read);
  CHECK(std::set<size_t>(match.begin(), match.end()).size() == g.size());
  float position = 0, scale = 0, rotation = 0, alpha = 0, colour = 0, sh = 0;
  for (size_t j = 0; j < read.size(); ++j) {
    const size_t i = match[j];
    for (int a = 0; a < 3; ++a) {
      position = std::max(position, std::abs(read.positions[3 * j + a] - g.positions[3 * i + a]));
      scale = std::max(scale, std::abs(read.log_scales[3 * j + a] - g.log_scales[3 * i + a]));
      colour = std::max(colour, std::abs(read.sh_dc[3 * j + a] - g.sh_dc[3 * i + a]) * 0.2821f);
    }
    rotation = std::max(rotation, QuaternionError(&read.rotations[4 * j], &g.rotations[4 * i]));
    const auto sigmoid = [](float x) { return 1 / (1 + std::exp(-x)); };
    alpha = std::max(alpha, std::abs(sigmoid(read.opacity_logits[j]) - sigmoid(g.opacity_logits[i])));
    for (int k = 0; k < 45; ++k) {
      // f_rest in the file: channel by channel; ours: coefficient by coefficient.
      sh = std::max(sh, std::abs(read.sh_rest[45 * j + k] - g.sh_rest[45 * i + k]));
    }
  }
  // A chunk of 256 of the 1000 splats along the Morton curve spans about a quarter of the box of 4: 11 and
  // 10 bits of it. The scales' range is 2 (in logarithms), colours about 1.7 (after SH_C0), opacity 1.
  CHECK(position < 4.0f / 1023);
  CHECK(scale < 2.0f / 1023);
  CHECK(rotation < 0.002f);
  CHECK(alpha < 0.6f / 255);
  CHECK(colour < 1.7f / 255);
  CHECK(sh < 8.0f / 256);
}

TEST_CASE("splat-transform reads our SPZ to within its quantisation, in the splat PLY's axes", "[viewer]") {
  TempDir dir;
  const Gaussians<float> g = RandomSplats(500, 3);
  const std::vector<char> bytes = SpzBytes(g);
  WriteFileAtomic(dir / "splats.spz", std::string_view(bytes.data(), bytes.size()));
  const Gaussians<float> read = ThroughSplatTransform(dir / "splats.spz", dir);
  REQUIRE(read.size() == g.size());
  REQUIRE(read.sh_degree == 3);
  float position = 0, scale = 0, rotation = 0, alpha = 0, colour = 0, sh = 0;
  for (size_t i = 0; i < read.size(); ++i) {  // SPZ keeps the order
    for (int a = 0; a < 3; ++a) {
      position = std::max(position, std::abs(read.positions[3 * i + a] - g.positions[3 * i + a]));
      scale = std::max(scale, std::abs(read.log_scales[3 * i + a] - g.log_scales[3 * i + a]));
      colour = std::max(colour, std::abs(read.sh_dc[3 * i + a] - g.sh_dc[3 * i + a]));
    }
    rotation = std::max(rotation, QuaternionError(&read.rotations[4 * i], &g.rotations[4 * i]));
    const auto sigmoid = [](float x) { return 1 / (1 + std::exp(-x)); };
    alpha = std::max(alpha, std::abs(sigmoid(read.opacity_logits[i]) - sigmoid(g.opacity_logits[i])));
    for (int k = 0; k < 45; ++k) sh = std::max(sh, std::abs(read.sh_rest[45 * i + k] - g.sh_rest[45 * i + k]));
  }
  // Positions in a box of 4 at 20 fractional bits, scales in steps of 1/16, opacity and colour of 1/255 (colour as
  // 0.15 f_dc), rotations in 9 bits, SH in steps of 1/128: a sign or axis wrong would be off by far more.
  CHECK(position < 1e-5f);
  CHECK(scale <= 0.5f / 16 + 1e-4f);
  CHECK(rotation < 0.002f);
  CHECK(alpha < 0.6f / 255);
  CHECK(colour < 0.6f / 255 / 0.15f);
  CHECK(sh < 0.6f / 128);
}

TEST_CASE("viewer.html in headless Chromium draws what our rasterizer renders, moves with a drag, stays offline",
          "[viewer]") {
  StageWorkspace setup;
  Config config = SmallStageConfig(60);
  config.Set("render.source", "splats", "test");
  config.Set("render.path", "none", "test");
  setup.runner.Run(setup.workspace, config, Until("render"));
  const fs::path splat_dir = setup.dir / "ws" / "35_splat", render_dir = setup.dir / "ws" / "40_render";
  const fs::path page = splat_dir / "viewer.html";
  const nlohmann::json report = ReadJsonFile(splat_dir / "splat_report.json");
  CHECK(report["viewer_bytes"].get<size_t>() == fs::file_size(page));

  // The training camera the page starts at, rendered by our rasterizer from splats.ply.
  const std::string html = ReadText(page);
  const std::string open = R"(<script id="p2n-scene" type="application/json">)";
  const size_t begin = html.find(open) + open.size();
  const nlohmann::json scene = nlohmann::json::parse(html.substr(begin, html.find("</script>", begin) - begin));
  const nlohmann::json& first = scene["cameras"].at(0);
  REQUIRE(first["split"] == "train");
  PinholeCamera camera;
  camera.width = first["width"], camera.height = first["height"];
  camera.fx = first["fx"], camera.fy = first["fy"], camera.cx = first["cx"], camera.cy = first["cy"];
  const std::vector<double> pose = first["pose"];
  camera.world_from_cam = Eigen::Map<const Eigen::Matrix4d>(pose.data());  // column-major
  const std::vector<float> background = report["background"];
  SaveFloatImage(RenderSplats(ReadSplatPly(splat_dir / "splats.ply"), camera,
                              {background[0], background[1], background[2]}, report["near"].get<double>()),
                 setup.dir / "train_view.png");
  // And a held-out camera, which the render stage drew from the same splats (its camera not from the page).
  const nlohmann::json heldout = ReadJsonFile(render_dir / "eval.json")["views"].at(0);

  for (const auto& [name, reference] :
       {std::pair{first["name"].get<std::string>(), setup.dir / "train_view.png"},
        std::pair{heldout["view"].get<std::string>(), render_dir / heldout["render"].get<std::string>()}}) {
    std::string output;
    const int status =
        RunCommand({P2N_NODE, P2N_NODE_DIR "/viewer_check.mjs", page.string(), name, reference.string()}, &output);
    INFO(name << ": " << output);
    REQUIRE(status == 0);
    const nlohmann::json result = nlohmann::json::parse(output.substr(output.rfind('{')));
    CHECK(result["errors"].empty());
    CHECK(result["requests"].empty());
    REQUIRE(result["psnr"].is_number());
    CHECK(result["psnr"].get<double>() >= 25);
    CHECK(result["drag_changed_picture"] == true);
  }
}

TEST_CASE("glTF-Validator finds nothing wrong in mesh.glb and splats.glb, and the report page draws the mesh offline",
          "[viewer]") {
  StageWorkspace setup;
  Config config = SmallStageConfig(150);
  config.Set("export.threshold", 2.0, "test");  // a young field's densities are low
  config.Set("export.max_triangles", 3000, "test");
  config.Set("export.texture_size", 512, "test");
  setup.runner.Run(setup.workspace, config, Until("report"));
  for (const char* file : {"mesh.glb", "mesh_preview.glb"}) {
    const fs::path glb = setup.dir / "ws" / "50_export" / file;
    std::string output;
    const int status = RunCommand({P2N_NODE, P2N_NODE_DIR "/gltf_check.mjs", glb.string()}, &output);
    INFO(output);
    REQUIRE(status == 0);
    const nlohmann::json result = nlohmann::json::parse(output.substr(output.find('{')));
    CHECK(result["errors"] == 0);
    CHECK(result["warnings"] == 0);
    const nlohmann::json& info = result["info"];
    const size_t triangles = info["totalTriangleCount"];
    CHECK((triangles > 100 && triangles <= 3000));
    CHECK(info["hasTextures"] == true);
    CHECK(info["resources"][1]["image"]["width"] == 512);
  }

  {
    // splats.glb: the validator knows no KHR_gaussian_splatting yet: it says so, and calls the attributes the
    // extension names invalid (glTF's own names or an underscore only); nothing else is wrong, and our reader finds
    // every splat of splats.ply.
    const fs::path glb = setup.dir / "ws" / "35_splat" / "splats.glb";
    std::string output;
    REQUIRE(RunCommand({P2N_NODE, P2N_NODE_DIR "/gltf_check.mjs", glb.string()}, &output) == 0);
    INFO(output);
    const nlohmann::json result = nlohmann::json::parse(output.substr(output.find('{')));
    int extension_errors = 0;
    for (const nlohmann::json& message : result["messages"]) {
      if (message["severity"].get<int>() > 1) continue;  // 0 errors, 1 warnings
      INFO(message.dump());
      const bool unknown_attribute =
          message["code"] == "MESH_PRIMITIVE_INVALID_ATTRIBUTE" &&
          message["pointer"].get<std::string>().find("/KHR_gaussian_splatting:") != std::string::npos;
      CHECK((unknown_attribute || message["code"] == "UNSUPPORTED_EXTENSION"));
      extension_errors += unknown_attribute;
    }
    CHECK(result["errors"] == extension_errors);
    CHECK(ParseSplatGlb(ReadText(glb), "splats.glb").size() ==
          ReadSplatPly(setup.dir / "ws" / "35_splat" / "splats.ply").size());
  }
  std::string output;
  const fs::path page = setup.dir / "ws" / "60_report" / "report.html";
  const int status = RunCommand({P2N_NODE, P2N_NODE_DIR "/report_mesh_check.mjs", page.string()}, &output);
  INFO(output);
  REQUIRE(status == 0);
  const nlohmann::json result = nlohmann::json::parse(output.substr(output.rfind('{')));
  CHECK(result["errors"].empty());
  CHECK(result["requests"].empty());
  CHECK(result["shown"] == true);
  CHECK(result["covered"].get<double>() > 0.01);  // a young field's mesh: scattered pieces
}

TEST_CASE("three.js draws our textured sphere from a camera as the sphere looks from there", "[viewer]") {
  // The sphere of radius 0.6 whose colour seen along direction d is (1 - d) / 2, meshed, simplified and textured.
  const NerfModel model = SphereModel();
  MeshOptions options;
  options.resolution = 96;
  options.density_threshold = kThreshold;
  const Mesh mesh = SimplifyMesh(ExtractMesh(model, options), 20000).mesh;
  const TempDir dir;
  const TexturedMesh textured = BakeTexture(
      mesh, 1024, [&](const auto& points, const auto& normals) { return SurfaceColours(model, points, normals); });
  WriteFileAtomic(dir / "sphere.glb", MeshGlbBytes(textured, TextureJpeg(textured), "test"));

  // A camera 2 units off, looking at the centre from below, its principal point off the image's centre.
  PinholeCamera camera;
  camera.width = 160, camera.height = 120, camera.fx = camera.fy = 150, camera.cx = 84, camera.cy = 57;
  const Eigen::Vector3d eye(0.3, -1.9, -0.6), forward = -eye.normalized();
  const Eigen::Vector3d right = forward.cross(Eigen::Vector3d::UnitZ()).normalized(), up = right.cross(forward);
  camera.world_from_cam.setIdentity();
  camera.world_from_cam.block<3, 3>(0, 0) << right, up, -forward;  // OpenGL axes: looking down -z
  camera.world_from_cam.block<3, 1>(0, 3) = eye;
  const Eigen::Matrix4d& pose = camera.world_from_cam;
  const nlohmann::json setup = {{"background", {0.2, 0.3, 0.4}},
                                {"near", 0.1},
                                {"far", 10},
                                {"cameras",
                                 {{{"width", camera.width},
                                   {"height", camera.height},
                                   {"fx", camera.fx},
                                   {"fy", camera.fy},
                                   {"cx", camera.cx},
                                   {"cy", camera.cy},
                                   {"pose", std::vector<double>(pose.data(), pose.data() + 16)}}}}};
  WriteJsonAtomic(dir / "cameras.json", setup);
  std::string output;
  const int status = RunCommand({P2N_NODE, P2N_NODE_DIR "/mesh_check.mjs", (dir / "sphere.glb").string(),
                                 (dir / "cameras.json").string(), dir.path().string()},
                                &output);
  INFO(output);
  REQUIRE(status == 0);
  const nlohmann::json result = nlohmann::json::parse(output.substr(output.rfind('{')));
  CHECK(result["errors"].empty());
  const FloatImage drawn = LoadImageForFit(dir / "0.png", FitAlpha::kIgnore);  // opaque: the background is drawn
  REQUIRE((drawn.width == camera.width && drawn.height == camera.height));

  // The analytic picture: each pixel's ray meets the sphere or shows the background. Where the sphere is seen
  // squarely (away from its outline, which the mesh's chords and antialiasing blur), within a level or two.
  FloatImage expected{camera.width, camera.height, 3, std::vector<float>(size_t(3) * camera.width * camera.height)};
  double error = 0;
  size_t inside = 0;
  for (int y = 0; y < camera.height; ++y) {
    for (int x = 0; x < camera.width; ++x) {
      const Ray ray = CameraRay(camera, x + 0.5, y + 0.5);
      const double b = ray.origin.dot(ray.direction), c = ray.origin.squaredNorm() - kRadius * kRadius;
      const double disc = b * b - c;
      const size_t i = 3 * (size_t(y) * camera.width + x);
      Eigen::Vector3d colour(0.2, 0.3, 0.4);
      if (disc > 0) {
        const Eigen::Vector3d normal = (ray.origin + (-b - std::sqrt(disc)) * ray.direction).normalized();
        colour = (Eigen::Vector3d::Ones() + normal) / 2;
        if (-normal.dot(ray.direction) > 0.4) {
          for (int k = 0; k < 3; ++k) error += std::abs(drawn.pixels[i + k] - colour[k]) / 3;
          ++inside;
        }
      }
      for (int k = 0; k < 3; ++k) expected.pixels[i + k] = static_cast<float>(colour[k]);
    }
  }
  REQUIRE(inside > 3000);
  CHECK(error / inside * 255 <= 2);  // levels, on average
  CHECK(Psnr(drawn, expected) >= 33);
}

}  // namespace p2n::testing

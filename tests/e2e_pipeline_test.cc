// The whole product with real COLMAP: `photo2nerf run PHOTOS -w WS` on the synthetic scene goes from photos to
// the report; the held-out PSNR is above a bound, the mesh opens and is finite, the report lists every stage and
// the grey photo it left out with its reason. A second run finds every stage fresh and recomputes nothing.

#include <catch2/catch.hpp>

#include <assimp/scene.h>
#include <assimp/Importer.hpp>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>

#include <cstdlib>

#include "base/file_util.h"
#include "examples/synthetic_scene.h"
#include "splat/splat_ply.h"
#include "tests/test_util.h"

namespace p2n::testing {
namespace fs = std::filesystem;

// `photo2nerf run PHOTOS -w WS` with budgets that keep the test short.
std::vector<std::string> RunCommandLine(const fs::path& photos, const fs::path& ws) {
  std::vector<std::string> command = {P2N_BINARY, "run", photos.string(), "-w", ws.string()};
  for (const auto& [key, value] : std::vector<std::pair<std::string, std::string>>{{"run.progress", "plain"},
                                                                                   {"train.preset", "fast"},
                                                                                   {"train.steps", "200"},
                                                                                   {"train.time_budget", "600"},
                                                                                   {"splat.steps", "60"},
                                                                                   {"splat.init_width", "64"},
                                                                                   {"render.frames", "8"},
                                                                                   {"render.width", "160"},
                                                                                   {"export.resolution", "96"},
                                                                                   {"export.threshold", "5"},
                                                                                   {"export.points_width", "64"}}) {
    command.push_back("--" + key);
    command.push_back(value);
  }
  return command;
}

// The mesh opens in Assimp, with faces and finite vertices.
void CheckMesh(const fs::path& mesh_ply) {
  Assimp::Importer importer;
  const aiScene* mesh_scene = importer.ReadFile(mesh_ply.string(), 0);
  REQUIRE(mesh_scene != nullptr);
  const aiMesh* mesh = mesh_scene->mMeshes[0];
  CHECK(mesh->mNumFaces > 100);
  for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
    REQUIRE((std::isfinite(mesh->mVertices[v].x) && std::isfinite(mesh->mVertices[v].y) &&
             std::isfinite(mesh->mVertices[v].z)));
  }
}

// When each stage folder of `ws` finished, by its manifest.
std::map<std::string, std::string> FinishedTimes(const fs::path& ws) {
  std::map<std::string, std::string> finished;
  for (const auto& entry : fs::directory_iterator(ws)) {
    if (fs::exists(entry.path() / "manifest.json")) {
      finished[entry.path().filename().string()] = ReadJsonFile(entry.path() / "manifest.json")["finished_utc"];
    }
  }
  return finished;
}

TEST_CASE("photo2nerf run: photos to report with real COLMAP, then everything fresh", "[e2e][colmap]") {
  if (std::system("colmap help > /dev/null 2>&1") != 0) {
    WARN("COLMAP is not installed (scripts/install_deps.sh installs it): skipping the end-to-end test");
    return;
  }
  TempDir dir;
  SyntheticSceneOptions scene;  // 24 views of 320 x 240
  WriteSyntheticScene(scene, dir / "photos");
  OIIO::ImageBuf blank(OIIO::ImageSpec(320, 240, 3, OIIO::TypeDesc::UINT8));  // a photo of nothing: left out
  OIIO::ImageBufAlgo::fill(blank, {0.5f, 0.5f, 0.5f});
  REQUIRE(blank.write((dir / "photos" / "zz_blank.png").string()));
  const std::vector<std::string> command = RunCommandLine(dir / "photos", dir / "ws");
  std::string output;
  REQUIRE(RunCommand(command, &output) == 0);
  INFO(output);
  const std::vector<std::string> stages = {"ingest", "sfm", "poses", "train", "splat", "render", "export", "report"};
  CHECK_THAT(output, Catch::Contains("8 of 8 stages ran"));

  const nlohmann::json eval = ReadJsonFile(dir / "ws" / "40_render" / "eval.json");
  CHECK(eval["views"].size() == 3);  // every 8th of 24
  CHECK(eval["psnr"].get<double>() > 18.0);
  CHECK(fs::file_size(dir / "ws" / "40_render" / "video.mp4") > 1000);

  CheckMesh(dir / "ws" / "50_export" / "mesh.ply");

  const nlohmann::json splats = ReadJsonFile(dir / "ws" / "35_splat" / "splat_report.json");
  CHECK(splats["heldout_psnr"].get<double>() > 15.0);  // 60 steps from a field of 200: a working stage, not a score
  CHECK(ReadSplatPly(dir / "ws" / "35_splat" / "splats.ply").size() == splats["splats"].get<size_t>());

  const std::string report = ReadText(dir / "ws" / "60_report" / "report.html");
  for (const std::string& stage : stages) {
    if (stage != "report") CHECK_THAT(report, Catch::Contains("<td>" + stage + "</td>"));  // the stages before it
  }
  const std::map<std::string, std::string> finished = FinishedTimes(dir / "ws");
  CHECK(finished.size() == 8);
  CHECK_THAT(report, Catch::Contains("COLMAP 3.") && Catch::Contains("24 of 25 images registered"));
  CHECK_THAT(report, Catch::Contains("Photos left out of the model: 1.") &&
                         Catch::Contains("<td>zz_blank.png</td><td>no_features</td>"));

  // Again: nothing to do, nothing rewritten.
  REQUIRE(RunCommand(command, &output) == 0);
  CHECK_THAT(output, Catch::Contains("0 of 8 stages ran"));
  for (const std::string& stage : stages) CHECK_THAT(output, Catch::Contains(stage + ": fresh, skipped"));
  for (const auto& [folder, time] : finished)
    CHECK(ReadJsonFile(dir / "ws" / folder / "manifest.json")["finished_utc"] == time);
}

}  // namespace p2n::testing

// The photo2nerf program: exit codes and messages of the error cases, help, and a real run.

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <catch2/catch.hpp>

#include "base/file_util.h"
#include "base/format.h"
#include "formats/colmap_model.h"
#include "pipeline/workspace.h"
#include "tests/test_util.h"

namespace p2n::testing {
namespace fs = std::filesystem;
namespace {

struct Result {
  int code;
  std::string output;
};

Result Photo2Nerf(std::vector<std::string> args) {
  args.insert(args.begin(), P2N_BINARY);
  Result result;
  result.code = RunCommand(args, &result.output);
  return result;
}

void MakePhotos(const fs::path& folder, int count) {
  fs::create_directories(folder);
  for (int i = 0; i < count; ++i) {
    OIIO::ImageBuf image(OIIO::ImageSpec(24, 16, 3, OIIO::TypeDesc::UINT8));
    OIIO::ImageBufAlgo::fill(image, {0.1f * i, 0.5f, 0.9f});
    REQUIRE(image.write((folder / ("photo " + std::to_string(i) + ".png")).string()));
  }
}

}  // namespace

TEST_CASE("cli: help, version and unknown commands", "[cli]") {
  CHECK(Photo2Nerf({"--version"}).code == 0);
  const Result usage = Photo2Nerf({});
  CHECK(usage.code == 1);
  CHECK_THAT(usage.output, Catch::Contains("run") && Catch::Contains("status") && Catch::Contains("ingest"));
  const Result unknown = Photo2Nerf({"trian"});
  CHECK(unknown.code == 1);
  CHECK_THAT(unknown.output, Catch::Contains("unknown command 'trian'") && Catch::Contains("run, status, clean"));
  const Result help = Photo2Nerf({"run", "--help"});
  CHECK(help.code == 0);
  CHECK_THAT(help.output,
             Catch::Contains("--ingest.max_image_size") && Catch::Contains("[px]") && Catch::Contains("--force"));
}

TEST_CASE("cli: a run, a fresh rerun, status and clean", "[cli]") {
  TempDir dir;
  MakePhotos(dir / "photos", 3);
  const std::string ws = (dir / "ws").string();
  Result first = Photo2Nerf({"run", (dir / "photos").string(), "-w", ws, "--until", "ingest"});
  REQUIRE(first.code == 0);
  CHECK_THAT(first.output, Catch::Contains("ingest: 3 images, 0 skipped"));
  Result second = Photo2Nerf({"run", "-w", ws, "--until", "ingest"});
  CHECK(second.code == 0);
  CHECK_THAT(second.output, Catch::Contains("ingest: fresh, skipped"));
  // An option given once is remembered; the stage command reruns the stage with it.
  CHECK(Photo2Nerf({"ingest", "-w", ws, "--ingest.max_image_size", "16"}).code == 0);
  CHECK_THAT(Photo2Nerf({"status", "-w", ws}).output,
             Catch::Contains("fresh") && Catch::Contains("options   ingest.max_image_size 16 (remembered"));
  Result status = Photo2Nerf({"status", "-w", ws, "--ingest.max_image_size", "20"});
  CHECK_THAT(status.output,
             Catch::Contains("stale") && Catch::Contains("option ingest.max_image_size changed (16 -> 20)"));
  // An option given twice: the last value wins (as with most tools).
  Result twice = Photo2Nerf({"status", "-w", ws, "--ingest.max_image_size", "30", "--ingest.max_image_size", "20"});
  CHECK_THAT(twice.output, Catch::Contains("(16 -> 20)"));
  CHECK(Photo2Nerf({"clean", "-w", ws}).code == 0);
  CHECK_THAT(Photo2Nerf({"status", "-w", ws}).output, Catch::Contains("missing"));
  CHECK(fs::exists(dir / "photos" / "photo 0.png"));
  CHECK(fs::exists(fs::path(ws) / "logs" / "photo2nerf.log"));
}

TEST_CASE(
    "cli: an option the workspace remembers that this version does not take or whose rule it breaks is left out, with "
    "a warning",
    "[cli]") {
  TempDir dir;
  MakePhotos(dir / "photos", 3);
  const std::string ws = (dir / "ws").string();
  REQUIRE(Photo2Nerf({"run", (dir / "photos").string(), "-w", ws, "--until", "ingest", "--ingest.max_image_size", "16"})
              .code == 0);
  // What a workspace made by another version may remember: an option since removed, a choice no longer offered.
  const fs::path options = fs::path(ws) / "options.json";
  nlohmann::json remembered = ReadJsonFile(options);
  remembered["train"]["no_such_option"] = 3;
  remembered["sfm"]["matcher"] = "telepathy";
  remembered["train"]["steps"] = -5;  // a rule since changed
  WriteText(options, remembered.dump());
  const Result status = Photo2Nerf({"status", "-w", ws});
  INFO(status.output);
  CHECK(status.code == 0);
  CHECK_THAT(status.output, Catch::Contains("'train.no_such_option'") && Catch::Contains("'telepathy'") &&
                                Catch::Contains("left out"));
  CHECK_THAT(status.output, Catch::Contains(format("option train.steps (from {}) must be", options.string())) &&
                                !Catch::Contains("train.steps -5"));
  CHECK_THAT(status.output, Catch::Contains("options   ingest.max_image_size 16 (remembered") &&
                                !Catch::Contains("matcher telepathy"));
  const Result rerun = Photo2Nerf({"run", "-w", ws, "--until", "ingest"});
  CHECK(rerun.code == 0);
  CHECK_THAT(rerun.output, Catch::Contains("ingest: fresh, skipped"));
  CHECK(ReadJsonFile(options) == nlohmann::json{{"ingest", {{"max_image_size", 16}}}});
}

TEST_CASE("cli: user errors exit 1 with a message naming what is wrong", "[cli]") {
  TempDir dir;
  MakePhotos(dir / "photos", 3);
  const std::string photos = (dir / "photos").string();
  const std::string ws = (dir / "ws").string();

  auto expect = [](const Result& result, const std::string& text) {
    INFO(result.output);
    CHECK(result.code == 1);
    CHECK_THAT(result.output, Catch::Contains(text));
  };
  expect(Photo2Nerf({"run", (dir / "missing").string(), "-w", ws}), "does not exist");
  CHECK_FALSE(fs::exists(ws));
  WriteText(dir / "file.txt", "x");
  expect(Photo2Nerf({"run", (dir / "file.txt").string(), "-w", ws}), "is a file, not a folder or a video");
  fs::create_directories(dir / "empty");
  expect(Photo2Nerf({"run", (dir / "empty").string(), "-w", ws}), "no photos or videos in");
  expect(Photo2Nerf({"run", photos, "-w", (dir / "file.txt" / "ws").string()}), "cannot create the workspace");
  fs::create_directories(dir / "mine");
  WriteText(dir / "mine" / "thesis.tex", "precious");
  expect(Photo2Nerf({"run", photos, "-w", (dir / "mine").string()}), "is not empty and is not a photo2nerf workspace");
  CHECK(ReadText(dir / "mine" / "thesis.tex") == "precious");
  CHECK(fs::directory_iterator(dir / "mine") != fs::directory_iterator());
  expect(Photo2Nerf({"run", photos, "-w", ws, "--ingest.max_image_siz", "100"}),
         "unknown option '--ingest.max_image_siz'; did you mean '--ingest.max_image_size'?");
  expect(Photo2Nerf({"run", photos, "-w", ws, "--ingest.max_image_size", "big"}), "must be an integer");
  expect(Photo2Nerf({"run", photos, "-w", ws, "--ingest.max_image_size", "-3"}),
         "option ingest.max_image_size (from --ingest.max_image_size) must be");
  WriteText(dir / "config.json", R"({"ingest": {"max_image_size": -3}})");
  expect(Photo2Nerf({"run", photos, "-w", ws, "--config", (dir / "config.json").string()}),
         format("option ingest.max_image_size (from {}) must be", (dir / "config.json").string()));
  WriteText(dir / "config.json", R"({"ingest": {"max_size": 3}})");
  expect(Photo2Nerf({"run", photos, "-w", ws, "--config", (dir / "config.json").string()}),
         "unknown option 'ingest.max_size'");
  expect(Photo2Nerf({"run", photos, "-w", ws, "--from", "trian"}), "unknown stage 'trian'");
  expect(Photo2Nerf({"status", "-w", (dir / "nowhere").string()}), "is not a photo2nerf workspace");
  expect(Photo2Nerf({"run", "-w", (dir / "nowhere").string()}), "is not a photo2nerf workspace");
  {
    const Workspace workspace = Workspace::Open(ws, true);
    WorkspaceLock lock(workspace, "a test holding the lock");
    expect(Photo2Nerf({"run", photos, "-w", ws}), "is in use by process");
  }
  MakePhotos(dir / "two", 2);
  expect(Photo2Nerf({"run", (dir / "two").string(), "-w", (dir / "ws2").string()}), "only 2 usable images");
}

}  // namespace p2n::testing

namespace p2n::testing {

TEST_CASE("cli: fit-image writes the reconstruction, the curve, the plot and the snapshots", "[cli][fit]") {
  TempDir dir;
  MakePhotos(dir / "in", 1);
  const std::string image = (dir / "in" / "photo 0.png").string();
  const std::string out = (dir / "out").string();
  const Result fit = Photo2Nerf({"fit-image", image, "-o", out, "--fit.model", "hashgrid", "--fit.max_steps", "30",
                                 "--fit.time_budget", "0", "--fit.snapshot_steps", "1,10"});
  INFO(fit.output);
  REQUIRE(fit.code == 0);
  for (const char* file : {"reconstruction.png", "psnr.png", "snapshots.png", "snapshot_step_000001.png",
                           "snapshot_step_000010.png", "fit_report.json", "config.json", "fit.log"}) {
    CHECK(fs::exists(fs::path(out) / file));
  }
  const std::string csv = ReadText(fs::path(out) / "metrics.csv");
  CHECK(csv.rfind("wall_seconds,step,psnr\n", 0) == 0);
  CHECK_THAT(csv, Catch::Contains(",30,"));
  CHECK_THAT(ReadText(fs::path(out) / "fit_report.json"), Catch::Contains("\"steps\": 30"));
  // The same folder can take another fit (it holds fit-image results).
  CHECK(
      Photo2Nerf({"fit-image", image, "-o", out, "--fit.max_steps", "2", "--fit.time_budget", "0", "--fit.width", "8"})
          .code == 0);

  const std::string sweep = (dir / "sweep").string();
  const Result swept = Photo2Nerf({"fit-image", image, "-o", sweep, "--sweep", "--fit.max_steps", "3",
                                   "--fit.time_budget", "0", "--fit.width", "8"});
  INFO(swept.output);
  REQUIRE(swept.code == 0);
  const std::string table = ReadText(fs::path(sweep) / "sweep.csv");
  CHECK(std::count(table.begin(), table.end(), '\n') == 9);  // header + 2 x 2 x 2 runs
  CHECK(fs::exists(fs::path(sweep) / "sweep.png"));
}

TEST_CASE("cli: fit-image refuses bad input with a clear error", "[cli][fit]") {
  TempDir dir;
  MakePhotos(dir / "in", 1);
  const std::string image = (dir / "in" / "photo 0.png").string();
  auto expect = [](const Result& result, const std::string& text) {
    INFO(result.output);
    CHECK(result.code == 1);
    CHECK_THAT(result.output, Catch::Contains(text));
  };
  WriteText(dir / "notes.png", "text");
  expect(Photo2Nerf({"fit-image", (dir / "notes.png").string(), "-o", (dir / "o1").string()}), "notes.png");
  expect(Photo2Nerf({"fit-image", (dir / "missing.png").string(), "-o", (dir / "o2").string()}), "missing.png");
  expect(Photo2Nerf({"fit-image", image, "-o", (dir / "o3").string(), "--fit.batch_size", "0"}),
         "fit.batch_size must be in 1..16777216, not 0");
  expect(Photo2Nerf({"fit-image", image, "-o", (dir / "o4").string(), "--fit.model", "siren"}),
         "option 'fit.model' (from --fit.model) must be one of: pe, hashgrid");
  expect(Photo2Nerf({"fit-image", image, "-o", (dir / "in").string()}), "is not empty");
  CHECK(fs::exists(dir / "in" / "photo 0.png"));
}

}  // namespace p2n::testing

namespace p2n::testing {

TEST_CASE("cli: a missing, crashing or failing COLMAP gives a clear error and the right exit code", "[cli][sfm]") {
  TempDir dir;
  MakePhotos(dir / "photos", 3);
  const std::string photos = (dir / "photos").string();
  // A stand-in for COLMAP: prints 3.8's banner, then behaves as the test needs.
  const auto fake_colmap = [&](const std::string& name, const std::string& behaviour) {
    const fs::path path = dir / name;
    WriteText(path, "#!/bin/sh\nif [ \"$1\" = help ]; then echo 'COLMAP 3.8 -- Structure-from-Motion'; exit 0; fi\n" +
                        behaviour + "\n");
    fs::permissions(path, fs::perms::owner_all);
    return path.string();
  };

  Result missing = Photo2Nerf({"run", photos, "-w", (dir / "ws1").string(), "--colmap", (dir / "no_colmap").string()});
  INFO(missing.output);
  CHECK(missing.code == 2);
  CHECK_THAT(missing.output, Catch::Contains("cannot start") && Catch::Contains("no_colmap"));

  Result killed =
      Photo2Nerf({"run", photos, "-w", (dir / "ws2").string(), "--colmap", fake_colmap("crashing", "kill -9 $$")});
  INFO(killed.output);
  CHECK(killed.code == 2);
  CHECK_THAT(killed.output,
             Catch::Contains("feature extraction was killed by signal 9") && Catch::Contains("feature_extraction.log"));

  const std::string no_pair = fake_colmap(
      "no_pair", "if [ \"$1\" = mapper ]; then echo 'No good initial image pair found.'; exit 1; fi\nexit 0");
  Result advice = Photo2Nerf({"run", photos, "-w", (dir / "ws3").string(), "--colmap", no_pair});
  INFO(advice.output);
  CHECK(advice.code == 1);
  CHECK_THAT(advice.output, Catch::Contains("no pair of photos to start the reconstruction from") &&
                                Catch::Contains("--sfm.matcher exhaustive"));
  // The failed stage is incomplete, never fresh.
  CHECK_THAT(Photo2Nerf({"status", "-w", (dir / "ws3").string(), "--colmap", no_pair}).output,
             Catch::Contains("incomplete"));

  // A mapper that registers 1 photo of 3 (it copies a prepared model to --output_path/0).
  ColmapModel model;
  model.cameras[1] = {1, "PINHOLE", 24, 16, {20, 20, 12, 8}};
  ColmapImage image;
  image.id = 1;
  image.camera_id = 1;
  image.name = "photo 1.png";
  model.images[1] = image;
  WriteColmapModelBinary(model, dir / "prepared" / "0");
  const std::string partial = fake_colmap(
      "partial", "if [ \"$1\" = mapper ]; then while [ $# -gt 0 ]; do if [ \"$1\" = --output_path ]; then cp -r '" +
                     (dir / "prepared" / "0").string() + "' \"$2\"/0; fi; shift; done; fi\nexit 0");
  Result few = Photo2Nerf(
      {"run", photos, "-w", (dir / "ws4").string(), "--colmap", partial, "--sfm.refine_principal_point", "false"});
  INFO(few.output);
  CHECK(few.code == 1);
  CHECK_THAT(few.output, Catch::Contains("registered only 1 of 3 photos") &&
                             Catch::Contains("photo 0.png (unknown), photo 2.png (unknown)") &&
                             Catch::Contains("--sfm.matcher exhaustive"));
  const nlohmann::json report = ReadJsonFile(dir / "ws4" / "10_sfm.partial" / "sfm_report.json");
  // The fake COLMAP wrote no database: why they were left out is unknown, and the report says so.
  REQUIRE(report["left_out"].size() == 2);
  CHECK(report["left_out"][0]["image"] == "photo 0.png");
  CHECK(report["left_out"][1]["reason"] == "unknown");
  CHECK_THAT(report["left_out"][1]["detail"].get<std::string>(), Catch::Contains("database"));
}

}  // namespace p2n::testing

// The report stage: one self-contained page (nothing fetched from a network) with every section, opened in
// a real browser (Debian's Chromium, headless): its script draws the cameras, and a screenshot shows the plot
// and the images. The screenshot is kept in the build folder (test_output/report_screenshot.png).

#include <catch2/catch.hpp>

#include <OpenImageIO/imagebuf.h>

#include <cmath>
#include <regex>

#include "base/file_util.h"
#include "base/format.h"
#include "stage_fixtures.h"

namespace p2n::testing {
namespace fs = std::filesystem;
namespace {

size_t Count(const std::string& text, const std::string& what) {
  size_t count = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++count;
  return count;
}

// Pixels of the screenshot within 40 (per channel) of an RGB colour.
size_t PixelsNear(const std::vector<uint8_t>& rgb, int r, int g, int b) {
  size_t count = 0;
  for (size_t i = 0; i + 2 < rgb.size(); i += 3) {
    count += std::abs(rgb[i] - r) < 40 && std::abs(rgb[i + 1] - g) < 40 && std::abs(rgb[i + 2] - b) < 40;
  }
  return count;
}

std::string Chromium() {
  for (const char* candidate : {"/usr/bin/chromium", "/usr/bin/chromium-browser", "/usr/bin/google-chrome"}) {
    if (fs::exists(candidate)) return candidate;
  }
  return "";
}

}  // namespace

TEST_CASE("report stage: a self-contained page with every section, drawn by headless Chromium", "[report]") {
  StageWorkspace setup;
  Config config = SmallStageConfig(60);
  setup.runner.Run(setup.workspace, config, {});
  const fs::path page = setup.dir / "ws" / "60_report" / "report.html";
  const std::string html = ReadText(page);

  CHECK_THAT(html, Catch::Contains("held-out PSNR against training time") && Catch::Contains("<svg"));
  CHECK_THAT(html, Catch::Contains("training loss against training time"));
  CHECK_THAT(html, Catch::Contains("splats: held-out PSNR against optimisation time") &&
                       Catch::Contains("href=\"../35_splat/splats.ply\"") &&
                       Catch::Contains("href=\"../35_splat/splats.spz\"") &&
                       Catch::Contains("href=\"../35_splat/viewer.html\""));
  for (const char* stage : {"poses", "train", "splat", "render", "export"})
    CHECK_THAT(html, Catch::Contains(format("<td>{}</td>", stage)));
  CHECK(Count(html, "data:image/jpeg;base64,") >= 6);  // 2 held-out views: photo, render, error map
  CHECK(Count(html, "data:video/mp4;base64,") == 1);
  CHECK_THAT(html, Catch::Contains("12 cameras in the normalised frame"));
  // Photos without alpha: the page shows the colour the field learnt behind the scene.
  const nlohmann::json background =
      ReadJsonFile(setup.dir / "ws" / "30_train" / "train_report.json")["trainer"]["background_colour"];
  CHECK_THAT(html, Catch::Contains("was learnt with the field") &&
                       Catch::Contains(format("({:.2f}, {:.2f}, {:.2f})", background[0].get<double>(),
                                              background[1].get<double>(), background[2].get<double>())));
  CHECK_THAT(html, Catch::Contains("mesh.ply"));
  const nlohmann::json throughput = ReadJsonFile(setup.dir / "ws" / "30_train" / "train_report.json")["throughput"];
  CHECK_THAT(html, Catch::Contains(format("{:.3g} samples per ray.", throughput["samples_per_ray"].get<double>())));
  // Self-contained: nothing is loaded from elsewhere.
  CHECK_FALSE(std::regex_search(html, std::regex(R"((src|href)\s*=\s*"(https?:)?//)")));
  CHECK(setup.Status(config, "report").state == StageState::kFresh);

  const std::string chromium = Chromium();
  INFO("Chromium is needed for this test: bash scripts/install_deps.sh installs it");
  REQUIRE_FALSE(chromium.empty());
  const std::vector<std::string> browser = {
      chromium,        "--headless",        "--no-sandbox",
      "--disable-gpu", "--hide-scrollbars", "--user-data-dir=" + (setup.dir / "chromium").string()};
  std::string dom;
  std::vector<std::string> dump = browser;
  dump.insert(dump.end(), {"--virtual-time-budget=3000", "--dump-dom", "file://" + page.string()});
  REQUIRE(RunCommand(dump, &dom) == 0);
  CHECK_THAT(dom, Catch::Contains("data-drawn=\"12 cameras,"));  // the viewer's script ran

  const fs::path screenshot = fs::path(P2N_TEST_OUTPUT_DIR) / "report_screenshot.png";
  fs::create_directories(screenshot.parent_path());
  fs::remove(screenshot);
  std::vector<std::string> shot = browser;
  shot.insert(shot.end(),
              {"--window-size=1280,3600", "--screenshot=" + screenshot.string(), "file://" + page.string()});
  std::string output;
  REQUIRE(RunCommand(shot, &output) == 0);
  OIIO::ImageBuf image(screenshot.string());
  REQUIRE(image.read());
  CHECK(image.spec().width == 1280);
  std::vector<uint8_t> rgb(size_t(image.spec().width) * image.spec().height * 3);
  REQUIRE(image.get_pixels(OIIO::ROI(0, image.spec().width, 0, image.spec().height, 0, 1, 0, 3), OIIO::TypeDesc::UINT8,
                           rgb.data()));
  CHECK(PixelsNear(rgb, 0x1f, 0x77, 0xb4) > 300);  // the PSNR curve
  CHECK(PixelsNear(rgb, 0x1f, 0x5f, 0xbf) > 100);  // training cameras in the 3D view
  CHECK(PixelsNear(rgb, 0xe0, 0x70, 0x00) > 20);   // held-out cameras

  // Rendered at another spacing than the training's evaluation, whose PSNR the page also shows: it says so.
  CHECK_THAT(html, !Catch::Contains("times its training step"));
  config.Set("render.step_scale", 0.25, "test");
  setup.runner.Run(setup.workspace, config, {});
  CHECK(ReadJsonFile(setup.dir / "ws" / "40_render" / "eval.json")["step_scale"] == 0.25);
  CHECK_THAT(ReadText(page), Catch::Contains("sampled at 0.25 times its training step"));
}

TEST_CASE("report stage: a render drawn from the splats (no samples per ray) is reported as such", "[report]") {
  StageWorkspace setup;
  Config config = SmallStageConfig(60);
  config.Set("render.source", "splats", "test");
  setup.runner.Run(setup.workspace, config, {});
  const std::string html = ReadText(setup.dir / "ws" / "60_report" / "report.html");
  CHECK_THAT(html, Catch::Contains("frames per second (from the splats)"));
  CHECK_THAT(html, !Catch::Contains("samples per ray)"));
}

}  // namespace p2n::testing

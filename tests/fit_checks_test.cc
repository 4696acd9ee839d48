// A product that notices a failed fit: the held-out views chosen inside the cameras' span, a plain background
// recognised, and the signs of a failed fit found in constructed failures and not in good results.

#include <catch2/catch.hpp>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>

#include "formats/camera_geometry.h"
#include "formats/transforms_json.h"
#include "stages/fitting/fit_checks.h"
#include "stages/ingest/plain_background.h"
#include "test_camera.h"

namespace p2n::testing {
namespace {

// Cameras on an arc of `degrees` around the origin, in order, each looking at it.
std::vector<CameraView> Arc(int count, double degrees) {
  std::vector<CameraView> views(count);
  for (int i = 0; i < count; ++i) {
    const double a = (i * degrees / (count - 1) - degrees / 2) * M_PI / 180;
    views[i].camera = CentredCamera(40, 30, 50);
    views[i].camera.world_from_cam = LookAtPose({3 * std::sin(a), 0.5, 3 * std::cos(a)}, {0, 0, 0});
  }
  return views;
}

Eigen::Vector3d Centre(const CameraView& view) { return view.camera.world_from_cam.topRightCorner<3, 1>(); }

std::vector<size_t> Heldout(const std::vector<CameraView>& views) {
  std::vector<size_t> heldout;
  for (size_t i = 0; i < views.size(); ++i) {
    if (views[i].split == ViewSplit::kVal) heldout.push_back(i);
  }
  return heldout;
}

bool HasCode(const std::vector<FitWarning>& warnings, const std::string& code) {
  return std::any_of(warnings.begin(), warnings.end(), [&](const FitWarning& w) { return w.code == code; });
}

// A good bounded field's figures: nothing to warn about.
FieldFit GoodFit() {
  FieldFit fit;
  fit.heldout_psnr = 30.5;
  fit.training_psnr = 31.4;
  fit.views = {{"r_0", 30.1, false}, {"r_8", 31.0, false}, {"r_16", 29.4, false}};
  fit.background_learnt = true;
  fit.background = {0.98, 0.97, 0.99};
  fit.behind_colour = std::array<double, 3>{1, 1, 1};
  fit.bounded = true;
  fit.occupied_fraction = 0.04;
  fit.samples_per_ray = 4.4;
  return fit;
}

}  // namespace

TEST_CASE("camera span: the ends of an arc lie outside the others' span, its middle inside", "[fit]") {
  const std::vector<CameraView> arc = Arc(11, 120);
  const auto others = [&](size_t left_out) {
    std::vector<Eigen::Vector3d> centres;
    for (size_t i = 0; i < arc.size(); ++i) {
      if (i != left_out) centres.push_back(Centre(arc[i]));
    }
    return centres;
  };
  CHECK(OutsideSpan(others(0), Centre(arc[0])));
  CHECK(OutsideSpan(others(10), Centre(arc[10])));
  for (size_t i = 1; i < 10; ++i) CHECK_FALSE(OutsideSpan(others(i), Centre(arc[i])));
  // Off the arc's plane by a unit (a third of its radius): outside; fewer than two cameras span nothing.
  CHECK(OutsideSpan(others(5), Centre(arc[5]) + Eigen::Vector3d(0, 1, 0)));
  CHECK_FALSE(OutsideSpan({Centre(arc[0])}, Centre(arc[5])));
}

TEST_CASE("held-out views: inside the span for fewer than 20 photos, every 8th from the first otherwise", "[fit]") {
  SECTION("11 photos on an arc: two, neither at an end, each inside the span of the training cameras") {
    std::vector<CameraView> views = Arc(11, 120);
    const std::string rule = AssignHoldout(&views, 8, true);
    CHECK_THAT(rule, Catch::Contains("2 of 11 views"));
    const std::vector<size_t> heldout = Heldout(views);
    REQUIRE(heldout.size() == 2);
    std::vector<Eigen::Vector3d> training;
    for (const CameraView& view : views) {
      if (view.split == ViewSplit::kTrain) training.push_back(Centre(view));
    }
    for (const size_t i : heldout) {
      CHECK(i != 0);
      CHECK(i != 10);
      CHECK_FALSE(OutsideSpan(training, Centre(views[i])));
    }
  }
  SECTION("the NeRF protocol where asked (LLFF data) and for 20 photos or more") {
    std::vector<CameraView> few = Arc(11, 120), many = Arc(25, 120);
    CHECK(AssignHoldout(&few, 8, false) == "every 8th view from the first");
    CHECK(Heldout(few) == std::vector<size_t>{0, 8});
    AssignHoldout(&many, 8, true);
    CHECK(Heldout(many) == std::vector<size_t>{0, 8, 16, 24});
  }
  SECTION("a dataset's own split stays; none held out with 0") {
    std::vector<CameraView> views = Arc(11, 120);
    views[4].split = ViewSplit::kTest;
    CHECK(AssignHoldout(&views, 0, true).empty());
    CHECK(Heldout(views).empty());
    CHECK(views[4].split == ViewSplit::kTest);
  }
}

TEST_CASE("plain background: one colour along every border is found, a photo's border is not one", "[fit]") {
  OIIO::ImageBuf white(OIIO::ImageSpec(40, 30, 3, OIIO::TypeDesc::UINT8));
  OIIO::ImageBufAlgo::fill(white, {1.0f, 1.0f, 1.0f});
  OIIO::ImageBufAlgo::fill(white, {0.2f, 0.5f, 0.1f}, OIIO::ROI(10, 30, 8, 22));  // an object in the middle
  const std::vector<Rgb> border = BorderPixels(white);
  CHECK(border.size() == 2 * 2 * 40 + 2 * 2 * 26);  // two rows top and bottom, two columns on the rows between
  const std::optional<Rgb> colour = SharedColour(border);
  REQUIRE(colour);
  CHECK((*colour)[0] == Approx(1.0f));
  CHECK((*colour)[1] == Approx(1.0f));
  // A gradient (a sky, a wall in light) is no plain colour.
  OIIO::ImageBuf sky(OIIO::ImageSpec(40, 30, 3, OIIO::TypeDesc::FLOAT));
  OIIO::ImageBufAlgo::fill(sky, {0.3f, 0.5f, 0.9f}, {0.3f, 0.5f, 0.9f}, {0.6f, 0.6f, 0.5f}, {0.6f, 0.6f, 0.5f});
  CHECK_FALSE(SharedColour(BorderPixels(sky)));
  CHECK_FALSE(SharedColour({}));
}

TEST_CASE("fit checks: silent on a good field, each sign of a failed fit found and explained", "[fit]") {
  CHECK(CheckFieldFit(GoodFit()).empty());
  SECTION("held-out views far below the training photos (wrong cameras)") {
    FieldFit fit = GoodFit();
    fit.heldout_psnr = 18.2;
    const std::vector<FitWarning> warnings = CheckFieldFit(fit);
    REQUIRE(HasCode(warnings, "heldout_below_training"));
    CHECK(warnings.front().figure == Approx(31.4 - 18.2));
    CHECK_THAT(warnings.front().message, Catch::Contains("sfm_report.json"));
  }
  SECTION("one held-out view far below the others: named, and whether it is an extrapolation") {
    FieldFit fit = GoodFit();
    fit.views[1] = {"r_8", 23.0, true};  // 6.75 dB below: views differ that much in a good fit
    CHECK(CheckFieldFit(fit).empty());
    fit.views[1].psnr = 21.0;
    const std::vector<FitWarning> warnings = CheckFieldFit(fit);
    REQUIRE(warnings.size() == 1);
    CHECK(warnings[0].code == "heldout_view_low");
    CHECK_THAT(warnings[0].message, Catch::Contains("r_8") && Catch::Contains("outside the span"));
    fit.views[1].outside_span = false;
    CHECK_THAT(CheckFieldFit(fit)[0].message, Catch::Contains("among the training cameras"));
  }
  SECTION("a learnt background that ran away from what the photos show behind the scene") {
    FieldFit fit = GoodFit();
    fit.background = {0.50, 0.56, 0.29};  // issue 52's object scene
    const std::vector<FitWarning> warnings = CheckFieldFit(fit);
    REQUIRE(HasCode(warnings, "background_off"));
    CHECK(warnings.front().figure == Approx(0.71));
    // A fixed one is the images' by construction, and where no ray ends on nothing there is nothing to compare.
    fit.background_learnt = false;
    CHECK(CheckFieldFit(fit).empty());
    fit.background_learnt = true;
    fit.behind_colour.reset();
    CHECK(CheckFieldFit(fit).empty());
  }
  SECTION("fog in an object's box: mostly occupied, or many samples a ray; unbounded scenes are not judged so") {
    FieldFit fit = GoodFit();
    fit.occupied_fraction = 0.41;
    CHECK(HasCode(CheckFieldFit(fit), "fog"));
    fit.occupied_fraction = 0.04;
    fit.samples_per_ray = 98;
    CHECK(HasCode(CheckFieldFit(fit), "fog"));
    fit.bounded = false;
    CHECK(CheckFieldFit(fit).empty());
  }
  SECTION("splats far below their field, and a splat view far below the others") {
    const std::vector<HeldoutViewFit> views = {{"a", 28, false}, {"b", 29, false}};
    CHECK(CheckSplatFit(views, 28.5, 28.0).empty());
    CHECK(HasCode(CheckSplatFit(views, 24.0, 28.0), "splats_below_field"));
    CHECK(
        HasCode(CheckSplatFit({{"a", 20, false}, {"b", 29, false}, {"c", 28, false}}, 25.7, 25.0), "heldout_view_low"));
    CHECK(CheckSplatFit(views, std::nullopt, 28.0).empty());
  }
}

}  // namespace p2n::testing

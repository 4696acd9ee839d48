// The splat library beyond the rasterizer: the PLY layout, similarity moves, placing Gaussians from surface
// points, and the optimiser (it fits, and a resumed run continues as an uninterrupted one would).

#include <catch2/catch.hpp>

#include <Eigen/Geometry>

#include <array>
#include <cmath>
#include <random>

#include "splat/blocks.h"
#include "splat/field_init.h"
#include "splat/rasterizer.h"
#include "splat/similarity.h"
#include "splat/splat_ply.h"
#include "splat/splat_trainer.h"
#include "splat/ssim_loss.h"
#include "tests/test_util.h"

namespace p2n::testing {
namespace {

PinholeCamera CameraAt(const Eigen::Vector3d& position, int size = 32,
                       const Eigen::Vector3d& target = Eigen::Vector3d::Zero()) {
  PinholeCamera camera;
  camera.width = camera.height = size;
  camera.fx = camera.fy = size;
  camera.cx = camera.cy = size / 2.0;
  camera.world_from_cam = LookAtPose(position, target);
  return camera;
}

Gaussians<float> RandomSplats(int count, int degree, uint64_t seed) {
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<float> uniform(-1, 1);
  Gaussians<float> g;
  g.sh_degree = degree;
  g.Resize(count);
  for (int i = 0; i < count; ++i) {
    for (int a = 0; a < 3; ++a) g.positions[3 * i + a] = 0.4f * uniform(random);
    for (int a = 0; a < 3; ++a) g.log_scales[3 * i + a] = std::log(0.12f) + 0.3f * uniform(random);
    for (int a = 0; a < 4; ++a) g.rotations[4 * i + a] = uniform(random) + (a == 0 ? 1.5f : 0.0f);
    g.opacity_logits[i] = uniform(random);
    for (int c = 0; c < 3; ++c) g.sh_dc[3 * i + c] = 1.5f * uniform(random);
  }
  return g;
}

// Views `size` pixels square of `centre` from a ring of cameras around it, their pixels rendered from `truth` over
// `background`.
std::vector<TrainView> ViewsOf(const Gaussians<float>& truth, int count,
                               const std::array<float, 3>& background = {1, 1, 1},
                               const Eigen::Vector3d& centre = Eigen::Vector3d::Zero(), int size = 32) {
  std::vector<TrainView> views;
  for (int v = 0; v < count; ++v) {
    const double angle = 2 * M_PI * v / count;
    TrainView view;
    view.camera = CameraAt(centre + Eigen::Vector3d(2.5 * std::cos(angle), 2.5 * std::sin(angle), 0.8), size, centre);
    const FloatImage image = RenderSplats(truth, view.camera, background, 0.01);
    for (const float value : image.pixels)
      view.pixels.push_back(static_cast<uint8_t>(std::lround(255 * std::clamp(value, 0.0f, 1.0f))));
    views.push_back(std::move(view));
  }
  return views;
}

// `truth` with its means moved and its colours changed at random: splats to optimise back towards it.
Gaussians<float> Disturbed(const Gaussians<float>& truth) {
  Gaussians<float> start = truth;
  std::mt19937_64 random(6);
  std::normal_distribution<float> noise(0, 1);
  for (float& v : start.positions) v += 0.05f * noise(random);
  for (float& v : start.sh_dc) v += 1.0f * noise(random);
  return start;
}

// The mean PSNR of `splats` over white in `views`.
double MeanPsnr(const Gaussians<float>& splats, const std::vector<TrainView>& views) {
  double sum = 0;
  for (const TrainView& view : views)
    sum += Psnr(RenderSplats(splats, view.camera, {1, 1, 1}, 0.01), PhotoOnBackground(view, {1, 1, 1}));
  return sum / views.size();
}

}  // namespace

TEST_CASE("Splat PLY files have the standard layout and read back exactly", "[splat]") {
  const Gaussians<float> g = RandomSplats(5, 3, 1);
  const std::vector<char> bytes = SplatPlyBytes(g, {"frame: test"});
  const std::string text(bytes.begin(), bytes.end());
  const std::string header = text.substr(0, text.find("end_header"));
  CHECK(header.find("element vertex 5\n") != std::string::npos);
  CHECK(header.find("property float f_dc_0\nproperty float f_dc_1\nproperty float f_dc_2\nproperty float f_rest_0\n") !=
        std::string::npos);
  CHECK(header.find("property float f_rest_44\nproperty float opacity\nproperty float scale_0\n") != std::string::npos);
  CHECK(header.find("property float rot_3\n") != std::string::npos);
  CHECK(bytes.size() == header.size() + std::string("end_header\n").size() + 5 * 62 * sizeof(float));

  const Gaussians<float> back = ParseSplatPly(text, "test.ply");
  CHECK(back.sh_degree == 3);
  CHECK(back.positions == g.positions);
  CHECK(back.log_scales == g.log_scales);
  CHECK(back.rotations == g.rotations);
  CHECK(back.opacity_logits == g.opacity_logits);
  CHECK(back.sh_dc == g.sh_dc);
  CHECK(back.sh_rest == g.sh_rest);

  // f_rest is channel-major: red's 15 coefficients first.
  Gaussians<float> one = RandomSplats(1, 1, 2);
  one.sh_rest = {1, 2, 3, 4, 5, 6, 7, 8, 9};  // coefficient 1 RGB, 2 RGB, 3 RGB
  const std::vector<char> one_bytes = SplatPlyBytes(one);
  const std::string one_text(one_bytes.begin(), one_bytes.end());
  const size_t body = one_text.find("end_header\n") + 11;
  float rest[9];
  std::memcpy(rest, one_text.data() + body + 9 * sizeof(float), sizeof(rest));
  CHECK(std::vector<float>(rest, rest + 9) == std::vector<float>{1, 4, 7, 2, 5, 8, 3, 6, 9});
}

TEST_CASE("Damaged splat PLY files are refused with the file's name", "[splat]") {
  const std::vector<char> bytes = SplatPlyBytes(RandomSplats(3, 1, 3));
  const std::string text(bytes.begin(), bytes.end());
  CHECK_THROWS_WITH(ParseSplatPly(text.substr(0, text.size() - 4), "cut.ply"),
                    Catch::Contains("cut.ply") && Catch::Contains("shorter"));
  CHECK_THROWS_WITH(ParseSplatPly("ply\nformat ascii 1.0\nend_header\n", "a.ply"), Catch::Contains("little-endian"));
  std::string no_opacity = text;
  no_opacity.replace(no_opacity.find("opacity"), 7, "opacitx");
  CHECK_THROWS_WITH(ParseSplatPly(no_opacity, "b.ply"), Catch::Contains("'opacity'"));
  CHECK_THROWS_WITH(ParseSplatPly("not a ply", "c.ply"), Catch::Contains("c.ply"));
}

TEST_CASE("A similarity moves splats (their view-dependent colour too) and cameras together, the picture the same",
          "[splat]") {
  Gaussians<float> g = RandomSplats(20, 3, 4);
  std::mt19937 random(5);
  std::uniform_real_distribution<float> uniform(-0.6f, 0.6f);
  for (float& c : g.sh_rest) c = uniform(random);  // strongly view-dependent
  const PinholeCamera camera = CameraAt({0.5, 2.0, 1.0}, 48);
  const FloatImage before = RenderSplats(g, camera, {0, 0, 0}, 0.01);
  const Eigen::Matrix3d rotation = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const double scale = 2.5;
  const Eigen::Vector3d shift(1, -2, 0.5);
  ApplySimilarity(scale * rotation, shift, &g);
  PinholeCamera moved = camera;
  moved.world_from_cam.topLeftCorner<3, 3>() = rotation * camera.world_from_cam.topLeftCorner<3, 3>();
  moved.world_from_cam.topRightCorner<3, 1>() = scale * rotation * camera.world_from_cam.topRightCorner<3, 1>() + shift;
  const FloatImage after = RenderSplats(g, moved, {0, 0, 0}, 0.01 * scale);
  CHECK(Psnr(before, after) > 60);
  CHECK_THROWS_AS(ApplySimilarity(-rotation, shift, &g), std::invalid_argument);  // a mirror
}

TEST_CASE("Points on a plane become flat splats along it, as many as asked at most", "[splat]") {
  std::vector<SurfacePoint> points;
  const Eigen::Vector3d normal = Eigen::Vector3d(1, 1, 2).normalized();
  const Eigen::Vector3d u = normal.unitOrthogonal(), v = normal.cross(u);
  for (int i = 0; i < 200; ++i) {
    for (int j = 0; j < 200; ++j) {
      SurfacePoint p;
      p.position = (i / 200.0 - 0.5) * u + (j / 200.0 - 0.5) * v;
      p.rgb = Eigen::Vector3f(0.2f, 0.4f, 0.6f);
      p.normal = normal.cast<float>();
      p.footprint = 1.0 / 200;
      points.push_back(p);
    }
  }
  const Gaussians<float> g = GaussiansFromPoints(points, 1000, 2);
  REQUIRE(g.size() > 100);
  CHECK(g.size() <= 1000);
  CHECK(g.sh_degree == 2);
  for (size_t i = 0; i < g.size(); ++i) {
    const Eigen::Quaterniond q(g.rotations[4 * i], g.rotations[4 * i + 1], g.rotations[4 * i + 2],
                               g.rotations[4 * i + 3]);
    const Eigen::Vector3d thin_axis = q.normalized().toRotationMatrix().col(2);
    CHECK(std::abs(thin_axis.dot(normal)) > 0.999);
    CHECK(g.log_scales[3 * i + 2] < g.log_scales[3 * i] - 2);  // thin across the plane
    const Eigen::Vector3d p(g.positions[3 * i], g.positions[3 * i + 1], g.positions[3 * i + 2]);
    CHECK(std::abs(p.dot(normal)) < 1e-5);
    CHECK(0.5 + kShC0 * g.sh_dc[3 * i + 1] == Approx(0.4).margin(1e-5));
  }
}

TEST_CASE("Sparse points become balls of their neighbours' distance at opacity 0.1, as 3D Gaussian Splatting starts",
          "[splat]") {
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector3f> rgb;
  for (int i = 0; i < 10; ++i) {
    for (int j = 0; j < 10; ++j) {
      for (int k = 0; k < 10; ++k) {
        points.emplace_back(0.1 * i, 0.1 * j, 0.1 * k);  // every point's three nearest are 0.1 away
        rgb.emplace_back(0.1f * i, 0.5f, 0.9f);
      }
    }
  }
  const Gaussians<float> g = GaussiansFromSparsePoints(points, rgb, 100'000, 1);
  // Cells of 2^round(log2 0.1) = 0.125 hold one or two points a side: between 1000 / 8 and 1000 balls.
  REQUIRE(g.size() >= 125);
  CHECK(g.size() <= 1000);
  CHECK(g.sh_degree == 1);
  for (size_t i = 0; i < g.size(); ++i) {
    for (int a = 0; a < 3; ++a) CHECK(std::exp(g.log_scales[3 * i + a]) == Approx(0.0625).epsilon(1e-5));
    CHECK(1 / (1 + std::exp(-g.opacity_logits[i])) == Approx(0.1).epsilon(1e-4));
    CHECK(0.5 + kShC0 * g.sh_dc[3 * i + 2] == Approx(0.9).margin(1e-5));
    const Eigen::Vector3d p(g.positions[3 * i], g.positions[3 * i + 1], g.positions[3 * i + 2]);
    CHECK((p.array() >= -1e-9).all());
    CHECK((p.array() <= 0.9 + 1e-9).all());
  }
  CHECK(GaussiansFromSparsePoints({}, {}, 10, 3).size() == 0);
}

TEST_CASE("Views at half size: each pixel the mean of four, every point where the camera put it, halved", "[splat]") {
  TrainView view;
  view.camera = CameraAt({0.3, -2, 0.5}, 5);  // 5 x 5: the last row and column are dropped
  view.camera.cx = 2.2;                       // off centre
  view.name = "a.png";
  for (int i = 0; i < 5 * 5 * 3; ++i) view.pixels.push_back(static_cast<uint8_t>(i * 3));
  const std::vector<TrainView> half = HalfSizeViews({view});
  REQUIRE(half.size() == 1);
  const TrainView& h = half[0];
  CHECK(h.camera.width == 2);
  CHECK(h.camera.height == 2);
  CHECK(h.name == "a.png");
  REQUIRE(h.pixels.size() == 2 * 2 * 3);
  for (int y = 0; y < 2; ++y) {
    for (int x = 0; x < 2; ++x) {
      for (int c = 0; c < 3; ++c) {
        int sum = 0;
        for (int dy = 0; dy < 2; ++dy) {
          for (int dx = 0; dx < 2; ++dx) sum += view.pixels[((2 * y + dy) * 5 + 2 * x + dx) * 3 + c];
        }
        CHECK(std::abs(h.pixels[(y * 2 + x) * 3 + c] - sum / 4.0) <= 0.5);
      }
    }
  }
  // A view without pixels (not in a photo window): its camera halved alone.
  view.pixels.clear();
  const TrainView empty = HalfSizeView(view);
  CHECK(empty.camera.fx == h.camera.fx);
  CHECK(empty.camera.width == 2);
  CHECK(empty.pixels.empty());
  for (const Eigen::Vector3d& p : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0.2, 0.1, -0.3)}) {
    double z_full = 0, z_half = 0;
    const Eigen::Vector2d full = Project(view.camera, p, &z_full), halved = Project(h.camera, p, &z_half);
    CHECK((halved - full / 2).norm() < 1e-9);  // pixel corners: full pixel 2x..2x+2 is half pixel x..x+1
    CHECK(z_half == Approx(z_full));
  }
}

TEST_CASE("Views fitted to a size: the largest's longest side at the size, each pixel the mean of those it covers",
          "[splat]") {
  TrainView large, small;
  large.camera = CameraAt({0.3, -2, 0.5}, 40);
  large.camera.height = 30;  // not square: both axes scale by the largest's factor
  small.camera = CameraAt({0.3, -2, 0.5}, 20);
  for (TrainView* view : {&large, &small}) {
    for (int y = 0; y < view->camera.height; ++y) {
      for (int x = 0; x < view->camera.width; ++x) {
        for (int c = 0; c < 3; ++c) view->pixels.push_back(static_cast<uint8_t>(3 * x + 2 * y + 20 * c));
      }
    }
  }
  const std::vector<TrainView> both = {large, small};
  CHECK(FitScale(both, 20) == 0.5);  // by half exactly
  const TrainView fitted = FittedView(large, 0.5, large.pixels);
  CHECK(fitted.camera.width == 20);
  CHECK(fitted.camera.height == 15);
  CHECK(FittedView(small, 0.5, small.pixels).camera.width == 10);
  CHECK(fitted.camera.fx == Approx(large.camera.fx / 2));
  CHECK(fitted.camera.cy == Approx(large.camera.cy / 2));
  REQUIRE(fitted.pixels.size() == fitted.PixelBytes());
  for (int y = 0; y < 15; ++y) {
    for (int x = 0; x < 20; ++x) {
      const double mean = 6 * x + 4 * y + 22.5;  // of the four pixels' green values
      CHECK(std::abs(fitted.pixels[(size_t(y) * 20 + x) * 3 + 1] - mean) <= 0.5);
    }
  }
  CHECK(FitScale({large}, 16) == Approx(0.4));
  const TrainView odd = FittedView(large, 0.4, large.pixels);  // 16 x 12
  CHECK(odd.camera.width == 16);
  CHECK(odd.camera.height == 12);
  CHECK(odd.camera.fy == Approx(large.camera.fy * 0.4));
  CHECK(FitScale({large}, 40) == 1);
  CHECK(FitScale({large}, 0) == 1);
  CHECK(FittedView(large, 1, large.pixels).pixels == large.pixels);

  // Without its pixels (a photo read later, as it is fitted): the same camera, no pixels.
  const TrainView camera = FittedView(large, 0.5, {});
  CHECK(camera.camera.width == fitted.camera.width);
  CHECK(camera.camera.fx == fitted.camera.fx);
  CHECK(camera.pixels.empty());
  CHECK_THROWS_AS(FittedView(large, 0.5, small.pixels), std::invalid_argument);  // another photo's pixels
}

TEST_CASE("SSIM of the splats' loss: 1 for the photo itself, its gradient against central differences", "[splat]") {
  constexpr int kWidth = 14, kHeight = 11, kChannels = 3;
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> uniform(0, 1);
  std::vector<double> render(kWidth * kHeight * kChannels), photo(render.size()), gradient(render.size());
  for (size_t i = 0; i < render.size(); ++i) {
    photo[i] = uniform(random);
    render[i] = std::clamp(photo[i] + 0.8 * (uniform(random) - 0.5), 0.0, 1.0);
  }
  SsimLoss ssim;
  std::vector<double> same_gradient(render.size());
  CHECK(ssim(photo.data(), photo.data(), kWidth, kHeight, kChannels, same_gradient.data()) == Approx(1).epsilon(1e-12));
  for (double g : same_gradient) CHECK(std::abs(g) < 1e-12);  // the maximum

  const double value = ssim(render.data(), photo.data(), kWidth, kHeight, kChannels, gradient.data());
  CHECK(value < 0.9);
  constexpr double kStep = 1e-6;
  for (size_t i = 0; i < render.size(); i += 7) {
    std::vector<double> plus = render, minus = render;
    plus[i] += kStep;
    minus[i] -= kStep;
    const double numeric = (ssim(plus.data(), photo.data(), kWidth, kHeight, kChannels, (double*)nullptr) -
                            ssim(minus.data(), photo.data(), kWidth, kHeight, kChannels, (double*)nullptr)) /
                           (2 * kStep);
    INFO("value " << i);
    CHECK(gradient[i] == Approx(numeric).margin(1e-9).epsilon(1e-5));
  }
  // The same in single precision, as the trainer uses it.
  std::vector<float> render_f(render.begin(), render.end()), photo_f(photo.begin(), photo.end());
  std::vector<float> gradient_f(render.size());
  CHECK(ssim(render_f.data(), photo_f.data(), kWidth, kHeight, kChannels, gradient_f.data()) ==
        Approx(value).epsilon(1e-5));
  for (size_t i = 0; i < render.size(); ++i) CHECK(gradient_f[i] == Approx(gradient[i]).margin(1e-7).epsilon(1e-3));
}

TEST_CASE("Splat optimisation fits photos, and a resumed run continues as an uninterrupted one", "[splat]") {
  const Gaussians<float> truth = RandomSplats(30, 0, 5);
  const std::vector<TrainView> views = ViewsOf(truth, 8);
  const Gaussians<float> start = Disturbed(truth);
  const SplatScene scene{&views, {1, 1, 1}, 2.5, 0.01};
  SplatTrainerOptions options;
  options.steps = 160;
  options.densify_from = 40;
  options.densify_interval = 40;
  const auto psnr = [&](const Gaussians<float>& g) { return MeanPsnr(g, views); };
  SplatTrainer whole(start, scene, options);
  for (int s = 0; s < options.steps; ++s) whole.Step();
  const double before = psnr(start), after = psnr(whole.gaussians());
  INFO("PSNR " << before << " -> " << after);
  CHECK(after > before + 4);

  SplatTrainer first(start, scene, options);
  for (int s = 0; s < 70; ++s) first.Step();
  BinaryWriter writer;
  first.Save(&writer);
  SplatTrainer resumed(RandomSplats(3, 0, 9), scene, options);
  BinaryReader reader(writer.buffer(), "checkpoint");
  resumed.Load(&reader);
  for (int s = 70; s < options.steps; ++s) resumed.Step();
  // Equal up to the order in which threads sum gradients (floating point), which differs between runs.
  REQUIRE(resumed.gaussians().size() == whole.gaussians().size());
  CHECK(resumed.step() == whole.step());
  CHECK(psnr(resumed.gaussians()) == Approx(after).margin(0.05));
}

TEST_CASE("A splat checkpoint keeps densification's cap: a trainer made with another goes on to the run's", "[splat]") {
  const Gaussians<float> truth = RandomSplats(30, 0, 5);
  const std::vector<TrainView> views = ViewsOf(truth, 4);
  const SplatScene scene{&views, {1, 1, 1}, 2.5, 0.01};
  SplatTrainerOptions options;
  options.densify_from = options.densify_interval = 4;
  options.densify_gradient = 1e-12;  // every splat drawn is a candidate
  options.max_gaussians = truth.size() + 5;
  SplatTrainer trainer(Disturbed(truth), scene, options);
  trainer.Step();
  BinaryWriter checkpoint;
  trainer.Save(&checkpoint);
  for (int s = 1; s < 4; ++s) trainer.Step();
  CHECK(trainer.gaussians().size() == truth.size() + 5);  // densified at the fourth step, to the cap

  options.max_gaussians = 1'000'000;
  SplatTrainer resumed(truth, scene, options);
  BinaryReader reader(checkpoint.buffer(), "checkpoint");
  resumed.Load(&reader);
  for (int s = 1; s < 4; ++s) resumed.Step();
  CHECK(resumed.gaussians().size() == truth.size() + 5);
}

// A photo window holds some views' pixels (base/photo_window.h): a view without them would throw if it were drawn.
TEST_CASE("Splat optimisation draws its views from those it is given, the epoch under way going on with them",
          "[splat]") {
  const Gaussians<float> truth = RandomSplats(20, 0, 5);
  std::vector<TrainView> views = ViewsOf(truth, 6, {1, 1, 1}, Eigen::Vector3d::Zero(), 16);
  const SplatScene scene{&views, {1, 1, 1}, 2.5, 0.01};
  SplatTrainer trainer(truth, scene, SplatTrainerOptions{});
  trainer.Step();  // an epoch of all six begins
  for (const size_t v : {0, 3, 5}) views[v].pixels.clear();
  trainer.SampleFrom({1, 2, 4});
  for (int s = 0; s < 30; ++s) CHECK_NOTHROW(trainer.Step());  // the rest of the epoch, then epochs of the three
  CHECK_THROWS_AS(trainer.SampleFrom({6}), std::invalid_argument);
  trainer.SampleFrom({});  // all of them again
  CHECK_THROWS_WITH(
      [&] {
        for (int s = 0; s < 12; ++s) trainer.Step();
      }(),
      Catch::Contains("has no pixels"));
}

TEST_CASE("Splats optimised on the photos at half size look as they should at full size", "[splat]") {
  const Gaussians<float> truth = RandomSplats(30, 0, 5);
  const std::vector<TrainView> views = ViewsOf(truth, 8, {1, 1, 1}, Eigen::Vector3d::Zero(), 64);
  const std::vector<TrainView> half = HalfSizeViews(views);
  const Gaussians<float> start = Disturbed(truth);
  const SplatScene scene{&views, {1, 1, 1}, 2.5, 0.01};
  SplatTrainerOptions options;
  options.steps = 160;
  options.densify_from = options.densify_interval = 40;
  // At half size with the dilation scaled (a pixel of the full size's), and with a pixel of the half size's.
  const auto at_full_size = [&](double scale) {
    SplatTrainer trainer(start, scene, options);
    trainer.SetViews(&half, scale);
    for (int s = 0; s < options.steps; ++s) trainer.Step();
    return MeanPsnr(trainer.gaussians(), views);
  };
  const double scaled = at_full_size(0.5), unscaled = at_full_size(1);
  INFO("PSNR at full size " << scaled << " with the dilation scaled, " << unscaled << " without");
  CHECK(scaled > unscaled + 0.5);  // 1.6 dB here, 1.1 with splats of another seed
}

TEST_CASE("Densification ends at the share of the run its owner sets, whatever the step", "[splat]") {
  const Gaussians<float> truth = RandomSplats(30, 0, 5);
  const std::vector<TrainView> views = ViewsOf(truth, 8);
  Gaussians<float> start = truth;
  for (float& v : start.sh_dc) v += 0.5f;  // something to learn: every drawn splat's mean is pulled
  const SplatScene scene{&views, {1, 1, 1}, 2.5, 0.01};
  SplatTrainerOptions options;  // a nominal 2,000 steps: by the step, step 10 would be early in the run
  options.densify_from = options.densify_interval = 10;
  options.densify_gradient = 1e-12;  // every splat drawn densifies
  const auto size_after_ten_steps = [&](double progress) {
    SplatTrainer trainer(start, scene, options);
    for (int s = 0; s < 10; ++s) trainer.SetProgress(progress), trainer.Step();
    return trainer.gaussians().size();
  };
  CHECK(size_after_ten_steps(0.4) > start.size());
  CHECK(size_after_ten_steps(0.6) == start.size());  // past densify_until (0.5): neither added nor pruned
}

TEST_CASE("Densification with room for some of its candidates only adds copies of those the loss pulls hardest",
          "[splat]") {
  const Gaussians<float> truth = RandomSplats(12, 0, 5);
  const std::vector<TrainView> views = ViewsOf(truth, 8);
  Gaussians<float> start = truth;
  const int moved = 3;  // the last three, far from where the photos show them: the loss pulls their means hardest
  for (size_t i = start.size() - moved; i < start.size(); ++i) start.positions[3 * i + 2] += 0.3f;
  const SplatScene scene{&views, {1, 1, 1}, 2.5, 0.01};
  SplatTrainerOptions options;
  options.densify_from = options.densify_interval = 8;
  options.densify_gradient = 1e-12;  // every splat drawn is a candidate
  options.dense_fraction = 1;        // every candidate is copied (none split)
  options.max_gaussians = start.size() + moved;
  SplatTrainer trainer(start, scene, options);
  for (int s = 0; s < 8; ++s) trainer.Step();
  const Gaussians<float>& after = trainer.gaussians();
  REQUIRE(after.size() == start.size() + moved);  // none pruned; as many copies as there was room for
  for (size_t k = start.size(); k < after.size(); ++k) {
    size_t source = start.size();
    for (size_t i = 0; i < start.size(); ++i) {
      if (after.positions[3 * i] == after.positions[3 * k] && after.positions[3 * i + 2] == after.positions[3 * k + 2])
        source = i;
    }
    INFO("copy " << k << " of splat " << source);
    CHECK(source >= start.size() - moved);
    CHECK(source < start.size());
  }
}

TEST_CASE("Splat optimisation learns the colour behind the splats from photos without alpha, and resumes it",
          "[splat]") {
  const Gaussians<float> truth = RandomSplats(30, 0, 5);
  const std::array<float, 3> sky = {0.3f, 0.5f, 0.7f};
  const std::vector<TrainView> views = ViewsOf(truth, 8, sky);  // opaque photos: the sky shows around the splats
  SplatScene scene{&views, {1, 1, 1}, 2.5, 0.01};
  SplatTrainerOptions options;
  options.steps = 120;
  const auto psnr = [&](const SplatTrainer& trainer) {
    double sum = 0;
    for (const TrainView& view : views) {
      sum += Psnr(RenderSplats(trainer.gaussians(), view.camera, trainer.background(), 0.01),
                  PhotoOnBackground(view, trainer.background()));
    }
    return sum / views.size();
  };
  SplatTrainer fixed(truth, scene, options);
  scene.learn_background = true;
  SplatTrainer learnt(truth, scene, options);
  for (int s = 0; s < options.steps; ++s) fixed.Step(), learnt.Step();
  CHECK(fixed.background() == std::array<float, 3>{1, 1, 1});
  for (int c = 0; c < 3; ++c) CHECK(learnt.background()[c] == Approx(sky[c]).margin(0.02));
  INFO("PSNR with the background fixed " << psnr(fixed) << ", learnt " << psnr(learnt));
  CHECK(psnr(learnt) > psnr(fixed) + 3);

  // A resumed run carries on from the background it had.
  SplatTrainer first(truth, scene, options);
  for (int s = 0; s < 50; ++s) first.Step();
  BinaryWriter writer;
  first.Save(&writer);
  SplatTrainer resumed(truth, scene, options);
  BinaryReader reader(writer.buffer(), "checkpoint");
  resumed.Load(&reader);
  CHECK(resumed.background() == first.background());
  for (int s = 50; s < options.steps; ++s) resumed.Step();
  for (int c = 0; c < 3; ++c) CHECK(resumed.background()[c] == Approx(learnt.background()[c]).margin(1e-3));

  // Photos with alpha were composited on a known background: it is not learnt.
  std::vector<TrainView> with_alpha = views;
  with_alpha[2].channels = 4;
  with_alpha[2].name = "cut_out.png";
  scene.views = &with_alpha;
  CHECK_THROWS_WITH(SplatTrainer(truth, scene, options), Catch::Contains("cut_out.png"));
}

TEST_CASE("Blocks: equal slabs across the widest axis, the views that see each, merged with every splat kept once",
          "[splat]") {
  Gaussians<float> splats = RandomSplats(300, 0, 7);
  for (size_t i = 0; i < splats.size(); ++i) splats.positions[3 * i + 1] *= 10;  // y spreads most: -4..4
  const Slabs blocks = CutIntoSlabs(Means(splats), 3);
  CHECK(blocks.axis == 1);
  REQUIRE(blocks.count() == 3);
  std::vector<int> counts(3, 0);
  for (int b = 0; b < 3; ++b) counts[b] = static_cast<int>(SplatsOfSlab(splats, blocks, b, true).size());
  for (const int count : counts) CHECK(std::abs(count - 100) <= 1);
  CHECK(SplatsOfSlab(splats, blocks, 1, false).size() == splats.size() - counts[1]);
  CHECK(CutIntoSlabs(Means(splats), 1).count() == 1);

  // Cameras looking at either end, from along x: each sees its end's block, the middle one both ends do not reach.
  std::vector<TrainView> views(2);
  views[0].camera = CameraAt({3, -4, 0}, 32, {0, -4, 0});
  views[1].camera = CameraAt({3, 4, 0}, 32, {0, 4, 0});
  CHECK(ViewsOfSlab(views, splats, blocks, 0, 0.01) == std::vector<size_t>{0});
  CHECK(ViewsOfSlab(views, splats, blocks, 2, 0.01) == std::vector<size_t>{1});

  // A splat that moved across a cut during its block's optimisation stays its block's: kept once, where it went.
  std::vector<Gaussians<float>> optimised;
  for (int b = 0; b < 3; ++b) optimised.push_back(SplatsOfSlab(splats, blocks, b, true));
  optimised[0].positions[1] = blocks.cuts[1] + 1;  // now in block 2
  const Gaussians<float> merged = MergeSlabs(optimised);
  CHECK(merged.size() == splats.size());
  CHECK(merged.positions[1] == blocks.cuts[1] + 1);
  CHECK(SplatsOfSlab(merged, blocks, 2, true).size() == optimised[2].size() + 1);
  CHECK_THROWS(MergeSlabs({}));
}

TEST_CASE("Block optimisation: optimised whole, then each block on the views that see it, fit as well as at once",
          "[splat]") {
  // Two objects 4 apart along x, each circled by its own cameras (which see the other behind it from some sides).
  Gaussians<float> truth = RandomSplats(20, 0, 5), right = RandomSplats(20, 0, 8);
  for (size_t i = 0; i < truth.size(); ++i) truth.positions[3 * i] -= 2, right.positions[3 * i] += 2;
  truth.Append(right);
  std::vector<TrainView> views = ViewsOf(truth, 8, {1, 1, 1}, {-2, 0, 0});
  for (TrainView& view : ViewsOf(truth, 8, {1, 1, 1}, {2, 0, 0})) views.push_back(std::move(view));
  Gaussians<float> start = truth;
  std::mt19937_64 random(6);
  std::normal_distribution<float> noise(0, 1);
  for (float& v : start.sh_dc) v += 1.0f * noise(random);
  const SplatScene scene{&views, {1, 1, 1}, 4.5, 0.01};
  SplatTrainerOptions options;
  options.steps = 240;
  options.densify_from = options.densify_interval = 40;
  const auto psnr = [&](const Gaussians<float>& g) { return MeanPsnr(g, views); };
  SplatTrainer whole(start, scene, options);
  for (int s = 0; s < options.steps / 2; ++s) whole.Step();
  BinaryWriter halfway;
  whole.Save(&halfway);
  for (int s = options.steps / 2; s < options.steps; ++s) whole.Step();

  // The second half by blocks, each from where the whole run was halfway, the other block drawn as it was then.
  SplatTrainer first_half(start, scene, options);
  BinaryReader reader(halfway.buffer(), "halfway");
  first_half.Load(&reader);
  const Gaussians<float>& middle = first_half.gaussians();
  const Slabs blocks = CutIntoSlabs(Means(middle), 2);
  CHECK(blocks.axis == 0);
  std::vector<Gaussians<float>> optimised;
  for (int b = 0; b < blocks.count(); ++b) {
    const Gaussians<float> others = SplatsOfSlab(middle, blocks, b, false);
    std::vector<TrainView> seeing;
    for (const size_t v : ViewsOfSlab(views, middle, blocks, b, 0.01)) seeing.push_back(views[v]);
    CHECK(seeing.size() >= 8);  // its own ring, and the other ring's views that show it
    CHECK(seeing.size() < views.size());
    const std::vector<bool> keep = InSlab(middle, blocks, b);
    SplatTrainer trainer(start, scene, options);
    BinaryReader again(halfway.buffer(), "halfway");
    trainer.Load(&again);
    trainer.Restrict(keep, &others, &seeing);
    CHECK(trainer.gaussians().positions == SplatsOfSlab(middle, blocks, b, true).positions);
    CHECK(trainer.Drawn().size() == middle.size());
    for (int s = options.steps / 2; s < options.steps; ++s) trainer.Step();
    optimised.push_back(trainer.gaussians());
  }
  const Gaussians<float> merged = MergeSlabs(optimised);
  CHECK(merged.size() == optimised[0].size() + optimised[1].size());
  const double before = psnr(start), blocked = psnr(merged), at_once = psnr(whole.gaussians());
  INFO("PSNR " << before << " -> " << blocked << " by blocks, " << at_once << " at once");
  CHECK(blocked > before + 4);
  CHECK(blocked > at_once - 1);

  Gaussians<float> other_degree = start;
  other_degree.sh_degree = 1;
  other_degree.Resize(start.size());
  const std::vector<bool> all(start.size(), true);
  CHECK_THROWS_WITH(first_half.Restrict(all, &other_degree, &views), Catch::Contains("SH degree"));
  const std::vector<TrainView> none;
  CHECK_THROWS_WITH(first_half.Restrict(all, nullptr, &none), Catch::Contains("no training views"));
  SplatScene mismatched = scene;
  mismatched.context = &other_degree;
  CHECK_THROWS_WITH(SplatTrainer(start, mismatched, options), Catch::Contains("SH degree"));
}

}  // namespace p2n::testing

// The trainer and the renderer on a scene with a known answer: a sphere coloured by its normal over a white
// background, seen from a ring of cameras. Training must learn it (held-out PSNR), resume from a checkpoint to
// the very same parameters, skip a non-finite step, and save a model that renders the same after loading.

#include <catch2/catch.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <random>
#include <set>
#include <stdexcept>

#include "base/file_util.h"
#include "base/float_image.h"
#include "base/photo_window.h"
#include "examples/synthetic_scene.h"
#include "nerf/appearance.h"
#include "nerf/camera_refinement.h"
#include "nerf/ngp_field.h"
#include "nerf/trainer.h"
#include "test_util.h"

namespace p2n::testing {
namespace {

constexpr int kSize = 40;

// The view of a sphere of radius 0.5 at the origin, coloured 0.5 + 0.5 * normal, over `sky`, or with a wall
// behind it (the plane x = -1.5, in stripes).
TrainView SphereView(double angle, double height, bool wall = false,
                     const Eigen::Vector3d& sky = Eigen::Vector3d::Ones()) {
  TrainView view;
  view.camera = LookAtCamera(Eigen::Vector3d(2.5 * std::cos(angle), 2.5 * std::sin(angle), height),
                             Eigen::Vector3d::Zero(), kSize, kSize, 45);
  view.pixels.resize(kSize * kSize * 3);
  for (int y = 0; y < kSize; ++y) {
    for (int x = 0; x < kSize; ++x) {
      const Ray ray = CameraRay(view.camera, x + 0.5, y + 0.5);
      const double b = ray.origin.dot(ray.direction), c = ray.origin.squaredNorm() - 0.25;
      Eigen::Vector3d colour = sky;
      if (wall && ray.direction.x() < 0) {
        const Eigen::Vector3d p = ray.origin + (-1.5 - ray.origin.x()) / ray.direction.x() * ray.direction;
        colour = Eigen::Vector3d(0.5 + 0.4 * std::sin(4 * p.y()), 0.5 + 0.4 * std::sin(3 * p.z()), 0.3);
      }
      if (b * b - c > 0) {
        const Eigen::Vector3d normal = (ray.origin + (-b - std::sqrt(b * b - c)) * ray.direction).normalized();
        colour = 0.5 * (normal + Eigen::Vector3d::Ones());
      }
      for (int ch = 0; ch < 3; ++ch)
        view.pixels[(y * kSize + x) * 3 + ch] = static_cast<uint8_t>(std::lround(255 * colour[ch]));
    }
  }
  return view;
}

TrainingData SphereScene(const Eigen::Vector3d& sky = Eigen::Vector3d::Ones()) {
  TrainingData data;
  for (int i = 0; i < 24; ++i) {
    data.train.push_back(SphereView(2 * M_PI * i / 24, i % 2 == 0 ? 0.8 : -0.5, false, sky));
  }
  for (int i = 0; i < 3; ++i) data.heldout.push_back(SphereView(2 * M_PI * (i + 0.5) / 3, 0.3, false, sky));
  return data;
}

TrainerOptions SmallOptions() {
  NgpFieldConfig field;
  field.grid.levels = 8;
  field.grid.log2_table_size = 14;
  field.grid.finest_resolution = 256;
  TrainerOptions options;
  options.field = field.ToJson();
  options.occupancy_resolution = 32;
  options.march_step = 2 * std::sqrt(3.0) / 128;
  options.batch_samples = 8192;
  options.seed = 5;
  return options;
}

std::vector<float> Parameters(NerfModel& model) {
  std::vector<float> values;
  for (const ParamBlock<float>& block : model.field->DenseParams())
    values.insert(values.end(), block.data, block.data + block.size);
  Encoding<float>* grid = model.field->TrainableEncoding();
  values.insert(values.end(), grid->params(), grid->params() + grid->num_params());
  return values;
}

// 300 steps take the held-out PSNR above 20 dB and 10 dB above the untrained field's.
void CheckLearns(Trainer* trainer) {
  const double before = Mean(trainer->HeldoutPsnr(0));
  for (int step = 0; step < 300; ++step) REQUIRE_FALSE(trainer->Step(step / 300.0).skipped);
  const double after = Mean(trainer->HeldoutPsnr(0));
  INFO("held-out PSNR before " << before << " dB, after " << after << " dB");
  CHECK(after > 20.0);
  CHECK(after > before + 10.0);
}

}  // namespace

TEST_CASE("training learns a sphere: held-out PSNR rises far above the untrained field's", "[trainer]") {
  const TrainingData data = SphereScene();
  TrainerOptions options = SmallOptions();
  options.error_sampling = GENERATE(false, true);
  CAPTURE(options.error_sampling);
  Trainer trainer(options, data);
  CheckLearns(&trainer);
  if (options.error_sampling) return;
  // The occupancy grid has found the sphere: most of the cube is empty, and renders take few samples.
  CHECK(trainer.model().occupancy.OccupiedFraction() < 0.5);
  RenderStats stats;
  trainer.HeldoutPsnr(0, &stats);
  CHECK(static_cast<double>(stats.samples_evaluated) / stats.rays < 20.0);

  // Early termination saves samples and changes the image by at most the threshold times a colour difference.
  RenderOptions full;
  full.min_transmittance = 0;
  const RenderedView all = RenderView(trainer.model(), data.heldout[1].camera, -1, -1, full);
  const RenderedView early = RenderView(trainer.model(), data.heldout[1].camera, -1, -1, {});
  CHECK(early.stats.samples_evaluated < all.stats.samples_evaluated);
  double worst = 0;
  for (size_t i = 0; i < all.rgb.pixels.size(); ++i)
    worst = std::max(worst, double(std::abs(all.rgb.pixels[i] - early.rgb.pixels[i])));
  CHECK(worst <= 2 * RenderOptions{}.min_transmittance);
  // One sample per ray and thousands per ray both stay finite.
  RenderOptions coarse, fine;
  coarse.step_scale = 100;
  fine.step_scale = 0.01;
  for (const RenderOptions& options : {coarse, fine}) {
    const RenderedView view = RenderView(trainer.model(), data.heldout[1].camera, -1, -1, options);
    for (const float v : view.rgb.pixels) REQUIRE(std::isfinite(v));
  }
}

TEST_CASE("the planes field learns the sphere too, and its model.bin renders the same after loading", "[trainer]") {
  const TrainingData data = SphereScene();
  TrainerOptions options = SmallOptions();
  NgpFieldConfig field;
  field.planes = PlaneGridConfig{.levels = 3, .features_per_level = 8, .finest_resolution = 64, .depth_resolution = 64};
  options.field = field.ToJson();
  Trainer trainer(options, data);
  CheckLearns(&trainer);
  CHECK(trainer.model().occupancy.OccupiedFraction() < 0.5);
  TempDir dir;
  SaveModel(trainer.model(), dir / "model.bin");
  const NerfModel loaded = LoadModel(dir / "model.bin");
  CHECK(loaded.field->Config() == field.ToJson());
  const RenderedView original = RenderView(trainer.model(), data.heldout[0].camera, -1, -1, {});
  const RenderedView copy = RenderView(loaded, data.heldout[0].camera, -1, -1, {});
  CHECK((original.rgb.pixels == copy.rgb.pixels));
}

TEST_CASE("a held-out evaluation reports every ray, and an exception from its callback (Ctrl-C) stops it",
          "[trainer]") {
  const TrainingData data = SphereScene();
  const Trainer trainer(SmallOptions(), data);
  std::atomic<size_t> rays{0};
  trainer.HeldoutPsnr(0, nullptr, [&](size_t count) { rays += count; });
  CHECK(rays == data.heldout.size() * kSize * kSize);
  std::atomic<int> calls{0};
  const auto interrupt = [&](size_t) {
    if (++calls == 2) throw std::runtime_error("interrupted");
  };
  CHECK_THROWS_WITH(trainer.HeldoutPsnr(0, nullptr, interrupt), "interrupted");
  // The renderer reports chunks of 256 rays: the first view's 7 chunks at most, not the evaluation's 21.
  CHECK(calls <= (kSize * kSize + 255) / 256);
}

TEST_CASE("a run resumed from a checkpoint reaches exactly the parameters of an uninterrupted one", "[trainer]") {
  const TrainingData data = SphereScene();
  TrainerOptions options = SmallOptions();
  options.appearance = GENERATE(false, true);
  // All or none: each has its own state to resume.
  options.refine_cameras = options.appearance;
  options.error_sampling = options.appearance;
  options.learn_background = options.appearance;
  options.refine_warmup = 10;
  Trainer straight(options, data);
  for (int step = 0; step < 40; ++step) straight.Step(step / 40.0);

  BinaryWriter writer;
  {
    Trainer first_half(options, data);
    for (int step = 0; step < 20; ++step) first_half.Step(step / 40.0);
    first_half.SaveCheckpoint(&writer);
  }
  Trainer resumed(options, data);
  BinaryReader reader(writer.buffer(), "checkpoint");
  resumed.LoadCheckpoint(&reader);
  CHECK(resumed.step() == 20);
  for (int step = 20; step < 40; ++step) resumed.Step(step / 40.0);
  CHECK((Parameters(resumed.model()) == Parameters(straight.model())));
  CHECK(resumed.appearance() == straight.appearance());
  CHECK(resumed.camera_corrections() == straight.camera_corrections());
  CHECK(resumed.model().background == straight.model().background);

  // A checkpoint of other options is refused.
  TrainerOptions other = options;
  other.seed = 6;
  Trainer stranger(other, data);
  BinaryReader again(writer.buffer(), "checkpoint");
  CHECK_THROWS_WITH(stranger.LoadCheckpoint(&again), Catch::Contains("other options"));
}

TEST_CASE("a step with a non-finite input is detected, reported and skipped, training goes on", "[trainer]") {
  const TrainingData data = SphereScene();
  Trainer trainer(SmallOptions(), data);
  for (int step = 0; step < 5; ++step) trainer.Step(0);
  const std::vector<float> before = Parameters(trainer.model());
  RayBatch batch = trainer.SampleBatch(64);
  batch.target(1, 10) = std::nanf("");
  const StepResult bad = trainer.StepOnBatch(batch, 0);
  CHECK(bad.skipped);
  CHECK_THAT(bad.problem, Catch::Contains("not finite"));
  CHECK(trainer.skipped_steps() == 1);
  CHECK((Parameters(trainer.model()) == before));
  batch.target(1, 10) = 0.5f;
  CHECK_FALSE(trainer.StepOnBatch(batch, 0).skipped);
  CHECK((Parameters(trainer.model()) != before));
}

TEST_CASE("model.bin renders the same after loading, newer and damaged files are refused", "[trainer]") {
  const TrainingData data = SphereScene();
  Trainer trainer(SmallOptions(), data);
  for (int step = 0; step < 60; ++step) trainer.Step(step / 60.0);
  TempDir dir;
  SaveModel(trainer.model(), dir / "model.bin");
  const NerfModel loaded = LoadModel(dir / "model.bin");
  const PinholeCamera camera = data.heldout[0].camera;
  const RenderedView original = RenderView(trainer.model(), camera, -1, -1, {});
  const RenderedView copy = RenderView(loaded, camera, -1, -1, {});
  CHECK((original.rgb.pixels == copy.rgb.pixels));
  CHECK((original.depth.pixels == copy.depth.pixels));

  // model.bin keeps the occupancy grid's bits without its densities (a checkpoint keeps both).
  CHECK((loaded.occupancy.bits() == trainer.model().occupancy.bits()));
  BinaryWriter with_densities;
  WriteModel(trainer.model(), &with_densities, true);
  CHECK(with_densities.buffer().size() >=
        std::filesystem::file_size(dir / "model.bin") + 4 * trainer.model().occupancy.densities().size());

  std::vector<char> bytes = ReadBinaryFile(dir / "model.bin");
  bytes[8] = 3;  // format version 3
  WriteBinaryFileAtomic(dir / "newer.bin", bytes);
  CHECK_THROWS_WITH(LoadModel(dir / "newer.bin"), Catch::Contains("format version 3") && Catch::Contains("newer.bin"));
  bytes[8] = 2;
  bytes.resize(bytes.size() / 2);
  WriteBinaryFileAtomic(dir / "short.bin", bytes);
  CHECK_THROWS_WITH(LoadModel(dir / "short.bin"), Catch::Contains("damaged"));
  WriteBinaryFileAtomic(dir / "other.bin", {'h', 'e', 'l', 'l', 'o'});
  CHECK_THROWS_WITH(LoadModel(dir / "other.bin"), Catch::Contains("not a photo2nerf model"));
  // The fuzzer's seeds are valid models (of every field; format version 1 with the densities, 2 without).
  for (const char* seed : {"tiny_ngp.bin", "tiny_vanilla.bin", "tiny_ngp_v2.bin", "tiny_vanilla_v2.bin",
                           "tiny_planes_v2.bin", "tiny_blocked_v2.bin"}) {
    const NerfModel tiny =
        LoadModel(std::filesystem::path(P2N_SOURCE_DIR) / "tests" / "fuzz" / "corpus" / "model" / seed);
    CHECK(tiny.occupancy.resolution() == 2);
  }
}

TEST_CASE("extreme inputs stay finite: black and white targets, near = far, rays that miss or graze the box",
          "[trainer]") {
  const TrainingData data = SphereScene();
  Trainer trainer(SmallOptions(), data);
  for (const float value : {0.0f, 1.0f}) {  // all-zero and all-saturated colours
    for (int step = 0; step < 20; ++step) {
      RayBatch batch = trainer.SampleBatch(256);
      batch.target.setConstant(value);
      const StepResult result = trainer.StepOnBatch(batch, 0);
      REQUIRE_FALSE(result.skipped);
      REQUIRE(std::isfinite(result.loss));
    }
  }
  for (const float v : Parameters(trainer.model())) REQUIRE(std::isfinite(v));
  const NerfModel& model = trainer.model();
  const Ray towards_centre{{0, -2.5, 0}, {0, 1, 0}};
  CHECK(SampleRay(model, towards_centre, 1.0, 1.0, model.march_step, 1000, nullptr).empty());  // near = far
  // A ray that misses the box, and one that only grazes its edge, render the background exactly.
  const std::vector<Ray> rays = {{{0, -2.5, 1.5}, {0, 1, 0}}, {{1, -2.5, 1}, {0, 1, 0}}};  // misses; on an edge
  const std::vector<Eigen::Vector2d> near_far(2, Eigen::Vector2d(-1, -1));
  float rgb[6], depth[2], opacity[2];
  RenderRays(model, rays, near_far, {}, rgb, depth, opacity, nullptr);
  for (int k = 0; k < 6; ++k) CHECK(rgb[k] == model.background[k % 3]);
  CHECK(opacity[0] == 0.0f);
}

TEST_CASE("unbounded scenes: the contraction maps all of space into the field's cube, continuously", "[trainer]") {
  NerfModel model;
  model.space = SceneSpace::kUnbounded;
  CHECK(FieldPoint(model, Eigen::Vector3d::Zero()).isApprox(Eigen::Vector3d::Constant(0.5)));
  CHECK(FieldPoint(model, Eigen::Vector3d(1, 0, 0)).isApprox(Eigen::Vector3d(0.75, 0.5, 0.5)));  // the box's face
  CHECK(FieldPoint(model, Eigen::Vector3d(1 + 1e-9, 0, 0)).isApprox(Eigen::Vector3d(0.75, 0.5, 0.5), 1e-8));
  const Eigen::Vector3d far = FieldPoint(model, Eigen::Vector3d(1e12, -3e12, 0));
  CHECK(far.maxCoeff() <= 1.0);
  CHECK(far.minCoeff() >= 0.0);
  CHECK(far[1] == Approx(0.0).margin(1e-9));
  // Samples of an unbounded ray get longer with the distance and reach far away.
  const Ray ray{{0, 0, 0}, {1, 0, 0}};
  const std::vector<MarchSample> samples = SampleRay(model, ray, -1, -1, 0.01, 100000, nullptr);
  REQUIRE(samples.size() > 10);
  CHECK(samples.back().t > 100);
  CHECK(samples.back().delta > 10 * samples.front().delta);
  // In the sampler's metric (the distortion loss's) every sample has the same length, near and far.
  for (size_t k = 0; k + 1 < samples.size(); k += 97) {
    const double half = 0.5 * samples[k].delta;
    const double length =
        SamplingDistance(model, ray, samples[k].t + half) - SamplingDistance(model, ray, samples[k].t - half);
    INFO("sample " << k << " at t = " << samples[k].t);
    CHECK(length == Approx(0.01).epsilon(0.02));
  }
}

TEST_CASE("a render without a step samples at the scene's default: half the training step when bounded", "[trainer]") {
  const TrainingData data = SphereScene();
  Trainer trainer(SmallOptions(), data);
  const PinholeCamera& camera = data.heldout[0].camera;
  for (const SceneSpace space : {SceneSpace::kBounded, SceneSpace::kUnbounded}) {
    trainer.model().space = space;
    RenderOptions by_scene, given;
    given.step_scale = space == SceneSpace::kBounded ? 0.5 : 1.0;
    CHECK(DefaultStepScale(trainer.model()) == given.step_scale);
    const RenderStats a = RenderView(trainer.model(), camera, -1, -1, by_scene).stats;
    const RenderStats b = RenderView(trainer.model(), camera, -1, -1, given).stats;
    CHECK(a.samples_marched == b.samples_marched);
    CHECK(a.samples_marched > 0);
  }
}

TEST_CASE("a forward-facing scene learns in the reference camera's NDC: the sphere before a wall, from one side",
          "[trainer]") {
  TrainingData data;
  for (int i = 0; i < 12; ++i) data.train.push_back(SphereView(0.05 * (i % 4) - 0.075, 0.12 * (i / 4) - 0.12, true));
  for (int i = 0; i < 2; ++i) data.heldout.push_back(SphereView(0.05 * i - 0.02, 0.05, true));
  for (TrainView& view : data.train) view.near = 1.5;  // the sphere's front is 2 away
  TrainerOptions options = SmallOptions();
  options.space = SceneSpace::kForward;
  Trainer trainer(options, data);
  const ForwardFrame& frame = trainer.model().forward;
  CHECK(frame.near == Approx(0.8 * 1.5).epsilon(0.02));
  CHECK((frame.cam_from_world.row(2).transpose() - Eigen::Vector3d(1, 0, 0)).norm() < 0.05);  // looks down -x
  CheckLearns(&trainer);
}

TEST_CASE("per-image appearance learns each photo's exposure and keeps it out of the field", "[trainer]") {
  // The sphere scene's photos at gains 0.6 .. 1.0 (the background too, as a camera would); the held-out ones at
  // their mean, 0.8, which is what the field learns under the mean transform.
  TrainingData data = SphereScene();
  std::vector<double> gains;
  const auto expose = [](TrainView* view, double gain) {
    for (uint8_t& value : view->pixels) value = static_cast<uint8_t>(std::lround(value * gain));
  };
  for (size_t v = 0; v < data.train.size(); ++v) {
    gains.push_back(0.6 + 0.1 * double((v * 7) % 5));
    expose(&data.train[v], gains.back());
  }
  for (TrainView& view : data.heldout) expose(&view, 0.8);
  double psnr[2];
  for (const bool appearance : {false, true}) {
    TrainerOptions options = SmallOptions();
    options.appearance = appearance;
    Trainer trainer(options, data);
    for (int step = 0; step < 400; ++step) REQUIRE_FALSE(trainer.Step(step / 400.0).skipped);
    psnr[appearance] = Mean(trainer.HeldoutPsnr(0));
    CHECK(trainer.appearance().size() == (appearance ? data.train.size() * kAppearanceParams : 0));
    if (!appearance) continue;
    for (size_t v = 0; v < gains.size(); ++v) {
      INFO("view " << v << ": gain " << gains[v]);
      CHECK(AppearanceGain(&trainer.appearance()[v * kAppearanceParams]) == Approx(gains[v] / 0.8).margin(0.06));
    }
    // A held-out photo at another exposure is scored after a fit on its left half (NeRF-W): the exposure costs
    // little then.
    TrainingData darker = data;
    for (TrainView& view : darker.heldout) expose(&view, 0.7);
    Trainer judge(options, darker);
    judge.model() = std::move(trainer.model());
    std::vector<double> fitted;
    const double neutral = Mean(judge.HeldoutPsnr(0, nullptr, {}, &fitted));
    INFO("held-out at gain 0.56: " << neutral << " dB as rendered, " << Mean(fitted) << " dB fitted");
    CHECK(Mean(fitted) > neutral + 5);
    CHECK(Mean(fitted) > psnr[1] - 2);
  }
  INFO("held-out PSNR without appearance " << psnr[0] << " dB, with " << psnr[1] << " dB");
  CHECK(psnr[1] > psnr[0] + 2);
}

TEST_CASE("the march refines from step fine_march_from on: twice the samples a ray, and the field learns on",
          "[trainer]") {
  // The sphere at 128 samples across the cube's diagonal, 256 from the 150th step: each ray's occupied stretch
  // gets about twice the samples, the model renders at the finer spacing, and training goes on undisturbed.
  const TrainingData data = SphereScene();
  TrainerOptions options = SmallOptions();
  options.fine_march_step = options.march_step / 2;
  options.fine_march_from = 150;
  Trainer trainer(options, data);
  double samples[2] = {0, 0}, rays[2] = {0, 0};
  for (int step = 0; step < 300; ++step) {
    const StepResult result = trainer.Step(step / 300.0);
    REQUIRE_FALSE(result.skipped);
    REQUIRE(trainer.model().march_step == (step < 150 ? options.march_step : options.fine_march_step));
    if (step >= 120 && step < 180) {
      samples[step >= 150] += double(result.samples);
      rays[step >= 150] += double(result.rays);
    }
  }
  const double ratio = (samples[1] / rays[1]) / (samples[0] / rays[0]);
  INFO("samples a ray " << samples[0] / rays[0] << " then " << samples[1] / rays[1]);
  CHECK(ratio > 1.5);
  CHECK(ratio < 2.5);
  const double psnr = Mean(trainer.HeldoutPsnr(0));
  INFO("held-out PSNR " << psnr << " dB");
  CHECK(psnr > 20.0);
}

TEST_CASE("the background learnt behind photos without alpha: the sky's colour, and a better field", "[trainer]") {
  // The sphere before a sky of (0.3, 0.5, 0.7); the data's background is white, as for any photo without alpha.
  const Eigen::Vector3d sky(0.3, 0.5, 0.7);
  const TrainingData data = SphereScene(sky);
  double psnr[2];
  for (const bool learn : {false, true}) {
    TrainerOptions options = SmallOptions();
    options.learn_background = learn;
    Trainer trainer(options, data);
    for (int step = 0; step < 300; ++step) REQUIRE_FALSE(trainer.Step(step / 300.0).skipped);
    psnr[learn] = Mean(trainer.HeldoutPsnr(0));
    const std::array<float, 3>& background = trainer.model().background;
    INFO("background (" << background[0] << ", " << background[1] << ", " << background[2] << ")");
    for (int c = 0; c < 3; ++c) CHECK(background[c] == Approx(learn ? sky[c] : 1.0).margin(0.05));
  }
  INFO("held-out PSNR with the background fixed " << psnr[0] << " dB, learnt " << psnr[1] << " dB");
  CHECK(psnr[1] > psnr[0] + 2);

  // Photos with alpha were composited on a known colour: it is not learnt.
  TrainingData with_alpha = SphereScene();
  TrainView& view = with_alpha.train[3];
  view.channels = 4;
  std::vector<uint8_t> rgba;
  for (size_t i = 0; i < view.pixels.size(); i += 3)
    rgba.insert(rgba.end(), {view.pixels[i], view.pixels[i + 1], view.pixels[i + 2], 255});
  view.pixels = rgba;
  view.name = "alpha.png";
  TrainerOptions options = SmallOptions();
  options.learn_background = true;
  CHECK_THROWS_WITH(Trainer(options, with_alpha), Catch::Contains("alpha.png") && Catch::Contains("alpha"));
}

TEST_CASE("camera refinement moves perturbed training cameras back towards the truth", "[trainer]") {
  // The sphere's photos from their true cameras, trained from cameras turned by about 1.5 degrees and moved by
  // about 0.04 (a pixel or two at 40 x 40, free of any common motion of all cameras, which the photos cannot
  // tell). A turn and a sideways move of a camera both shift the whole image; what the photos pin down is where
  // the scene's points appear: the corrections must bring those back towards where the true cameras see them.
  TrainingData data = SphereScene();
  const std::vector<PinholeCamera> truth = [&] {
    std::vector<PinholeCamera> cameras;
    for (const TrainView& view : data.train) cameras.push_back(view.camera);
    return cameras;
  }();
  std::mt19937_64 random(11);
  std::normal_distribution<float> rotation(0.0f, 0.015f), shift(0.0f, 0.025f);
  std::vector<float> perturbations(data.train.size() * kPoseParams);
  std::vector<Eigen::Vector3d> centres;
  for (size_t k = 0; k < perturbations.size(); ++k) perturbations[k] = k % 6 < 3 ? rotation(random) : shift(random);
  for (const PinholeCamera& camera : truth) centres.push_back(camera.world_from_cam.block<3, 1>(0, 3));
  RemoveCommonMotion(centres, &perturbations);
  for (size_t v = 0; v < data.train.size(); ++v) {
    data.train[v].camera = CorrectedCamera(truth[v], &perturbations[v * kPoseParams]);
  }
  // The mean distance in pixels between where the true and the (corrected) training cameras see points of the
  // sphere's bounding box.
  const auto reprojection_error = [&](const std::vector<float>& corrections) {
    double sum = 0;
    int count = 0;
    for (size_t v = 0; v < truth.size(); ++v) {
      const PinholeCamera camera = corrections.empty()
                                       ? data.train[v].camera
                                       : CorrectedCamera(data.train[v].camera, &corrections[v * kPoseParams]);
      for (int corner = 0; corner < 8; ++corner) {
        const Eigen::Vector3d point(corner & 1 ? 0.5 : -0.5, corner & 2 ? 0.5 : -0.5, corner & 4 ? 0.5 : -0.5);
        sum += (Project(camera, point) - Project(truth[v], point)).norm();
        ++count;
      }
    }
    return sum / count;
  };
  double psnr[2], pixels[2];
  for (const bool refine : {false, true}) {
    TrainerOptions options = SmallOptions();
    options.refine_cameras = refine;
    Trainer trainer(options, data);
    for (int step = 0; step < 600; ++step) REQUIRE_FALSE(trainer.Step(step / 600.0).skipped);
    psnr[refine] = Mean(trainer.HeldoutPsnr(0));
    pixels[refine] = reprojection_error(trainer.camera_corrections());
    CHECK(trainer.camera_corrections().size() == (refine ? data.train.size() * kPoseParams : 0));
  }
  INFO("reprojection error " << pixels[0] << " px as given, " << pixels[1] << " px refined; held-out PSNR " << psnr[0]
                             << " dB fixed, " << psnr[1] << " dB refined");
  CHECK(pixels[1] < 0.5 * pixels[0]);
  CHECK(psnr[1] > psnr[0] + 1);
}

// Photos that show one grey everywhere, over the same grey: the colours say nothing of where the surface is, so
// only the depth loss can place it. Each training view sees depth points on the sphere of radius 0.5 (where its
// rays meet it); after training, rays through them must render the sphere's distance.
TEST_CASE("the depth loss places the surface where the sparse points say, where the colours cannot", "[trainer]") {
  TrainingData data;
  data.background = {0.5f, 0.5f, 0.5f};
  data.background_known = true;
  std::vector<Ray> rays;
  std::vector<double> distances;
  for (int i = 0; i < 12; ++i) {
    TrainView view = SphereView(2 * M_PI * i / 12, i % 2 == 0 ? 0.6 : -0.4);
    std::fill(view.pixels.begin(), view.pixels.end(), uint8_t{128});
    for (int y = 4; y < kSize; y += 4) {
      for (int x = 4; x < kSize; x += 4) {
        const Ray ray = CameraRay(view.camera, x, y);
        const double b = ray.origin.dot(ray.direction), c = ray.origin.squaredNorm() - 0.25;
        if (b * b - c <= 0) continue;
        const double distance = -b - std::sqrt(b * b - c);
        view.depth_points.push_back({float(x), float(y), float(distance), 0.5f});
        rays.push_back(ray);
        distances.push_back(distance);
      }
    }
    data.train.push_back(view);
  }
  REQUIRE(rays.size() > 200);
  // The median relative error of the rendered distance (depth / opacity) on the depth points' rays.
  const auto median_error = [&](double depth_weight) {
    TrainerOptions options = SmallOptions();
    options.depth_weight = depth_weight;
    Trainer trainer(options, data);
    for (int step = 0; step < 300; ++step) REQUIRE_FALSE(trainer.Step(step / 300.0).skipped);
    const std::vector<Eigen::Vector2d> near_far(rays.size(), Eigen::Vector2d(-1, -1));
    std::vector<float> rgb(3 * rays.size()), depth(rays.size()), opacity(rays.size());
    RenderRays(trainer.model(), rays, near_far, {}, rgb.data(), depth.data(), opacity.data(), nullptr);
    std::vector<double> errors;
    for (size_t r = 0; r < rays.size(); ++r) {
      const double rendered = opacity[r] > 0.01f ? depth[r] / opacity[r] : 0.0;
      errors.push_back(std::abs(rendered - distances[r]) / distances[r]);
    }
    std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
    return errors[errors.size() / 2];
  };
  const double with_depth = median_error(1.0), without = median_error(0.0);
  INFO("median relative error of the rendered distance: " << with_depth << " with the depth loss, " << without
                                                          << " without");
  CHECK(with_depth < 0.05);
  CHECK(without > 4 * with_depth);
}

}  // namespace p2n::testing

namespace p2n::testing {

TEST_CASE("rays are drawn from the sampled views only: uniformly, by the error map and through depth points",
          "[trainer]") {
  TrainingData data = SphereScene();
  for (TrainView& view : data.train) view.depth_points = {{10.5f, 20.5f, 2.0f, 0.5f}};
  std::vector<uint8_t>().swap(data.train[5].pixels);  // not in memory: never drawn, even by default
  for (const bool error_sampling : {false, true}) {
    TrainerOptions options = SmallOptions();
    options.error_sampling = error_sampling;
    options.depth_weight = 1;
    Trainer trainer(options, data);
    CHECK(trainer.sampled_views().size() == data.train.size() - 1);
    const RayBatch all = trainer.SampleBatch(4096);
    CHECK(std::count(all.views.begin(), all.views.end(), 5) == 0);
    CHECK(std::set<int>(all.views.begin(), all.views.end()).size() == data.train.size() - 1);

    trainer.SampleFrom({3, 17});
    const RayBatch batch = trainer.SampleBatch(4096);
    CHECK(std::count(batch.views.begin(), batch.views.end(), 3) +
              std::count(batch.views.begin(), batch.views.end(), 17) ==
          4096);
    CHECK(std::count(batch.views.begin(), batch.views.end(), 3) > 1500);  // both, about as often
    CHECK(std::count(batch.views.begin(), batch.views.end(), 17) > 1500);
    for (size_t r = 0; r < batch.depth.size(); ++r) {  // a depth ray's target is its view's point
      if (batch.depth[r].y() > 0) CHECK(batch.depth[r].x() == 2.0f);
    }
    CHECK_THROWS_WITH(trainer.SampleFrom({5}), Catch::Contains("has no pixels in memory"));
  }
}

TEST_CASE("a window of a third of the photos in memory learns the sphere as well as all of them", "[trainer]") {
  const TrainingData all = SphereScene();
  TrainingData data = SphereScene();
  for (TrainView& view : data.train) std::vector<uint8_t>().swap(view.pixels);
  const size_t view_bytes = all.train.front().PixelBytes();
  PhotoWindow window(
      &data.train, [&all](size_t v) { return all.train[v].pixels; }, 10 * view_bytes, 5);
  REQUIRE(window.size() == 8);
  Trainer windowed(SmallOptions(), data), whole(SmallOptions(), all);
  for (int step = 0; step < 300; ++step) {
    if (window.MoveTo(windowed.step())) windowed.SampleFrom(window.resident());
    REQUIRE_FALSE(windowed.Step(step / 300.0).skipped);
    REQUIRE_FALSE(whole.Step(step / 300.0).skipped);
  }
  const double windowed_psnr = Mean(windowed.HeldoutPsnr(0)), whole_psnr = Mean(whole.HeldoutPsnr(0));
  INFO("held-out PSNR with a window " << windowed_psnr << " dB, with every photo " << whole_psnr << " dB");
  CHECK(windowed_psnr > 20.0);
  CHECK(windowed_psnr > whole_psnr - 1.0);
}

}  // namespace p2n::testing

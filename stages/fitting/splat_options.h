#pragma once
// The splat stage's options (splat.*), apart from the stage so that its helpers include them alone.

#include <string>
#include "formats/output_frame.h"
#include "pipeline/options.h"

namespace p2n {

enum class SplatInit { kAuto, kField, kSparse };
template <>
struct EnumNames<SplatInit> {
  static constexpr std::pair<SplatInit, const char*> kValues[] = {
      {SplatInit::kAuto, "auto"}, {SplatInit::kField, "field"}, {SplatInit::kSparse, "sparse"}};
};

enum class SplatBackground { kAuto, kFixed };
template <>
struct EnumNames<SplatBackground> {
  static constexpr std::pair<SplatBackground, const char*> kValues[] = {{SplatBackground::kAuto, "auto"},
                                                                        {SplatBackground::kFixed, "fixed"}};
};

struct SplatOptions {
  static constexpr const char* kSection = "splat";  // its options are splat.NAME

  bool enabled = true;
  double time_budget = 0;  // seconds of optimisation; 0: by the training preset (SplatTimeBudget)
  int steps = 0;           // stop after this many steps; 0: no step limit
  int sh_degree = 3;
  SplatInit init = SplatInit::kAuto;  // where the first Gaussians come from (ResolveSplatInit)
  int init_width = 128;               // training views rendered this wide to place the first Gaussians
  int max_gaussians = 100'000;        // of the first (more in a large scene); densification may double it
  int blocks = 1;                     // optimised in this many spatial blocks after a whole part (splat/blocks.h)
  double coarse = 0.75;               // share of the optimisation on the photos at half size
  int max_image_size = 1080;          // the photos are downsized to at most this on their longest side; 0: any size
  double ssim_weight = 0.1;           // the loss: (1 - w) L1 + w (1 - SSIM)
  SplatBackground background = SplatBackground::kAuto;  // learnt behind photos, the field's where known
  FrameKind frame = FrameKind::kSource;
  double eval_interval = 30;  // seconds of optimisation between held-out evaluations (each of every held-out view)
  double checkpoint_interval = 60;
  double photo_memory = 2048;  // MB the training photos may take; beyond it a window over them (photo_window.h)
  int seed = 0;

  template <class V>
  void Visit(V& v) {
    v("enabled", enabled, "make 3D Gaussian splats of the scene (splats.ply, for live viewing)");
    v("time_budget", time_budget,
      "optimisation time of the splats; 0: by the training preset (fast 30, default 180, quality 480); above 320 s "
      "the means' learning rate decays over proportionally more steps",
      "s");
    v("steps", steps, "stop after this many steps (one training photo each); 0: no step limit", "steps");
    v("sh_degree", sh_degree, "spherical-harmonics degree of the splats' colours (0: one colour each)");
    v("init", init,
      "where the first splats come from: field (its surfaces, seen by the training views), sparse (the structure from "
      "motion's points, or the dataset's, as 3D Gaussian Splatting starts), or auto: sparse for an unbounded scene "
      "(a capture all round) of at least 20 training photos with at least 1,000 points, else field");
    v("init_width", init_width,
      "width the training views are rendered at to place the first splats (narrower beyond 2 M pixels in all)",
      "pixels");
    v("max_gaussians", max_gaussians,
      "splats placed from the field where a training view sees at least half of the scene; where it sees less (a "
      "street, a survey) more in proportion, so that a view draws about as many; at most one per 64 training pixels "
      "(densification may add as many again)");
    v("blocks", blocks,
      "optimise the splats whole for half the budget, then in this many blocks (slabs across the scene's widest axis) "
      "for the other half each, every block on the training views that see it with the others drawn as the whole "
      "optimisation left them, then merged: for scenes too large for one optimisation in the time; 1: whole");
    v("coarse", coarse,
      "share of the optimisation time spent on the photos at half size (four times the steps; coarse to fine), "
      "ending sooner after 40 passes over the training photos");
    v("max_image_size", max_image_size,
      "longest side of the photos the splats are optimised on: larger ones are downsized to it with an area filter "
      "(the coarse share at half that); held-out views are scored at their own size; 0: as they are",
      "px");
    v("ssim_weight", ssim_weight,
      "weight of the structural dissimilarity (1 - SSIM) in the loss, the rest L1 (3D Gaussian Splatting uses 0.2)");
    v("background", background,
      "the colour behind the splats: auto (learnt with them where the photos have no alpha: what lies beyond the "
      "splats, a sky or a far wall; the field's where the images have alpha or the import knows the colour they were "
      "composited or rendered on) or fixed (the field's)");
    v("frame", frame,
      "coordinates of splats.ply: source (COLMAP's world, or the dataset's) or normalized (the training frame)");
    v("eval_interval", eval_interval, "optimisation time between held-out evaluations (metrics.csv rows)", "s");
    v("checkpoint_interval", checkpoint_interval, "time between checkpoints that a killed run resumes from; 0: none",
      "s", OptionKind::kRuntime);
    v("photo_memory", photo_memory,
      "memory the training photos (at splat.max_image_size) may take; when they would take more, a window over them "
      "is kept in memory, moving on every few steps, the next photos read from disk while the splats are optimised",
      "MB");
    v("seed", seed, "random seed (view order, splits)");
  }
  void Check() const;
};

}  // namespace p2n

#pragma once
// The train stage's options (train.*), apart from the stage so that others include them alone.

#include <string>
#include "nerf/trainer.h"
#include "pipeline/options.h"
#include "stages/fitting/train_presets.h"

namespace p2n {

// train.field: the hash grid with tiny MLPs, factorised planes with the same MLPs, or the seed's
// positional-encoding MLP.
enum class FieldKind { kNgp, kPlanes, kVanilla };
template <>
struct EnumNames<FieldKind> {
  static constexpr std::pair<FieldKind, const char*> kValues[] = {
      {FieldKind::kNgp, "ngp"}, {FieldKind::kPlanes, "planes"}, {FieldKind::kVanilla, "vanilla"}};
};

// train.scene: a scene space, or auto.
enum class SceneChoice { kAuto, kBounded, kUnbounded, kForward };
template <>
struct EnumNames<SceneChoice> {
  static constexpr std::pair<SceneChoice, const char*> kValues[] = {{SceneChoice::kAuto, "auto"},
                                                                    {SceneChoice::kBounded, "bounded"},
                                                                    {SceneChoice::kUnbounded, "unbounded"},
                                                                    {SceneChoice::kForward, "forward"}};
};

// train.background.
enum class BackgroundChoice { kAuto, kRandom, kLearnt, kFixed };
template <>
struct EnumNames<BackgroundChoice> {
  static constexpr std::pair<BackgroundChoice, const char*> kValues[] = {{BackgroundChoice::kAuto, "auto"},
                                                                         {BackgroundChoice::kRandom, "random"},
                                                                         {BackgroundChoice::kLearnt, "learnt"},
                                                                         {BackgroundChoice::kFixed, "fixed"}};
};

struct TrainOptions {
  static constexpr const char* kSection = "train";  // its options are train.NAME

  PresetName preset = PresetName::kDefault;  // sizes, sample spacing and time budget together
  FieldKind field = FieldKind::kNgp;
  SceneChoice scene = SceneChoice::kAuto;  // a SceneSpace (nerf_model.h), or auto (ResolveSceneSpace)
  double time_budget = 0;                  // seconds of training; 0: the preset's (fast 60, default 240, quality 900)
  int steps = 0;                           // stop after this many steps (0: no step limit)
  int batch_samples = 0;                   // samples per step; 0: the preset's
  int march_samples = 0;                   // samples across the scene cube's diagonal (ngp); 0: the preset's
  int vanilla_samples = 64;                // stratified samples per ray (vanilla)
  int hash_table_log2 = 0;                 // log2 of the hash-grid entries per level (ngp); 0: the preset's
  int plane_resolution = 0;                // cells across x and y of the finest planes (planes); 0: by the scene
  int plane_depth_resolution = 0;          // cells along z of the finest planes (planes); 0: by the scene
  double learning_rate = 0;                // 0: the field's (ngp and planes 1e-2, vanilla 5e-4)
  PhotometricLoss loss = PhotometricLoss::kMse;
  // Auto: random for images with alpha, fixed where the import knows it, else learnt.
  BackgroundChoice background = BackgroundChoice::kAuto;
  AutoOrNumber distortion;          // weight of the distortion loss; auto: by the scene (DistortionWeight)
  AutoOrNumber depth;               // weight of the depth loss on the sparse points; auto: by the views (DepthWeight)
  bool appearance = false;          // a colour transform per training photo
  bool refine_cameras = false;      // a pose correction per training photo (ngp only)
  bool error_sampling = false;      // pixels drawn where the error is
  double eval_interval = 10;        // seconds of training between held-out evaluations
  double eval_share = 0.1;          // held-out evaluations during training take at most this share of wall time
  int eval_pixels = 4096;           // held-out pixels per view in each evaluation during training (0: all)
  int final_eval_pixels = 65536;    // held-out pixels per view in the final evaluation (0: all)
  double checkpoint_interval = 60;  // seconds between checkpoints (0: none)
  double photo_memory = 2048;       // MB the training photos may take; beyond it a window over them (photo_window.h)
  int blocks = 1;                   // trained whole for half the budget, then in this many spatial blocks
  int seed = 0;

  template <class V>
  void Visit(V& v) {
    v("preset", preset, "fast (a preview in about a minute), default, or quality");
    v("field", field,
      "ngp (hash grid + tiny MLPs), planes (K-planes' factorised feature planes + the same MLPs) or vanilla (the "
      "seed's positional-encoding MLP)");
    v("scene", scene,
      "bounded (an object inside the unit box), unbounded (space beyond it contracted), forward (every camera "
      "looking one way, as LLFF captures: a mean camera's normalised device coordinates), or auto: bounded for "
      "Blender and .npz datasets, forward for captures whose cameras all look within 15 degrees of their "
      "mean direction (LLFF data or photos), else unbounded");
    v("time_budget", time_budget, "training time; 0: the preset's (fast 60, default 240, quality 900)", "s");
    v("steps", steps, "stop after this many steps; 0: no step limit", "steps");
    v("batch_samples", batch_samples, "samples per training step; 0: the preset's", "samples");
    v("march_samples", march_samples, "samples across the scene cube's diagonal (ngp); 0: the preset's", "samples");
    v("vanilla_samples", vanilla_samples, "stratified samples per ray (vanilla)", "samples");
    v("hash_table_log2", hash_table_log2, "log2 of the hash-grid entries per level (ngp); 0: the preset's");
    v("plane_resolution", plane_resolution,
      "cells across x and y (in a forward-facing scene the image plane) of the finest planes (planes); 0: by the "
      "scene",
      "cells");
    v("plane_depth_resolution", plane_depth_resolution, "cells along z of the finest planes (planes); 0: by the scene",
      "cells");
    v("learning_rate", learning_rate, "Adam learning rate; 0: the field's (ngp and planes 1e-2, vanilla 5e-4)");
    v("loss", loss, "photometric loss: mse, or huber (delta 0.1)");
    v("background", background,
      "the colour behind the scene; auto: random behind images with alpha (they learn transparency), fixed where "
      "the import knows it (images composited or rendered on a plain colour), learnt for photos (a sky, a far "
      "wall); fixed: the dataset's background colour (white when unknown)");
    v("distortion", distortion,
      "weight of the distortion loss, which gathers each ray's weight into one place (against haze and floaters); "
      "auto: the weight measured best on real captures for unbounded scenes, 0 for bounded ones");
    v("depth", depth,
      "weight of the depth loss: rays through the sparse points each training photo sees (the structure from "
      "motion's) learn to end at them, less so for points with a larger reprojection error (as depth-supervised "
      "NeRF); auto: on for captures of fewer than 20 training photos, where it was measured to help, else off");
    v("appearance", appearance,
      "on: a colour transform per training photo learnt with the field, for photos that differ in exposure and "
      "white balance (novel views show the average photo)");
    v("refine_cameras", refine_cameras,
      "on: each training photo's camera is corrected by a small turn and shift learnt with the field (ngp only); "
      "train_report.json says how far each moved, and the refined cameras are exported; for cameras off by a pixel "
      "or more");
    v("error_sampling", error_sampling,
      "on: training pixels are drawn half uniformly and half where the recent error is large (instant-ngp's error "
      "map), their losses weighted so that the expected gradient is the uniform one's");
    v("eval_interval", eval_interval, "training time between held-out evaluations (metrics.csv rows)", "s");
    v("eval_share", eval_share,
      "held-out evaluations during training take at most this share of the wall time (the interval grows when "
      "they would take more); 1: every eval_interval whatever they cost");
    v("eval_pixels", eval_pixels, "held-out pixels per view in each evaluation during training; 0: all", "pixels");
    v("final_eval_pixels", final_eval_pixels, "held-out pixels per view in the final evaluation; 0: all", "pixels");
    v("checkpoint_interval", checkpoint_interval, "time between checkpoints that a killed run resumes from; 0: none",
      "s", OptionKind::kRuntime);
    v("photo_memory", photo_memory,
      "memory the training photos may take; when they would take more, a window over them is kept in memory, "
      "moving on every few steps, the next photos read from disk while the field trains",
      "MB");
    v("blocks", blocks,
      "train the field whole for half the budget, then in this many blocks (slabs across the scene's widest axis, "
      "each with equal shares of the surface the photos see), each on the photos that see it for the other half, "
      "one after the other or as jobs at once under a scheduler; each point is then answered by its slab's field");
    v("seed", seed, "random seed (initialisation, rays, samples)");
  }
  void Check() const;
};

}  // namespace p2n

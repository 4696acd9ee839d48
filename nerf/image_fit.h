#pragma once
// Fits a neural field to one image: an MLP maps a pixel's normalised (x, y) to its colour, trained on random
// pixel batches (the 2D warm-up of the NeRF seed). Built from the 3D engine's components: an encoding
// (positional or hash grid), the MLP and Adam.

#include <filesystem>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "base/enum_names.h"
#include "base/float_image.h"

namespace p2n {

enum class FitModel { kPe, kHashGrid };
template <>
struct EnumNames<FitModel> {
  static constexpr std::pair<FitModel, const char*> kValues[] = {{FitModel::kPe, "pe"},
                                                                 {FitModel::kHashGrid, "hashgrid"}};
};

// What an image's alpha does: composited over white, or dropped.
enum class FitAlpha { kComposite, kIgnore };
template <>
struct EnumNames<FitAlpha> {
  static constexpr std::pair<FitAlpha, const char*> kValues[] = {{FitAlpha::kComposite, "composite"},
                                                                 {FitAlpha::kIgnore, "ignore"}};
};

// Loads an image for fitting: grey stays grey, 8-bit and 16-bit become [0, 1]; alpha is dropped or composited
// over white. Throws std::invalid_argument naming the file.
FloatImage LoadImageForFit(const std::filesystem::path& path, FitAlpha alpha);

struct ImageFitOptions {
  static constexpr const char* kName = "fit";  // checks name fit.FIELD
  FitModel model = FitModel::kPe;              // positional encoding + 256-wide MLP (the seed), or a hash grid + MLP
  double time_budget = 30;                     // seconds of training (evaluation time not counted); 0: no limit
  int max_steps = 0;                           // 0: no limit (then time_budget must be set)
  int batch_size = 10000;                      // random pixels per step
  double learning_rate = 1e-2;                 // Adam
  int width = 0;                               // MLP width; 0: the model's default (pe 256, hashgrid 64)
  int depth = 0;                               // hidden layers; 0: the model's default (pe 3, hashgrid 2)
  int pe_levels = 10;                          // L, frequencies of the positional encoding; 0: raw (x, y) only
  int hash_levels = 16;
  int hash_log2_table_size = 19;
  int hash_finest_resolution = 0;                  // cells per axis of the finest level; 0: the image's longer side
  double eval_interval = 1.0;                      // seconds of training between PSNR evaluations
  std::string snapshot_steps = "25,100,500,2000";  // steps whose reconstruction is kept, comma-separated
  FitAlpha alpha = FitAlpha::kComposite;           // RGBA input: composited over white, or the alpha ignored
  int seed = 0;

  template <class V>
  void Visit(V& v) {
    v("model", model, "pe (positional encoding + MLP, the seed's model) or hashgrid", "");
    v("time_budget", time_budget, "training time (evaluation not counted); 0: no limit", "s");
    v("max_steps", max_steps, "steps at most; 0: no limit", "steps");
    v("batch_size", batch_size, "random pixels per step", "pixels");
    v("learning_rate", learning_rate, "Adam learning rate");
    v("width", width, "MLP width; 0: the model's default (pe 256, hashgrid 64)", "neurons");
    v("depth", depth, "hidden layers; 0: the model's default (pe 3, hashgrid 2)", "layers");
    v("pe_levels", pe_levels, "L, frequencies of the positional encoding (pe); 0: raw (x, y) only");
    v("hash_levels", hash_levels, "levels of the hash grid (hashgrid)");
    v("hash_log2_table_size", hash_log2_table_size, "log2 of the entries per hash-grid level (hashgrid)");
    v("hash_finest_resolution", hash_finest_resolution,
      "cells per axis of the finest hash-grid level; 0: the image's longer side", "cells");
    v("eval_interval", eval_interval, "training time between PSNR evaluations", "s");
    v("snapshot_steps", snapshot_steps, "steps whose reconstruction is saved, comma-separated", "");
    v("alpha", alpha, "RGBA input: composite over white, or ignore the alpha", "");
    v("seed", seed, "random seed (initialisation and batches)");
  }
  // Throws std::invalid_argument naming the option and the rule.
  void Check() const;
  std::vector<int> SnapshotSteps() const;
};

struct FitCurvePoint {
  double wall_seconds;  // training time so far
  int step;
  double psnr;  // on the evaluation pixels (all pixels up to 65536, else a fixed random subset)
};

struct ImageFitResult {
  std::vector<FitCurvePoint> curve;
  std::vector<std::pair<int, FloatImage>> snapshots;  // (step, reconstruction)
  FloatImage reconstruction;
  int steps = 0;
  double train_seconds = 0;
  double psnr = 0;              // of the whole reconstruction
  nlohmann::json model_config;  // encoding and network, each with its "otype"
};

// Called after every evaluation (for progress display).
using FitObserver = std::function<void(const FitCurvePoint&)>;

// Trains until the time budget or the step limit; throws std::runtime_error on a non-finite loss.
ImageFitResult FitImage(const ImageFitOptions& options, const FloatImage& target, const FitObserver& observer = {});

}  // namespace p2n

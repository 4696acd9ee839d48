#include "nerf/image_fit.h"

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>
#include <sstream>

#include "base/declared_fields.h"
#include "base/image_io.h"
#include "nerf/adam.h"
#include "nerf/denormals.h"
#include "nerf/encoding.h"
#include "nerf/mlp.h"

namespace p2n {
namespace {

using Matrix = Eigen::MatrixXf;
constexpr Eigen::Index kChunk = 512;  // samples per task: activations stay in L2
constexpr size_t kMaxEvalPixels = 65536;

// The encoding + MLP of a model, and their optimisers.
struct Model {
  std::unique_ptr<Encoding<float>> encoding;
  std::unique_ptr<Mlp<float>> mlp;
  std::unique_ptr<Adam<float>> encoding_adam, mlp_adam;
};

Model MakeModel(const ImageFitOptions& options, const FloatImage& target) {
  Model model;
  const bool pe = options.model == FitModel::kPe;
  if (pe) {
    model.encoding = std::make_unique<PositionalEncoding<float>>(2, options.pe_levels);
  } else {
    HashGridConfig grid;
    grid.levels = options.hash_levels;
    grid.log2_table_size = options.hash_log2_table_size;
    grid.finest_resolution =
        options.hash_finest_resolution > 0 ? options.hash_finest_resolution : std::max(target.width, target.height);
    grid.base_resolution = std::min(16, grid.finest_resolution);
    model.encoding = std::make_unique<HashGridEncoding<float>>(2, grid, options.seed + 1);
  }
  MlpConfig network;
  network.inputs = model.encoding->output_dims();
  network.outputs = target.channels;
  network.width = options.width > 0 ? options.width : (pe ? 256 : 64);
  network.hidden_layers = options.depth > 0 ? options.depth : (pe ? 3 : 2);
  network.output_activation = OutputActivation::kSigmoid;
  model.mlp = std::make_unique<Mlp<float>>(network, options.seed);
  model.mlp_adam =
      std::make_unique<Adam<float>>(AdamOptions{options.learning_rate, 0.9, 0.999, 1e-8}, model.mlp->num_params());
  if (model.encoding->num_params() > 0) {
    // The hash table: sparse updates with per-entry step counts, epsilon 1e-15 (tiny-cuda-nn).
    model.encoding_adam = std::make_unique<Adam<float>>(AdamOptions{options.learning_rate, 0.9, 0.99, 1e-15},
                                                        model.encoding->num_params(), model.encoding->entry_size());
  }
  return model;
}

// Normalised coordinates ((x + 0.5) / w, (y + 0.5) / h) of pixel indices.
Matrix Coordinates(const FloatImage& image, const std::vector<uint32_t>& pixels) {
  Matrix coordinates(2, static_cast<Eigen::Index>(pixels.size()));
  for (size_t i = 0; i < pixels.size(); ++i) {
    coordinates(0, i) = (pixels[i] % image.width + 0.5f) / image.width;
    coordinates(1, i) = (pixels[i] / image.width + 0.5f) / image.height;
  }
  return coordinates;
}

// Predicted colours (channels x n) for coordinates, in parallel chunks.
Matrix Predict(const Model& model, const Matrix& coordinates) {
  Matrix colours(model.mlp->config().outputs, coordinates.cols());
  tbb::parallel_for(Eigen::Index{0}, (coordinates.cols() + kChunk - 1) / kChunk, [&](Eigen::Index chunk) {
    FlushDenormalsOnThisThread();
    const Eigen::Index begin = chunk * kChunk, count = std::min(kChunk, coordinates.cols() - begin);
    Matrix encoded, out;
    Mlp<float>::Cache cache;
    model.encoding->Forward(coordinates.middleCols(begin, count), &encoded);
    model.mlp->Forward(encoded, &out, &cache);
    colours.middleCols(begin, count) = out;
  });
  return colours;
}

FloatImage Reconstruct(const Model& model, const FloatImage& target) {
  std::vector<uint32_t> all(static_cast<size_t>(target.width) * target.height);
  for (size_t i = 0; i < all.size(); ++i) all[i] = static_cast<uint32_t>(i);
  const Matrix colours = Predict(model, Coordinates(target, all));
  FloatImage image{target.width, target.height, target.channels, {}};
  image.pixels.assign(colours.data(), colours.data() + colours.size());
  return image;
}

double PsnrOfPixels(const Model& model, const FloatImage& target, const std::vector<uint32_t>& pixels) {
  const Matrix colours = Predict(model, Coordinates(target, pixels));
  double squared_error = 0;
  for (size_t i = 0; i < pixels.size(); ++i) {
    for (int c = 0; c < target.channels; ++c) {
      const double d = colours(c, i) - target.pixels[size_t{pixels[i]} * target.channels + c];
      squared_error += d * d;
    }
  }
  return PsnrOfMse(squared_error / (pixels.size() * target.channels));
}

// One Adam step on a random batch; returns the batch's mean squared error.
double TrainStep(Model& model, const FloatImage& target, const std::vector<uint32_t>& batch,
                 tbb::enumerable_thread_specific<std::vector<float>>& mlp_grads) {
  const Matrix coordinates = Coordinates(target, batch);
  const Eigen::Index n = coordinates.cols();
  const int channels = target.channels;
  const float scale = 2.0f / (static_cast<float>(n) * channels);  // d(mean squared error)/d(prediction)
  Matrix d_encoded(model.encoding->output_dims(), n);
  for (auto& grads : mlp_grads) std::fill(grads.begin(), grads.end(), 0.0f);
  tbb::enumerable_thread_specific<double> losses(0.0);
  const bool trainable_encoding = model.encoding->num_params() > 0;
  tbb::parallel_for(Eigen::Index{0}, (n + kChunk - 1) / kChunk, [&](Eigen::Index chunk) {
    FlushDenormalsOnThisThread();
    const Eigen::Index begin = chunk * kChunk, count = std::min(kChunk, n - begin);
    Matrix encoded, out;
    Mlp<float>::Cache cache;
    model.encoding->Forward(coordinates.middleCols(begin, count), &encoded);
    model.mlp->Forward(encoded, &out, &cache);
    Matrix d_out(channels, count);
    double loss = 0;
    for (Eigen::Index i = 0; i < count; ++i) {
      for (int c = 0; c < channels; ++c) {
        const float d = out(c, i) - target.pixels[size_t{batch[begin + i]} * channels + c];
        loss += double{d} * d;
        d_out(c, i) = scale * d;
      }
    }
    losses.local() += loss;
    std::vector<float>& grads = mlp_grads.local();
    if (grads.empty()) grads.assign(model.mlp->num_params(), 0.0f);
    Matrix d_input;
    model.mlp->Backward(cache, d_out, grads.data(), trainable_encoding ? &d_input : nullptr);
    if (trainable_encoding) d_encoded.middleCols(begin, count) = d_input;
  });
  const double loss = losses.combine(std::plus<double>()) / (static_cast<double>(n) * channels);
  if (!std::isfinite(loss)) throw std::runtime_error("the training loss is not finite");
  std::vector<float> total(model.mlp->num_params(), 0.0f);
  for (const auto& grads : mlp_grads) {
    for (size_t k = 0; k < grads.size(); ++k) total[k] += grads[k];
  }
  model.mlp_adam->Step(model.mlp->params(), total.data());
  if (trainable_encoding) {
    model.encoding->Backward(coordinates, d_encoded);  // its gradient is zero: the last sparse step zeroed it
    model.encoding_adam->StepSparse(model.encoding->params(), model.encoding->grads(), model.encoding->touched());
  }
  return loss;
}

}  // namespace

void ImageFitOptions::Check() const {
  CheckField(*this, time_budget, time_budget >= 0, "must be 0 (no limit) or positive");
  CheckField(*this, max_steps, max_steps >= 0, "must be 0 (no limit) or positive");
  CheckField(*this, time_budget, time_budget > 0 || max_steps > 0, "must be positive when fit.max_steps is 0 (no end)");
  CheckField(*this, batch_size, batch_size >= 1 && batch_size <= (1 << 24), "must be in 1..16777216");
  CheckField(*this, learning_rate, learning_rate > 0 && learning_rate < 10, "must be in (0, 10)");
  CheckField(*this, width, width >= 0 && width <= 4096, "must be 0 (default) to 4096");
  CheckField(*this, depth, depth >= 0 && depth <= 32, "must be 0 (default) to 32");
  CheckField(*this, pe_levels, pe_levels >= 0 && pe_levels <= 20, "must be 0 to 20");
  CheckField(*this, hash_levels, hash_levels >= 1 && hash_levels <= 32, "must be 1 to 32");
  CheckField(*this, hash_log2_table_size, hash_log2_table_size >= 4 && hash_log2_table_size <= 24, "must be 4 to 24");
  CheckField(*this, hash_finest_resolution, hash_finest_resolution >= 0, "must be 0 (image size) or positive");
  CheckField(*this, eval_interval, eval_interval > 0, "must be positive");
  SnapshotSteps();
}

std::vector<int> ImageFitOptions::SnapshotSteps() const {
  std::vector<int> steps;
  std::stringstream list(snapshot_steps);
  std::string item;
  while (std::getline(list, item, ',')) {
    if (item.empty()) continue;
    size_t used = 0;
    int step = -1;
    try {
      step = std::stoi(item, &used);
    } catch (const std::exception&) {
    }
    CheckField(*this, snapshot_steps, used == item.size() && step > 0,
               "must be positive step numbers separated by commas");
    steps.push_back(step);
  }
  std::sort(steps.begin(), steps.end());
  return steps;
}

FloatImage LoadImageForFit(const std::filesystem::path& path, FitAlpha alpha_mode) {
  ReadImageResult read = ReadImage(path);
  if (!read.ok()) throw std::invalid_argument("cannot use '" + path.string() + "' as an image: " + read.error);
  const OIIO::ImageSpec& spec = read.image.spec();
  const int alpha = spec.alpha_channel >= 0 ? spec.alpha_channel
                                            : (spec.nchannels == 2 || spec.nchannels == 4 ? spec.nchannels - 1 : -1);
  const int colours = alpha >= 0 ? spec.nchannels - 1 : std::min(spec.nchannels, 3);
  FloatImage image{spec.width, spec.height, colours == 1 ? 1 : 3, {}};
  std::vector<float> all(static_cast<size_t>(spec.width) * spec.height * spec.nchannels);
  read.image.get_pixels(OIIO::ROI::All(), OIIO::TypeDesc::FLOAT, all.data());
  image.pixels.resize(static_cast<size_t>(spec.width) * spec.height * image.channels);
  for (size_t p = 0; p < static_cast<size_t>(spec.width) * spec.height; ++p) {
    const float* in = all.data() + p * spec.nchannels;
    const float a = alpha >= 0 && alpha_mode == FitAlpha::kComposite ? std::clamp(in[alpha], 0.0f, 1.0f) : 1.0f;
    for (int c = 0; c < image.channels; ++c) {
      const float value = std::clamp(in[std::min(c, colours - 1)], 0.0f, 1.0f);
      image.pixels[p * image.channels + c] = a * value + (1 - a);  // over white
    }
  }
  return image;
}

ImageFitResult FitImage(const ImageFitOptions& options, const FloatImage& target, const FitObserver& observer) {
  options.Check();
  FlushDenormalsOnThisThread();
  Model model = MakeModel(options, target);
  ImageFitResult result;
  result.model_config = {{"encoding", model.encoding->Config()}, {"network", model.mlp->config().ToJson()}};

  std::mt19937_64 random(options.seed);
  const uint32_t num_pixels = static_cast<uint32_t>(target.width * target.height);
  std::uniform_int_distribution<uint32_t> pick(0, num_pixels - 1);
  std::vector<uint32_t> eval_pixels;
  if (num_pixels <= kMaxEvalPixels) {
    for (uint32_t i = 0; i < num_pixels; ++i) eval_pixels.push_back(i);
  } else {
    for (size_t i = 0; i < kMaxEvalPixels; ++i) eval_pixels.push_back(pick(random));
  }
  const std::vector<int> snapshot_steps = options.SnapshotSteps();
  auto next_snapshot = snapshot_steps.begin();

  tbb::enumerable_thread_specific<std::vector<float>> mlp_grads;
  std::vector<uint32_t> batch(options.batch_size);
  double train_seconds = 0, next_eval = 0;
  int step = 0;
  const auto evaluate = [&] {
    const FitCurvePoint point{train_seconds, step, PsnrOfPixels(model, target, eval_pixels)};
    result.curve.push_back(point);
    if (observer) observer(point);
  };
  evaluate();
  while ((options.max_steps == 0 || step < options.max_steps) &&
         (options.time_budget == 0 || train_seconds < options.time_budget)) {
    const auto start = std::chrono::steady_clock::now();
    for (uint32_t& pixel : batch) pixel = pick(random);
    TrainStep(model, target, batch, mlp_grads);
    ++step;
    train_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (next_snapshot != snapshot_steps.end() && *next_snapshot == step) {
      result.snapshots.emplace_back(step, Reconstruct(model, target));
      ++next_snapshot;
    }
    if (train_seconds >= next_eval + options.eval_interval) {
      next_eval = train_seconds;
      evaluate();
    }
  }
  if (result.curve.back().step != step) evaluate();
  result.steps = step;
  result.train_seconds = train_seconds;
  result.reconstruction = Reconstruct(model, target);
  result.psnr = Psnr(result.reconstruction, target);
  return result;
}

}  // namespace p2n

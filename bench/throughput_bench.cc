// Throughput of the ngp field's MLPs against this machine's dense matrix-multiply speed, measured in one run:
// an Eigen single-precision GEMM of comparable shape (64 x 64 times 64 x N) and a large square one, then the
// density and colour MLPs' forward + backward on N samples (FLOPs counted from their layer sizes), then the
// whole field (hash grid included) and the hash grid alone, for the grid of NgpFieldConfig and those of the default
// and quality presets, and the same for the planes (train.field planes) of the default preset. Uses the TBB threads
// given (default: all cores) by splitting N. Usage: throughput_bench [SAMPLES [REPEATS]]

#include <tbb/parallel_for.h>
#include <Eigen/Core>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <utility>
#include <vector>

#include "nerf/encoding.h"
#include "nerf/heap.h"
#include "nerf/ngp_field.h"
#include "stages/fitting/train_presets.h"

namespace {

using Clock = std::chrono::steady_clock;

template <class F>
double MedianSeconds(int repeats, F work) {
  std::vector<double> times;
  for (int r = 0; r < repeats; ++r) {
    const auto start = Clock::now();
    work();
    times.push_back(std::chrono::duration<double>(Clock::now() - start).count());
  }
  std::sort(times.begin(), times.end());
  return times[times.size() / 2];
}

// FLOPs of forward + backward of one MLP per sample: 2 per multiply-add forward, twice that backward (weight
// and input gradients).
double MlpFlops(const p2n::MlpConfig& c) {
  double macs = 0;
  int in = c.inputs;
  for (int l = 0; l <= c.hidden_layers; ++l) {
    const int out = l == c.hidden_layers ? c.outputs : c.width;
    macs += double(in) * out;
    in = out;
  }
  return 2 * macs * 3;
}

// A batch of samples as the trainer steps on: `chunks` chunks of `per_chunk`, and the whole of them.
struct Batch {
  int chunks = 64, per_chunk = 0, repeats = 7;
  std::vector<Eigen::MatrixXf> positions, directions;
  Eigen::MatrixXf all_positions;

  Batch(int n, int repeat_count) : per_chunk(n / chunks), repeats(repeat_count), positions(chunks), directions(chunks) {
    all_positions.resize(3, per_chunk * chunks);
    for (int c = 0; c < chunks; ++c) {
      positions[c] = (Eigen::MatrixXf::Random(3, per_chunk).array() * 0.5f + 0.5f).matrix();
      directions[c] = Eigen::MatrixXf::Random(3, per_chunk).colwise().normalized();
      all_positions.middleCols(c * per_chunk, per_chunk) = positions[c];
    }
  }
  double samples() const { return double(per_chunk) * chunks; }
};

// GFLOP/s of a dense GEMM of the MLP's shape, chunked over threads like the trainer, and of one large GEMM.
std::pair<double, double> GemmRates(const Batch& batch) {
  const Eigen::MatrixXf w = Eigen::MatrixXf::Random(64, 64);
  std::vector<Eigen::MatrixXf> inputs(batch.chunks, Eigen::MatrixXf::Random(64, batch.per_chunk)),
      outputs(batch.chunks);
  const double gemm_seconds = MedianSeconds(
      batch.repeats, [&] { tbb::parallel_for(0, batch.chunks, [&](int c) { outputs[c].noalias() = w * inputs[c]; }); });
  const Eigen::MatrixXf a = Eigen::MatrixXf::Random(2048, 2048), b = Eigen::MatrixXf::Random(2048, 2048);
  Eigen::MatrixXf product(2048, 2048);
  const double big_seconds = MedianSeconds(3, [&] { product.noalias() = a * b; });
  return {2.0 * 64 * 64 * batch.samples() / gemm_seconds / 1e9, 2.0 * 2048 * 2048 * 2048 / big_seconds / 1e9};
}

// The MLPs alone: forward and backward of both networks on the encoded inputs.
double MlpSeconds(p2n::NgpField<float>& field, const Batch& batch) {
  std::vector<std::vector<float>> d_dense(batch.chunks, std::vector<float>(field.num_dense_params()));
  return MedianSeconds(batch.repeats, [&] {
    tbb::parallel_for(0, batch.chunks, [&](int c) {
      Eigen::MatrixXf density_out, rgb, d_in;
      p2n::Mlp<float>::Cache density_cache, colour_cache;
      const Eigen::MatrixXf encoded = Eigen::MatrixXf::Constant(32, batch.per_chunk, 0.01f);
      const Eigen::MatrixXf colour_in = Eigen::MatrixXf::Constant(31, batch.per_chunk, 0.1f);
      field.density_mlp().Forward(encoded, &density_out, &density_cache);
      field.colour_mlp().Forward(colour_in, &rgb, &colour_cache);
      field.colour_mlp().Backward(colour_cache, rgb, d_dense[c].data(), &d_in);
      field.density_mlp().Backward(density_cache, density_out, d_dense[c].data(), &d_in);
    });
  });
}

// The whole field as the trainer runs it: the grid's encoding of the whole batch, then chunk by chunk the networks
// and spherical harmonics, forward and backward, then the grid's backward pass over the whole batch (its gradient
// accumulates over the repeats, as nothing here consumes it).
double FieldSeconds(p2n::NgpField<float>& field, const Batch& batch) {
  std::vector<std::vector<float>> d_params(batch.chunks, std::vector<float>(field.num_dense_params()));
  std::vector<p2n::RadianceField<float>::Cache> caches(batch.chunks);
  return MedianSeconds(batch.repeats, [&] {
    Eigen::MatrixXf encoded, d_encoded(field.encoding().output_dims(), batch.all_positions.cols());
    field.encoding().Forward(batch.all_positions, &encoded);
    tbb::parallel_for(0, batch.chunks, [&](int c) {
      Eigen::MatrixXf density, rgb, d_chunk;
      field.ForwardEncoded(batch.positions[c], encoded.middleCols(c * batch.per_chunk, batch.per_chunk),
                           batch.directions[c], &density, &rgb, &caches[c]);
      field.Backward(caches[c], density, rgb, d_params[c].data(), &d_chunk);
      d_encoded.middleCols(c * batch.per_chunk, batch.per_chunk) = d_chunk;
    });
    field.encoding().Backward(batch.all_positions, d_encoded);
  });
}

// The encoding alone, as the trainer calls it (the whole batch at once): forward and backward seconds.
std::pair<double, double> GridSeconds(p2n::Encoding<float>& grid, const Batch& batch) {
  Eigen::MatrixXf encoded;
  const Eigen::MatrixXf d_grid = Eigen::MatrixXf::Random(grid.output_dims(), batch.all_positions.cols());
  return std::pair(MedianSeconds(batch.repeats, [&] { grid.Forward(batch.all_positions, &encoded); }),
                   MedianSeconds(batch.repeats, [&] { grid.Backward(batch.all_positions, d_grid); }));
}

// The field's grid as NgpFieldConfig has it, as the default preset trains it (a table of 2^17 entries a level) and as
// the quality preset does (8 levels of 4 features); then the planes (train.field planes) as the default preset trains
// them.
void PrintEncodings(const p2n::NgpFieldConfig& config, const Batch& batch, double mlp_seconds) {
  const double samples = batch.samples();
  for (const auto& [name, layout] : {std::pair("NgpFieldConfig", config.grid),
                                     std::pair("default preset", p2n::PresetFor(p2n::PresetName::kDefault).grid),
                                     std::pair("quality preset", p2n::PresetFor(p2n::PresetName::kQuality).grid)}) {
    p2n::NgpFieldConfig measured_config = config;
    measured_config.grid = layout;
    p2n::NgpField<float> measured(measured_config, 1);
    const double whole = FieldSeconds(measured, batch);
    const auto [forward, backward] = GridSeconds(measured.encoding(), batch);
    std::printf(
        "%-15s grid %2dx%d, 2^%d: whole field fwd+bwd %.2f M samples/s (MLPs %.0f%% of its time); grid "
        "forward %.2f, backward %.2f M samples/s\n",
        name, layout.levels, layout.features_per_level, layout.log2_table_size, samples / whole / 1e6,
        100 * mlp_seconds / whole, samples / forward / 1e6, samples / backward / 1e6);
  }
  p2n::NgpFieldConfig planes_config = config;
  planes_config.planes = p2n::PlanesFor(p2n::SceneSpace::kForward);
  p2n::NgpField<float> planes(planes_config, 1);
  const double whole = FieldSeconds(planes, batch);
  const auto [forward, backward] = GridSeconds(planes.encoding(), batch);
  std::printf(
      "planes %d x %d, %d^2 x %d: whole field fwd+bwd %.2f M samples/s (MLPs %.0f%% of its time); planes forward "
      "%.2f, backward %.2f M samples/s\n",
      planes_config.planes->levels, planes_config.planes->features_per_level, planes_config.planes->finest_resolution,
      planes_config.planes->depth_resolution, samples / whole / 1e6, 100 * mlp_seconds / whole, samples / forward / 1e6,
      samples / backward / 1e6);
}

}  // namespace

int main(int argc, char** argv) {
  p2n::KeepFreedBlocksInHeap();  // as photo2nerf does
  const Batch batch(argc > 1 ? std::atoi(argv[1]) : 65536, argc > 2 ? std::atoi(argv[2]) : 7);
  const auto [gemm_gflops, big_gflops] = GemmRates(batch);
  p2n::NgpFieldConfig config;
  p2n::NgpField<float> field(config, 1);
  const double mlp_flops = MlpFlops(field.density_mlp().config()) + MlpFlops(field.colour_mlp().config());
  const double mlp_seconds = MlpSeconds(field, batch);
  const double samples = batch.samples();
  std::printf("samples per batch                 %.0f\n", samples);
  std::printf("GEMM 64x64 * 64xN (chunked)       %.1f GFLOP/s\n", gemm_gflops);
  std::printf("GEMM 2048^3                       %.1f GFLOP/s\n", big_gflops);
  std::printf("MLPs fwd+bwd                      %.1f GFLOP/s = %.0f%% of the chunked GEMM, %.2f M samples/s\n",
              mlp_flops * samples / mlp_seconds / 1e9, 100 * mlp_flops * samples / mlp_seconds / 1e9 / gemm_gflops,
              samples / mlp_seconds / 1e6);
  std::printf("MLP FLOPs per sample (fwd+bwd)    %.0f\n", mlp_flops);
  PrintEncodings(config, batch, mlp_seconds);
  return 0;
}

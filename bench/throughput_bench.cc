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

}  // namespace

int main(int argc, char** argv) {
  p2n::KeepFreedBlocksInHeap();  // as photo2nerf does
  const int n = argc > 1 ? std::atoi(argv[1]) : 65536;
  const int repeats = argc > 2 ? std::atoi(argv[2]) : 7;
  const int chunks = 64;
  const int per_chunk = n / chunks;

  // Dense GEMM of the MLP's shape, chunked over threads like the trainer.
  const Eigen::MatrixXf w = Eigen::MatrixXf::Random(64, 64);
  std::vector<Eigen::MatrixXf> inputs(chunks, Eigen::MatrixXf::Random(64, per_chunk)), outputs(chunks);
  const double gemm_seconds = MedianSeconds(
      repeats, [&] { tbb::parallel_for(0, chunks, [&](int c) { outputs[c].noalias() = w * inputs[c]; }); });
  const double gemm_gflops = 2.0 * 64 * 64 * per_chunk * chunks / gemm_seconds / 1e9;
  const Eigen::MatrixXf a = Eigen::MatrixXf::Random(2048, 2048), b = Eigen::MatrixXf::Random(2048, 2048);
  Eigen::MatrixXf product(2048, 2048);
  const double big_seconds = MedianSeconds(3, [&] { product.noalias() = a * b; });
  const double big_gflops = 2.0 * 2048 * 2048 * 2048 / big_seconds / 1e9;

  p2n::NgpFieldConfig config;
  p2n::NgpField<float> field(config, 1);
  const double mlp_flops = MlpFlops(field.density_mlp().config()) + MlpFlops(field.colour_mlp().config());
  std::vector<Eigen::MatrixXf> positions(chunks), directions(chunks);
  for (int c = 0; c < chunks; ++c) {
    positions[c] = (Eigen::MatrixXf::Random(3, per_chunk).array() * 0.5f + 0.5f).matrix();
    directions[c] = Eigen::MatrixXf::Random(3, per_chunk).colwise().normalized();
  }
  std::vector<std::vector<float>> d_dense(chunks, std::vector<float>(field.num_dense_params()));
  // MLPs alone: forward and backward of both networks on the encoded inputs.
  std::vector<p2n::RadianceField<float>::Cache> caches(chunks);
  const double mlp_seconds = MedianSeconds(repeats, [&] {
    tbb::parallel_for(0, chunks, [&](int c) {
      Eigen::MatrixXf density_out, rgb, d_in;
      p2n::Mlp<float>::Cache density_cache, colour_cache;
      const Eigen::MatrixXf encoded = Eigen::MatrixXf::Constant(32, per_chunk, 0.01f);
      const Eigen::MatrixXf colour_in = Eigen::MatrixXf::Constant(31, per_chunk, 0.1f);
      field.density_mlp().Forward(encoded, &density_out, &density_cache);
      field.colour_mlp().Forward(colour_in, &rgb, &colour_cache);
      field.colour_mlp().Backward(colour_cache, rgb, d_dense[c].data(), &d_in);
      field.density_mlp().Backward(density_cache, density_out, d_dense[c].data(), &d_in);
    });
  });
  // The whole field as the trainer runs it: the grid's encoding of the whole batch, then chunk by chunk the
  // networks and spherical harmonics, forward and backward, then the grid's backward pass over the whole batch (its
  // gradient accumulates over the repeats, as nothing here consumes it).
  Eigen::MatrixXf all_positions(3, per_chunk * chunks);
  for (int c = 0; c < chunks; ++c) all_positions.middleCols(c * per_chunk, per_chunk) = positions[c];
  const auto field_seconds = [&](p2n::NgpField<float>& measured) {
    std::vector<std::vector<float>> d_params(chunks, std::vector<float>(measured.num_dense_params()));
    return MedianSeconds(repeats, [&] {
      Eigen::MatrixXf encoded, d_encoded(measured.encoding().output_dims(), all_positions.cols());
      measured.encoding().Forward(all_positions, &encoded);
      tbb::parallel_for(0, chunks, [&](int c) {
        Eigen::MatrixXf density, rgb, d_chunk;
        measured.ForwardEncoded(positions[c], encoded.middleCols(c * per_chunk, per_chunk), directions[c], &density,
                                &rgb, &caches[c]);
        measured.Backward(caches[c], density, rgb, d_params[c].data(), &d_chunk);
        d_encoded.middleCols(c * per_chunk, per_chunk) = d_chunk;
      });
      measured.encoding().Backward(all_positions, d_encoded);
    });
  };
  // The encoding alone, as the trainer calls it (the whole batch at once).
  const auto grid_seconds = [&](p2n::Encoding<float>& grid) {
    Eigen::MatrixXf encoded;
    const Eigen::MatrixXf d_grid = Eigen::MatrixXf::Random(grid.output_dims(), all_positions.cols());
    return std::pair(MedianSeconds(repeats, [&] { grid.Forward(all_positions, &encoded); }),
                     MedianSeconds(repeats, [&] { grid.Backward(all_positions, d_grid); }));
  };
  const double samples = double(per_chunk) * chunks;
  std::printf("samples per batch                 %.0f\n", samples);
  std::printf("GEMM 64x64 * 64xN (chunked)       %.1f GFLOP/s\n", gemm_gflops);
  std::printf("GEMM 2048^3                       %.1f GFLOP/s\n", big_gflops);
  std::printf("MLPs fwd+bwd                      %.1f GFLOP/s = %.0f%% of the chunked GEMM, %.2f M samples/s\n",
              mlp_flops * samples / mlp_seconds / 1e9, 100 * mlp_flops * samples / mlp_seconds / 1e9 / gemm_gflops,
              samples / mlp_seconds / 1e6);
  std::printf("MLP FLOPs per sample (fwd+bwd)    %.0f\n", mlp_flops);
  // The field's grid as NgpFieldConfig has it, as the default preset trains it (a table of 2^17 entries a level)
  // and as the quality preset does (8 levels of 4 features).
  for (const auto& [name, layout] : {std::pair("NgpFieldConfig", config.grid),
                                     std::pair("default preset", p2n::PresetFor(p2n::PresetName::kDefault).grid),
                                     std::pair("quality preset", p2n::PresetFor(p2n::PresetName::kQuality).grid)}) {
    p2n::NgpFieldConfig measured_config = config;
    measured_config.grid = layout;
    p2n::NgpField<float> measured(measured_config, 1);
    const double whole = field_seconds(measured);
    const auto [forward, backward] = grid_seconds(measured.encoding());
    std::printf(
        "%-15s grid %2dx%d, 2^%d: whole field fwd+bwd %.2f M samples/s (MLPs %.0f%% of its time); grid "
        "forward %.2f, backward %.2f M samples/s\n",
        name, layout.levels, layout.features_per_level, layout.log2_table_size, samples / whole / 1e6,
        100 * mlp_seconds / whole, samples / forward / 1e6, samples / backward / 1e6);
  }
  // The planes (train.field planes) as the default preset trains them.
  p2n::NgpFieldConfig planes_config = config;
  planes_config.planes = p2n::PlanesFor(p2n::SceneSpace::kForward);
  p2n::NgpField<float> planes(planes_config, 1);
  const double whole = field_seconds(planes);
  const auto [forward, backward] = grid_seconds(planes.encoding());
  std::printf(
      "planes %d x %d, %d^2 x %d: whole field fwd+bwd %.2f M samples/s (MLPs %.0f%% of its time); planes forward "
      "%.2f, backward %.2f M samples/s\n",
      planes_config.planes->levels, planes_config.planes->features_per_level, planes_config.planes->finest_resolution,
      planes_config.planes->depth_resolution, samples / whole / 1e6, 100 * mlp_seconds / whole, samples / forward / 1e6,
      samples / backward / 1e6);
  return 0;
}

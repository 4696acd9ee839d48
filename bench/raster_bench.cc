// The splat rasterizer's training step: times Forward and Backward on a workspace's training views with its
// 35_splat/splats.ply, the loss's gradient that of L1 against the photo, and prints the median seconds of each a
// view (REPEATS of each view) and the gradients' sums (to compare two builds' gradients: they agree to rounding).
// Usage: raster_bench WORKSPACE [VIEWS (0: all)] [REPEATS]

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "formats/output_frame.h"
#include "nerf/heap.h"
#include "splat/rasterizer.h"
#include "splat/splat_ply.h"
#include "stages/stage_reports.h"
#include "stages/training_data.h"

namespace {

double Median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

double Seconds(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

int main(int argc, char** argv) {
  p2n::KeepFreedBlocksInHeap();  // as photo2nerf does
  if (argc < 2) {
    std::fprintf(stderr, "usage: raster_bench WORKSPACE [VIEWS] [REPEATS]\n");
    return 1;
  }
  const std::filesystem::path ws = argv[1];
  const size_t max_views = argc > 2 ? std::atoi(argv[2]) : 0;
  const int repeats = argc > 3 ? std::max(1, std::atoi(argv[3])) : 3;
  const p2n::ImportedDataset poses = p2n::LoadTransformsJson(ws / "20_poses" / "transforms.json", ws);
  p2n::TrainingData data = p2n::LoadTrainingData(poses);
  if (max_views > 0 && data.train.size() > max_views) data.train.resize(max_views);
  const p2n::SplatReport report = p2n::SplatReport::Read(ws / "35_splat" / "splat_report.json");
  const p2n::OutputFrame frame = p2n::MakeOutputFrame(report.frame, poses);
  const p2n::Gaussians<float> gaussians = p2n::ReadSplatPly(ws / "35_splat" / "splats.ply");
  p2n::RasterOptions options;
  options.projection.near = report.near;
  for (int c = 0; c < 3; ++c) options.background[c] = report.background[c];

  std::vector<double> forward, backward, entries;
  double mean_sum = 0, opacity_sum = 0, colour_sum = 0;
  p2n::Rasterizer<float> rasterizer;
  p2n::Gaussians<float> grads;
  grads.sh_degree = gaussians.sh_degree;
  grads.Resize(gaussians.size());
  for (p2n::TrainView& view : data.train) {
    view.camera.world_from_cam = frame.Pose(view.camera.world_from_cam);
    const p2n::FloatImage photo = p2n::PhotoOnBackground(view, report.background);
    for (int r = 0; r < repeats; ++r) {
      auto start = std::chrono::steady_clock::now();
      rasterizer.Forward(gaussians, view.camera, options);
      forward.push_back(Seconds(start));
      entries.push_back(static_cast<double>(rasterizer.tile_entries()));
      std::vector<float> d_rgb(rasterizer.rgb().size());
      for (size_t i = 0; i < d_rgb.size(); ++i) {
        d_rgb[i] = (rasterizer.rgb()[i] > photo.pixels[i] ? 1.0f : -1.0f) / static_cast<float>(d_rgb.size());
      }
      grads.SetZero();
      start = std::chrono::steady_clock::now();
      rasterizer.Backward(d_rgb, &grads);
      backward.push_back(Seconds(start));
      if (r > 0) continue;
      for (const float g : grads.positions) mean_sum += std::abs(g);
      for (const float g : grads.opacity_logits) opacity_sum += std::abs(g);
      for (const float g : grads.sh_dc) colour_sum += std::abs(g);
    }
  }
  std::printf("%zu splats, %zu views %dx%d, %.0f tile entries: forward %.4f s, backward %.4f s a view (medians)\n",
              gaussians.size(), data.train.size(), data.train[0].camera.width, data.train[0].camera.height,
              Median(entries), Median(forward), Median(backward));
  std::printf("sums of |gradient|: means %.6e, opacities %.6e, colours %.6e\n", mean_sum, opacity_sum, colour_sum);
  return 0;
}

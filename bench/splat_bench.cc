// Rendering from splats: renders a workspace's held-out views from 35_splat/splats.ply on the CPU and prints the
// seconds per view (median of REPEATS renders of each view), frames per second and PSNR against the photos;
// with SAVE_DIR, writes the renders and the photos there as PNGs.
// With SPLIT train, the training views instead of the held-out ones. With FORMAT spz, the splats as they read back
// from SPZ (splat/spz.h), and the sizes of both files.
// Usage: splat_bench WORKSPACE [VIEWS (0: all)] [REPEATS] [SAVE_DIR (- for none)] [SPLIT] [FORMAT]

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>

#include "base/file_util.h"
#include "formats/output_frame.h"
#include "nerf/heap.h"
#include "splat/rasterizer.h"
#include "splat/splat_ply.h"
#include "splat/spz.h"
#include "stages/stage_reports.h"
#include "stages/training_data.h"

int main(int argc, char** argv) {
  p2n::KeepFreedBlocksInHeap();  // as photo2nerf does
  if (argc < 2) {
    std::fprintf(stderr, "usage: splat_bench WORKSPACE [VIEWS] [REPEATS] [SAVE_DIR] [SPLIT] [FORMAT]\n");
    return 1;
  }
  const std::filesystem::path ws = argv[1];
  const size_t max_views = argc > 2 ? std::atoi(argv[2]) : 0;
  const int repeats = argc > 3 ? std::max(1, std::atoi(argv[3])) : 3;
  const std::filesystem::path transforms = ws / "20_poses" / "transforms.json";
  const p2n::ImportedDataset poses = p2n::LoadTransformsJson(transforms, ws);
  p2n::TrainingData data = p2n::LoadTrainingData(poses);
  if (argc > 5 && std::string(argv[5]) == "train") data.heldout = data.train;
  if (max_views > 0 && data.heldout.size() > max_views) data.heldout.resize(max_views);
  const p2n::SplatReport report = p2n::SplatReport::Read(ws / "35_splat" / "splat_report.json");
  const p2n::OutputFrame frame = p2n::MakeOutputFrame(report.frame, poses);
  p2n::Gaussians<float> gaussians = p2n::ReadSplatPly(ws / "35_splat" / "splats.ply");
  if (argc > 6 && std::string(argv[6]) == "spz") {
    const std::vector<char> spz = p2n::SpzBytes(gaussians);
    const size_t ply = std::filesystem::file_size(ws / "35_splat" / "splats.ply");
    std::printf("splats.ply %.2f MB (%.1f bytes a splat), SPZ %.2f MB (%.1f bytes a splat, %.3f of the PLY)\n",
                ply / 1e6, double(ply) / gaussians.size(), spz.size() / 1e6, double(spz.size()) / gaussians.size(),
                double(spz.size()) / ply);
    gaussians = p2n::ParseSpz(std::string(spz.begin(), spz.end()), "splats.spz");
  }
  const std::array<float, 3> background = report.background;  // the learnt one behind photos without alpha
  const double near = report.near;

  std::vector<double> seconds;
  double psnr = 0;
  for (size_t v = 0; v < data.heldout.size(); ++v) {
    p2n::TrainView& view = data.heldout[v];
    view.camera.world_from_cam = frame.Pose(view.camera.world_from_cam);
    p2n::RasterOptions options;
    options.projection.near = near;
    for (int c = 0; c < 3; ++c) options.background[c] = background[c];
    p2n::Rasterizer<float> rasterizer;
    std::vector<double> times;
    for (int r = 0; r < repeats; ++r) {
      const auto start = std::chrono::steady_clock::now();
      rasterizer.Forward(gaussians, view.camera, options);
      times.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }
    std::nth_element(times.begin(), times.begin() + times.size() / 2, times.end());
    seconds.push_back(times[times.size() / 2]);
    const p2n::FloatImage image{view.camera.width, view.camera.height, 3, rasterizer.rgb()};
    const p2n::FloatImage photo = p2n::PhotoOnBackground(view, background);
    psnr += p2n::Psnr(image, photo) / data.heldout.size();
    if (argc > 4 && std::string(argv[4]) != "-") {
      const std::filesystem::path dir = argv[4];
      p2n::SaveFloatImage(image, dir / (std::to_string(v) + ".png"));
      p2n::SaveFloatImage(photo, dir / (std::to_string(v) + "_photo.png"));
    }
  }
  double total = 0;
  for (const double s : seconds) total += s;
  std::printf("%zu splats, %zu views %dx%d: %.4f s per view (%.1f frames/s), %.3f s in all, %.2f dB\n",
              gaussians.size(), seconds.size(), data.heldout[0].camera.width, data.heldout[0].camera.height,
              total / seconds.size(), seconds.size() / total, total, psnr);
  return 0;
}

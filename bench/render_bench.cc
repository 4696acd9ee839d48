// Rendering error against render time (a work-precision diagram) for one trained workspace: renders the held-out
// views with sample spacings from coarse to fine, (a) as the renderer does (occupancy grid + early termination),
// (b) without early termination, (c) without either (every cell occupied). Error is PSNR against a very fine
// reference render (spacing / 8, no termination) and against the photos. Writes OUT.csv and OUT.png.
// With --speed instead of OUT: renders the held-out views as the render stage does and prints the seconds per
// view, samples per ray, samples (field evaluations) per second and the PSNR against the photos, at the render
// stage's sample spacing or STEP_SCALE times the model's march step.
// Usage: render_bench WORKSPACE OUT|--speed [VIEWS] [STEP_SCALE]

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>

#include "nerf/plot.h"
#include "nerf/renderer.h"
#include "stages/training_data.h"

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: render_bench WORKSPACE OUT|--speed [VIEWS] [STEP_SCALE]\n");
    return 1;
  }
  const std::filesystem::path ws = argv[1];
  const std::string out = argv[2];
  const size_t max_views = argc > 3 ? std::atoi(argv[3]) : 3;
  p2n::TrainingData data = p2n::LoadTrainingData(p2n::LoadTransformsJson(ws / "20_poses" / "transforms.json", ws));
  if (data.heldout.size() > max_views) data.heldout.resize(max_views);
  const p2n::NerfModel model = p2n::LoadModel(ws / "30_train" / "model.bin");
  if (out == "--speed") {
    p2n::RenderOptions options;
    options.step_scale = argc > 4 ? std::atof(argv[4]) : 0.0;
    p2n::RenderStats total;
    double psnr = 0;
    for (const p2n::TrainView& view : data.heldout) {
      const p2n::RenderedView rendered = p2n::RenderView(model, view.camera, view.near, view.far, options);
      total.seconds += rendered.stats.seconds;
      total.rays += rendered.stats.rays;
      total.samples_evaluated += rendered.stats.samples_evaluated;
      psnr += p2n::Psnr(rendered.rgb, p2n::PhotoOnBackground(view, model.background)) / data.heldout.size();
    }
    std::printf("%zu views: %.3f s per view, %.2f samples per ray, %.2f M samples/s, %.2f M rays/s, %.2f dB\n",
                data.heldout.size(), total.seconds / data.heldout.size(), double(total.samples_evaluated) / total.rays,
                total.samples_evaluated / total.seconds / 1e6, total.rays / total.seconds / 1e6, psnr);
    return 0;
  }
  p2n::NerfModel dense = p2n::LoadModel(ws / "30_train" / "model.bin");
  dense.occupancy.MarkAllOccupied();

  std::vector<p2n::FloatImage> reference, photos;
  p2n::RenderOptions fine;
  fine.step_scale = 0.125;
  fine.min_transmittance = 0;
  for (const p2n::TrainView& view : data.heldout) {
    reference.push_back(p2n::RenderView(model, view.camera, view.near, view.far, fine).rgb);
    photos.push_back(p2n::PhotoOnBackground(view, model.background));
  }
  std::ofstream csv(out + ".csv");
  csv << "method,step_scale,seconds_per_frame,samples_per_ray,psnr_vs_reference,psnr_vs_photos\n";
  std::vector<p2n::PlotSeries> series;
  struct Method {
    const char* name;
    const p2n::NerfModel* model;
    float min_transmittance;
  };
  for (const Method& method :
       {Method{"occupancy + early termination", &model, 1e-4f}, Method{"occupancy, no termination", &model, 0.0f},
        Method{"no occupancy, no termination", &dense, 0.0f}}) {
    p2n::PlotSeries line{method.name, {}, {}};
    for (const double scale : {8.0, 4.0, 2.0, 1.0, 0.5, 0.25}) {
      p2n::RenderOptions options;
      options.step_scale = scale;
      options.min_transmittance = method.min_transmittance;
      double seconds = 0, vs_reference = 0, vs_photos = 0, samples = 0, rays = 0;
      for (size_t v = 0; v < data.heldout.size(); ++v) {
        const p2n::TrainView& view = data.heldout[v];
        const p2n::RenderedView rendered = p2n::RenderView(*method.model, view.camera, view.near, view.far, options);
        seconds += rendered.stats.seconds;
        samples += rendered.stats.samples_evaluated;
        rays += rendered.stats.rays;
        vs_reference += p2n::Psnr(rendered.rgb, reference[v]);
        vs_photos += p2n::Psnr(rendered.rgb, photos[v]);
      }
      const double n = data.heldout.size();
      csv << method.name << "," << scale << "," << seconds / n << "," << samples / rays << "," << vs_reference / n
          << "," << vs_photos / n << "\n";
      std::printf("%-30s step x%-5g %8.3f s/frame %7.1f samples/ray  %6.2f dB vs reference  %6.2f dB vs photos\n",
                  method.name, scale, seconds / n, samples / rays, vs_reference / n, vs_photos / n);
      line.x.push_back(seconds / n);
      line.y.push_back(vs_reference / n);
    }
    series.push_back(line);
  }
  p2n::WriteLinePlot(out + ".png",
                     {"rendering: error against time", "seconds per frame", "PSNR vs fine reference (dB)"}, series);
  return 0;
}

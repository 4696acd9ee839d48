// Rendering error against render time (a work-precision diagram) for one trained workspace: renders the held-out
// views with sample spacings from coarse to fine, (a) as the renderer does (occupancy grid + early termination),
// (b) without early termination, (c) without either (every cell occupied). Error is PSNR against a very fine
// reference render (spacing / 8, no termination) and against the photos. Writes OUT.csv and OUT.png.
// With --speed instead of OUT: renders the held-out views as the render stage does and prints the seconds per
// view, samples per ray, samples (field evaluations) per second and the PSNR against the photos, at the render
// stage's sample spacing or STEP_SCALE times the model's march step, rays stopped below MIN_TRANSMITTANCE (the
// renderer's default unless given); --speed-float the same with the networks' training pass (Mlp's, Eigen's
// matrix products) instead of the rendering one (RenderMlp), for comparison.
// Usage: render_bench WORKSPACE OUT|--speed|--speed-float [VIEWS] [STEP_SCALE] [MIN_TRANSMITTANCE]

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <optional>

#include "base/plot.h"
#include "nerf/heap.h"
#include "nerf/renderer.h"
#include "stages/training_data.h"

namespace {

// A field rendered with its training pass: Render() as RadianceField's default, everything else the field's.
class FloatRendering : public p2n::RadianceField<float> {
 public:
  explicit FloatRendering(std::unique_ptr<p2n::RadianceField<float>> field) : field_(std::move(field)) {}
  nlohmann::json Config() const override { return field_->Config(); }
  void Forward(const Matrix& positions, const Matrix& directions, Matrix* density, Matrix* rgb,
               Cache* cache) const override {
    field_->Forward(positions, directions, density, rgb, cache);
  }
  void Density(const Matrix& positions, Matrix* density) const override { field_->Density(positions, density); }
  void Backward(const Cache& cache, const Matrix& d_density, const Matrix& d_rgb, float* d_dense,
                Matrix* d_encoded) const override {
    field_->Backward(cache, d_density, d_rgb, d_dense, d_encoded);
  }
  std::vector<p2n::ParamBlock<float>> DenseParams() override { return field_->DenseParams(); }

 private:
  std::unique_ptr<p2n::RadianceField<float>> field_;
};

// The held-out views rendered at the workspace's settings (`float_rendering`: through FloatRendering): seconds, samples
// and PSNR.
void MeasureSpeed(p2n::NerfModel model, const p2n::TrainingData& data, bool float_rendering, double step_scale,
                  std::optional<float> min_transmittance) {
  if (float_rendering) model.field = std::make_unique<FloatRendering>(std::move(model.field));
  p2n::RenderOptions options;
  options.step_scale = step_scale;
  if (min_transmittance) options.min_transmittance = *min_transmittance;
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
}

struct Method {
  const char* name;
  const p2n::NerfModel* model;
  float min_transmittance;
};

// One method's error against time over the step scales: a CSV row and a printed line a scale, a plot series.
p2n::PlotSeries SweepMethod(const Method& method, const p2n::TrainingData& data,
                            const std::vector<p2n::FloatImage>& reference, const std::vector<p2n::FloatImage>& photos,
                            std::ofstream& csv) {
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
    csv << method.name << "," << scale << "," << seconds / n << "," << samples / rays << "," << vs_reference / n << ","
        << vs_photos / n << "\n";
    std::printf("%-30s step x%-5g %8.3f s/frame %7.1f samples/ray  %6.2f dB vs reference  %6.2f dB vs photos\n",
                method.name, scale, seconds / n, samples / rays, vs_reference / n, vs_photos / n);
    line.x.push_back(seconds / n);
    line.y.push_back(vs_reference / n);
  }
  return line;
}

}  // namespace

int main(int argc, char** argv) {
  p2n::KeepFreedBlocksInHeap();  // as photo2nerf does
  if (argc < 3) {
    std::fprintf(stderr,
                 "usage: render_bench WORKSPACE OUT|--speed|--speed-float [VIEWS] [STEP_SCALE] [MIN_TRANSMITTANCE]\n");
    return 1;
  }
  const std::filesystem::path ws = argv[1];
  const std::string out = argv[2];
  const size_t max_views = argc > 3 ? std::atoi(argv[3]) : 3;
  p2n::TrainingData data = p2n::LoadTrainingData(p2n::LoadTransformsJson(ws / "20_poses" / "transforms.json", ws));
  if (data.heldout.size() > max_views) data.heldout.resize(max_views);
  p2n::NerfModel model = p2n::LoadModel(ws / "30_train" / "model.bin");
  if (out == "--speed" || out == "--speed-float") {
    MeasureSpeed(std::move(model), data, out == "--speed-float", argc > 4 ? std::atof(argv[4]) : 0.0,
                 argc > 5 ? std::optional<float>(static_cast<float>(std::atof(argv[5]))) : std::nullopt);
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
  for (const Method& method :
       {Method{"occupancy + early termination", &model, 1e-4f}, Method{"occupancy, no termination", &model, 0.0f},
        Method{"no occupancy, no termination", &dense, 0.0f}}) {
    series.push_back(SweepMethod(method, data, reference, photos, csv));
  }
  p2n::WriteLinePlot(out + ".png",
                     {"rendering: error against time", "seconds per frame", "PSNR vs fine reference (dB)"}, series);
  return 0;
}

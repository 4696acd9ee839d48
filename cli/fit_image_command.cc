// photo2nerf fit-image: fit a neural field to one image, or sweep the seed's hyperparameters.

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "base/errors.h"
#include "base/file_util.h"
#include "base/format.h"
#include "base/plot.h"
#include "cli/cli_options.h"
#include "cli/commands.h"
#include "nerf/image_fit.h"
#include "pipeline/log.h"
#include "stages/stages.h"

namespace p2n {
namespace fs = std::filesystem;
namespace {

constexpr const char* kReportName = "fit_report.json";
constexpr double kReportTimes[] = {10, 30, 60, 120, 300, 600};
constexpr double kLogInterval = 5.0;  // seconds of training between progress lines

// The output folder must be new, empty, or an earlier fit-image output: nothing else is overwritten.
void PrepareOutputFolder(const fs::path& folder) {
  std::error_code error;
  if (fs::exists(folder) && !fs::is_directory(folder)) {
    throw UserError(format("output '{}' is a file; give a folder for the results", folder.string()));
  }
  if (fs::exists(folder) && !fs::is_empty(folder, error) && !fs::exists(folder / kReportName)) {
    throw UserError(
        format("output folder '{}' is not empty and holds no earlier fit-image results; choose a new "
               "or empty folder so that nothing of yours is overwritten",
               folder.string()));
  }
  fs::create_directories(folder, error);
  if (error) throw UserError(format("cannot create the output folder '{}': {}", folder.string(), error.message()));
}

void WriteCurve(const fs::path& path, const std::vector<FitCurvePoint>& curve) {
  std::string text = "wall_seconds,step,psnr\n";
  for (const FitCurvePoint& point : curve)
    text += format("{:.3f},{},{:.4f}\n", point.wall_seconds, point.step, point.psnr);
  WriteFileAtomic(path, text);
}

PlotSeries CurveSeries(const std::string& name, const std::vector<FitCurvePoint>& curve) {
  PlotSeries series{name, {}, {}};
  for (const FitCurvePoint& point : curve) {
    series.x.push_back(point.wall_seconds);
    series.y.push_back(point.psnr);
  }
  return series;
}

// PSNR of the last evaluation at or before each report time (what was reached within that time).
nlohmann::json PsnrAtTimes(const std::vector<FitCurvePoint>& curve) {
  nlohmann::json at = nlohmann::json::object();
  for (const double seconds : kReportTimes) {
    if (curve.back().wall_seconds < seconds) break;
    double psnr = curve.front().psnr;
    for (const FitCurvePoint& point : curve) {
      if (point.wall_seconds <= seconds) psnr = point.psnr;
    }
    at[format("{:g}", seconds)] = psnr;
  }
  return at;
}

ImageFitResult FitAndLog(const ImageFitOptions& options, const FloatImage& target, const std::string& label) {
  double next_log = 0;
  return FitImage(options, target, [&](const FitCurvePoint& point) {
    if (point.wall_seconds < next_log) return;
    next_log = point.wall_seconds + kLogInterval;
    LogInfo(format("{}step {}, {:.1f} s, PSNR {:.2f} dB", label, point.step, point.wall_seconds, point.psnr));
  });
}

nlohmann::json Report(const fs::path& image, const FloatImage& target, const ImageFitOptions& options,
                      const ImageFitResult& result) {
  return {{"image", image.string()},
          {"width", target.width},
          {"height", target.height},
          {"channels", target.channels},
          {"model", EnumName(options.model)},
          {"model_config", result.model_config},
          {"steps", result.steps},
          {"train_seconds", result.train_seconds},
          {"psnr", result.psnr},
          {"psnr_at_seconds", PsnrAtTimes(result.curve)}};
}

void FitOnce(const fs::path& image, const FloatImage& target, const ImageFitOptions& options, const fs::path& out) {
  const ImageFitResult result = FitAndLog(options, target, "fit: ");
  SaveFloatImage(result.reconstruction, out / "reconstruction.png");
  WriteCurve(out / "metrics.csv", result.curve);
  WriteLinePlot(
      out / "psnr.png",
      {format("fit-image {} ({}x{}): PSNR against training time", EnumName(options.model), target.width, target.height),
       "training time [s]", "PSNR [dB]"},
      {CurveSeries(EnumName(options.model), result.curve)});
  std::vector<CaptionedImage> strip;
  for (const auto& [step, snapshot] : result.snapshots) {
    SaveFloatImage(snapshot, out / format("snapshot_step_{:06d}.png", step));
    strip.push_back({format("step {}", step), &snapshot});
  }
  strip.push_back({format("final, step {}", result.steps), &result.reconstruction});
  strip.push_back({"target", &target});
  WriteImageStrip(out / "snapshots.png", strip);
  WriteJsonAtomic(out / kReportName, Report(image, target, options, result));
  LogInfo(format("fit: {} steps in {:.1f} s of training, PSNR {:.2f} dB; results in {}", result.steps,
                 result.train_seconds, result.psnr, out.string()));
}

// The seed's study: positional-encoding levels L, hidden layers and learning rate.
void Sweep(const fs::path& image, const FloatImage& target, ImageFitOptions options, const fs::path& out) {
  options.model = FitModel::kPe;
  options.snapshot_steps = "";
  std::vector<PlotSeries> curves;
  std::string table = "pe_levels,depth,learning_rate,steps,train_seconds,psnr\n";
  nlohmann::json runs = nlohmann::json::array();
  for (const int levels : {0, 10}) {
    for (const int depth : {2, 3}) {
      for (const double learning_rate : {1e-3, 1e-2}) {
        options.pe_levels = levels;
        options.depth = depth;
        options.learning_rate = learning_rate;
        const std::string name = format("L{} depth{} lr{:g}", levels, depth, learning_rate);
        const ImageFitResult result = FitAndLog(options, target, name + ": ");
        const fs::path folder = out / "sweep" / format("L{}_depth{}_lr{:g}", levels, depth, learning_rate);
        fs::create_directories(folder);
        WriteCurve(folder / "metrics.csv", result.curve);
        SaveFloatImage(result.reconstruction, folder / "reconstruction.png");
        curves.push_back(CurveSeries(name, result.curve));
        table += format("{},{},{:g},{},{:.3f},{:.4f}\n", levels, depth, learning_rate, result.steps,
                        result.train_seconds, result.psnr);
        runs.push_back(Report(image, target, options, result));
        LogInfo(format("{}: PSNR {:.2f} dB after {} steps", name, result.psnr, result.steps));
      }
    }
  }
  WriteFileAtomic(out / "sweep.csv", table);
  WriteLinePlot(out / "sweep.png",
                {format("fit-image sweep ({}x{}): positional-encoding levels L, depth, learning rate", target.width,
                        target.height),
                 "training time [s]", "PSNR [dB]"},
                curves);
  WriteJsonAtomic(out / kReportName, {{"sweep", runs}});
}

}  // namespace

int RunFitImage(int argc, char** argv) {
  OptionRegistry registry;
  RegisterOptions<RunOptions>(registry, RunOptions::kSection);
  RegisterOptions<ImageFitOptions>(registry, "fit");
  CLI::App app(
      "Fit a neural field to one image: writes the reconstruction, PSNR against time (CSV and plot) and "
      "snapshots. --sweep repeats the seed's study of L, depth and learning rate.",
      "photo2nerf fit-image");
  std::string image, output, config_file;
  bool sweep = false;
  std::map<std::string, std::string> option_text;
  app.add_option("image", image, "the image (jpg, png, tif, exr; grey, RGB or RGBA; 8 or 16 bits)")->required();
  app.add_option("-o,--output", output, "folder for the results (new, empty, or an earlier fit-image output)")
      ->required();
  app.add_option("--config", config_file, "JSON file of options, nested or as dotted keys");
  app.add_flag("--sweep", sweep, "fit the pe model for L in {0, 10} x depth {2, 3} x lr {1e-3, 1e-2}");
  AddOptionFlags(app, registry, &option_text);
  if (auto code = Parse(app, registry, argc, argv)) return *code;

  Config config(registry);
  if (!config_file.empty()) config.MergeFile(config_file);
  for (const auto& [key, text] : option_text) config.SetFromText(key, text, "--" + key);
  ImageFitOptions options;
  try {
    options = ReadOptions<ImageFitOptions>(config, "fit");
  } catch (const std::invalid_argument& e) {
    throw UserError(e.what());
  }
  FloatImage target;
  try {
    target = LoadImageForFit(image, options.alpha);
  } catch (const std::invalid_argument& e) {
    throw UserError(e.what());
  }
  const fs::path out = output;
  PrepareOutputFolder(out);
  const auto thread_limit = ApplyRunOptions(config, out / "fit.log");
  WriteJsonAtomic(out / "config.json", config.ToJson());
  LogInfo(format("fit-image {} ({}x{}, {} channels) -> {}", image, target.width, target.height, target.channels,
                 out.string()));
  if (sweep) {
    Sweep(image, target, options, out);
  } else {
    FitOnce(image, target, options, out);
  }
  return kExitOk;
}

}  // namespace p2n

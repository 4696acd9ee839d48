#include "stages/outputs/report_stage.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include "base/file_util.h"
#include "base/format.h"
#include "base/plot.h"
#include "formats/dataset_import.h"
#include "photo2nerf/version.h"
#include "pipeline/log.h"
#include "pipeline/runner.h"
#include "stages/fitting/splat_options.h"
#include "stages/outputs/render_options.h"
#include "stages/outputs/report_html.h"
#include "stages/stage_reports.h"
#include "stages/training_data.h"
#include "viewer/viewer_page.h"

namespace p2n {
namespace fs = std::filesystem;
namespace {

// A typed report (stage_reports.h), or none when the file is not there.
template <class Report>
std::optional<Report> ReadReportIfExists(const fs::path& file) {
  return fs::exists(file) ? std::optional(Report::Read(file)) : std::nullopt;
}

// A JSON value as text: floats with `digits` significant digits.
std::string Number(const nlohmann::json& value, int digits = 4) {
  if (value.is_number_float()) return format("{:.{}g}", value.get<double>(), digits);
  if (value.is_string()) return value.get<std::string>();
  return value.is_null() ? "-" : value.dump();
}

std::string Number(const std::optional<double>& value, int digits = 4) {
  return value ? format("{:.{}g}", *value, digits) : "-";
}

// A link from the report's folder to `file` in a sibling stage's folder (an upstream stage's result).
std::string Link(const fs::path& file) {
  return "../" + file.parent_path().filename().string() + "/" + file.filename().string();
}

std::string Card(const std::string& value, const std::string& label) {
  return format("<div class=\"card\"><div class=\"value\">{}</div><div class=\"label\">{}</div></div>\n",
                HtmlEscape(value), HtmlEscape(label));
}

std::string TrainingSection(const TrainResult& result, const std::optional<TrainReport>& train) {
  const std::string metrics = ReadTextFile(result.metrics());
  std::string html = "<h2>Training: error against run time</h2>\n<div class=\"plots\">\n";
  html += SvgLinePlot({"held-out PSNR against training time", "training time (s)", "PSNR (dB)"},
                      {CsvSeries("held-out PSNR (dB)", metrics, 0, 3)});
  html += SvgLinePlot({"training loss against training time", "training time (s)", "loss"},
                      {CsvSeries("training loss", metrics, 0, 2)});
  html += "</div>\n";
  if (!train) return html;
  const TrainReport& report = *train;
  const auto pixels = [](int count) { return count == 0 ? std::string("all") : format("{}", count); };
  html += format(
      "<p>{} steps in {:.1f} s of training; final held-out PSNR {} dB over {} {} views ({} pixels each); "
      "{:.3g} samples per ray when rendering; {:.1f}% of the occupancy grid occupied.</p>\n",
      report.steps, report.wall_seconds, Number(report.heldout_psnr), report.heldout_views,
      EnumName(report.heldout_split), pixels(report.heldout_pixels_per_view), report.samples_per_ray_rendered,
      100 * report.occupied_fraction);
  if (report.throughput && report.throughput->steps > 0) {
    html += format("<p>Training evaluated the field at {:.3g} million samples a second, {:.3g} samples per ray.</p>\n",
                   report.throughput->SamplesPerSecond() / 1e6, report.throughput->SamplesPerRay());
  }
  const TrainReport::Evaluations& evals = report.evaluations_during_training;
  html += format(
      "<p>Distortion loss weight {:.4g}; {} held-out evaluations during training ({} pixels per view) took "
      "{:.1f} s.</p>\n",
      report.trainer.distortion_weight, evals.count, pixels(evals.pixels_per_view), evals.seconds);
  if (report.trainer.background == BackgroundChoice::kLearnt) {
    const std::array<double, 3>& c = report.trainer.background_colour;
    const auto byte = [](double v) { return static_cast<int>(std::lround(255 * std::clamp(v, 0.0, 1.0))); };
    html += format(
        "<p>The colour behind the scene (what no ray reaches: a sky, a far wall) was learnt with the field: "
        "<span style=\"display:inline-block;width:2em;border:1px solid #888;background:rgb({},{},{})\">&nbsp;</span> "
        "({:.2f}, {:.2f}, {:.2f}).</p>\n",
        byte(c[0]), byte(c[1]), byte(c[2]), c[0], c[1], c[2]);
  }
  if (report.appearance.enabled) {
    html += format(
        "<p>Each training photo has its own colour transform (exposure, white balance): it makes white "
        "{:.3g} to {:.3g} of itself. Novel views show the average photo; a held-out photo given its own, "
        "fitted on its left half, scores {} dB on its right half.</p>\n",
        report.appearance.gain_min, report.appearance.gain_max, Number(report.heldout_psnr_fitted));
  }
  const TrainReport::Refinement& cameras = report.refinement;
  if (cameras.enabled) {
    html += format(
        "<p>Camera refinement turned the training cameras by {:.3g}&deg; (median; at most {:.3g}&deg;) and "
        "moved them by {:.3g} (median; at most {:.3g}) normalised units; the export stage writes the refined "
        "cameras (transforms.json).</p>\n",
        cameras.rotation_degrees_median, cameras.rotation_degrees_max, cameras.shift_median, cameras.shift_max);
  }
  return html;
}

// The splats: their numbers beside the field's, their error against optimisation time, and the file.
std::string SplatSection(const SplatResult& result, const SplatReport& report,
                         const std::optional<TrainReport>& train) {
  if (!report.enabled) {
    return format("<h2>Splats</h2>\n<p>Off (<code>--{} false</code>).</p>\n", OptionKey(&SplatOptions::enabled));
  }
  std::string html = "<h2>Splats: error against optimisation time</h2>\n";
  html += format(
      "<p><a href=\"{}\"><b>Open the scene in the live viewer</b></a> (viewer.html, {:.1f} MB, "
      "works offline in any browser with WebGL 2: drag to orbit, right-drag to pan, wheel or pinch to zoom, W A S D "
      "to fly, the training cameras in its menu).</p>\n",
      Link(result.viewer()), report.viewer_bytes / 1e6);
  html += "<div class=\"plots\">\n";
  html += SvgLinePlot({"splats: held-out PSNR against optimisation time", "optimisation time (s)", "PSNR (dB)"},
                      {CsvSeries("held-out PSNR (dB)", ReadTextFile(result.metrics()), 0, 4)});
  html += "</div>\n";
  html += format(
      "<p>The field baked into {} 3D Gaussian splats (spherical harmonics of degree {}; {} placed from the {}, "
      "a training photo seeing {:.0f}% of them, then optimised for {:.0f} s, {} steps): held-out PSNR {} dB and "
      "SSIM {} (the field: {} dB), {:.3f} s per held-out view on the CPU. <a href=\"{}\">splats.ply</a> ({:.1f} "
      "MB) is in the standard 3D Gaussian Splatting layout, {}; SuperSplat, the PlayCanvas and three.js splat viewers "
      "open it as it is. "
      "<a href=\"{}\">splats.spz</a> ({:.1f} MB) holds the same splats in Niantic's compact SPZ, for the web (Spark, "
      "Babylon.js, SuperSplat) and Scaniverse; <a href=\"{}\">splats.glb</a> ({:.1f} MB) in glTF with "
      "KHR_gaussian_splatting, upright (+Y up), for the glTF tools that read it.</p>\n",
      report.splats, report.sh_degree, report.initial_splats,
      report.init == SplatInit::kSparse ? "sparse points" : "field", 100 * report.view_share, report.seconds,
      report.steps, Number(report.heldout_psnr), Number(report.heldout_ssim, 3),
      Number(train ? train->heldout_psnr : std::nullopt), report.seconds_per_view, Link(result.splats()),
      report.file_bytes / 1e6, HtmlEscape(report.frame_description), Link(result.spz()), report.spz_bytes / 1e6,
      Link(result.glb()), report.glb_bytes / 1e6);
  return html;
}

// The signs of a failed fit the train and splat stages found (fit_checks.h), first on the page.
std::string WarningsSection(const std::optional<TrainReport>& train, const SplatReport& splat) {
  std::vector<std::pair<std::string, FitWarning>> warnings;
  if (train) {
    for (const FitWarning& w : train->warnings) warnings.emplace_back("training", w);
  }
  for (const FitWarning& w : splat.warnings) warnings.emplace_back("splats", w);
  if (warnings.empty()) return "";
  std::string html =
      format("<div class=\"warnings\" id=\"warnings\"><h2>{} warning{}: this result may have failed</h2>\n<ul>\n",
             warnings.size(), warnings.size() == 1 ? "" : "s");
  for (const auto& [stage, w] : warnings) {
    html += format("<li><b>{}</b> ({}, <code>{}</code>): {}</li>\n", HtmlEscape(stage), HtmlEscape(w.code),
                   format("{:.3g}", w.figure), HtmlEscape(w.message));
  }
  return html +
         "</ul>\n<p>docs/troubleshooting.md (Warnings about a result) says what each means and what to do.</p></div>\n";
}

std::string StagesSection(const StageContext& context) {
  std::string html =
      "<h2>Stages</h2>\n<table>\n<tr><th>stage</th><th>state</th><th>wall time</th><th>finished (UTC)"
      "</th><th>key</th><th>summary</th><th>options set (the others at their defaults)</th></tr>\n";
  for (const StageStatus& status : context.runner->Status(context.workspace, context.config)) {
    const std::string name = status.stage->name();
    if (name == ReportResult::kId.name) continue;
    std::string summary, options;
    if (status.manifest) {
      for (const auto& [key, value] : status.manifest->summary.items()) summary += key + " " + Number(value) + "; ";
      for (const auto& [key, value] : status.manifest->inputs.options.items())
        options += key + " = " + Number(value) + "; ";
      if (options.empty()) options = "(defaults)";
    }
    html += format(
        "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td><code>{}</code></td><td>{}</td><td>{}</td></tr>\n", name,
        StageStateName(status.state), status.manifest ? format("{:.1f} s", status.manifest->wall_seconds) : "-",
        status.manifest ? status.manifest->finished_utc : "-", status.expected_key.substr(0, 12), HtmlEscape(summary),
        HtmlEscape(options));
  }
  return html + "</table>\n";
}

// For each video ingest took frames from: the sharpness of every frame against its time, and of those taken.
std::string VideosSection(const StageContext& context) {
  const fs::path file = InWorkspace<IngestResult>(context.workspace).report();
  if (!context.runner->Find(IngestResult::kId.name) || !fs::exists(file)) return "";
  std::string html;
  for (const IngestedVideo& video : IngestReport::Read(file).videos) {
    PlotSeries every{"every frame", {}, video.sharpness}, taken{"taken", {}, {}};
    for (size_t i = 0; i < video.frames; ++i) every.x.push_back(video.fps > 0 ? i / video.fps : double(i));
    for (const IngestedVideo::Frame& frame : video.taken) {
      taken.x.push_back(frame.time);
      taken.y.push_back(video.sharpness.at(frame.index));
    }
    html += format(
        "<h2>Video {}</h2>\n<p>{} frames in {:.1f} s ({}x{}, {:.3g} frames a second): {} taken, the sharpest of each "
        "stretch of equal camera motion; {} left as near repeats of the frame before, the other {} for a sharper "
        "frame near them.</p>\n",
        HtmlEscape(video.file), video.frames, video.seconds, video.width, video.height, video.fps, video.taken.size(),
        video.repeats.size(), video.frames - video.taken.size() - video.repeats.size());
    html += SvgLinePlot({"frames taken on the time line", "time (s)", "sharpness (variance of the Laplacian)"},
                        {every, taken}, 960, 300);
  }
  return html;
}

// The photos the chosen model left out, each with its reason, and the models COLMAP made when it made several.
std::string LeftOutHtml(const SfmReport& sfm) {
  std::string html;
  if (sfm.models.size() > 1) {
    html += format("<p>COLMAP's mapper made {} models; the largest is used:", sfm.models.size());
    for (const SfmReport::Model& model : sfm.models)
      html += format(" {} ({} photos{})", HtmlEscape(model.path), model.registered,
                     model.path == sfm.chosen_model ? ", used" : "");
    html += ".</p>\n";
  }
  if (sfm.left_out.empty()) return html;
  html +=
      format("<p>Photos left out of the model: {}.</p>\n<table><tr><th>photo</th><th>reason</th><th>why</th></tr>\n",
             sfm.left_out.size());
  for (const SfmReport::LeftOut& photo : sfm.left_out)
    html += format("<tr><td>{}</td><td>{}</td><td>{}</td></tr>\n", HtmlEscape(photo.image), EnumName(photo.reason),
                   HtmlEscape(photo.detail));
  return html + "</table>\n";
}

std::string CamerasSection(const StageContext& context, const ImportedDataset& dataset, ViewSplit heldout_split) {
  std::string html = "<h2>Cameras</h2>\n";
  const std::optional<SfmReport> sfm =
      context.runner->Find(SfmResult::kId.name)
          ? ReadReportIfExists<SfmReport>(InWorkspace<SfmResult>(context.workspace).report())
          : std::nullopt;
  if (sfm && !dataset.meta.dataset_kind) {
    html += format(
        "<p>COLMAP {}: {} of {} images registered ({:.0f}%), mean reprojection error {:.3g} px, {} sparse points, "
        "mean track length {:.3g}, {} matching.</p>\n",
        HtmlEscape(sfm->colmap_version), sfm->registered, sfm->images_given, sfm->registered_percent,
        sfm->mean_reprojection_error_px, sfm->points, sfm->mean_track_length, HtmlEscape(sfm->matcher));
    html += "<table><tr><th>COLMAP step</th><th>wall time</th></tr>\n";
    for (const SfmReport::Step& step : sfm->steps)
      html += format("<tr><td>{}</td><td>{:.1f} s</td></tr>\n", HtmlEscape(step.step), step.wall_seconds);
    html += "</table>\n" + LeftOutHtml(*sfm);
  } else {
    html += format("<p>Cameras imported from a {} dataset (no structure from motion needed).</p>\n",
                   dataset.meta.dataset_kind ? EnumName(*dataset.meta.dataset_kind) : "given");
  }
  std::vector<ViewerCamera> cameras;
  for (const ImportedView& view : dataset.views)
    cameras.push_back({view.view.camera, view.view.split == heldout_split});
  std::vector<ColouredPoint> points;
  const fs::path sparse = Upstream<PosesResult>(context).sparse_points();
  if (fs::exists(sparse)) points = ReadPly(sparse);
  html += format("<p>{} cameras in the normalised frame{}.</p>\n", cameras.size(),
                 points.empty() ? "" : format(" with {} sparse points", points.size()));
  return html + SceneViewerHtml(cameras, points);
}

// Why the held-out PSNR here is not the training's: the render stage sampled the field at another spacing.
std::string StepScaleNote(const EvalReport& eval, const std::optional<TrainReport>& train) {
  if (!eval.step_scale || !train || !train->heldout_step_scale || !train->heldout_psnr ||
      std::abs(*eval.step_scale - *train->heldout_step_scale) < 1e-9)
    return "";
  return format(
      " The field was sampled at {:.3g} times its training step here ({}); the training's own evaluation, {} dB, at "
      "{:.3g}.",
      *eval.step_scale, OptionKey(&RenderStageOptions::step_scale), Number(train->heldout_psnr),
      *train->heldout_step_scale);
}

std::string HeldoutSection(const RenderResult& render, const std::optional<EvalReport>& eval,
                           const std::optional<TrainReport>& train, const std::array<float, 3>& background,
                           int image_width) {
  if (!eval || eval->views.empty())
    return format("<h2>Held-out views</h2>\n<p>None rendered: no view was held out, or {} is false.</p>\n",
                  OptionKey(&RenderStageOptions::heldout));
  std::string html = format(
      "<h2>Held-out views</h2>\n<p>{} views of the {} split ({}), never trained on: PSNR {} dB, SSIM {} "
      "on average.{} Error maps: mean absolute RGB error, black 0 to yellow {} and above.</p>\n",
      eval->views.size(), EnumName(eval->split),
      HtmlEscape(train && !train->heldout_rule.empty() ? train->heldout_rule : "as the dataset splits them"),
      Number(eval->psnr, 4), Number(eval->ssim, 3), StepScaleNote(*eval, train),
      format("{:.2g}", eval->heat_map_max_error));
  for (const HeldoutScore& view : eval->views) {
    const auto figure = [&](const std::string& uri, const std::string& caption) {
      return format("<figure><img src=\"{}\" alt=\"{}\"><figcaption>{}</figcaption></figure>", uri, HtmlEscape(caption),
                    HtmlEscape(caption));
    };
    html += "<div class=\"triple\">" + figure(ImageDataUri(view.photo, image_width, background), "photo " + view.view) +
            figure(ImageDataUri(render.dir / view.render, image_width),
                   format("render: {:.2f} dB, SSIM {:.3f}", view.psnr, view.ssim)) +
            figure(ImageDataUri(render.dir / view.error_map, image_width), "error map") + "</div>\n";
  }
  return html;
}

// The files' size in MB, as the page states it.
double Megabytes(const fs::path& file) { return fs::exists(file) ? fs::file_size(file) / 1e6 : 0.0; }

std::string ExportSection(const ExportResult& result, const ExportReport& exported) {
  const ExportReport::Mesh& mesh = exported.mesh;
  std::string html = format(
      "<h2>Exports</h2>\n<p>Mesh <a href=\"{}\">mesh.ply</a> ({:.1f} MB): {} vertices, {} triangles (simplified from "
      "{}), {}watertight (marching cubes at {}^3 over {}, {}), in the {} frame.",
      Link(result.mesh()), Megabytes(result.mesh()), mesh.vertices, mesh.triangles, mesh.marched_triangles,
      mesh.watertight ? "" : "not ", mesh.resolution,
      mesh.region == MeshRegion::kBox
          ? std::string("the scene box")
          : format("the region the photos look at (a cube of half size {:.3g})", mesh.half_size),
      mesh.surface == MeshSurface::kDepths ? std::string("where the training views' depths agree")
                                           : format("density threshold {:.4g}", mesh.threshold),
      EnumName(exported.frame));
  const ExportReport::Textured& textured = exported.textured;
  if (!textured.file.empty()) {
    html += format(
        " Textured, <a href=\"{}\">mesh.glb</a> ({:.1f} MB, its {} x {} texture inside) for Blender, the web, "
        "Sketchfab and game engines",
        Link(result.mesh_glb()), Megabytes(result.mesh_glb()), textured.texture_size, textured.texture_size);
    html += textured.obj.empty() ? "."
                                 : format("; <a href=\"{}\">mesh.obj</a> ({:.1f} MB) with its material.",
                                          Link(result.mesh_obj()), Megabytes(result.mesh_obj()));
  }
  if (exported.points) {
    html += format(" Point cloud <a href=\"{}\">points.ply</a> ({:.1f} MB): {} points.", Link(result.points()),
                   Megabytes(result.points()), exported.points->count);
  }
  html += "</p>\n";
  if (fs::exists(result.mesh_preview())) {
    html +=
        "<p class=\"muted\">The textured mesh, simplified for this page: drag to turn it, scroll to zoom, "
        "right-drag to move it.</p>\n";
    html += MeshViewHtml(ReadTextFile(result.mesh_preview()), 640, 400);
  }
  return html;
}

}  // namespace

void ReportOptions::Check() const {
  CheckField(*this, image_width, image_width >= 32 && image_width <= 4096, "must be 32..4096");
}

void ReportStage::Run(StageContext& context) const {
  const ReportOptions options = ReadOptions<ReportOptions>(context.config);
  const TrainResult train_result = Upstream<TrainResult>(context);
  const SplatResult splat = Upstream<SplatResult>(context);
  const RenderResult render = Upstream<RenderResult>(context);
  const ExportResult export_result = Upstream<ExportResult>(context);
  const ImportedDataset dataset =
      LoadTransformsJson(Upstream<PosesResult>(context).transforms(), context.workspace.root());
  const ViewSplit heldout_split = HeldoutSplit(dataset);
  const std::optional<TrainReport> train = ReadReportIfExists<TrainReport>(train_result.report());
  const SplatReport splat_report = SplatReport::Read(splat.report());
  const std::optional<EvalReport> eval = ReadReportIfExists<EvalReport>(render.eval());
  const std::optional<ExportReport> exported = ReadReportIfExists<ExportReport>(export_result.report());
  const std::array<float, 3> background = dataset.meta.Background();

  std::string body = "<h1>photo2nerf report</h1>\n";
  body += format(
      "<p class=\"muted\">Workspace <code>{}</code>; input <code>{}</code>; photo2nerf {}; made {} UTC.</p>\n",
      HtmlEscape(context.workspace.root().string()),
      HtmlEscape(context.workspace.input() ? context.workspace.input()->string() : "-"), kVersion, UtcTimestamp());
  body += WarningsSection(train, splat_report);
  body += "<div class=\"cards\">\n";
  body += Card(eval && eval->psnr ? format("{:.2f} dB", *eval->psnr) : "-", "held-out PSNR");
  body += Card(eval && eval->ssim ? format("{:.3f}", *eval->ssim) : "-", "held-out SSIM");
  body += Card(train ? format("{:.0f} s", train->wall_seconds) : "-", "training time");
  body += Card(format("{}", dataset.views.size()), "cameras");
  if (exported) body += Card(format("{}", exported->mesh.triangles), "mesh triangles");
  body += "</div>\n";
  body += TrainingSection(train_result, train);
  body += SplatSection(splat, splat_report, train);
  body += StagesSection(context);
  body += VideosSection(context);
  body += CamerasSection(context, dataset, heldout_split);
  body += HeldoutSection(render, eval, train, background, options.image_width);
  if (const std::optional<PathReport> path = ReadReportIfExists<PathReport>(render.report())) {
    std::string how = path->samples_per_ray ? format("{:.3g} samples per ray", *path->samples_per_ray)
                                            : "from the " + std::string(EnumName(path->source));
    if (path->rendered_frames < path->frames)
      how += format("; {} drawn, the others repeat them", path->rendered_frames);
    body += format("<h2>New views</h2>\n<p>{} path, {} frames of {}x{} at {:.2f} frames per second ({}).</p>\n",
                   EnumName(path->kind), path->frames, path->width, path->height, path->frames_per_second, how);
    const fs::path video = render.video();
    if (fs::exists(video)) {
      const std::string source = options.embed_video ? FileDataUri(video, "video/mp4") : Link(video);
      body +=
          format("<video id=\"path-video\" controls loop muted autoplay playsinline src=\"{}\" width=\"{}\"></video>\n",
                 source, options.image_width);
    } else {
      body += format("<img src=\"{}\" alt=\"first frame\">\n",
                     ImageDataUri(render.frames() / (RenderResult::FrameStem(0) + ".png"), options.image_width));
    }
  }
  if (exported) body += ExportSection(export_result, *exported);
  WriteFileAtomic(ReportResult{context.output_dir}.page(), HtmlPage("photo2nerf report", body));
  const fs::path page = InWorkspace<ReportResult>(context.workspace).page();
  context.summary = {{"report", page.string()}};
  LogInfo(format("report: {}", page.string()));
}

}  // namespace p2n

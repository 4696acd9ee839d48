#include "stages/sfm/sfm_stage.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <iterator>
#include <set>

#include "base/errors.h"
#include "base/file_util.h"
#include "base/format.h"
#include "formats/camera_geometry.h"
#include "formats/colmap_model.h"
#include "pipeline/log.h"
#include "pipeline/run_options.h"
#include "stages/sfm/cluster_mapping.h"
#include "stages/sfm/colmap_flags.h"
#include "stages/sfm/colmap_run.h"
#include "stages/sfm/left_out.h"
#include "stages/sfm/matcher_choice.h"
#include "stages/sfm/sfm_blocks.h"
#include "stages/stage_reports.h"

namespace p2n {
namespace fs = std::filesystem;
namespace {

constexpr double kSuspiciousFocusAngleDeg = 20;  // correct orbit models stay near 8 (docs/design.md §7)
constexpr size_t kMaxNamesListed = 20;

// Whether every image is a frame of one video (their names then sort in the video's order).
bool OneVideo(const IngestReport& ingest) {
  return ingest.videos.size() == 1 && std::all_of(ingest.images.begin(), ingest.images.end(),
                                                  [](const IngestedImage& image) { return image.frame.has_value(); });
}

// The photos of `names` that `model` does not hold.
std::vector<std::string> LeftOutNames(const ColmapModel& model, const std::vector<std::string>& names) {
  std::set<std::string> registered;
  for (const auto& [id, image] : model.images) registered.insert(image.name);
  std::vector<std::string> left_out;
  std::copy_if(names.begin(), names.end(), std::back_inserter(left_out),
               [&](const std::string& name) { return !registered.count(name); });
  return left_out;
}

// What sfm_report.json says of a model: registration, points, errors, and whether the cameras look at a common
// point (a warning when not); not which photos it left out.
SfmReport ModelReport(const ColmapModel& model, const std::vector<std::string>& names) {
  std::vector<Eigen::Vector3d> centres, axes;
  for (const auto& [id, image] : model.images) {
    const Eigen::Matrix3d world_from_cam = image.cam_from_world_rotation.toRotationMatrix().transpose();
    centres.push_back(-world_from_cam * image.cam_from_world_translation);
    axes.push_back(world_from_cam.col(2));  // COLMAP cameras look along +z
  }
  SfmReport report;
  double error_sum = 0, observations = 0;
  for (const auto& [id, point] : model.points) {
    error_sum += point.error * point.track.size();
    observations += point.track.size();
  }
  report.images_given = names.size();
  report.registered = model.images.size();
  report.registered_percent = 100.0 * model.images.size() / names.size();
  report.points = model.points.size();
  report.mean_reprojection_error_px = observations > 0 ? error_sum / observations : 0.0;
  report.mean_track_length = model.points.empty() ? 0.0 : observations / model.points.size();
  if (const auto focus = FindFocusPoint(centres, axes)) {
    report.median_axis_to_focus_angle_deg = focus->median_angle_deg;
    if (focus->median_angle_deg > kSuspiciousFocusAngleDeg) {
      LogWarning(
          format("sfm: the cameras' optical axes miss their common focus point by a median {:.1f} degrees; "
                 "for photos taken around an object this suggests a wrong reconstruction; {}",
                 focus->median_angle_deg, RegistrationAdvice()));
    }
  }
  return report;
}

// UserError when sfm_report.json's model registers less than sfm.min_registered of the photos.
void CheckRegistered(const SfmReport& report, double min_registered) {
  const double fraction = double(report.registered) / report.images_given;
  if (fraction >= min_registered) return;
  std::string listed;
  for (size_t i = 0; i < report.left_out.size() && i < kMaxNamesListed; ++i)
    listed += format("{}{} ({})", i ? ", " : "", report.left_out[i].image, EnumName(report.left_out[i].reason));
  if (report.left_out.size() > kMaxNamesListed)
    listed += format(" and {} more", report.left_out.size() - kMaxNamesListed);
  throw UserError(format("COLMAP registered only {} of {} photos ({:.0f}%, {} is {:.0f}%); left out: {}; {}",
                         report.registered, report.images_given, 100 * fraction, OptionKey(&SfmOptions::min_registered),
                         100 * min_registered, listed, RegistrationAdvice()));
}

// Matches with `matcher` and maps; when that registers less than sfm.min_registered of the photos (or nothing),
// adds the other kind of matching (RetryMatcher) once and maps again, *matching then naming both ("sequential +
// vocab_tree"). Returns the chosen model's folder.
fs::path MatchAndMap(const ColmapRun& colmap, const SfmOptions& options, size_t photos, Matcher matcher,
                     std::string* matching, std::vector<SfmReport::Model>* models) {
  *matching = EnumName(matcher);
  colmap.Match(matcher, photos);
  const std::optional<Matcher> retry = options.matcher == Matcher::kAuto ? RetryMatcher(matcher, photos) : std::nullopt;
  std::string failure;
  try {
    const fs::path chosen = colmap.MapLargestModel(photos, "mapping", "sparse", models);
    const size_t registered = ReadColmapModel(chosen).images.size();
    if (!retry || registered >= options.min_registered * photos) return chosen;
    failure = format("registered {} of {} photos", registered, photos);
  } catch (const UserError&) {
    if (!retry) throw;
    failure = "reconstructed nothing";
  }
  LogWarning(format("sfm: {} matching {}; adding {} matching and mapping again", *matching, failure, EnumName(*retry)));
  colmap.steps->AddSteps(3);  // the vocabulary tree or our descriptor matching, COLMAP's matching, mapping
  colmap.Match(*retry, photos);
  matching->append(" + ").append(EnumName(*retry));
  return colmap.MapLargestModel(photos, "mapping again", "sparse_again", models);
}

}  // namespace

void SfmOptions::Check() const {
  CheckField(*this, exhaustive_max_images, exhaustive_max_images >= 2, "must be at least 2");
  CheckField(*this, sequential_overlap, sequential_overlap >= 1, "must be at least 1");
  CheckField(*this, retrieval_neighbours, retrieval_neighbours >= 1, "must be at least 1");
  CheckField(*this, max_image_size, max_image_size >= 100,
             format("must be at least 100 pixels, not {}", max_image_size));
  CheckField(*this, max_num_features, max_num_features >= 100, "must be at least 100");
  CheckField(*this, block_images, block_images >= 1, "must be at least 1");
  CheckField(*this, hierarchical_min_images, hierarchical_min_images >= 0, "must be 0 (never) or a photo count");
  CheckField(*this, leaf_max_images, leaf_max_images >= 8, "must be at least 8");
  CheckField(*this, min_registered, min_registered > 0 && min_registered <= 1, "must be in (0, 1]");
  CheckField(*this, colmap, !colmap.empty(), "must name the COLMAP program");
}

std::map<std::string, std::string> SfmStage::ExternalInputs(const Workspace& workspace, const Config& config) const {
  const std::string program = ReadOptions<SfmOptions>(config).colmap;
  try {
    return {{"tool colmap", DetectColmapVersion(program, workspace.LogDir() / "colmap_version.log").ToString()}};
  } catch (const std::exception&) {
    return {{"tool colmap", "not found"}};  // Run() says why
  }
}

void SfmStage::CheckResult(const fs::path& result_dir, const Config& config) const {
  CheckRegistered(SfmReport::Read(SfmResult{result_dir}.report()), ReadOptions<SfmOptions>(config).min_registered);
}

std::vector<CameraGroup> CameraGroups(const IngestReport& ingest) {
  std::map<std::tuple<std::string, int, int>, std::vector<std::string>> by_camera;
  for (const IngestedImage& image : ingest.images)
    by_camera[{image.camera, image.width, image.height}].push_back(image.name);
  std::vector<CameraGroup> groups;
  for (const auto& [key, images] : by_camera) {
    const auto& [camera, width, height] = key;
    groups.push_back(
        {camera.empty() ? format("{}x{}", width, height) : format("{}, {}x{}", camera, width, height), images});
  }
  return groups;
}

// What every COLMAP step of the stage (or of one of its parts) is given.
struct SfmSetup {
  SfmOptions options;
  SfmResult out;
  IngestResult ingest;
  ColmapFlags flags;
  ColmapVersion version;
  int threads = -1;  // COLMAP's: every core

  // COLMAP's version asked with its answer in logs/`version_log` (one for each process at once).
  SfmSetup(const StageContext& context, const std::string& version_log)
      : options(ReadOptions<SfmOptions>(context.config)),
        out{context.output_dir},
        ingest(Upstream<IngestResult>(context)) {
    fs::create_directories(out.logs());
    version = DetectColmapVersion(options.colmap, out.logs() / version_log);
    flags = ColmapFlagsFor(version);
    const int run_threads = ReadOptions<RunOptions>(context.config).threads;
    if (run_threads > 0) threads = run_threads;
  }

  ColmapRun Colmap(StepRunner* steps, const StageContext& context) const {
    return {.options = options,
            .flags = flags,
            .images = ingest.images(),
            .masks = fs::is_directory(ingest.masks()) ? ingest.masks() : fs::path(),
            .out = out,
            .seed = std::to_string(options.seed),
            .threads = std::to_string(threads),
            .steps = steps,
            .context = &context};
  }
};

void SfmStage::RunPart(StageContext& context, const std::string& work, int part) const {
  const SfmSetup setup(context, format("version_{}_{}.log", work, part));
  StepRunner steps(setup.out.logs(), 1);
  const ColmapRun colmap = setup.Colmap(&steps, context);
  if (work == kExtractionWork) {
    colmap.ExtractBlock(setup.out.dir / "extraction", part);
  } else if (work == kMatchingWork) {
    colmap.MatchBlock(setup.out.dir / "matching", part);
  } else if (work == kClusterWork) {
    colmap.MapCluster(setup.out.dir / "clusters", part);
  } else {
    Stage::RunPart(context, work, part);
  }
}

void SfmStage::Run(StageContext& context) const {
  const SfmSetup setup(context, "version.log");
  const SfmOptions& options = setup.options;
  const SfmResult& out = setup.out;
  const ColmapVersion& version = setup.version;
  const IngestResult& ingest = setup.ingest;
  const fs::path images = ingest.images();
  const std::vector<std::string> names = ImageNames(images);
  // COLMAP's shared camera would skip every photo of another size: with several sizes, features are extracted
  // once per size, each run making one camera for its photos.
  const IngestReport ingested = IngestReport::Read(ingest.report());
  const std::vector<CameraGroup> groups = CameraGroups(ingested);
  const bool camera_per_group = options.single_camera && groups.size() > 1;
  if (camera_per_group) {
    std::string list;
    for (size_t i = 0; i < groups.size(); ++i)
      list += format("{}{}: {} ({} images)", i ? "; " : "", i + 1, groups[i].label, groups[i].images.size());
    LogInfo(format("sfm: the photos come from {} cameras, each solved on its own: {}", groups.size(), list));
  }
  const Matcher matcher = options.matcher != Matcher::kAuto
                              ? options.matcher
                              : AutoMatcher(names, options.exhaustive_max_images, OneVideo(ingested));
  const bool hierarchical = UsesHierarchicalMapper(options, names.size());
  LogInfo(format("sfm: COLMAP {}, {} photos, {} matching, features at {} px, the {} mapper", version.ToString(),
                 names.size(), EnumName(matcher), options.max_image_size,
                 hierarchical ? "hierarchical" : "incremental"));
  // The photos as extracted: a group per camera, or all as one.
  const std::vector<CameraGroup> extracted = camera_per_group ? groups : std::vector<CameraGroup>{{"", names}};
  // Extraction (one per group, or in blocks and merged), the vocabulary tree or our matching, COLMAP's matching,
  // mapping, the triangulation after the hierarchical mapper, the principal point's adjustment, undistortion.
  StepRunner steps(out.logs(), (options.refine_principal_point ? 5 : 4) + (hierarchical ? 1 : 0));
  const ColmapRun colmap = setup.Colmap(&steps, context);
  if (!colmap.masks.empty()) steps.AddSteps(1);
  steps.AddSteps(colmap.Blocks(names.size()) > 1 ? 2 : static_cast<int>(extracted.size()));
  colmap.ExtractFeatures(extracted, names.size());
  std::vector<SfmReport::Model> models;
  std::string matching;
  const fs::path chosen = MatchAndMap(colmap, options, names.size(), matcher, &matching, &models);
  const fs::path mapped = hierarchical ? colmap.Retriangulate(chosen) : chosen;
  const fs::path model_dir = options.refine_principal_point ? colmap.RefinePrincipalPoint(mapped) : mapped;
  const ColmapModel model = ReadColmapModel(model_dir);
  SfmReport report = ModelReport(model, names);
  report.colmap_version = version.ToString();
  report.matcher = matching;
  report.models = models;
  report.chosen_model = fs::relative(chosen, out.dir).string();
  report.left_out = ExplainLeftOut(LeftOutNames(model, names), out.database(), out.dir, models, report.chosen_model);
  report.steps = steps.timings();
  WriteJsonAtomic(out.report(), report.ToJson());  // also for a run that fails the check below
  context.summary = {{"registered", model.images.size()}, {"images", names.size()}, {"points", model.points.size()}};
  LogInfo(format("sfm: {}/{} photos registered, {} points, mean reprojection error {:.2f} px", model.images.size(),
                 names.size(), model.points.size(), report.mean_reprojection_error_px));
  CheckRegistered(report, options.min_registered);
  colmap.Undistort(model_dir);
  report.steps = steps.timings();
  WriteJsonAtomic(out.report(), report.ToJson());
}

}  // namespace p2n

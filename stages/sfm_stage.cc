#include "stages/sfm_stage.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <chrono>
#include <functional>
#include <iterator>
#include <set>

#include "base/errors.h"
#include "base/file_util.h"
#include "base/format.h"
#include "formats/camera_geometry.h"
#include "formats/colmap_model.h"
#include "pipeline/cancel.h"
#include "pipeline/log.h"
#include "pipeline/run_options.h"
#include "pipeline/subprocess.h"
#include "stages/cluster_mapping.h"
#include "stages/colmap_flags.h"
#include "stages/feature_matching.h"
#include "stages/left_out.h"
#include "stages/matcher_choice.h"
#include "stages/retrieval.h"
#include "stages/sfm_blocks.h"
#include "stages/stage_reports.h"

namespace p2n {
namespace fs = std::filesystem;
namespace {

constexpr double kSuspiciousFocusAngleDeg = 20;  // correct orbit models stay near 8 (docs/design.md §7)
constexpr size_t kMaxNamesListed = 20;
// Global bundle adjustments, the mapper's and the final one, stop when an iteration changes the cost by less than
// this share of it (Ceres's own default; COLMAP's 0 runs each to its iteration limit, 100 for the final one, on a
// cost that stopped falling after the first few: most of the sfm stage at many photos, docs/benchmarks.md).
constexpr const char* kGlobalAdjustmentTolerance = "1e-6";
// How the mapper adjusts while the model grows (COLMAP's defaults otherwise): a global adjustment runs when the
// images or points grew by 40% since the last (COLMAP's 10%), and local ones stop after 10 iterations (25): faster
// mapping, the cameras as close to the references (docs/benchmarks.md, structure from motion).
constexpr const char* kMapperTuning[] = {"--Mapper.ba_global_function_tolerance", kGlobalAdjustmentTolerance,
                                         "--Mapper.ba_global_images_ratio",       "1.4",
                                         "--Mapper.ba_global_points_ratio",       "1.4",
                                         "--Mapper.ba_local_max_num_iterations",  "10"};
// The clusters' models are aligned on the points whose reprojection errors stay under this (pixels): COLMAP's
// model_merger's 64 admits alignments that bend the merged model by degrees where its mapper's own 4 does not.
constexpr const char* kMergeMaxReprojectionError = "4";
// The vocabulary tree's k-means (TreeSizeFor has its size): narrower and shallower than COLMAP's defaults (branching
// 256, 11 iterations), which were three times slower on fox's 50 photos (docs/benchmarks.md).
constexpr int kTreeBranching = 16, kTreeIterations = 5;

// Whether `photos` are mapped by COLMAP's hierarchical mapper (sfm.hierarchical_min_images).
bool UsesHierarchicalMapper(const SfmOptions& options, size_t photos) {
  return options.hierarchical_min_images > 0 && photos >= static_cast<size_t>(options.hierarchical_min_images);
}

// What to try when too few photos register.
std::string Advice() {
  return format("try --{} exhaustive, more features (--{}), a larger --{}, or photos with more overlap",
                OptionKey(&SfmOptions::matcher), OptionKey(&SfmOptions::max_num_features),
                OptionKey(&SfmOptions::max_image_size));
}

// Runs a COLMAP command with its log, glog's messages in it too (COLMAP otherwise leaves a file in the temporary
// folder at every run). Failures throw ExternalToolError, unless `allow_failure`.
SubprocessResult RunColmap(std::vector<std::string> argv, const fs::path& log, const std::string& step,
                           bool allow_failure = false) {
  argv.insert(argv.end(), {"--log_to_stderr", "1"});
  return allow_failure ? RunSubprocess(argv, log, step) : CheckSubprocess(argv, log, step);
}

// Runs the COLMAP steps in order with their own logs and timings.
class StepRunner {
 public:
  StepRunner(fs::path log_dir, int total) : log_dir_(std::move(log_dir)), total_(total) {}

  // For the step count in the log: `count` more steps than planned.
  void AddSteps(int count) { total_ += count; }

  // Runs one step; returns its log. Failures throw ExternalToolError, unless `allow_failure`.
  fs::path Run(const std::string& step, const std::vector<std::string>& argv, bool allow_failure = false) {
    Announce(step);
    const fs::path log = log_dir_ / (FileStem(step) + ".log");
    const SubprocessResult result = RunColmap(argv, log, step, allow_failure);
    last_ok_ = result.signal == 0 && result.exit_code == 0;
    timings_.push_back({step, fs::relative(log, log_dir_.parent_path()).string(), result.wall_seconds});
    ThrowIfCancelled();
    return log;
  }
  // Runs one step of our own, in this process; its log is the stage's.
  void RunHere(const std::string& step, const std::function<void()>& work) {
    Announce(step);
    const auto start = std::chrono::steady_clock::now();
    work();
    timings_.push_back({step, fs::relative(log_dir_ / "photo2nerf.log", log_dir_.parent_path()).string(),
                        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()});
  }
  bool last_ok() const { return last_ok_; }
  // A step's name as the stem of its files in the log folder.
  static std::string FileStem(std::string step) {
    std::replace(step.begin(), step.end(), ' ', '_');
    return step;
  }
  const std::vector<SfmReport::Step>& timings() const { return timings_; }

 private:
  void Announce(const std::string& step) {
    ++index_;
    LogInfo(format("sfm: {} ({}/{})", step, index_, total_));
  }

  fs::path log_dir_;
  int total_;
  int index_ = 0;
  bool last_ok_ = true;
  std::vector<SfmReport::Step> timings_;
};

std::vector<std::string> ImageNames(const fs::path& folder) {
  std::vector<std::string> names;
  for (const fs::directory_entry& entry : fs::directory_iterator(folder)) {
    if (entry.is_regular_file()) names.push_back(entry.path().filename().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

// Whether every image is a frame of one video (their names then sort in the video's order).
bool OneVideo(const IngestReport& ingest) {
  return ingest.videos.size() == 1 && std::all_of(ingest.images.begin(), ingest.images.end(),
                                                  [](const IngestedImage& image) { return image.frame.has_value(); });
}

// One COLMAP reconstruction in the staging folder `out`: each step a subprocess through `steps`.
struct ColmapRun {
  const SfmOptions& options;
  ColmapFlags flags;
  fs::path images;
  fs::path masks;  // the photos' masks named as their images, or empty
  SfmResult out;
  std::string seed, threads;
  StepRunner* steps;
  const StageContext* context;  // hands the clusters of the photos to the scheduler, when there is one

  fs::path database() const { return out.database(); }  // always new: the staging folder starts empty

  // COLMAP's feature extraction of the photos of `list` (every photo when empty) into `database`.
  std::vector<std::string> ExtractCommand(const fs::path& database, const fs::path& list = {}) const {
    std::vector<std::string> command = {options.colmap,
                                        "feature_extractor",
                                        "--database_path",
                                        database.string(),
                                        "--image_path",
                                        images.string(),
                                        "--random_seed",
                                        seed,
                                        "--ImageReader.camera_model",
                                        options.camera_model,
                                        "--ImageReader.single_camera",
                                        options.single_camera ? "1" : "0",
                                        flags.extraction_use_gpu,
                                        "0",
                                        flags.extraction_num_threads,
                                        threads,
                                        flags.extraction_max_image_size,
                                        std::to_string(options.max_image_size),
                                        flags.extraction_max_num_features,
                                        std::to_string(options.max_num_features)};
    if (!list.empty()) command.insert(command.end(), {"--image_list_path", list.string()});
    return command;
  }

  // The blocks `photos` are extracted and their pairs matched in, each a part of the stage (a job of its own):
  // under a scheduler, as many as sfm.block_images asks; else one.
  size_t Blocks(size_t photos) const {
    const auto block = static_cast<size_t>(options.block_images);
    return context->Scheduled() ? (photos + block - 1) / block : 1;
  }

  // The features of every photo of `groups` (each group's photos one camera with sfm.single_camera): one extraction
  // for one group, one a group for several, or in blocks (Blocks) merged.
  void ExtractFeatures(const std::vector<CameraGroup>& groups, size_t photos) const {
    if (Blocks(photos) > 1) return ExtractInBlocks(groups);
    if (groups.size() == 1) {
      steps->Run("feature extraction", ExtractCommand(database()));
      return;
    }
    for (size_t i = 0; i < groups.size(); ++i) {
      const fs::path list = out.logs() / format("images_camera_{}.txt", i + 1);
      std::string lines;
      for (const std::string& name : groups[i].images) lines += name + "\n";
      WriteFileAtomic(list, lines);
      steps->Run(format("feature extraction camera {} of {}", i + 1, groups.size()), ExtractCommand(database(), list));
    }
  }

  // Extraction in blocks of at most sfm.block_images photos (sfm_blocks.h), merged.
  void ExtractInBlocks(const std::vector<CameraGroup>& groups) const {
    const fs::path dir = out.dir / "extraction";
    fs::remove_all(dir);
    const std::vector<ExtractionBlock> blocks = PlanExtractionBlocks(groups, options.block_images);
    const std::vector<int> parts = WriteExtractionBlocks(blocks, dir);
    LogInfo(format("sfm: features extracted in {} blocks of at most {} photos, as parts of the stage", parts.size(),
                   options.block_images));
    steps->RunHere("feature extraction",
                   [&] { context->RunParts(kExtractionWork, parts, [&](int part) { ExtractBlock(dir, part); }); });
    steps->RunHere("merging features", [&] { MergeExtractionBlocks(blocks, dir, database(), options.single_camera); });
    fs::remove_all(dir);
  }

  // Block `part` of the photos extracted into its own database: a part of the stage's work.
  void ExtractBlock(const fs::path& dir, int part) const {
    const fs::path database = ExtractionBlockDatabase(dir, part);
    RemoveBlockDatabase(database);
    RunColmap(ExtractCommand(database, ExtractionBlockList(dir, part)),
              out.logs() / format("feature_extraction_block_{}.log", part),
              format("feature extraction of block {}", part));
  }

  // A vocabulary tree of the photos' own features, for matching by retrieval.
  fs::path BuildVocabularyTree(size_t photos) const {
    const fs::path tree = out.vocab_tree();
    const VocabularyTreeSize size = TreeSizeFor(photos, static_cast<size_t>(options.max_num_features));
    steps->Run("vocabulary tree",
               {options.colmap, "vocab_tree_builder", "--database_path", database().string(), "--vocab_tree_path",
                tree.string(), "--num_visual_words", std::to_string(size.words), "--branching",
                std::to_string(kTreeBranching), "--num_iterations", std::to_string(kTreeIterations), "--max_num_images",
                std::to_string(size.photos), "--random_seed", seed});
    return tree;
  }

  // Our descriptor matching (feature_matching.h) of the pairs of exhaustive or sequential matching, or of those
  // COLMAP's retrieval finds (RetrievePairs), then COLMAP's verification of them (in blocks they come verified:
  // MatchInBlocks, which retrieval's pairs and sequential matching's with the pairs that close a walk's loops,
  // LoopPairs, always take). COLMAP matches every pair we could not (a database we cannot read, as another COLMAP
  // version might write it), and by retrieval itself when its retrieval's answer cannot be read.
  void Match(Matcher matcher, size_t photos) const {
    const std::vector<std::pair<size_t, size_t>> loops =
        matcher == Matcher::kSequential
            ? LoopPairs(photos, options.sequential_overlap, std::max(1, options.sequential_overlap / 2))
            : std::vector<std::pair<size_t, size_t>>{};
    fs::path tree;
    std::vector<std::pair<size_t, size_t>> pairs;
    if (matcher == Matcher::kVocabTree) {
      steps->AddSteps(1);  // the retrieval, beside the tree and the matching
      tree = BuildVocabularyTree(photos);
      pairs = RetrievePairs(tree);
    } else {
      pairs = matcher == Matcher::kExhaustive ? ExhaustivePairs(photos)
                                              : SequentialPairs(photos, options.sequential_overlap);
      pairs.insert(pairs.end(), loops.begin(), loops.end());
    }
    // Pairs COLMAP's matcher would not make (retrieval's, the loops) are verified in a block's database here too:
    // COLMAP reads them from a list, and the ids there hold no spaces where names may.
    const bool in_blocks = Blocks(photos) > 1 || (matcher == Matcher::kVocabTree && !pairs.empty()) || !loops.empty();
    bool verified = false;
    steps->RunHere(in_blocks ? "descriptor matching and verification" : "descriptor matching", [&] {
      try {
        if (in_blocks) {
          MatchInBlocks(pairs, Blocks(photos));
          verified = true;
        } else {
          MatchIntoDatabase(database(), pairs);
        }
      } catch (const ExternalToolError& e) {
        LogWarning(format("sfm: COLMAP matches the photos itself (slower): {}", e.what()));
      }
    });
    if (matcher == Matcher::kVocabTree && verified) return;
    if (matcher == Matcher::kVocabTree) steps->AddSteps(1);  // COLMAP's matcher after ours
    steps->Run(std::string(EnumName(matcher)) + " matching", MatcherCommand(matcher, tree));
    if (!loops.empty() && !verified) {
      steps->AddSteps(1);
      VerifyPairs("loop matching", loops);
    }
  }

  // COLMAP's own matcher of kind `matcher` (by retrieval in `tree` for vocab_tree): it matches what the database
  // lacks and verifies what is not verified.
  std::vector<std::string> MatcherCommand(Matcher matcher, const fs::path& tree) const {
    std::vector<std::string> command = {options.colmap,
                                        std::string(EnumName(matcher)) + "_matcher",
                                        "--database_path",
                                        database().string(),
                                        "--random_seed",
                                        seed,
                                        flags.matching_use_gpu,
                                        "0",
                                        flags.matching_num_threads,
                                        threads};
    if (matcher == Matcher::kSequential) {
      command.insert(command.end(), {"--SequentialMatching.overlap", std::to_string(options.sequential_overlap),
                                     "--SequentialMatching.loop_detection", "0"});
    }
    if (matcher == Matcher::kVocabTree) {
      command.insert(command.end(),
                     {"--VocabTreeMatching.vocab_tree_path", tree.string(), "--VocabTreeMatching.num_images",
                      std::to_string(options.retrieval_neighbours + 1)});  // the photo itself comes first
    }
    return command;
  }

  // Each photo paired with its sfm.retrieval_neighbours most similar photos by COLMAP's retrieval in `tree`, and half
  // as many more spread through the next four times as many (RetrievalPicks, retrieval.h), as indices in name order;
  // none when its answer cannot be read (COLMAP's matcher then retrieves and matches itself).
  std::vector<std::pair<size_t, size_t>> RetrievePairs(const fs::path& tree) const {
    const size_t neighbours = options.retrieval_neighbours;
    const RetrievalPicks picks{neighbours, neighbours / 2};
    const fs::path log =
        steps->Run("retrieval",
                   {options.colmap, "vocab_tree_retriever", "--database_path", database().string(), "--vocab_tree_path",
                    tree.string(), "--num_images", std::to_string(picks.Candidates()), "--random_seed", seed},
                   /*allow_failure=*/true);
    try {
      if (!steps->last_ok())
        throw ExternalToolError(format("COLMAP's vocab_tree_retriever failed (log: {})", log.string()));
      return RetrievedPairs(ReadTextFile(log), ColmapDatabase(database(), /*read_only=*/true).Images(), picks);
    } catch (const ExternalToolError& e) {
      LogWarning(format("sfm: COLMAP retrieves and matches the photos itself (slower): {}", e.what()));
      return {};
    }
  }

  // Our matching and COLMAP's verification of `pairs` in `count` blocks of them, each a part of the stage
  // (sfm_blocks.h), merged.
  void MatchInBlocks(const std::vector<std::pair<size_t, size_t>>& pairs, size_t count) const {
    const fs::path dir = out.dir / "matching";
    fs::remove_all(dir);
    const std::vector<int> parts = WriteMatchingBlocks(pairs, count, dir);
    LogInfo(
        format("sfm: {} pairs matched and verified in {} blocks, as parts of the stage", pairs.size(), parts.size()));
    try {
      context->RunParts(kMatchingWork, parts, [&](int part) { MatchBlock(dir, part); });
      MergeMatchingBlocks(dir, parts, database());
    } catch (const ExternalToolError&) {
      fs::remove_all(dir);  // COLMAP matches what is missing (Match): no blocks' databases left in the result
      throw;
    }
    fs::remove_all(dir);
  }

  // Block `part` of the pairs matched by us and verified by COLMAP in the block's database: a part of the stage's
  // work.
  void MatchBlock(const fs::path& dir, int part) const {
    p2n::MatchBlock(database(), dir, part);
    RunColmap({options.colmap, "matches_importer", "--database_path", MatchingBlockDatabase(dir, part).string(),
               "--match_list_path", MatchingBlockNames(dir, part).string(), "--match_type", "pairs", "--random_seed",
               seed, flags.matching_use_gpu, "0", flags.matching_num_threads, threads},
              out.logs() / format("verification_block_{}.log", part), format("verification of block {}", part));
  }

  // COLMAP's verification of `pairs` (indices into the photos in name order), listed in logs/STEP.txt; it matches
  // any pair whose raw matches the database lacks. Only when our matching failed: the list names photos, and a
  // name holding a space is lost.
  void VerifyPairs(const std::string& step, const std::vector<std::pair<size_t, size_t>>& pairs) const {
    const std::vector<std::string> names = ImageNames(images);
    std::string lines;
    for (const auto& [i, j] : pairs) lines += names.at(i) + " " + names.at(j) + "\n";
    const fs::path list = out.logs() / (StepRunner::FileStem(step) + ".txt");
    WriteFileAtomic(list, lines);
    steps->Run(step, {options.colmap, "matches_importer", "--database_path", database().string(), "--match_list_path",
                      list.string(), "--match_type", "pairs", flags.matching_use_gpu, "0", flags.matching_num_threads,
                      threads});
  }

  // COLMAP's incremental mapper, or when `hierarchical` (UsesHierarchicalMapper) its hierarchical one: the
  // photos' scene graph cut into clusters of at most sfm.leaf_max_images, each grown by a quarter of that many
  // photos of its neighbours (COLMAP's 50 for our default 200; the merge aligns the clusters on them), mapped on
  // its own, as many at once as there are threads, and the models merged.
  std::vector<std::string> MapperCommand(bool hierarchical, const fs::path& output) const {
    std::vector<std::string> command({options.colmap, hierarchical ? "hierarchical_mapper" : "mapper",
                                      "--database_path", database().string(), "--image_path", images.string(),
                                      "--output_path", output.string(), "--random_seed", seed,
                                      "--Mapper.min_model_size", "3"});
    if (hierarchical) {
      command.insert(command.end(),
                     {"--num_workers", threads, "--leaf_max_num_images", std::to_string(options.leaf_max_images),
                      "--image_overlap", std::to_string(options.leaf_max_images / 4)});
    } else {
      command.insert(command.end(), {"--Mapper.num_threads", threads});
    }
    command.insert(command.end(), std::begin(kMapperTuning), std::end(kMapperTuning));
    return command;
  }

  // Cluster `part` of the photos (PlanClusters) mapped by COLMAP's incremental mapper, in its folder: a part of
  // the stage's work. A cluster the mapper cannot start on makes no model (the merge leaves it out).
  void MapCluster(const fs::path& clusters, int part) const {
    const fs::path models = ClusterModels(clusters, part);
    fs::remove_all(models);  // what a stopped run of it left
    fs::create_directories(models);
    std::vector<std::string> command = MapperCommand(false, models);
    command.insert(command.end(), {"--image_list_path", ClusterImageList(clusters, part).string()});
    const fs::path log = out.logs() / format("mapping_cluster_{}.log", part);
    const SubprocessResult result = RunColmap(command, log, format("mapping cluster {}", part), /*allow_failure=*/true);
    if (result.signal != 0 || result.exit_code != 0) {
      LogWarning(format("sfm: COLMAP's mapper failed on cluster {} of the photos; log: {}", part, log.string()));
    }
  }

  // The hierarchical mapper's work with each cluster a part for the scheduler (cluster_mapping.h): the models into
  // out/`folder` as the mappers write theirs, the merged one first.
  void MapInClusters(const std::string& step, const std::string& folder) const {
    const fs::path clusters = out.dir / "clusters";
    fs::remove_all(clusters);
    const size_t overlap = options.leaf_max_images / 4;
    const std::vector<int> parts = PlanClusters(database(), clusters, options.leaf_max_images, overlap);
    LogInfo(format("sfm: {} clusters of at most {} photos (each grown by {}), mapped as parts of the stage",
                   parts.size(), options.leaf_max_images, overlap));
    steps->RunHere(step,
                   [&] { context->RunParts(kClusterWork, parts, [&](int part) { MapCluster(clusters, part); }); });
    steps->AddSteps(static_cast<int>(parts.size()) - 1);
    int merges = 0;
    MergeClusterModels(clusters, out.dir / folder, [&](const fs::path& a, const fs::path& b, const fs::path& into) {
      steps->Run(format("merging models {}", ++merges),
                 {options.colmap, "model_merger", "--input_path1", a.string(), "--input_path2", b.string(),
                  "--output_path", into.string(), "--max_reproj_error", kMergeMaxReprojectionError});
    });
  }

  // Runs the mapper (the step `step`) into out/`folder`; returns the folder of the model with the most registered
  // images (COLMAP's exit code says nothing about that) and lists every model in `models`. UserError when there is
  // none.
  fs::path MapLargestModel(size_t photos, const std::string& step, const std::string& folder,
                           std::vector<SfmReport::Model>* models) const {
    fs::create_directories(out.dir / folder);
    const bool hierarchical = UsesHierarchicalMapper(options, photos);
    fs::path log = out.logs() / "mapping_cluster_1.log";  // in clusters: the first one's says why it made nothing
    if (hierarchical && context->Scheduled()) {
      MapInClusters(step, folder);
    } else {
      log = steps->Run(step, MapperCommand(hierarchical, out.dir / folder), /*allow_failure=*/true);
    }
    if (!steps->last_ok()) {
      if (ReadTextFile(log).find("No good initial image pair found") != std::string::npos) {
        throw UserError(
            format("COLMAP found no pair of photos to start the reconstruction from (log: {}): the "
                   "photos overlap too little or show too little texture; {}",
                   log.string(), Advice()));
      }
      throw ExternalToolError(format("COLMAP's mapper failed; log: {}", log.string()));
    }
    models->clear();
    fs::path chosen;
    size_t most = 0;
    for (const fs::directory_entry& entry : fs::directory_iterator(out.dir / folder)) {
      if (!entry.is_directory()) continue;
      const size_t registered = ReadColmapModel(entry.path()).images.size();
      models->push_back({fs::relative(entry.path(), out.dir).string(), registered});
      if (registered > most) {
        most = registered;
        chosen = entry.path();
      }
    }
    if (chosen.empty()) {
      throw UserError(format("COLMAP could not reconstruct any camera from the {} photos (log: {}); {}", photos,
                             log.string(), Advice()));
    }
    return chosen;
  }

  // The hierarchical mapper's merged model triangulated anew from every match, the cameras kept: the clusters'
  // own points tie them together only where they overlap, and the final bundle adjustment then bends the cameras
  // (docs/benchmarks.md). Returns the new model's folder.
  fs::path Retriangulate(const fs::path& model) const {
    const fs::path triangulated = out.dir / "retriangulated";
    fs::create_directories(triangulated);
    steps->Run("triangulation", {options.colmap, "point_triangulator", "--database_path", database().string(),
                                 "--image_path", images.string(), "--input_path", model.string(), "--output_path",
                                 triangulated.string(), "--clear_points", "1", "--Mapper.num_threads", threads});
    return triangulated;
  }

  // A final bundle adjustment that also refines the principal point; returns the refined model's folder.
  fs::path RefinePrincipalPoint(const fs::path& model) const {
    const fs::path refined = out.dir / "refined";
    fs::create_directories(refined);
    steps->Run("bundle adjustment", {options.colmap, "bundle_adjuster", "--input_path", model.string(), "--output_path",
                                     refined.string(), "--BundleAdjustment.refine_principal_point", "1",
                                     "--BundleAdjustment.function_tolerance", kGlobalAdjustmentTolerance});
    return refined;
  }

  // Pinhole images and model in out/undistorted (without COLMAP's dense-stereo scripts), and the masks undistorted
  // as the images (out.undistorted_masks()) when the photos have masks.
  void Undistort(const fs::path& model) const {
    UndistortInto(images, model, out.undistorted(), "undistortion");
    if (masks.empty()) return;
    const fs::path folder = out.undistorted_masks().parent_path();
    UndistortInto(masks, model, folder, "undistortion of the masks");
    for (const char* spare : {"sparse", "stereo"}) fs::remove_all(folder / spare);
  }

  void UndistortInto(const fs::path& from, const fs::path& model, const fs::path& to, const std::string& step) const {
    const fs::path log =
        steps->Run(step, {options.colmap, "image_undistorter", "--image_path", from.string(), "--input_path",
                          model.string(), "--output_path", to.string(), "--output_type", "COLMAP"});
    if (!fs::exists(to / "sparse" / "cameras.bin")) {
      throw ExternalToolError(
          format("COLMAP's image_undistorter wrote no model into '{}'; log: {}", to.string(), log.string()));
    }
    for (const fs::directory_entry& entry : fs::directory_iterator(to)) {
      if (entry.path().extension() == ".sh") fs::remove(entry.path());
    }
  }
};

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
                 focus->median_angle_deg, Advice()));
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
                         100 * min_registered, listed, Advice()));
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
  CheckOption(*this, exhaustive_max_images, exhaustive_max_images >= 2, "must be at least 2");
  CheckOption(*this, sequential_overlap, sequential_overlap >= 1, "must be at least 1");
  CheckOption(*this, retrieval_neighbours, retrieval_neighbours >= 1, "must be at least 1");
  CheckOption(*this, max_image_size, max_image_size >= 100,
              format("must be at least 100 pixels, not {}", max_image_size));
  CheckOption(*this, max_num_features, max_num_features >= 100, "must be at least 100");
  CheckOption(*this, block_images, block_images >= 1, "must be at least 1");
  CheckOption(*this, hierarchical_min_images, hierarchical_min_images >= 0, "must be 0 (never) or a photo count");
  CheckOption(*this, leaf_max_images, leaf_max_images >= 8, "must be at least 8");
  CheckOption(*this, min_registered, min_registered > 0 && min_registered <= 1, "must be in (0, 1]");
  CheckOption(*this, colmap, !colmap.empty(), "must name the COLMAP program");
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

#include "stages/sfm/colmap_run.h"

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
#include "stages/sfm/cluster_mapping.h"
#include "stages/sfm/colmap_flags.h"
#include "stages/sfm/feature_matching.h"
#include "stages/sfm/left_out.h"
#include "stages/sfm/matcher_choice.h"
#include "stages/sfm/retrieval.h"
#include "stages/sfm/sfm_blocks.h"
#include "stages/stage_reports.h"

namespace p2n {
namespace fs = std::filesystem;
namespace {

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

}  // namespace

// Whether `photos` are mapped by COLMAP's hierarchical mapper (sfm.hierarchical_min_images).
bool UsesHierarchicalMapper(const SfmOptions& options, size_t photos) {
  return options.hierarchical_min_images > 0 && photos >= static_cast<size_t>(options.hierarchical_min_images);
}

// What to try when too few photos register.
std::string RegistrationAdvice() {
  return format("try --{} exhaustive, more features (--{}), a larger --{}, or photos with more overlap",
                OptionKey(&SfmOptions::matcher), OptionKey(&SfmOptions::max_num_features),
                OptionKey(&SfmOptions::max_image_size));
}

// Runs a COLMAP command with its log, glog's messages in it too (COLMAP otherwise leaves a file in the temporary
// folder at every run). Failures throw ExternalToolError, unless `allow_failure`.
SubprocessResult RunColmap(std::vector<std::string> argv, const fs::path& log, const std::string& step,
                           bool allow_failure) {
  argv.insert(argv.end(), {"--log_to_stderr", "1"});
  return allow_failure ? RunSubprocess(argv, log, step) : CheckSubprocess(argv, log, step);
}

std::vector<std::string> ImageNames(const fs::path& folder) {
  std::vector<std::string> names;
  for (const fs::directory_entry& entry : fs::directory_iterator(folder)) {
    if (entry.is_regular_file()) names.push_back(entry.path().filename().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

fs::path StepRunner::Run(const std::string& step, const std::vector<std::string>& argv, bool allow_failure) {
  Announce(step);
  const fs::path log = log_dir_ / (FileStem(step) + ".log");
  const SubprocessResult result = RunColmap(argv, log, step, allow_failure);
  last_ok_ = result.signal == 0 && result.exit_code == 0;
  timings_.push_back({step, fs::relative(log, log_dir_.parent_path()).string(), result.wall_seconds});
  ThrowIfCancelled();
  return log;
}

void StepRunner::RunHere(const std::string& step, const std::function<void()>& work) {
  Announce(step);
  const auto start = std::chrono::steady_clock::now();
  work();
  timings_.push_back({step, fs::relative(log_dir_ / "photo2nerf.log", log_dir_.parent_path()).string(),
                      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()});
}

std::string StepRunner::FileStem(std::string step) {
  std::replace(step.begin(), step.end(), ' ', '_');
  return step;
}

void StepRunner::Announce(const std::string& step) {
  ++index_;
  LogInfo(format("sfm: {} ({}/{})", step, index_, total_));
}

std::vector<std::string> ColmapRun::ExtractCommand(const fs::path& database, const fs::path& list) const {
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

size_t ColmapRun::Blocks(size_t photos) const {
  const auto block = static_cast<size_t>(options.block_images);
  return context->Scheduled() ? (photos + block - 1) / block : 1;
}

void ColmapRun::ExtractFeatures(const std::vector<CameraGroup>& groups, size_t photos) const {
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

void ColmapRun::ExtractInBlocks(const std::vector<CameraGroup>& groups) const {
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

void ColmapRun::ExtractBlock(const fs::path& dir, int part) const {
  const fs::path database = ExtractionBlockDatabase(dir, part);
  RemoveBlockDatabase(database);
  RunColmap(ExtractCommand(database, ExtractionBlockList(dir, part)),
            out.logs() / format("feature_extraction_block_{}.log", part),
            format("feature extraction of block {}", part));
}

fs::path ColmapRun::BuildVocabularyTree(size_t photos) const {
  const fs::path tree = out.vocab_tree();
  const VocabularyTreeSize size = TreeSizeFor(photos, static_cast<size_t>(options.max_num_features));
  steps->Run("vocabulary tree",
             {options.colmap, "vocab_tree_builder", "--database_path", database().string(), "--vocab_tree_path",
              tree.string(), "--num_visual_words", std::to_string(size.words), "--branching",
              std::to_string(kTreeBranching), "--num_iterations", std::to_string(kTreeIterations), "--max_num_images",
              std::to_string(size.photos), "--random_seed", seed});
  return tree;
}

void ColmapRun::Match(Matcher matcher, size_t photos) const {
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
    pairs =
        matcher == Matcher::kExhaustive ? ExhaustivePairs(photos) : SequentialPairs(photos, options.sequential_overlap);
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

std::vector<std::string> ColmapRun::MatcherCommand(Matcher matcher, const fs::path& tree) const {
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

std::vector<std::pair<size_t, size_t>> ColmapRun::RetrievePairs(const fs::path& tree) const {
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

void ColmapRun::MatchInBlocks(const std::vector<std::pair<size_t, size_t>>& pairs, size_t count) const {
  const fs::path dir = out.dir / "matching";
  fs::remove_all(dir);
  const std::vector<int> parts = WriteMatchingBlocks(pairs, count, dir);
  LogInfo(format("sfm: {} pairs matched and verified in {} blocks, as parts of the stage", pairs.size(), parts.size()));
  try {
    context->RunParts(kMatchingWork, parts, [&](int part) { MatchBlock(dir, part); });
    MergeMatchingBlocks(dir, parts, database());
  } catch (const ExternalToolError&) {
    fs::remove_all(dir);  // COLMAP matches what is missing (Match): no blocks' databases left in the result
    throw;
  }
  fs::remove_all(dir);
}

void ColmapRun::MatchBlock(const fs::path& dir, int part) const {
  p2n::MatchBlock(database(), dir, part);
  RunColmap({options.colmap, "matches_importer", "--database_path", MatchingBlockDatabase(dir, part).string(),
             "--match_list_path", MatchingBlockNames(dir, part).string(), "--match_type", "pairs", "--random_seed",
             seed, flags.matching_use_gpu, "0", flags.matching_num_threads, threads},
            out.logs() / format("verification_block_{}.log", part), format("verification of block {}", part));
}

void ColmapRun::VerifyPairs(const std::string& step, const std::vector<std::pair<size_t, size_t>>& pairs) const {
  const std::vector<std::string> names = ImageNames(images);
  std::string lines;
  for (const auto& [i, j] : pairs) lines += names.at(i) + " " + names.at(j) + "\n";
  const fs::path list = out.logs() / (StepRunner::FileStem(step) + ".txt");
  WriteFileAtomic(list, lines);
  steps->Run(
      step, {options.colmap, "matches_importer", "--database_path", database().string(), "--match_list_path",
             list.string(), "--match_type", "pairs", flags.matching_use_gpu, "0", flags.matching_num_threads, threads});
}

std::vector<std::string> ColmapRun::MapperCommand(bool hierarchical, const fs::path& output) const {
  std::vector<std::string> command({options.colmap, hierarchical ? "hierarchical_mapper" : "mapper", "--database_path",
                                    database().string(), "--image_path", images.string(), "--output_path",
                                    output.string(), "--random_seed", seed, "--Mapper.min_model_size", "3"});
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

void ColmapRun::MapCluster(const fs::path& clusters, int part) const {
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

void ColmapRun::MapInClusters(const std::string& step, const std::string& folder) const {
  const fs::path clusters = out.dir / "clusters";
  fs::remove_all(clusters);
  const size_t overlap = options.leaf_max_images / 4;
  const std::vector<int> parts = PlanClusters(database(), clusters, options.leaf_max_images, overlap);
  LogInfo(format("sfm: {} clusters of at most {} photos (each grown by {}), mapped as parts of the stage", parts.size(),
                 options.leaf_max_images, overlap));
  steps->RunHere(step, [&] { context->RunParts(kClusterWork, parts, [&](int part) { MapCluster(clusters, part); }); });
  steps->AddSteps(static_cast<int>(parts.size()) - 1);
  int merges = 0;
  MergeClusterModels(clusters, out.dir / folder, [&](const fs::path& a, const fs::path& b, const fs::path& into) {
    steps->Run(format("merging models {}", ++merges),
               {options.colmap, "model_merger", "--input_path1", a.string(), "--input_path2", b.string(),
                "--output_path", into.string(), "--max_reproj_error", kMergeMaxReprojectionError});
  });
}

fs::path ColmapRun::MapLargestModel(size_t photos, const std::string& step, const std::string& folder,
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
                 log.string(), RegistrationAdvice()));
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
                           log.string(), RegistrationAdvice()));
  }
  return chosen;
}

fs::path ColmapRun::Retriangulate(const fs::path& model) const {
  const fs::path triangulated = out.dir / "retriangulated";
  fs::create_directories(triangulated);
  steps->Run("triangulation", {options.colmap, "point_triangulator", "--database_path", database().string(),
                               "--image_path", images.string(), "--input_path", model.string(), "--output_path",
                               triangulated.string(), "--clear_points", "1", "--Mapper.num_threads", threads});
  return triangulated;
}

fs::path ColmapRun::RefinePrincipalPoint(const fs::path& model) const {
  const fs::path refined = out.dir / "refined";
  fs::create_directories(refined);
  steps->Run("bundle adjustment", {options.colmap, "bundle_adjuster", "--input_path", model.string(), "--output_path",
                                   refined.string(), "--BundleAdjustment.refine_principal_point", "1",
                                   "--BundleAdjustment.function_tolerance", kGlobalAdjustmentTolerance});
  return refined;
}

void ColmapRun::Undistort(const fs::path& model) const {
  UndistortInto(images, model, out.undistorted(), "undistortion");
  if (masks.empty()) return;
  const fs::path folder = out.undistorted_masks().parent_path();
  UndistortInto(masks, model, folder, "undistortion of the masks");
  for (const char* spare : {"sparse", "stereo"}) fs::remove_all(folder / spare);
}

void ColmapRun::UndistortInto(const fs::path& from, const fs::path& model, const fs::path& to,
                              const std::string& step) const {
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

}  // namespace p2n

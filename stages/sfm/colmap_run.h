#pragma once
// One COLMAP reconstruction as the sfm stage runs it (ColmapRun): feature extraction, our matching and COLMAP's
// verification, the mapper (incremental or hierarchical, in clusters under a scheduler), the principal point's
// refinement and undistortion, each a COLMAP subprocess with its own log (StepRunner) or a step of ours.

#include <filesystem>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "pipeline/stage.h"
#include "pipeline/subprocess.h"
#include "stages/sfm/colmap_flags.h"
#include "stages/sfm/matcher_choice.h"
#include "stages/sfm/sfm_blocks.h"
#include "stages/sfm/sfm_options.h"
#include "stages/stage_reports.h"
#include "stages/stage_results.h"

namespace p2n {

// Whether `photos` are mapped by COLMAP's hierarchical mapper (sfm.hierarchical_min_images).
bool UsesHierarchicalMapper(const SfmOptions& options, size_t photos);

// What to try when too few photos register.
std::string RegistrationAdvice();

// Runs a COLMAP command with its log, glog's messages in it too (COLMAP otherwise leaves a file in the temporary
// folder at every run). Failures throw ExternalToolError, unless `allow_failure`.
SubprocessResult RunColmap(std::vector<std::string> argv, const std::filesystem::path& log, const std::string& step,
                           bool allow_failure = false);

// The names of the files in `folder`, sorted.
std::vector<std::string> ImageNames(const std::filesystem::path& folder);

// Runs the COLMAP steps in order with their own logs and timings.
class StepRunner {
 public:
  StepRunner(std::filesystem::path log_dir, int total) : log_dir_(std::move(log_dir)), total_(total) {}

  // For the step count in the log: `count` more steps than planned.
  void AddSteps(int count) { total_ += count; }
  // Runs one step; returns its log. Failures throw ExternalToolError, unless `allow_failure`.
  std::filesystem::path Run(const std::string& step, const std::vector<std::string>& argv, bool allow_failure = false);
  // Runs one step of our own, in this process; its log is the stage's.
  void RunHere(const std::string& step, const std::function<void()>& work);
  bool last_ok() const { return last_ok_; }
  // A step's name as the stem of its files in the log folder.
  static std::string FileStem(std::string step);
  const std::vector<SfmReport::Step>& timings() const { return timings_; }

 private:
  void Announce(const std::string& step);

  std::filesystem::path log_dir_;
  int total_;
  int index_ = 0;
  bool last_ok_ = true;
  std::vector<SfmReport::Step> timings_;
};

// One COLMAP reconstruction in the staging folder `out`: each step a subprocess through `steps`.
struct ColmapRun {
  const SfmOptions& options;
  ColmapFlags flags;
  std::filesystem::path images;
  std::filesystem::path masks;  // the photos' masks named as their images, or empty
  SfmResult out;
  std::string seed, threads;
  StepRunner* steps;
  const StageContext* context;  // hands the clusters of the photos to the scheduler, when there is one

  std::filesystem::path database() const { return out.database(); }  // always new: the staging folder starts empty

  // COLMAP's feature extraction of the photos of `list` (every photo when empty) into `database`.
  std::vector<std::string> ExtractCommand(const std::filesystem::path& database,
                                          const std::filesystem::path& list = {}) const;

  // The blocks `photos` are extracted and their pairs matched in, each a part of the stage (a job of its own):
  // under a scheduler, as many as sfm.block_images asks; else one.
  size_t Blocks(size_t photos) const;

  // The features of every photo of `groups` (each group's photos one camera with sfm.single_camera): one extraction
  // for one group, one a group for several, or in blocks (Blocks) merged.
  void ExtractFeatures(const std::vector<CameraGroup>& groups, size_t photos) const;

  // Extraction in blocks of at most sfm.block_images photos (sfm_blocks.h), merged.
  void ExtractInBlocks(const std::vector<CameraGroup>& groups) const;

  // Block `part` of the photos extracted into its own database: a part of the stage's work.
  void ExtractBlock(const std::filesystem::path& dir, int part) const;

  // A vocabulary tree of the photos' own features, for matching by retrieval.
  std::filesystem::path BuildVocabularyTree(size_t photos) const;

  // Our descriptor matching (feature_matching.h) of the pairs of exhaustive or sequential matching, or of those
  // COLMAP's retrieval finds (RetrievePairs), then COLMAP's verification of them (in blocks they come verified:
  // MatchInBlocks, which retrieval's pairs and sequential matching's with the pairs that close a walk's loops,
  // LoopPairs, always take). COLMAP matches every pair we could not (a database we cannot read, as another COLMAP
  // version might write it), and by retrieval itself when its retrieval's answer cannot be read.
  void Match(Matcher matcher, size_t photos) const;

  // COLMAP's own matcher of kind `matcher` (by retrieval in `tree` for vocab_tree): it matches what the database
  // lacks and verifies what is not verified.
  std::vector<std::string> MatcherCommand(Matcher matcher, const std::filesystem::path& tree) const;

  // Each photo paired with its sfm.retrieval_neighbours most similar photos by COLMAP's retrieval in `tree`, and half
  // as many more spread through the next four times as many (RetrievalPicks, retrieval.h), as indices in name order;
  // none when its answer cannot be read (COLMAP's matcher then retrieves and matches itself).
  std::vector<std::pair<size_t, size_t>> RetrievePairs(const std::filesystem::path& tree) const;

  // Our matching and COLMAP's verification of `pairs` in `count` blocks of them, each a part of the stage
  // (sfm_blocks.h), merged.
  void MatchInBlocks(const std::vector<std::pair<size_t, size_t>>& pairs, size_t count) const;

  // Block `part` of the pairs matched by us and verified by COLMAP in the block's database: a part of the stage's
  // work.
  void MatchBlock(const std::filesystem::path& dir, int part) const;

  // COLMAP's verification of `pairs` (indices into the photos in name order), listed in logs/STEP.txt; it matches
  // any pair whose raw matches the database lacks. Only when our matching failed: the list names photos, and a
  // name holding a space is lost.
  void VerifyPairs(const std::string& step, const std::vector<std::pair<size_t, size_t>>& pairs) const;

  // COLMAP's incremental mapper, or when `hierarchical` (UsesHierarchicalMapper) its hierarchical one: the
  // photos' scene graph cut into clusters of at most sfm.leaf_max_images, each grown by a quarter of that many
  // photos of its neighbours (COLMAP's 50 for our default 200; the merge aligns the clusters on them), mapped on
  // its own, as many at once as there are threads, and the models merged.
  std::vector<std::string> MapperCommand(bool hierarchical, const std::filesystem::path& output) const;

  // Cluster `part` of the photos (PlanClusters) mapped by COLMAP's incremental mapper, in its folder: a part of
  // the stage's work. A cluster the mapper cannot start on makes no model (the merge leaves it out).
  void MapCluster(const std::filesystem::path& clusters, int part) const;

  // The hierarchical mapper's work with each cluster a part for the scheduler (cluster_mapping.h): the models into
  // out/`folder` as the mappers write theirs, the merged one first.
  void MapInClusters(const std::string& step, const std::string& folder) const;

  // Runs the mapper (the step `step`) into out/`folder`; returns the folder of the model with the most registered
  // images (COLMAP's exit code says nothing about that) and lists every model in `models`. UserError when there is
  // none.
  std::filesystem::path MapLargestModel(size_t photos, const std::string& step, const std::string& folder,
                                        std::vector<SfmReport::Model>* models) const;

  // The hierarchical mapper's merged model triangulated anew from every match, the cameras kept: the clusters'
  // own points tie them together only where they overlap, and the final bundle adjustment then bends the cameras
  // (docs/benchmarks.md). Returns the new model's folder.
  std::filesystem::path Retriangulate(const std::filesystem::path& model) const;

  // A final bundle adjustment that also refines the principal point; returns the refined model's folder.
  std::filesystem::path RefinePrincipalPoint(const std::filesystem::path& model) const;

  // Pinhole images and model in out/undistorted (without COLMAP's dense-stereo scripts), and the masks undistorted
  // as the images (out.undistorted_masks()) when the photos have masks.
  void Undistort(const std::filesystem::path& model) const;

  // COLMAP's image_undistorter of the images in `from` by `model` into `to` (the step `step`); ExternalToolError
  // when it wrote no model.
  void UndistortInto(const std::filesystem::path& from, const std::filesystem::path& model,
                     const std::filesystem::path& to, const std::string& step) const;
};

}  // namespace p2n

#pragma once
// The sfm stage: COLMAP feature_extractor -> matcher -> mapper -> bundle_adjuster (principal point) ->
// image_undistorter, each a subprocess with its own log, always on a fresh database. Picks the model with the
// most registered images and writes sfm_report.json.

#include <string>
#include <vector>

#include "pipeline/options.h"
#include "stages/sfm/matcher_choice.h"
#include "stages/sfm/sfm_blocks.h"
#include "stages/sfm/sfm_options.h"
#include "stages/stage_reports.h"
#include "stages/stage_results.h"

namespace p2n {

// The photos grouped by camera (CameraGroup, sfm_blocks.h).
std::vector<CameraGroup> CameraGroups(const IngestReport& ingest);

class SfmStage : public StageOf<SfmResult> {
 public:
  // 2: loop pairs in sequential matching, the reasons photos were left out; 3: the final bundle adjustment stops
  // when the cost stops falling.
  int format_version() const override { return 3; }
  std::vector<std::string> upstream() const override { return {IngestResult::kId.name}; }
  // "tool colmap" -> its version: a result made with another COLMAP is stale.
  std::map<std::string, std::string> ExternalInputs(const Workspace& workspace, const Config& config) const override;
  void Run(StageContext& context) const override;
  // Under a scheduler, features are extracted in blocks of photos and matched in blocks of pairs (sfm_blocks.h;
  // kExtractionWork, kMatchingWork: part k does block k), and photos the hierarchical mapper would map are mapped in
  // clusters (cluster_mapping.h; kClusterWork: part k maps cluster k).
  void RunPart(StageContext& context, const std::string& work, int part) const override;
  void CheckResult(const std::filesystem::path& result_dir, const Config& config) const override;
};

}  // namespace p2n

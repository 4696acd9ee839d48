#pragma once
// The poses stage of a dataset that already has cameras: validates and copies its images (decoding each, taking
// its mask from the dataset's masks/ as alpha, undistorting distorted ones (transparent ones keep their alpha),
// downsizing those larger than poses.max_image_size), normalises the cameras like the COLMAP path does and writes
// the same transforms.json.
// Replaces ingest -> sfm -> poses.

#include <string>

#include "stages/ingest/import_options.h"
#include "stages/sfm/poses_options.h"
#include "stages/stage_results.h"

namespace p2n {

class ImportStage : public StageOf<PosesResult> {
 public:
  // 2: images downsized to poses.max_image_size; 3: the background recorded only where the images show it, and
  // fewer than 20 views (but LLFF data) hold out views inside the span of the others; 4: transparent images keep
  // their alpha; 5: sparse_tracks.json, and LLFF's points where the dataset has them; 6: masks/ as alpha
  int format_version() const override { return 6; }
  std::vector<std::string> option_sections() const override {
    return {PosesOptions::kSection, ImportOptions::kSection};
  }
  // Every file of the dataset that the result depends on, by SHA-1.
  std::map<std::string, std::string> ExternalInputs(const Workspace& workspace, const Config& config) const override;
  void Run(StageContext& context) const override;
};

}  // namespace p2n

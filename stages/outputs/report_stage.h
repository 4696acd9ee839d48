#pragma once
// The report stage: one self-contained HTML page per workspace (report.html; images, plots, video and the
// script of its 3D view are inside it, so it opens without a network or the workspace): error against run
// time, the stages with their wall times, cache state and options, the camera recovery, the held-out photos
// beside their renders and error maps, the video, a 3D view of the cameras and sparse points, the exports.

#include "stages/outputs/report_options.h"
#include "stages/stage_results.h"

namespace p2n {

class ReportStage : public StageOf<ReportResult> {
 public:
  int format_version() const override { return 1; }
  std::vector<std::string> upstream() const override {
    return {PosesResult::kId.name, TrainResult::kId.name, SplatResult::kId.name, RenderResult::kId.name,
            ExportResult::kId.name};
  }
  void Run(StageContext& context) const override;
};

}  // namespace p2n

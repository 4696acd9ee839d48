#include "stages/stages.h"

#include "pipeline/format.h"
#include "stages/dataset_import.h"
#include "stages/export_stage.h"
#include "stages/import_stage.h"
#include "stages/ingest_stage.h"
#include "stages/poses_stage.h"
#include "stages/render_stage.h"
#include "stages/report_stage.h"
#include "stages/sfm_stage.h"
#include "stages/train_stage.h"

namespace p2n {

void RunOptions::Check() const {
  CheckOption(threads >= 0, "run.threads", format("must be 0 (every core) or more, not {}", threads));
}

OptionRegistry AllOptions() {
  OptionRegistry registry;
  RegisterOptions<RunOptions>(registry, "run");
  RegisterOptions<IngestOptions>(registry, "ingest");
  RegisterOptions<SfmOptions>(registry, "sfm");
  RegisterOptions<PosesOptions>(registry, "poses");
  RegisterOptions<ImportOptions>(registry, "import");
  RegisterOptions<TrainOptions>(registry, "train");
  RegisterOptions<RenderStageOptions>(registry, "render");
  RegisterOptions<ExportOptions>(registry, "export");
  RegisterOptions<ReportOptions>(registry, "report");
  return registry;
}

void CheckAllOptions(const Config& config) {
  ReadOptions<RunOptions>(config, "run");
  ReadOptions<IngestOptions>(config, "ingest");
  ReadOptions<SfmOptions>(config, "sfm");
  ReadOptions<PosesOptions>(config, "poses");
  ReadOptions<ImportOptions>(config, "import");
  ReadOptions<TrainOptions>(config, "train");
  ReadOptions<RenderStageOptions>(config, "render");
  ReadOptions<ExportOptions>(config, "export");
  ReadOptions<ReportOptions>(config, "report");
}

Runner MakeRunner(const std::optional<std::filesystem::path>& input) {
  std::vector<std::unique_ptr<Stage>> stages;
  if (input && !DatasetKind(*input).empty()) {
    stages.push_back(std::make_unique<ImportStage>());
  } else {
    stages.push_back(std::make_unique<IngestStage>());
    stages.push_back(std::make_unique<SfmStage>());
    stages.push_back(std::make_unique<PosesStage>());
  }
  stages.push_back(std::make_unique<TrainStage>());
  stages.push_back(std::make_unique<RenderStage>());
  stages.push_back(std::make_unique<ExportStage>());
  stages.push_back(std::make_unique<ReportStage>());
  return Runner(std::move(stages));
}

}  // namespace p2n

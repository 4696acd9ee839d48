#include "stages/stages.h"

#include "base/format.h"
#include "formats/dataset_import.h"
#include "stages/fitting/splat_stage.h"
#include "stages/fitting/train_stage.h"
#include "stages/ingest/import_stage.h"
#include "stages/ingest/ingest_stage.h"
#include "stages/outputs/export_stage.h"
#include "stages/outputs/render_stage.h"
#include "stages/outputs/report_stage.h"
#include "stages/sfm/poses_stage.h"
#include "stages/sfm/sfm_stage.h"

namespace p2n {

namespace {

// Calls `section.operator()<Options>()` for every option section, in the order `--help` lists them: the one
// table of sections.
template <class Section>
void ForEachSection(Section&& section) {
  section.template operator()<RunOptions>();
  section.template operator()<SlurmOptions>();
  section.template operator()<IngestOptions>();
  section.template operator()<SfmOptions>();
  section.template operator()<PosesOptions>();
  section.template operator()<ImportOptions>();
  section.template operator()<TrainOptions>();
  section.template operator()<SplatOptions>();
  section.template operator()<RenderStageOptions>();
  section.template operator()<ExportOptions>();
  section.template operator()<ReportOptions>();
}

}  // namespace

OptionRegistry AllOptions() {
  OptionRegistry registry;
  ForEachSection([&]<class Options>() { RegisterOptions<Options>(registry, Options::kSection); });
  return registry;
}

void CheckAllOptions(const Config& config) {
  ForEachSection([&]<class Options>() { ReadOptions<Options>(config); });
}

Runner MakeRunner(const std::optional<std::filesystem::path>& input) {
  std::vector<std::unique_ptr<Stage>> stages;
  if (input && DetectDataset(*input)) {
    stages.push_back(std::make_unique<ImportStage>());
  } else {
    stages.push_back(std::make_unique<IngestStage>());
    stages.push_back(std::make_unique<SfmStage>());
    stages.push_back(std::make_unique<PosesStage>());
  }
  stages.push_back(std::make_unique<TrainStage>());
  stages.push_back(std::make_unique<SplatStage>());
  stages.push_back(std::make_unique<RenderStage>());
  stages.push_back(std::make_unique<ExportStage>());
  stages.push_back(std::make_unique<ReportStage>());
  return Runner(std::move(stages));
}

}  // namespace p2n

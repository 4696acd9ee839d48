#include "stages/stages.h"

#include "formats/dataset_import.h"
#include "pipeline/format.h"
#include "stages/export_stage.h"
#include "stages/import_stage.h"
#include "stages/ingest_stage.h"
#include "stages/poses_stage.h"
#include "stages/render_stage.h"
#include "stages/report_stage.h"
#include "stages/sfm_stage.h"
#include "stages/splat_stage.h"
#include "stages/train_stage.h"

namespace p2n {

void RunOptions::Check() const {
  CheckOption(threads >= 0, "run.threads", format("must be 0 (every core) or more, not {}", threads));
}

namespace {

// Calls `section.operator()<Options>(name)` for every option section, in the order `--help` lists them: the one
// table of sections.
template <class Section>
void ForEachSection(Section&& section) {
  section.template operator()<RunOptions>("run");
  section.template operator()<IngestOptions>("ingest");
  section.template operator()<SfmOptions>("sfm");
  section.template operator()<PosesOptions>("poses");
  section.template operator()<ImportOptions>("import");
  section.template operator()<TrainOptions>("train");
  section.template operator()<SplatOptions>("splat");
  section.template operator()<RenderStageOptions>("render");
  section.template operator()<ExportOptions>("export");
  section.template operator()<ReportOptions>("report");
}

}  // namespace

OptionRegistry AllOptions() {
  OptionRegistry registry;
  ForEachSection([&]<class Options>(const char* name) { RegisterOptions<Options>(registry, name); });
  return registry;
}

void CheckAllOptions(const Config& config) {
  ForEachSection([&]<class Options>(const char* name) { ReadOptions<Options>(config, name); });
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
  stages.push_back(std::make_unique<SplatStage>());
  stages.push_back(std::make_unique<RenderStage>());
  stages.push_back(std::make_unique<ExportStage>());
  stages.push_back(std::make_unique<ReportStage>());
  return Runner(std::move(stages));
}

}  // namespace p2n

// libFuzzer: the reports between stages (ingest_report.json, sfm_report.json, train_report.json,
// splat_report.json, eval.json, render_report.json, export_report.json) as their readers read them: any input is read
// or refused with a UserError.
#include "base/errors.h"
#include "stages/stage_reports.h"
#include "tests/fuzz/fuzz_util.h"

namespace {

template <class Report>
void TryRead(const std::filesystem::path& file) {
  try {
    Report::Read(file);
  } catch (const p2n::UserError&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto file = p2n::fuzz::ScratchDir() / "report.json";
  p2n::fuzz::WriteBytes(file, data, size);
  TryRead<p2n::IngestReport>(file);
  TryRead<p2n::SfmReport>(file);
  TryRead<p2n::TrainReport>(file);
  TryRead<p2n::SplatReport>(file);
  TryRead<p2n::EvalReport>(file);
  TryRead<p2n::PathReport>(file);
  TryRead<p2n::ExportReport>(file);
  return 0;
}

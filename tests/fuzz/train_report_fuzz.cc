// libFuzzer: train_report.json's camera refinement, as the splat and export stages read it back (ReadTrainedField),
// and on its own from whatever JSON the file holds.
#include "base/errors.h"
#include "base/file_util.h"
#include "stages/camera_corrections.h"
#include "stages/stage_reports.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto file = p2n::fuzz::ScratchDir() / "train_report.json";
  p2n::fuzz::WriteBytes(file, data, size);
  try {
    const nlohmann::json json = p2n::ReadJsonFile(file);
    p2n::CameraCorrections(json.is_object() ? json.value("camera_refinement", nlohmann::json()) : nlohmann::json(),
                           file);
  } catch (const p2n::UserError&) {
  }
  try {
    p2n::CameraCorrections(p2n::TrainReport::Read(file).camera_refinement, file);
  } catch (const p2n::UserError&) {
  }
  return 0;
}

#include "stages/stage_io.h"

#include "base/errors.h"
#include "base/file_util.h"
#include "base/format.h"

namespace p2n {

void WriteOrExplain(const std::function<void()>& write) {
  try {
    write();
  } catch (const UserError&) {
    throw;
  } catch (const std::runtime_error& error) {
    throw UserError(
        format("{}; check the free space, file-size limit (ulimit -f) and permissions of the workspace, "
               "then run again (finished stages are kept)",
               error.what()));
  }
}

NerfModel LoadTrainedModel(const std::filesystem::path& model_bin) {
  try {
    return LoadModel(model_bin);
  } catch (const std::runtime_error& error) {
    throw UserError(format("{}; remake it with: photo2nerf train -w WORKSPACE --force", error.what()));
  }
}

TrainedField ReadTrainedField(const TrainResult& train) {
  TrainedField field{LoadTrainedModel(train.model()), TrainReport::Read(train.report()), {}};
  field.corrections = CameraCorrections(field.report.camera_refinement, train.report());
  return field;
}

std::optional<nlohmann::json> OfThisRun(const StageContext& context, const std::filesystem::path& path) {
  if (!std::filesystem::exists(path)) return std::nullopt;
  nlohmann::json json = ReadJsonFile(path);
  if (json.value("key", "") != context.key) return std::nullopt;
  return json;
}

}  // namespace p2n

// The trainer's checkpoints (trainer.h: SaveCheckpoint, LoadCheckpoint): magic, the options that must match, the
// model (with its background), the step counters, every optimiser's moments, the per-view appearance and camera
// corrections, and the error map.

#include "nerf/trainer.h"

namespace p2n {
namespace {

constexpr char kCheckpointMagic[] = "P2NCKPT1";

// The options that must match for a checkpoint to be resumed.
nlohmann::json CheckpointIdentity(const TrainerOptions& options) {
  return {{"field", options.field},
          {"occupancy_resolution", options.occupancy_resolution},
          {"march_step", options.march_step},
          {"fine_march_step", options.fine_march_step},
          {"fine_march_from", options.fine_march_from},
          {"space", SceneSpaceName(options.space)},
          {"stratified_samples", options.stratified_samples},
          {"appearance", options.appearance},
          {"refine_cameras", options.refine_cameras},
          {"error_sampling", options.error_sampling},
          {"learn_background", options.learn_background},
          {"seed", options.seed}};
}

}  // namespace

void Trainer::SaveCheckpoint(BinaryWriter* writer) const {
  writer->PutBytes(kCheckpointMagic, 8);
  writer->PutString(CheckpointIdentity(options_).dump());
  WriteModel(model_, writer, true);
  writer->Put<int32_t>(step_);
  writer->Put<int32_t>(skipped_);
  writer->Put<double>(samples_per_ray_);
  writer->Put<uint64_t>(model_.occupancy.cursor());
  for (const Adam<float>& adam : dense_adams_) adam.Save(writer);
  if (grid_adam_) grid_adam_->Save(writer);
  if (background_adam_) background_adam_->Save(writer);
  if (appearance_adam_) {
    writer->PutVector(appearance_);
    appearance_adam_->Save(writer);
  }
  if (pose_adam_) {
    writer->PutVector(poses_);
    pose_adam_->Save(writer);
  }
  if (error_map_) error_map_->Save(writer);
}

void Trainer::LoadCheckpoint(BinaryReader* reader) {
  reader->ExpectMagic(kCheckpointMagic, "a photo2nerf training checkpoint");
  if (reader->GetString() != CheckpointIdentity(options_).dump()) {
    reader->Fail("it was written by a training run with other options");
  }
  NerfModel model = ReadModel(reader);
  const int step = reader->Get<int32_t>(), skipped = reader->Get<int32_t>();
  const double samples_per_ray = reader->Get<double>();
  model.occupancy.set_cursor(reader->Get<uint64_t>());
  for (Adam<float>& adam : dense_adams_) adam.Load(reader);
  if (grid_adam_) grid_adam_->Load(reader);
  if (background_adam_) background_adam_->Load(reader);
  std::vector<float> appearance;
  if (appearance_adam_) {
    appearance = reader->GetVector<float>(appearance_.size());
    appearance_adam_->Load(reader);
  }
  std::vector<float> poses;
  if (pose_adam_) {
    poses = reader->GetVector<float>(poses_.size());
    pose_adam_->Load(reader);
  }
  std::unique_ptr<ErrorMap> error_map;
  if (error_map_) {
    error_map = std::make_unique<ErrorMap>(*error_map_);
    error_map->Load(reader);
  }
  if (!reader->AtEnd()) reader->Fail("there are bytes after the checkpoint");
  appearance_ = std::move(appearance);
  poses_ = std::move(poses);
  error_map_ = std::move(error_map);
  model_ = std::move(model);
  step_ = step;
  skipped_ = skipped;
  samples_per_ray_ = samples_per_ray;
}

}  // namespace p2n

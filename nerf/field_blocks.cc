#include "nerf/field_blocks.h"

#include <algorithm>
#include <cstring>
#include <stdexcept>

#include "nerf/renderer.h"

namespace p2n {

std::vector<Eigen::Matrix3Xd> SurfaceSeen(const NerfModel& model, const std::vector<TrainView>& views,
                                          int rays_per_side) {
  std::vector<Eigen::Matrix3Xd> seen;
  RenderOptions options;
  options.median_depth = true;
  for (const TrainView& view : views) {
    std::vector<Ray> rays;
    for (int j = 0; j < rays_per_side; ++j) {
      for (int i = 0; i < rays_per_side; ++i) {
        rays.push_back(CameraRay(view.camera, (i + 0.5) * view.camera.width / rays_per_side,
                                 (j + 0.5) * view.camera.height / rays_per_side));
      }
    }
    const std::vector<Eigen::Vector2d> near_far(rays.size(), Eigen::Vector2d(view.near, view.far));
    std::vector<float> rgb(3 * rays.size()), depth(rays.size()), opacity(rays.size());
    RenderRays(model, rays, near_far, options, rgb.data(), depth.data(), opacity.data(), nullptr);
    std::vector<Eigen::Vector3d> points;
    for (size_t r = 0; r < rays.size(); ++r) {
      if (!(opacity[r] >= 0.5f)) continue;
      points.push_back(FieldPoint(model, rays[r].origin + (depth[r] / opacity[r]) * rays[r].direction));
    }
    Eigen::Matrix3Xd matrix(3, points.size());
    for (size_t p = 0; p < points.size(); ++p) matrix.col(p) = points[p];
    seen.push_back(std::move(matrix));
  }
  return seen;
}

void CopyFieldParameters(RadianceField<float>& from, RadianceField<float>* to) {
  if (from.Config() != to->Config()) throw std::invalid_argument("CopyFieldParameters: the fields' configs differ");
  const std::vector<ParamBlock<float>> source = from.DenseParams(), target = to->DenseParams();
  for (size_t b = 0; b < source.size(); ++b) {
    std::memcpy(target[b].data, source[b].data, source[b].size * sizeof(float));
  }
  if (Encoding<float>* encoding = from.TrainableEncoding()) {
    std::memcpy(to->TrainableEncoding()->params(), encoding->params(), encoding->num_params() * sizeof(float));
  }
}

NerfModel MergeBlockModels(const Slabs& slabs, std::vector<NerfModel> blocks) {
  if (static_cast<int>(blocks.size()) != slabs.count()) {
    throw std::invalid_argument("MergeBlockModels: " + std::to_string(blocks.size()) + " models for " +
                                std::to_string(slabs.count()) + " slabs");
  }
  NerfModel merged;
  const NerfModel& first = blocks.front();
  merged.space = first.space;
  merged.forward = first.forward;
  merged.march_step = first.march_step;
  merged.stratified_samples = first.stratified_samples;
  merged.info = first.info;
  merged.background = {0, 0, 0};
  std::vector<const OccupancyGrid*> grids;
  std::vector<std::unique_ptr<RadianceField<float>>> fields;
  for (NerfModel& block : blocks) {
    if (block.space != first.space || block.stratified_samples != first.stratified_samples) {
      throw std::invalid_argument("MergeBlockModels: the blocks' scene spaces or sampling differ");
    }
    merged.march_step = std::min(merged.march_step, block.march_step);
    for (int c = 0; c < 3; ++c) merged.background[c] += block.background[c] / blocks.size();
    grids.push_back(&block.occupancy);
    fields.push_back(std::move(block.field));
  }
  merged.occupancy =
      OccupancyGrid::Merge(grids, [&](const Eigen::Vector3d& centre) { return slabs.SlabOf(centre[slabs.axis]); });
  merged.field = std::make_unique<BlockedField<float>>(slabs, std::move(fields));
  return merged;
}

}  // namespace p2n

#pragma once
// Why COLMAP's mapper left a photo out of the chosen model, from what its database and the other models hold:
// no features (a blank, dark or blurred photo), no verified match with any other photo (it shows something else),
// apart (its matches are all with photos left out too: a group that shares nothing with the model, such as another
// scene), too few inliers to place it (its best pair with a photo of the model has fewer than the mapper needs), in
// another model (the photos split into groups that share too little), or not placed though it matches the model's
// photos (its matches disagree with the model's points); unknown when the database cannot be read.

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "stages/stage_reports.h"

namespace p2n {

// COLMAP's Mapper.abs_pose_min_num_inliers: the 2D-3D inliers it needs to place a photo.
inline constexpr size_t kMapperMinInliers = 30;

// What the database and the models say of one photo left out.
struct LeftOutEvidence {
  size_t features = 0;
  size_t matched_in_model = 0;  // photos of the chosen model it has verified matches with
  size_t best_inliers = 0;      // the inlier matches of its best verified pair with one of them
  size_t matched_left_out = 0;  // photos left out too that it has verified matches with
  std::string other_model;      // the other model that holds it (its folder), if any
  size_t other_model_size = 0;
};

SfmReport::LeftOut ExplainLeftOut(const std::string& image, const LeftOutEvidence& evidence);

// Each photo of `left_out` explained from COLMAP's database and the models in `sfm_dir` other than `chosen_model`
// (paths relative to `sfm_dir`, as SfmReport::Model's). A database that cannot be read (another COLMAP's) leaves
// the photos no other model holds unknown, saying why.
std::vector<SfmReport::LeftOut> ExplainLeftOut(const std::vector<std::string>& left_out,
                                               const std::filesystem::path& database,
                                               const std::filesystem::path& sfm_dir,
                                               const std::vector<SfmReport::Model>& models,
                                               const std::string& chosen_model);

}  // namespace p2n

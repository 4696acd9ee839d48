#include "stages/sfm/left_out.h"

#include <algorithm>
#include <map>
#include <set>

#include "base/errors.h"
#include "base/format.h"
#include "formats/colmap_database.h"
#include "formats/colmap_model.h"

namespace p2n {
namespace fs = std::filesystem;

namespace {

// Each photo's features and verified pairs, from COLMAP's database; pairs with a photo of `left_out` counted apart.
void AddDatabaseEvidence(const fs::path& database, const std::set<std::string>& left_out,
                         std::map<std::string, LeftOutEvidence>* evidence) {
  const ColmapDatabase db(database);
  std::map<uint32_t, std::string> names;
  for (const ColmapDatabaseImage& image : db.Images()) names[image.id] = image.name;
  for (const auto& [id, count] : db.FeatureCounts()) (*evidence)[names[id]].features = count;
  for (const VerifiedPair& pair : db.VerifiedPairs()) {
    const std::string& a = names[pair.image_id1];
    const std::string& b = names[pair.image_id2];
    for (const auto& [photo, other] : {std::pair(&a, &b), std::pair(&b, &a)}) {
      LeftOutEvidence& e = (*evidence)[*photo];
      if (left_out.count(*other)) {
        ++e.matched_left_out;
      } else {
        ++e.matched_in_model;
        e.best_inliers = std::max(e.best_inliers, pair.inliers);
      }
    }
  }
}

}  // namespace

SfmReport::LeftOut ExplainLeftOut(const std::string& image, const LeftOutEvidence& evidence) {
  if (!evidence.other_model.empty()) {
    return {image, LeftOutReason::kOtherModel,
            format("registered in another model ({}, {} photos) that shares too little with the chosen one",
                   evidence.other_model, evidence.other_model_size)};
  }
  if (evidence.features == 0) {
    return {image, LeftOutReason::kNoFeatures, "COLMAP found no features in it (blank, dark or blurred?)"};
  }
  if (evidence.matched_in_model == 0 && evidence.matched_left_out == 0) {
    return {image, LeftOutReason::kNoMatches,
            format("none of its {} features has a verified match in another photo", evidence.features)};
  }
  if (evidence.matched_in_model == 0) {
    return {image, LeftOutReason::kApart,
            format("it matches only {} photos left out too: a group that shares nothing with the model (another "
                   "scene, or too far from the rest)",
                   evidence.matched_left_out)};
  }
  const std::string matched = format("verified matches with {} photos of the model, at most {} inliers",
                                     evidence.matched_in_model, evidence.best_inliers);
  if (evidence.best_inliers < kMapperMinInliers) {
    return {image, LeftOutReason::kTooFewInliers,
            format("{}; the mapper needs {} to place a photo", matched, kMapperMinInliers)};
  }
  return {image, LeftOutReason::kNotPlaced, matched + ", yet the mapper could not place it against the model"};
}

std::vector<SfmReport::LeftOut> ExplainLeftOut(const std::vector<std::string>& left_out, const fs::path& database,
                                               const fs::path& sfm_dir, const std::vector<SfmReport::Model>& models,
                                               const std::string& chosen_model) {
  if (left_out.empty()) return {};
  std::map<std::string, LeftOutEvidence> evidence;
  for (const SfmReport::Model& model : models) {
    if (model.path == chosen_model) continue;
    for (const auto& [id, image] : ReadColmapModel(sfm_dir / model.path).images) {
      evidence[image.name].other_model = model.path;
      evidence[image.name].other_model_size = model.registered;
    }
  }
  std::string unreadable;
  try {
    AddDatabaseEvidence(database, {left_out.begin(), left_out.end()}, &evidence);
  } catch (const ExternalToolError& e) {
    unreadable = e.what();
  }
  std::vector<SfmReport::LeftOut> explained;
  for (const std::string& image : left_out) {
    const LeftOutEvidence& photo = evidence[image];
    explained.push_back(!unreadable.empty() && photo.other_model.empty()
                            ? SfmReport::LeftOut{image, LeftOutReason::kUnknown, unreadable}
                            : ExplainLeftOut(image, photo));
  }
  return explained;
}

}  // namespace p2n

// Why a photo was left out, from the evidence of COLMAP's database and models: each reason where its evidence
// decides it, in the order the mapper's needs come (another model first, then features, matches, inliers).

#include <catch2/catch.hpp>

#include "stages/sfm/left_out.h"

namespace p2n::testing {
namespace {

LeftOutEvidence Evidence(size_t features, size_t matched_in_model, size_t best_inliers, size_t matched_left_out,
                         const std::string& other_model = "", size_t other_model_size = 0) {
  LeftOutEvidence evidence;
  evidence.features = features;
  evidence.matched_in_model = matched_in_model;
  evidence.best_inliers = best_inliers;
  evidence.matched_left_out = matched_left_out;
  evidence.other_model = other_model;
  evidence.other_model_size = other_model_size;
  return evidence;
}

LeftOutReason Reason(const LeftOutEvidence& evidence) { return ExplainLeftOut("a.jpg", evidence).reason; }

}  // namespace

TEST_CASE("a photo left out: the reason its database and models give", "[sfm]") {
  CHECK(Reason(Evidence(0, 0, 0, 0)) == LeftOutReason::kNoFeatures);
  CHECK(Reason(Evidence(900, 0, 0, 0)) == LeftOutReason::kNoMatches);
  CHECK(Reason(Evidence(900, 0, 0, 2)) == LeftOutReason::kApart);
  CHECK(Reason(Evidence(900, 3, 29, 2)) == LeftOutReason::kTooFewInliers);
  CHECK(Reason(Evidence(900, 3, 30, 0)) == LeftOutReason::kNotPlaced);
  CHECK(Reason(Evidence(900, 3, 300, 0, "sparse/1", 4)) == LeftOutReason::kOtherModel);  // whatever its matches

  const SfmReport::LeftOut few = ExplainLeftOut("a.jpg", Evidence(900, 3, 12, 0));
  CHECK(few.image == "a.jpg");
  CHECK_THAT(few.detail, Catch::Contains("3 photos of the model, at most 12 inliers") && Catch::Contains("needs 30"));
  CHECK_THAT(ExplainLeftOut("b.jpg", Evidence(0, 0, 0, 0, "sparse/1", 4)).detail,
             Catch::Contains("sparse/1, 4 photos"));
}

}  // namespace p2n::testing

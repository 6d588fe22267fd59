// Reports of a pair verification run (matching/verification_driver.h):
//
// CSV, one header line and one line a pair:
//   image_id1,image_id2,name1,name2,source,num_matches,has_vio_prior,
//   vio_outlier_ratio,vio_rotation_only,vio_rejected,num_inliers,accepted,
//   resumed,reason
// booleans as 0/1, the outlier ratio with 6 decimals or "nan" when the VIO
// check did not run. Names are written as they are (database image names
// hold no comma; a name with a comma, quote or line break is an InputError).
//
// JSON: {"summary": {counts and seconds}, "options": {name: value text},
//        "pairs": [{one object a pair, the CSV's fields; vio_outlier_ratio
//                   null when the check did not run}]}.
//
// Both are written atomically (temporary file, then rename).
#pragma once

#include <filesystem>
#include <vector>

#include "viosfm/scene/pair_decision.h"

namespace viosfm {

void WritePairDecisionsCsv(const std::filesystem::path& path,
                           const std::vector<PairDecision>& decisions);

void WriteVerificationJson(const std::filesystem::path& path, const VerificationSummary& summary,
                           const std::vector<PairDecision>& decisions);

}  // namespace viosfm

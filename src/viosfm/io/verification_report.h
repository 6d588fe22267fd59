// Reports of a pair verification run (matching/verification_driver.h):
//
// CSV, one header line and one line a pair:
//   image_id1,image_id2,name1,name2,source,num_matches,has_vio_prior,
//   vio_outlier_ratio,vio_rotation_only,vio_rejected,num_inliers,accepted,
//   resumed,reason,vio_depth_applied,vio_depth_inconsistent_ratio,
//   vio_depth_rejected,vio_correction_sigmas,vio_corrected,guided_band_px
// booleans as 0/1, the ratios, the correction's sigmas and the guided band
// with 6 decimals or "nan" when the check did not run (or, for the depth
// ratio, did not apply; for the sigmas, no correction was sought; for the
// band, the pair was not matched in one). The 14-, 17- and 19-column forms
// of earlier versions are read too. Names are written as they are (database image
// names hold no comma; a name with a comma, quote or line break is an InputError).
//
// JSON: {"summary": {"database": path, counts and seconds},
//        "options": {name: value text},
//        "pairs": [{one object a pair, the CSV's fields; the ratios null
//                   when NaN}]}.
//
// Both are written atomically (temporary file, then rename).
#pragma once

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "viosfm/scene/pair_decision.h"

namespace viosfm {

void WritePairDecisionsCsv(const std::filesystem::path& path,
                           const std::vector<PairDecision>& decisions);

void WriteVerificationJson(const std::filesystem::path& path, const VerificationSummary& summary,
                           const std::vector<PairDecision>& decisions);

// Reads a CSV written by WritePairDecisionsCsv (also one without the three
// depth columns, as written before they existed). Throws InputError naming
// the file and line for a missing file, a wrong header, a row with the wrong
// number of fields or a field that does not parse.
std::vector<PairDecision> ReadPairDecisionsCsv(const std::filesystem::path& path);

// Ground-truth evaluations of verification runs (`viosfm check-pairs`):
// {"options": {name: value text}, "runs": [{"name", "num_candidates",
// "num_correct_candidates", "num_accepted", "num_accepted_correct",
// "num_accepted_wrong", "num_accepted_other", "num_baseline_correct",
// "num_baseline_correct_kept", "recall_vs_baseline" (null if undefined),
// "wrong_pairs": [[name1, name2], ...]}]}. Written atomically.
void WriteVerificationTruthJson(const std::filesystem::path& path,
                                const std::vector<VerificationTruthSummary>& summaries,
                                const std::vector<std::pair<std::string, std::string>>& options);

// summary.database of a verification JSON; empty when the key is absent.
// Throws InputError for a missing file or invalid JSON.
std::string ReadVerificationDatabasePath(const std::filesystem::path& path);

}  // namespace viosfm

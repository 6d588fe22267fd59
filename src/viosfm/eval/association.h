// Which estimated pose is compared with which reference pose.
//
// Three rules:
//  - by index: pair i of both trajectories, for i < min(n_est, n_ref);
//  - nearest (evo's `associate_trajectories`): every pose of the shorter
//    trajectory (the estimate when both are equally long) takes the pose of
//    the other with the nearest stamp, if |dt| <= max_dt. Poses of the longer
//    trajectory may be taken more than once. Stamps are compared exactly in
//    ns, except that an exact tie, and a |dt| of exactly max_dt, are decided
//    as evo decides them, on the stamps as double seconds (evo reads them as
//    Python floats): of two equally near stamps the later wins only if its
//    double |dt| is strictly smaller, else the earlier (numpy's argmin);
//  - greedy (TUM `evaluate_ate.py` `associate`): all pairs with |dt| < max_dt
//    (strictly) are sorted by (|dt|, reference stamp, estimate stamp) and taken
//    greedily so that every stamp is used at most once.
// `offset_ns` is added to the estimate's stamps before comparing
// (est + offset ~ ref). Stamps must not decrease (of repeated stamps the
// first wins a tie). Pairs are returned
// sorted by reference index (then estimate index).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "viosfm/util/timestamp.h"

namespace viosfm {

struct PosePair {
  size_t est_index = 0;
  size_t ref_index = 0;
  bool operator==(const PosePair& other) const = default;
};

enum class AssociationMethod {
  kAuto,  // kIndex if either trajectory has no stamps (KITTI), else kNearest
  kIndex,
  kNearest,
  kGreedy,
};

// "auto", "index", "nearest", "greedy"; throws InputError otherwise.
AssociationMethod ParseAssociationMethod(const std::string& name);
std::string AssociationMethodName(AssociationMethod method);

std::vector<PosePair> AssociateByIndex(size_t num_est, size_t num_ref);

std::vector<PosePair> AssociateNearest(const std::vector<timestamp_ns_t>& est_stamps,
                                       const std::vector<timestamp_ns_t>& ref_stamps,
                                       int64_t max_dt_ns, int64_t offset_ns = 0);

std::vector<PosePair> AssociateGreedy(const std::vector<timestamp_ns_t>& est_stamps,
                                      const std::vector<timestamp_ns_t>& ref_stamps,
                                      int64_t max_dt_ns, int64_t offset_ns = 0);

}  // namespace viosfm

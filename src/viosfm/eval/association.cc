#include "viosfm/eval/association.h"

#include <algorithm>
#include <cstdlib>
#include <tuple>

#include "viosfm/util/errors.h"
#include "viosfm/util/string_util.h"

namespace viosfm {
namespace {

void CheckSorted(const std::vector<timestamp_ns_t>& stamps, const char* name) {
  for (size_t i = 1; i < stamps.size(); ++i) {
    VIOSFM_CHECK_LE(stamps[i - 1], stamps[i]) << name << " stamps must not decrease at " << i;
  }
}

// |a - b| without overflow for any int64 stamps.
uint64_t AbsDiff(int64_t a, int64_t b) {
  return a >= b ? static_cast<uint64_t>(a) - static_cast<uint64_t>(b)
                : static_cast<uint64_t>(b) - static_cast<uint64_t>(a);
}

// A stamp as evo holds it: the double nearest to its decimal seconds (what
// Python's float() gives for the text of the file).
double EvoSeconds(int64_t ns) {
  return std::strtod(FormatNsAsSeconds(ns, 9).c_str(), nullptr);
}

void SortByReference(std::vector<PosePair>& pairs) {
  std::sort(pairs.begin(), pairs.end(), [](const PosePair& a, const PosePair& b) {
    return std::tie(a.ref_index, a.est_index) < std::tie(b.ref_index, b.est_index);
  });
}

}  // namespace

AssociationMethod ParseAssociationMethod(const std::string& name) {
  const std::string lower = ToLower(Trim(name));
  if (lower == "auto") return AssociationMethod::kAuto;
  if (lower == "index") return AssociationMethod::kIndex;
  if (lower == "nearest") return AssociationMethod::kNearest;
  if (lower == "greedy") return AssociationMethod::kGreedy;
  throw InputError("unknown association '" + name + "': expected auto, index, nearest or greedy");
}

std::string AssociationMethodName(AssociationMethod method) {
  switch (method) {
    case AssociationMethod::kAuto: return "auto";
    case AssociationMethod::kIndex: return "index";
    case AssociationMethod::kNearest: return "nearest";
    case AssociationMethod::kGreedy: return "greedy";
  }
  return "unknown";
}

std::vector<PosePair> AssociateByIndex(size_t num_est, size_t num_ref) {
  std::vector<PosePair> pairs(std::min(num_est, num_ref));
  for (size_t i = 0; i < pairs.size(); ++i) pairs[i] = {i, i};
  return pairs;
}

std::vector<PosePair> AssociateNearest(const std::vector<timestamp_ns_t>& est_stamps,
                                       const std::vector<timestamp_ns_t>& ref_stamps,
                                       int64_t max_dt_ns, int64_t offset_ns) {
  VIOSFM_CHECK_GE(max_dt_ns, 0);
  CheckSorted(est_stamps, "estimate");
  CheckSorted(ref_stamps, "reference");
  const bool iterate_ref = ref_stamps.size() < est_stamps.size();
  const std::vector<timestamp_ns_t>& short_stamps = iterate_ref ? ref_stamps : est_stamps;
  const std::vector<timestamp_ns_t>& long_stamps = iterate_ref ? est_stamps : ref_stamps;
  // The offset moves the estimate: long + long_offset is compared with short.
  const int64_t long_offset_ns = iterate_ref ? offset_ns : -offset_ns;

  // evo's |dt| in double seconds (see EvoSeconds), for exact ties and the
  // tolerance boundary.
  const double long_offset_s = EvoSeconds(long_offset_ns);
  const auto evo_dt = [&](size_t long_index, timestamp_ns_t short_stamp) {
    return std::abs((EvoSeconds(long_stamps[long_index]) + long_offset_s) -
                    EvoSeconds(short_stamp));
  };

  std::vector<PosePair> pairs;
  pairs.reserve(short_stamps.size());
  for (size_t i = 0; i < short_stamps.size(); ++i) {
    // Search long + long_offset ~ short, i.e. long ~ short - long_offset.
    const timestamp_ns_t target = short_stamps[i] - long_offset_ns;
    const size_t k = static_cast<size_t>(
        std::lower_bound(long_stamps.begin(), long_stamps.end(), target) - long_stamps.begin());
    // Candidates: the first of the stamps equal to long[k - 1] (before the
    // target) and long[k] (at or after it).
    size_t before = long_stamps.size();
    if (k > 0) {
      before = k - 1;
      while (before > 0 && long_stamps[before - 1] == long_stamps[before]) --before;
    }
    const size_t after = k < long_stamps.size() ? k : long_stamps.size();
    size_t best = before;
    if (best == long_stamps.size()) {
      best = after;
    } else if (after != long_stamps.size()) {
      const uint64_t dt_before = AbsDiff(long_stamps[before], target);
      const uint64_t dt_after = AbsDiff(long_stamps[after], target);
      // An exact tie goes to the later stamp only if evo's double arithmetic
      // finds it strictly nearer (numpy's argmin keeps the first minimum).
      if (dt_after < dt_before || (dt_after == dt_before && evo_dt(after, short_stamps[i]) <
                                                                evo_dt(before, short_stamps[i]))) {
        best = after;
      }
    }
    if (best == long_stamps.size()) continue;
    const uint64_t best_dt = AbsDiff(long_stamps[best], target);
    if (best_dt > static_cast<uint64_t>(max_dt_ns)) continue;
    if (best_dt == static_cast<uint64_t>(max_dt_ns) &&
        !(evo_dt(best, short_stamps[i]) <= EvoSeconds(max_dt_ns))) {
      continue;
    }
    pairs.push_back(iterate_ref ? PosePair{best, i} : PosePair{i, best});
  }
  SortByReference(pairs);
  return pairs;
}

std::vector<PosePair> AssociateGreedy(const std::vector<timestamp_ns_t>& est_stamps,
                                      const std::vector<timestamp_ns_t>& ref_stamps,
                                      int64_t max_dt_ns, int64_t offset_ns) {
  VIOSFM_CHECK_GE(max_dt_ns, 0);
  CheckSorted(est_stamps, "estimate");
  CheckSorted(ref_stamps, "reference");
  struct Candidate {
    uint64_t dt;
    size_t ref_index;
    size_t est_index;
  };
  std::vector<Candidate> candidates;
  // Both lists are sorted: slide a window over the reference.
  size_t first_ref = 0;
  for (size_t e = 0; e < est_stamps.size(); ++e) {
    const timestamp_ns_t stamp = est_stamps[e] + offset_ns;
    while (first_ref < ref_stamps.size() && ref_stamps[first_ref] < stamp &&
           AbsDiff(ref_stamps[first_ref], stamp) >= static_cast<uint64_t>(max_dt_ns)) {
      ++first_ref;
    }
    for (size_t r = first_ref; r < ref_stamps.size(); ++r) {
      const uint64_t dt = AbsDiff(ref_stamps[r], stamp);
      if (ref_stamps[r] > stamp && dt >= static_cast<uint64_t>(max_dt_ns)) break;
      if (dt < static_cast<uint64_t>(max_dt_ns)) candidates.push_back({dt, r, e});
    }
  }
  // Stamps are increasing, so sorting by index equals sorting by stamp.
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
    return std::tie(a.dt, a.ref_index, a.est_index) < std::tie(b.dt, b.ref_index, b.est_index);
  });
  std::vector<bool> est_used(est_stamps.size(), false);
  std::vector<bool> ref_used(ref_stamps.size(), false);
  std::vector<PosePair> pairs;
  for (const Candidate& candidate : candidates) {
    if (est_used[candidate.est_index] || ref_used[candidate.ref_index]) continue;
    est_used[candidate.est_index] = true;
    ref_used[candidate.ref_index] = true;
    pairs.push_back({candidate.est_index, candidate.ref_index});
  }
  SortByReference(pairs);
  return pairs;
}

}  // namespace viosfm

#include "viosfm/sfm/vio_gaps.h"

#include <algorithm>
#include <map>
#include <sstream>
#include <unordered_map>

#include "viosfm/util/logging.h"

namespace viosfm {

std::string VioGapSummary::ToString() const {
  std::ostringstream out;
  out << num_gaps << " gap(s) in the VIO's poses: " << num_confirmed
      << " confirmed by the images (one segment across), " << num_jumps
      << " contradicted (breaks), " << num_unseen << " without a pair across (breaks); "
      << num_pairs_dropped << " pair(s) against a confirmed VIO pose dropped; " << num_segments
      << " VIO segment(s)";
  return out.str();
}

VioGapSummary DecideVioGaps(BatchedMapperInput* input) {
  VioGapSummary summary;
  std::vector<MapperImage>& images = input->images;
  std::unordered_map<image_t, size_t> index_of_image;
  for (size_t i = 0; i < images.size(); ++i) index_of_image[images[i].image_id] = i;
  // A gap: (segment, gap count after it). Its evidence: pairs across it.
  struct Evidence {
    int supporting = 0;
    int contradicting = 0;
  };
  std::map<std::pair<int, int>, Evidence> gaps;
  int previous_segment = -1, previous_gap = 0;
  for (const MapperImage& image : images) {
    if (!image.vio_cam_from_world) continue;
    const VioOdometer& odometer = image.vio_odometer;
    if (odometer.segment == previous_segment) {
      for (int g = previous_gap + 1; g <= odometer.gap; ++g) gaps[{odometer.segment, g}];
    }
    previous_segment = odometer.segment;
    previous_gap = odometer.gap;
  }
  summary.num_gaps = static_cast<int>(gaps.size());
  // The gaps a pair lies across (both frames posed by the VIO, one segment).
  const auto gaps_across = [&](const ImagePairMatches& pair, int* segment, int* first, int* last) {
    const MapperImage& a = images[index_of_image.at(pair.image_id1)];
    const MapperImage& b = images[index_of_image.at(pair.image_id2)];
    if (!a.vio_cam_from_world || !b.vio_cam_from_world) return false;
    if (a.vio_odometer.segment != b.vio_odometer.segment) return false;
    *segment = a.vio_odometer.segment;
    *first = std::min(a.vio_odometer.gap, b.vio_odometer.gap) + 1;
    *last = std::max(a.vio_odometer.gap, b.vio_odometer.gap);
    return *first <= *last;
  };
  for (const ImagePairMatches& pair : input->verified_pairs) {
    int segment = 0, first = 0, last = 0;
    if (!gaps_across(pair, &segment, &first, &last)) continue;
    if (!pair.vio_contradicted) {
      for (int g = first; g <= last; ++g) ++gaps[{segment, g}].supporting;
    } else if (first == last) {
      // Only a pair across one gap says which one jumped.
      ++gaps[{segment, first}].contradicting;
    }
  }
  std::map<std::pair<int, int>, bool> is_break;
  for (const auto& [gap, evidence] : gaps) {
    const bool confirmed = evidence.supporting > 0 && evidence.supporting >= evidence.contradicting;
    is_break[gap] = !confirmed;
    if (confirmed) {
      ++summary.num_confirmed;
    } else if (evidence.contradicting > 0) {
      ++summary.num_jumps;
    } else {
      ++summary.num_unseen;
    }
  }
  // Pairs against a confirmed VIO pose go; those across a break stay.
  std::vector<ImagePairMatches> kept;
  for (ImagePairMatches& pair : input->verified_pairs) {
    int segment = 0, first = 0, last = 0;
    if (pair.vio_contradicted && gaps_across(pair, &segment, &first, &last)) {
      bool across_break = false;
      for (int g = first; g <= last; ++g) across_break = across_break || is_break[{segment, g}];
      if (!across_break) {
        ++summary.num_pairs_dropped;
        continue;
      }
    }
    kept.push_back(std::move(pair));
  }
  input->verified_pairs = std::move(kept);
  // The segments split at the breaks, renumbered in time order.
  std::map<std::pair<int, int>, int> new_segment;  // (segment, breaks before) -> new id
  for (MapperImage& image : images) {
    VioOdometer& odometer = image.vio_odometer;
    int breaks = 0;
    for (int g = 1; g <= odometer.gap; ++g) {
      const auto it = is_break.find({odometer.segment, g});
      if (it != is_break.end() && it->second) ++breaks;
    }
    if (!image.vio_cam_from_world) continue;
    const auto [it, inserted] = new_segment.emplace(std::make_pair(odometer.segment, breaks),
                                                    static_cast<int>(new_segment.size()));
    (void)inserted;
    odometer.segment = it->second;
  }
  summary.num_segments = static_cast<int>(new_segment.size());
  if (summary.num_gaps > 0) VIOSFM_LOG(INFO) << "mapper input: " << summary.ToString();
  if (summary.num_jumps + summary.num_unseen > 0) {
    VIOSFM_LOG(WARNING) << "mapper input: " << summary.num_jumps + summary.num_unseen
                        << " gap(s) in the VIO's poses taken as breaks (" << summary.num_jumps
                        << " where the images contradict the VIO's relative pose, "
                        << summary.num_unseen << " where no pair crosses them)";
  }
  return summary;
}

}  // namespace viosfm

#include "viosfm/sfm/vio_gaps.h"

#include <Eigen/Geometry>
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
      << " contradicted (breaks), " << num_unseen << " without a pair across (" << num_unseen_kept
      << " of them kept: the VIO no faster across them than elsewhere); " << num_pairs_dropped
      << " pair(s) against a confirmed VIO pose dropped; " << num_segments << " VIO segment(s)";
  return out.str();
}

namespace {

// The VIO's speed and turn rate between two consecutive poses of a segment.
struct VioStep {
  std::pair<int, int> gap;  // the gap crossed ({-1, 0} when none)
  double speed_m_s = 0.0;
  double turn_rad_s = 0.0;
};

// Which gaps without a pair across keep their segment: those the VIO
// crosses no faster, in speed and in turn rate, than 1.5 times the fastest
// step elsewhere in its poses (within a stretch or across a confirmed gap).
// A re-initialisation restarts the world frame and jumps; a gap where the
// frames simply do not overlap moves as the VIO did before and after.
std::map<std::pair<int, int>, bool> PlausibleUnseenGaps(
    const std::vector<MapperImage>& images, const std::map<std::pair<int, int>, bool>& is_break) {
  std::vector<VioStep> steps;
  const MapperImage* previous = nullptr;
  for (const MapperImage& image : images) {
    if (!image.vio_cam_from_world) continue;
    if (previous != nullptr && previous->vio_odometer.segment == image.vio_odometer.segment &&
        image.timestamp_ns > previous->timestamp_ns) {
      const double dt_s = 1e-9 * static_cast<double>(image.timestamp_ns - previous->timestamp_ns);
      const Rigid3d& a = *previous->vio_cam_from_world;
      const Rigid3d& b = *image.vio_cam_from_world;
      VioStep step;
      step.gap = image.vio_odometer.gap != previous->vio_odometer.gap
                     ? std::make_pair(image.vio_odometer.segment, image.vio_odometer.gap)
                     : std::make_pair(-1, 0);
      step.speed_m_s = (a.Inverse().translation - b.Inverse().translation).norm() / dt_s;
      step.turn_rad_s = Eigen::AngleAxisd(b.rotation * a.rotation.inverse()).angle() / dt_s;
      steps.push_back(step);
    }
    previous = &image;
  }
  double max_speed = -1.0, max_turn = -1.0;
  for (const VioStep& step : steps) {
    const auto it = is_break.find(step.gap);
    if (it != is_break.end() && it->second) continue;
    max_speed = std::max(max_speed, step.speed_m_s);
    max_turn = std::max(max_turn, step.turn_rad_s);
  }
  std::map<std::pair<int, int>, bool> plausible;
  if (max_speed < 0.0) return plausible;
  for (const VioStep& step : steps) {
    const auto it = is_break.find(step.gap);
    if (it == is_break.end() || !it->second) continue;
    plausible[step.gap] =
        step.speed_m_s <= 1.5 * max_speed && step.turn_rad_s <= 1.5 * max_turn + 1e-9;
  }
  return plausible;
}

}  // namespace

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
  // Rounds: a pair speaks for the one gap it crosses that is not yet
  // confirmed, when every other gap it crosses is confirmed (the VIO's
  // relative pose holds across those). A pair across several undecided gaps
  // says nothing about any one of them: a jump in either looks the same.
  std::map<std::pair<int, int>, bool> is_break;
  for (const auto& entry : gaps) is_break[entry.first] = true;
  for (bool changed = true; changed;) {
    changed = false;
    for (auto& entry : gaps) entry.second = Evidence{};
    for (const ImagePairMatches& pair : input->verified_pairs) {
      int segment = 0, first = 0, last = 0;
      if (!gaps_across(pair, &segment, &first, &last)) continue;
      int open_gap = -1, num_open = 0;
      for (int g = first; g <= last; ++g) {
        if (is_break[{segment, g}]) {
          open_gap = g;
          ++num_open;
        }
      }
      if (num_open != 1) continue;
      Evidence& evidence = gaps[{segment, open_gap}];
      ++(pair.vio_contradicted ? evidence.contradicting : evidence.supporting);
    }
    for (const auto& [gap, evidence] : gaps) {
      if (is_break[gap] && evidence.supporting > 0 &&
          evidence.supporting >= evidence.contradicting) {
        is_break[gap] = false;
        changed = true;
      }
    }
  }
  const std::map<std::pair<int, int>, bool> plausible = PlausibleUnseenGaps(images, is_break);
  for (const auto& [gap, evidence] : gaps) {
    if (!is_break[gap]) {
      ++summary.num_confirmed;
    } else if (evidence.contradicting > 0) {
      ++summary.num_jumps;
    } else {
      ++summary.num_unseen;
      if (plausible.count(gap) > 0 && plausible.at(gap)) {
        is_break[gap] = false;
        ++summary.num_unseen_kept;
      }
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
  if (summary.num_jumps + summary.num_unseen - summary.num_unseen_kept > 0) {
    VIOSFM_LOG(WARNING) << "mapper input: "
                        << summary.num_jumps + summary.num_unseen - summary.num_unseen_kept
                        << " gap(s) in the VIO's poses taken as breaks (" << summary.num_jumps
                        << " where the images contradict the VIO's relative pose, "
                        << summary.num_unseen - summary.num_unseen_kept
                        << " where no pair crosses them and the VIO jumps)";
  }
  return summary;
}

}  // namespace viosfm

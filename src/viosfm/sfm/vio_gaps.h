// The gaps in a VIO trajectory file's poses, judged by the images. A file
// does not say where its VIO re-initialised, and a time gap alone is no
// reset: a keyframe trajectory has gaps of seconds between consecutive
// poses and one world frame throughout. So every gap longer than the
// run's vio_max_gap is a candidate break (VioOdometer::gap), and the
// verified pairs whose frames lie on its two sides decide:
//  - pairs accepted under the VIO's relative pose (step 1 of the
//    verification) confirm it: one segment across the gap;
//  - pairs step 1 rejected that RANSAC accepted alone (the VIO's relative
//    pose contradicted: ImagePairMatches::vio_contradicted) outnumbering
//    them show a jump: the segment is split there;
//  - no pair across it: the images show nothing, and the gap is a break
//    too (the frames after it are registered from the images where they
//    can be, and otherwise form a model of their own).
// Where a gap is confirmed, the pairs that contradicted the VIO across it
// are dropped (a look-alike place's matches, which the VIO's pose refuted);
// where it is a break, they stay (the images join the two sides).
#pragma once

#include <string>
#include <vector>

#include "viosfm/sfm/mapper_input.h"

namespace viosfm {

struct VioGapSummary {
  int num_gaps = 0;        // candidate breaks
  int num_confirmed = 0;   // one segment across them
  int num_jumps = 0;       // contradicted by the images: breaks
  int num_unseen = 0;      // no pair across them: breaks
  int num_pairs_dropped = 0;  // pairs that contradicted a confirmed gap's VIO pose
  int num_segments = 0;    // VIO segments after the decisions
  std::string ToString() const;
};

// Decides every candidate gap of `input` (its images' VioOdometer::gap, its
// verified pairs' vio_contradicted flags): splits the segments at the
// breaks (images' vio_odometer.segment renumbered 0, 1, ... in time order)
// and drops the contradicting pairs of confirmed gaps.
VioGapSummary DecideVioGaps(BatchedMapperInput* input);

}  // namespace viosfm

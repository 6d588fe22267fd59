// The relative-pose priors of the batched mapper's bundle adjustment: the
// VIO's relative pose between consecutive frames (the paper's E_r) and, beyond
// the paper, "bridging" priors between frames farther apart across stretches
// the images barely connect (batched_mapper.h), each weighted by how far the
// VIO can be trusted between those two frames (scene/vio_uncertainty.h).
//
// A prior joins two frames of one VIO segment only: a VIO that lost track
// and re-initialised gives its later poses in another world frame, and a
// relative pose across that reset means nothing. Frames without a VIO pose
// get no prior; the priors skip them (consecutive = consecutive among the
// segment's posed frames).
#pragma once

#include <utility>
#include <vector>

#include "viosfm/ba/bundle_adjustment.h"
#include "viosfm/scene/vio_uncertainty.h"
#include "viosfm/sfm/mapper_input.h"

namespace viosfm {

struct RelativePosePriorOptions {
  // Spans (in posed frames of a segment) of the bridging priors, each >= 2;
  // empty: none. Default {10, 50}.
  std::vector<int> bridge_spans = {10, 50};
  // A consecutive pair with fewer verified matches is bridged. Default 30.
  // With the covariance weighting the matches that cross the cut between
  // the two frames count (those of every verified pair (i, j) with i <= k
  // < j), not only the consecutive pair's.
  int bridge_max_matches = 30;
  // kCovariance: every prior carries the square-root information of the
  // model's covariance and the bridging priors are full 6-DoF ones;
  // kPaper: no covariance, bridging priors rotation-only (the weighting of
  // the paper plus rotation-only bridging).
  PriorWeighting weighting = PriorWeighting::kCovariance;
  VioUncertaintyModel vio_uncertainty;
};

struct RelativePosePriors {
  std::vector<RelativePosePrior> priors;
  // Per prior, the indices (into the input's images, first < second) of its
  // frames.
  std::vector<std::pair<size_t, size_t>> frame_indices;
  // Per prior, whether it is a bridging prior (RelativePosePriorOptions::
  // bridge_spans).
  std::vector<bool> bridging;
  int num_consecutive = 0;
  int num_bridging = 0;
};

// The VIO frame of an input image (it must have a VIO pose, CHECK).
VioSample VioSampleOfImage(const MapperImage& image);

// Consecutive and bridging priors of `input` (see the top of the file).
RelativePosePriors MakeRelativePosePriors(const BatchedMapperInput& input,
                                          const RelativePosePriorOptions& options);
// The same of `images` and their verified pairs.
RelativePosePriors MakeRelativePosePriors(const std::vector<MapperImage>& images,
                                          const std::vector<ImagePairMatches>& verified_pairs,
                                          const RelativePosePriorOptions& options);

// The relative-pose priors between consecutive frames (time order), with
// the paper's weighting (no covariance): cam2_from_cam1 from their VIO
// poses, num_verified_matches the number of verified matches of the pair (0
// if the pair was not verified; the largest count if it is listed more than
// once). Frames without a VIO pose are skipped and no prior crosses a
// segment.
std::vector<RelativePosePrior> MakeConsecutiveRelativePosePriors(const BatchedMapperInput& input);

// The rotation-only bridging priors of the paper weighting over
// `consecutive` (MakeConsecutiveRelativePosePriors(input) of an input whose
// frames all have a VIO pose in one segment, CHECK): for each span s and
// each i, frames i and i + s are joined when one of the consecutive pairs
// between them has fewer than `max_matches` verified matches; its
// num_verified_matches is the fewest of those pairs.
std::vector<RelativePosePrior> MakeBridgingRelativePosePriors(
    const BatchedMapperInput& input, const std::vector<RelativePosePrior>& consecutive,
    const std::vector<int>& spans, int max_matches);

}  // namespace viosfm

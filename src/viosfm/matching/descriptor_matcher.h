// Descriptor matching: nearest neighbour with Lowe's ratio test, a maximum
// distance and a mutual (cross) check, on the CPU.
//
// Descriptors are compared as unit vectors: each uint8 row is converted to
// float and divided by its L2 norm once per image (NormalizeDescriptors), and
// for unit vectors ||a - b||^2 = 2 - 2 a.b, so the whole distance matrix is
// one matrix product, computed in blocks of rows to bound memory.
//
// Rules (the same for brute-force and guided matching):
//  - distances are Euclidean distances between unit descriptors, in [0, 2];
//  - descriptor i of image 1 matches its nearest neighbour j in image 2 if
//    d(i, j) <= max_distance and d(i, j) < max_ratio * d2, where d2 is the
//    distance to the second nearest neighbour; a second neighbour farther
//    than an orthogonal descriptor (sqrt(2)) counts as sqrt(2), so a lone
//    candidate is compared with an orthogonal one (as COLMAP does);
//  - two equally near neighbours are ambiguous: no match;
//  - with cross_check, (i, j) is kept only if i is also j's match in the
//    other direction (under the same ratio and distance tests).
// Matches are returned sorted by point2D_idx1. The result does not depend on
// the number of threads.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "viosfm/matching/image_pair.h"
#include "viosfm/scene/features.h"

namespace viosfm {

struct DescriptorMatchingOptions {
  // Lowe's ratio test: best distance < max_ratio * second-best distance.
  // Unitless, in (0, 1]. Default 0.8 (COLMAP's).
  double max_ratio = 0.8;
  // Largest Euclidean distance between unit-length descriptors, in (0, 2].
  // Default 0.7 (COLMAP's default is 0.7 as an angle in rad, i.e. a
  // Euclidean distance of 0.686).
  double max_distance = 0.7;
  // Mutual nearest neighbours only. Default true (COLMAP's).
  bool cross_check = true;
  // Rows of image 1 per block of the distance matrix (memory: block_size *
  // rows of image 2 floats per thread). Default 1024.
  int block_size = 1024;
  // Threads for one pair (over row blocks; MatchImagePairs uses them over
  // pairs instead). -1: all hardware threads. Default -1.
  int num_threads = -1;

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }
};

// Descriptors as unit-length float rows.
using FloatDescriptors = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// Converts to float and divides every row by its L2 norm (a row of zeros
// stays zero: it is sqrt(2) from everything and matches nothing).
FloatDescriptors NormalizeDescriptors(const FeatureDescriptors& descriptors);

// Brute-force matching of two images' normalised descriptors (same number
// of columns).
FeatureMatches MatchDescriptors(const FloatDescriptors& descriptors1,
                                const FloatDescriptors& descriptors2,
                                const DescriptorMatchingOptions& options);
// Convenience: normalises both and matches.
FeatureMatches MatchDescriptors(const FeatureDescriptors& descriptors1,
                                const FeatureDescriptors& descriptors2,
                                const DescriptorMatchingOptions& options);

struct GuidedMatchingOptions {
  DescriptorMatchingOptions matching;
  // Half width of the epipolar band (pixels): (i, j) is a candidate only if
  // point j lies within this distance of the epipolar line F * point i in
  // image 2 (EpipolarLineDistance, the paper's EE). Default 20 px (T_EE).
  double max_epipolar_distance_px = 20.0;
  // Side of the grid cells used to find the points near a line (pixels);
  // 0: automatic (max(8, max_epipolar_distance_px)). Default 0.
  double cell_size_px = 0.0;

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }
};

// Guided matching: the same rules as MatchDescriptors, but only the pairs
// (i, j) with EpipolarLineDistance(fundamental, points1[i], points2[j]) <=
// max_epipolar_distance_px are compared (in both directions of the cross
// check). `fundamental` maps image-1 points to image-2 lines (x2^T F x1 = 0)
// in the coordinates of points1/points2 (e.g. undistorted pixels). Points of
// image 2 are bucketed in a grid and only the cells the band crosses are
// visited, so the cost grows with the band's area, not with the image's.
// The descriptors are the stored uint8 rows: a candidate's score is the exact
// integer dot product (descriptor_dot.h) times the two rows' inverse norms,
// the cosine MatchDescriptors computes in float (equal up to float rounding,
// so only a near tie can come out differently).
FeatureMatches MatchDescriptorsGuided(const FeatureDescriptors& descriptors1,
                                      const FeatureDescriptors& descriptors2,
                                      const std::vector<Eigen::Vector2d>& points1,
                                      const std::vector<Eigen::Vector2d>& points2,
                                      const Eigen::Matrix3d& fundamental,
                                      const GuidedMatchingOptions& options);

// Matches every pair, in parallel over pairs (each pair on one thread;
// options.num_threads threads). `descriptors(image_id)` must be thread-safe
// and return the image's normalised descriptors. Result i is pairs[i]'s
// matches, point2D_idx1 in pairs[i].image_id1.
using DescriptorProvider = std::function<std::shared_ptr<const FloatDescriptors>(image_t)>;
std::vector<FeatureMatches> MatchImagePairs(const std::vector<ImagePair>& pairs,
                                            const DescriptorProvider& descriptors,
                                            const DescriptorMatchingOptions& options);

}  // namespace viosfm

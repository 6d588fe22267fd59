// Lowe's difference-of-Gaussians keypoint detector on a scale space that
// starts at the image's own resolution (first octave 0), for sift.cc:
// cv::SIFT 4.6 always starts from the image doubled in size, which costs
// four times the pixels in its first octave, and its detector cannot be
// told otherwise. The keypoints come out in cv::SIFT's own form (position,
// size = 2 sigma, angle in degrees from +x towards +y, octave and layer
// packed as cv::SIFT packs them), so cv::SIFT describes them on a pyramid
// that starts at octave 0 too (Feature2D::compute with the keypoints).
//
// Scale space (as cv::SIFT's, so the described layer is the detected one):
// the image, assumed blurred by 0.5 pixel, blurred to sigma_0 = 1.6; in
// each octave num_layers + 3 Gaussian layers of sigma_0 * 2^(i / num_layers)
// (in the octave's pixels), each blurred from the previous one; the next
// octave's first layer takes every second pixel of layer num_layers.
// Octaves until the shorter side would fall below about 8 pixels.
//
// Keypoints: extrema of the DoG over their 26 neighbours in layers 1 to
// num_layers, at least 5 pixels from the border, whose DoG exceeds half the
// peak threshold; refined by the quadratic fit of the DoG around them (at
// most 5 steps, moving to the neighbour the offset points to); kept if the
// refined DoG is at least the peak threshold and the ratio of principal
// curvatures at most the edge threshold. One keypoint per dominant
// orientation: the peaks of a 36-bin histogram of gradient directions
// (weighted by magnitude and a Gaussian of 1.5 times the keypoint's scale,
// smoothed by [1 4 6 4 1] / 16) at 80 % of the highest or more, each
// interpolated by a parabola.
#pragma once

#include <opencv2/core.hpp>
#include <opencv2/core/types.hpp>
#include <vector>

namespace viosfm {

struct DogDetectorOptions {
  int num_layers = 3;                  // DoG levels per octave
  double peak_threshold = 0.02 / 3.0;  // minimum |DoG|, intensities in [0, 1]
  double edge_threshold = 10.0;        // maximum ratio of principal curvatures
  // Extrema kept, the strongest by |DoG|, before orientations are assigned
  // (each may give more than one keypoint); 0 keeps all.
  int max_num_extrema = 0;
};

// Keypoints of an 8-bit single-channel image, positions with pixel centres
// at integer coordinates, the strongest extrema first (the orientations of
// one extremum together); an extremum reached from two candidates counts
// once.
std::vector<cv::KeyPoint> DetectDogKeypoints(const cv::Mat& image,
                                             const DogDetectorOptions& options);

}  // namespace viosfm

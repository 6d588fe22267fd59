// The VIO in the final bundle adjustment as what it is: poses that carry a
// slowly drifting world frame plus noise of their own, frame by frame.
//
// The relative-pose priors (relative_pose_priors.h) join consecutive frames,
// each weighted by the covariance of the VIO's relative pose between them
// (scene/vio_uncertainty.h): the drift accumulated between the two frames
// plus the two frames' own noise. A chain of them counts every frame's noise
// twice, once in each of its two priors, as if independent: over N frames
// the chain allows the VIO's relative pose N times the frame noise, where
// the VIO's own error is the drift over the N frames plus two frames' noise.
// At 10 Hz, where the frame noise dominates each step, that trusts the VIO's
// pose over a few seconds several times less than the model itself does
// (roll and pitch, which barely drift, dozens of times less).
//
// Here instead each VIO frame i of a segment gets a state of its own, G_i =
// world_from_vio_world: the VIO's world frame as the model's world sees it
// at that frame's time. Two kinds of terms:
//   - the frame's VIO pose, cam_from_vio_world V_i, against the model's
//     cam_from_world P_i seen through G_i: E = P_i G_i V_i^-1 (camera i's
//     frame), residual [Log R_E; t_E] whitened by the frame noise of the
//     model (white and slowly varying noise, rotation and position);
//   - the drift between consecutive frames i and j: the frame-j pose the
//     two states predict, B = V_j G_j^-1 and A = V_j G_i^-1, differ by E = B
//     A^-1 = V_j G_j^-1 G_i V_j^-1, whose residual the model's covariance of
//     the drift between the frames (RelativePoseCovariance without the frame
//     noise, within the segment's scale) whitens, times the paper's
//     connectivity factor exp(-beta c) on the information (c: the two
//     frames' verified matches): where the images hold the frames together
//     the drift may bend, where they do not the VIO's chain holds.
// So the VIO's relative pose between any two frames of a segment is trusted
// as the model says: the drift over the way between them plus the two
// frames' noise. Both kinds of terms are whitened residuals under the
// priors' Tukey loss (a VIO jump within a segment costs nothing beyond
// prior_loss_scale sigmas) and weighed against the reprojection errors in
// units of image_noise_px, as the priors are (ba/bundle_adjustment.h).
//
// Simplification: the slowly varying frame noise is counted as white (its
// variance added to the frame noise); over its correlation time (1 s by
// default) the average of several frames is then trusted more than it
// deserves, by up to the square root of the frames in that time. (A
// Gauss-Markov state per frame, which counts it exactly, does no better.)
//
// Off by default: on the simulated trust sequences the chain of priors
// gives the better model. See docs/history/benchmarks-2026.md, section
// "The VIO as drift states: its own model, measured worse than the chain".
#pragma once

#include <Eigen/Core>
#include <functional>
#include <vector>

#include "viosfm/ba/bundle_adjustment.h"
#include "viosfm/geometry/pose_parameters.h"
#include "viosfm/geometry/rigid3.h"
#include "viosfm/scene/vio_uncertainty.h"
#include "viosfm/util/types.h"

namespace viosfm {

// One frame of the chain: its image, the VIO's sample of it (pose, segment,
// odometer).
struct VioDriftFrame {
  image_t image_id = kInvalidImageId;
  VioSample vio;
};

// A link of the chain: frames `first` and `second` (indices into the
// frames, one segment), with their verified matches for the connectivity
// factor.
struct VioDriftLink {
  size_t first = 0;
  size_t second = 0;
  int num_verified_matches = 0;
};

struct VioDriftTermsOptions {
  // The VIO's uncertainty (its frame noise and drift rates, within the
  // segment's scale: WithinSegment is applied here).
  VioUncertaintyModel vio_uncertainty;
  // The connectivity factor's beta, the Tukey loss scale and the image noise
  // the whitened terms are weighed against (BundleAdjustmentOptions'
  // prior_beta, prior_loss_scale, image_noise_px).
  double prior_beta = 0.003;
  double prior_loss_scale = 10.0;
  double image_noise_px = 1.0;
};

class VioDriftTerms : public BundleAdjustmentTerms {
 public:
  // Every frame of a link gets a state and a frame term; frames in no link
  // get nothing. The links' frames must share a segment (CHECK).
  VioDriftTerms(std::vector<VioDriftFrame> frames, std::vector<VioDriftLink> links,
                const VioDriftTermsOptions& options);

  // Frames whose image has no pose block are left out, and so are the links
  // touching them. Each state starts where its frame's term is zero (G_i =
  // P_i^-1 V_i).
  size_t NumParameters() const override;
  std::vector<double*> AddTo(ceres::Problem* problem,
                             const std::function<double*(image_t)>& pose_block,
                             double* storage) override;
  void TakeSolution(const double* storage) override;

  int num_frame_terms() const { return num_frame_terms_; }
  int num_drift_terms() const { return num_drift_terms_; }

  // The square-root informations of the two kinds of terms (before the
  // connectivity factor and the image-noise unit), for tests.
  static Eigen::Matrix<double, 6, 6> FrameSqrtInformation(const VioUncertaintyModel& model);
  static Eigen::Matrix<double, 6, 6> DriftSqrtInformation(const VioUncertaintyModel& model,
                                                          const VioSample& frame1,
                                                          const VioSample& frame2);

 private:
  std::vector<VioDriftFrame> frames_;
  std::vector<VioDriftLink> links_;
  VioDriftTermsOptions options_;
  int num_frame_terms_ = 0;
  int num_drift_terms_ = 0;
};

}  // namespace viosfm

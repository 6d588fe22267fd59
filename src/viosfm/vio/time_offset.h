// Camera-IMU time offset from the images and the gyro.
//
// A camera and an IMU on separate clocks (or with an unmodelled exposure
// and transfer delay) stamp the same instant differently. The VIO reads the
// IMU between two image stamps, so an offset of a few tens of milliseconds
// turns every frame-to-frame rotation into a wrong one: on the real
// RealSense recording in ../shared/data (images 47 ms late against its IMU,
// no offset in its Kalibr calibration), the gyro's rotation between two
// frames explains the tracked corners half as well as at the right offset,
// enough to break initialisation and triangulation.
//
// The estimate: for each pair of frames up to max_frame_gap apart, the
// corners tracked in both are related by the gyro's rotation between the
// two stamps, shifted by a candidate offset (through the rig's
// body_from_cam), and an unknown translation: x2^T [t]x R x1 = 0. With R fixed, the translation
// direction is the least-squares solution (refitted on the better 70 % of the corners), and the
// pair's cost is the median epipolar residual; the candidate's cost is the mean over the pairs.
// Translation thus costs nothing, and the residual measures only how well the gyro's rotation
// explains the images. The offset minimising it is found on a grid,
// refined on a finer grid and by a parabola through the three best points.
// Checked on simulated sequences (time_offset_test) and on the real
// recording (-47 ms over its first 90 degrees of rotation, the same as over
// all 30 s).
//
// The driver collects frames until they rotate target_rotation_deg (the sum
// of the gyro rotation angles between consecutive frames) or for max_wait_s.
// The estimate is trusted only if they rotate at least min_total_rotation_deg, the minimum lies
// inside the search range, the cost there is clearly below the cost at the offset the
// calibration gave, and its standard error (a jackknife over blocks of frame pairs) is small
// and the calibration's offset lies outside its confidence interval; otherwise the
// calibration's offset stands.
#pragma once

#include <string>
#include <vector>

#include "viosfm/geometry/rigid3.h"
#include "viosfm/sensor/imu.h"
#include "viosfm/util/timestamp.h"
#include "viosfm/vio/frame_features.h"

namespace viosfm {

struct TimeOffsetOptions {
  // Estimate the offset at the start of a run (default true); false keeps
  // the calibration's.
  bool estimate = true;
  // s, candidates lie within +- this of the calibration's offset. Default 0.1.
  double max_offset_s = 0.1;
  // s, step of the coarse grid (default 0.004) and of the fine grid around
  // its best point (default 0.0005).
  double coarse_step_s = 0.004;
  double fine_step_s = 0.0005;
  // Fewest corners tracked in both frames for a pair to count. Default 15.
  int min_tracks_per_pair = 15;
  // Frames are paired with each of the next max_frame_gap frames.
  // Frames are paired with each of the next max_frame_gap frames (the
  // corners tracked through). Default 3: an offset rotates a pair's gyro
  // rotation by about the change of the angular rate between its frames
  // times the offset, which grows with the pair's span; on simulated rooms
  // with blur, white walls, auto exposure and a rolling shutter together,
  // consecutive frames alone (1) gave estimates 2.5 to 14 ms from a 47 ms
  // truth, pairs up to 3 apart 0.2 to 2.1 ms.
  int max_frame_gap = 3;
  // deg, the gyro rotation (summed over consecutive frames) the driver
  // collects frames for before the estimate, up to max_wait_s: the more
  // rotation, the more precise the estimate. Default 90.
  double target_rotation_deg = 90.0;
  // deg, the least rotation with which an estimate is made and trusted.
  // Default 30: on the simulated room with every imperfection at once (blur,
  // auto exposure, white walls, a 30 ms rolling shutter, a 47 ms offset) 20
  // to 30 degrees gave 43.3 ms, 90 degrees 45.0 ms; on stretches of the real
  // RealSense recording that start in motion and turn less than 90 degrees
  // in 10 s, 30 degrees gave -42.5 to -57.3 ms (the whole recording -47.3 ms
  // with a 21 ms readout), and the VIO then tracks them without a reset,
  // where the calibration's 0 ms left 31 to 160 frames on the IMU alone
  // (docs/benchmarks.md, "Starting in motion").
  double min_total_rotation_deg = 30.0;
  // Estimate a rolling shutter's readout time with the offset (default
  // true; used when the frames are given uncorrected and with the image
  // height): each corner's observation time is its frame's stamp plus its
  // row's time (rolling_shutter.h), the cost the same. The readout
  // minimising the cost at the offset found as a global shutter, then the
  // offset again at that readout; kept when it lowers the cost by
  // min_cost_reduction and lies inside (0, max_readout_s).
  bool estimate_readout = true;
  // s, the longest readout considered (default 0.05: 720p sensors read out
  // in 10 to 35 ms) and the step of its coarse grid (default 0.002); the
  // fine grid is fine_step_s.
  double max_readout_s = 0.05;
  double readout_coarse_step_s = 0.002;
  // s, the longest stretch of frames collected while waiting for
  // target_rotation_deg; after it, the estimate is made with what there is
  // (and trusted from min_total_rotation_deg on). Default 10.
  double max_wait_s = 10.0;
  // The estimate replaces the calibration's offset only when its cost is
  // below (1 - min_cost_reduction) times the cost at the calibration's
  // offset. Default 0.02.
  double min_cost_reduction = 0.02;
  // How well the images and the gyro determine the offset: its standard
  // error, by a jackknife over ten blocks of consecutive frame pairs (each
  // left out in turn, the offset found again within +-uncertainty_range_s of
  // the estimate). The estimate replaces the calibration's offset only when
  // its standard error is at most max_sigma_s and it lies at least
  // min_significance standard errors from the calibration's; otherwise the
  // calibration's offset stands (the data do not contradict it). Defaults
  // 0.02 s, 0.005 s and 3: an offset error of 5 ms moves a corner by 1.2 px
  // at 30 deg/s on a 460 px camera, about the tracker's precision.
  double uncertainty_range_s = 0.02;
  double max_sigma_s = 0.005;
  double min_significance = 3.0;

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }
};

struct TimeOffsetEstimate {
  // Whether offset_ns is the estimate (true) or the calibration's (false).
  bool estimated = false;
  // t_imu = t_cam + offset_ns.
  timestamp_ns_t offset_ns = 0;
  timestamp_ns_t calibration_offset_ns = 0;
  // Mean over the frame pairs of the median epipolar residual (px at
  // focal_length_px) at the estimate and at the calibration's offset.
  double cost_px = 0.0;
  double calibration_cost_px = 0.0;
  // The rolling-shutter readout (s) and whether it was estimated (false:
  // a global shutter explains the images as well, or not asked).
  bool readout_estimated = false;
  double readout_s = 0.0;
  // The residuals (px, as cost_px) of the best offset as a global shutter
  // and with the readout estimated, when a readout was tried (0 otherwise):
  // their ratio is the images' evidence for it.
  double global_shutter_cost_px = 0.0;
  double rolling_shutter_cost_px = 0.0;
  // s, the standard error of the offset the images and the gyro give
  // (TimeOffsetOptions::max_sigma_s), also when the calibration's is kept;
  // when not sigma_bounded, the offset is undetermined within +-sigma_s.
  // 0: not computed (too few pairs, too little rotation, or the minimum at
  // the edge of the search).
  double sigma_s = 0.0;
  bool sigma_bounded = false;
  int num_pairs = 0;
  double total_rotation_deg = 0.0;
  std::string message;  // one line: the estimate or why it was not trusted
};

// The estimate's decision in a short line: "camera-IMU time offset -48.4 ms,
// +- 0.3 ms (the calibration's 0.0 ms replaced); readout 27.7 ms" (+- the
// standard error; the rolling-shutter readout when estimated) or "camera-IMU
// time offset of the calibration kept (0.0 ms)".
std::string TimeOffsetHeadline(const TimeOffsetEstimate& estimate);

// Sum over consecutive frames of the gyro rotation angle (deg) between
// their stamps (camera clock, converted with offset_ns); frames without IMU
// coverage count zero.
double GyroRotationSumDeg(const std::vector<FrameFeatures>& frames,
                          const std::vector<ImuSample>& imu, timestamp_ns_t offset_ns);

// frames: consecutive tracked frames stamped on the camera clock, in order;
// imu: samples in strictly increasing stamp order; calibration_offset_ns:
// the offset the calibration gives (t_imu = t_cam + offset);
// focal_length_px only scales the reported costs. With image_height > 0
// and options.estimate_readout, the frames' observations must be as tracked
// (not corrected for a rolling shutter) and the readout is estimated too.
TimeOffsetEstimate EstimateTimeOffset(const std::vector<FrameFeatures>& frames,
                                      const std::vector<ImuSample>& imu,
                                      const Rigid3d& body_from_cam,
                                      timestamp_ns_t calibration_offset_ns, double focal_length_px,
                                      const TimeOffsetOptions& options = {}, int image_height = 0);

}  // namespace viosfm

// The metric scale of a `viosfm run` from the IMU (sfm/imu_scale.h), applied
// to the reconstruction at the end of the mapper stage.
//
// The mapped shape carries the VIO's scale (through the relative-pose
// priors and the first batch's placement), off by the VIO's scale error.
// With an IMU in the dataset, the scale of the registered frames' body
// trajectory is estimated from it (or, where the final adjustment's IMU
// factors held, taken from them and checked by that estimate:
// ImuScaleOptions::use_factor_scale); when usable, it is fused with the VIO's
// (1, with the VIO uncertainty model's scale_sigma) by inverse variance and
// the reconstruction (points and camera positions, about the world origin)
// is scaled by the result. When the IMU's scale refutes the VIO's (lies
// many sigmas from it, ImuScaleOptions::vio_refuted_sigmas; a VIO whose
// initialisation in motion got the scale wrong), the IMU's is applied alone,
// with its own sigma, and a warning says so.
//
// The same fit gives the direction of gravity in the reconstruction's world
// frame, from every registered frame's IMU; the world frame itself is the
// VIO's, levelled by the VIO's gravity at the frames that fixed it (the
// first batch's), to within that VIO's tilt error there. When the fit is
// usable, the reconstruction is turned about the world origin so that the
// fitted gravity points along -z: a level model (see
// docs/history/benchmarks-2026.md, section "A level model").
#pragma once

#include <string>

#include "viosfm/scene/reconstruction.h"
#include "viosfm/scene/sequence.h"
#include "viosfm/sfm/imu_scale.h"

namespace viosfm {

struct MetricScaleSummary {
  bool estimated = false;      // the dataset had an IMU and enough frames were posed
  ImuScaleResult imu;          // the IMU's estimate
  double applied_scale = 1.0;  // what the reconstruction was multiplied by
  // Relative standard deviation of the model's scale after that: the fused
  // one when the IMU's was usable, else the VIO's.
  double applied_scale_sigma = 0.0;
  // The IMU's scale refuted the VIO's (ImuScaleOptions::vio_refuted_sigmas)
  // and was applied alone.
  bool vio_scale_refuted = false;
  // The final adjustment's IMU factors' scale of the model (0 when they did
  // not hold) and whether it was the IMU's estimate
  // (ImuScaleOptions::use_factor_scale).
  double factor_scale = 0.0;
  bool factor_scale_used = false;
  // Degrees the reconstruction was turned to level it with the IMU's
  // gravity (0 when not).
  double levelling_deg = 0.0;
  std::string message;
};

// Turns `reconstruction` about the world origin by the smallest rotation
// that takes `gravity_in_world` (any length > 0) to -z: points, and every
// image's cam_from_world, so that every image sees every point where it
// did. Returns the angle turned, degrees.
double LevelWithGravity(const Eigen::Vector3d& gravity_in_world, Reconstruction* reconstruction);

// Estimates and, when usable, applies the IMU's metric scale and levels the
// reconstruction with its gravity (LevelWithGravity): the registered
// images of `reconstruction` (cam_from_world) from the
// sequence's IMU. `rig` gives body_from_cam, the camera-IMU time offset and
// the IMU noise figures (the sequence's own, or as viosfm's own VIO
// estimated and checked them). vio_scale_sigma: the VIO's relative scale
// uncertainty. factor_scale: the final adjustment's IMU factors' metric
// scale of `reconstruction` (BatchedMapperSummary::inertial_scale), 0 when
// they did not hold.
MetricScaleSummary ApplyImuMetricScale(const Sequence& sequence, const SensorRig& rig,
                                       double vio_scale_sigma, const ImuScaleOptions& options,
                                       Reconstruction* reconstruction, double factor_scale = 0.0);

}  // namespace viosfm

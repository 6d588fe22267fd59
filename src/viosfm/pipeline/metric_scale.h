// The metric scale of a `viosfm run` from the IMU (sfm/imu_scale.h), applied
// to the reconstruction at the end of the mapper stage.
//
// The mapped shape carries the VIO's scale (through the relative-pose
// priors and the first batch's placement), off by the VIO's scale error.
// With an IMU in the dataset, the scale of the registered frames' body
// trajectory is estimated from it; when usable, it is fused with the VIO's
// (1, with the VIO uncertainty model's scale_sigma) by inverse variance and
// the reconstruction (points and camera positions, about the world origin)
// is scaled by the result.
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
  std::string message;
};

// Estimates and, when usable, applies the IMU's metric scale to the
// registered images of `reconstruction` (cam_from_world) from the
// sequence's IMU. `rig` gives body_from_cam, the camera-IMU time offset and
// the IMU noise figures (the sequence's own, or as viosfm's own VIO
// estimated and checked them). vio_scale_sigma: the VIO's relative scale
// uncertainty.
MetricScaleSummary ApplyImuMetricScale(const Sequence& sequence, const SensorRig& rig,
                                       double vio_scale_sigma, const ImuScaleOptions& options,
                                       Reconstruction* reconstruction);

}  // namespace viosfm

#include "viosfm/pipeline/metric_scale.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <numbers>
#include <sstream>

#include "viosfm/util/errors.h"

namespace viosfm {

double LevelWithGravity(const Eigen::Vector3d& gravity_in_world, Reconstruction* reconstruction) {
  VIOSFM_CHECK(reconstruction != nullptr);
  VIOSFM_CHECK(gravity_in_world.norm() > 0.0) << "no gravity direction";
  // level_from_world: gravity to -z.
  const Eigen::Quaterniond level_from_world =
      Eigen::Quaterniond::FromTwoVectors(gravity_in_world.normalized(), -Eigen::Vector3d::UnitZ());
  for (const image_t image_id : reconstruction->ImageIds()) {
    Rigid3d& cam_from_world = reconstruction->GetImage(image_id).cam_from_world;
    cam_from_world.rotation = (cam_from_world.rotation * level_from_world.conjugate()).normalized();
  }
  for (const point3D_t point3D_id : reconstruction->Point3DIds()) {
    Eigen::Vector3d& xyz = reconstruction->GetPoint3D(point3D_id).xyz;
    xyz = level_from_world * xyz;
  }
  return Eigen::AngleAxisd(level_from_world).angle() * 180.0 / std::numbers::pi;
}

MetricScaleSummary ApplyImuMetricScale(const Sequence& sequence, const SensorRig& rig,
                                       double vio_scale_sigma, const ImuScaleOptions& options,
                                       Reconstruction* reconstruction, double factor_scale) {
  VIOSFM_CHECK(reconstruction != nullptr);
  VIOSFM_CHECK(factor_scale >= 0.0) << factor_scale;
  MetricScaleSummary summary;
  summary.factor_scale = factor_scale;
  summary.applied_scale_sigma = vio_scale_sigma;
  if (!sequence.has_imu()) {
    summary.message = "no IMU in the dataset: the scale is the VIO's";
    return summary;
  }
  const Rigid3d cam_from_body = rig.body_from_cam.Inverse();
  Trajectory body;
  for (const image_t image_id : reconstruction->RegImageIds()) {
    const Image& image = reconstruction->GetImage(image_id);
    if (!image.timestamp_ns) continue;
    // On the IMU's clock.
    body.poses.push_back(
        {rig.CamToImuTime(*image.timestamp_ns), image.cam_from_world.Inverse() * cam_from_body});
  }
  std::sort(body.poses.begin(), body.poses.end(), [](const StampedPose& a, const StampedPose& b) {
    return a.timestamp_ns < b.timestamp_ns;
  });
  summary.estimated = true;
  summary.imu = EstimateImuScale(body, sequence.imu, rig.imu_noise, options);
  std::ostringstream message;
  message << summary.imu.message;
  const ImuScaleResult& imu = summary.imu;
  const double imu_variance = std::pow(imu.scale_sigma * imu.scale, 2);
  const double vio_variance = std::max(1e-12, vio_scale_sigma * vio_scale_sigma);
  const double sigmas_from_vio = std::abs(imu.scale - 1.0) / std::sqrt(imu_variance + vio_variance);
  // Only a scale from frames far enough apart refutes: the consecutive
  // frames' is shrunk towards zero by their jitter (sfm/imu_scale.h), and
  // looks precise while it is (0.19 +- 0.02 where the frames 1 s apart
  // gave 0.43 +- 0.13 on the real recording started in motion at 15 s).
  summary.vio_scale_refuted = imu.num_pairs > 0 && imu.scale > 0.0 && imu.spaced_used &&
                              imu.scale_sigma <= options.max_refuting_scale_sigma &&
                              imu.residual_ratio <= options.max_refuting_residual_ratio &&
                              sigmas_from_vio > options.vio_refuted_sigmas;
  if (imu.usable || summary.vio_scale_refuted) {
    std::ostringstream applied;
    if (summary.vio_scale_refuted) {
      // The VIO's scale is not an estimate to fuse with: the IMU's alone.
      summary.applied_scale = imu.scale;
      summary.applied_scale_sigma = imu.scale_sigma;
      applied << std::fixed << std::setprecision(1) << "; the VIO's scale is refuted ("
              << sigmas_from_vio << " sigma from the IMU's, its sigma taken as "
              << std::setprecision(5) << vio_scale_sigma << "): applied the IMU's " << imu.scale
              << " +- " << imu.scale_sigma * imu.scale << " alone";
    } else {
      // The IMU's estimate: the factors' scale where the fit confirms it
      // (they solved it with the shape and the biases of every second),
      // with the fit's relative sigma.
      double imu_scale = imu.scale;
      if (factor_scale > 0.0 && options.use_factor_scale) {
        const double sigmas_from_fit = std::abs(factor_scale - imu.scale) / std::sqrt(imu_variance);
        summary.factor_scale_used = sigmas_from_fit <= options.max_factor_disagreement;
        applied << std::fixed << std::setprecision(5)
                << "; the final adjustment's IMU factors' scale " << factor_scale
                << std::setprecision(1) << " (" << sigmas_from_fit << " sigma from the fit's) "
                << (summary.factor_scale_used ? "taken as the IMU's"
                                              : "not used: further than max_factor_disagreement");
        if (summary.factor_scale_used) imu_scale = factor_scale;
      }
      // Inverse-variance fusion with the VIO's scale (1 +- vio_scale_sigma).
      const double variance = std::pow(imu.scale_sigma * imu_scale, 2);
      summary.applied_scale =
          (imu_scale / variance + 1.0 / vio_variance) / (1.0 / variance + 1.0 / vio_variance);
      summary.applied_scale_sigma =
          std::sqrt(1.0 / (1.0 / variance + 1.0 / vio_variance)) / summary.applied_scale;
      applied << std::fixed << std::setprecision(5) << "; applied " << summary.applied_scale
              << " (fused with the VIO's scale, +- " << vio_scale_sigma << ")";
    }
    const double s = summary.applied_scale;
    for (const image_t image_id : reconstruction->ImageIds()) {
      reconstruction->GetImage(image_id).cam_from_world.translation *= s;
    }
    for (const point3D_t point3D_id : reconstruction->Point3DIds()) {
      reconstruction->GetPoint3D(point3D_id).xyz *= s;
    }
    message << applied.str() << std::fixed;
    summary.levelling_deg = LevelWithGravity(summary.imu.gravity_in_world, reconstruction);
    message << std::setprecision(3) << "; levelled with the IMU's gravity (turned by "
            << summary.levelling_deg << " deg)";
  }
  summary.message = message.str();
  return summary;
}

}  // namespace viosfm

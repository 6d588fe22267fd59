#include "viosfm/scene/rolling_shutter.h"

#include <Eigen/Geometry>
#include <algorithm>

#include "viosfm/sensor/camera_models.h"

namespace viosfm {

double RowTimeOffset(double row, int height, double readout_s) {
  return ((row + 0.5) / height - 0.5) * readout_s;
}

Eigen::Vector3d CamAngularRate(const SensorRig& rig, const std::vector<ImuSample>& imu,
                               timestamp_ns_t cam_ns) {
  if (imu.empty()) return Eigen::Vector3d::Zero();
  constexpr timestamp_ns_t kHalfWindowNs = 10'000'000;
  const timestamp_ns_t imu_ns = rig.CamToImuTime(cam_ns);
  const auto by_time = [](const ImuSample& sample, timestamp_ns_t t) {
    return sample.timestamp_ns < t;
  };
  auto it = std::lower_bound(imu.begin(), imu.end(), imu_ns - kHalfWindowNs, by_time);
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  int count = 0;
  for (; it != imu.end() && it->timestamp_ns <= imu_ns + kHalfWindowNs; ++it) {
    sum += it->gyro;
    ++count;
  }
  Eigen::Vector3d body_rate;
  if (count > 0) {
    body_rate = sum / count;
  } else {
    const auto next = std::lower_bound(imu.begin(), imu.end(), imu_ns, by_time);
    body_rate = next == imu.end() ? imu.back().gyro : next->gyro;
  }
  return rig.body_from_cam.rotation.conjugate() * body_rate;
}

Eigen::Vector2d RotateBearingToStamp(const Eigen::Vector2d& normalized,
                                     const Eigen::Vector3d& cam_angular_rate, double offset_s) {
  const Eigen::Vector3d rotation_vector = cam_angular_rate * offset_s;
  const double angle = rotation_vector.norm();
  if (angle == 0.0) return normalized;
  const Eigen::Vector3d at_stamp =
      Eigen::AngleAxisd(angle, rotation_vector / angle) * normalized.homogeneous();
  return at_stamp.z() > 0.0 ? Eigen::Vector2d(at_stamp.hnormalized()) : normalized;
}

void CompensateRollingShutterRotation(const Camera& camera, double readout_s,
                                      const Eigen::Vector3d& cam_angular_rate,
                                      FeatureKeypoints* keypoints) {
  if (readout_s == 0.0 || camera.height == 0) return;
  const int height = static_cast<int>(camera.height);
  for (FeatureKeypoint& keypoint : *keypoints) {
    const Eigen::Vector2d pixel(keypoint.x, keypoint.y);
    const double offset_s = RowTimeOffset(pixel.y(), height, readout_s);
    const Eigen::Vector2d at_stamp = CamToImage(
        camera, RotateBearingToStamp(ImageToCam(camera, pixel), cam_angular_rate, offset_s));
    keypoint.x = static_cast<float>(at_stamp.x());
    keypoint.y = static_cast<float>(at_stamp.y());
  }
}

}  // namespace viosfm

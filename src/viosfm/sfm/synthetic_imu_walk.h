// Test helpers: a hand-held-like walk with a closed form and a rig, for the
// tests of the IMU's terms in the final adjustment (gyro_priors_test,
// inertial_terms_test).
#pragma once

#include <Eigen/Geometry>
#include <cmath>

#include "viosfm/geometry/rigid3.h"
#include "viosfm/sensor/sensor_rig.h"

namespace viosfm {

// The body's rotation: yaw, pitch and roll sinusoids and a slow turn.
inline Eigen::Matrix3d WalkWorldFromBody(double t) {
  return (Eigen::AngleAxisd(0.8 * std::sin(0.3 * t) + 0.05 * t, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(0.1 * std::sin(0.7 * t), Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(0.05 * std::sin(1.1 * t), Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

// A rig whose camera looks along the body's x axis.
inline SensorRig CameraAlongXRig() {
  SensorRig rig;
  rig.body_from_cam =
      Rigid3d(Eigen::Quaterniond(Eigen::AngleAxisd(0.5 * M_PI, Eigen::Vector3d::UnitY()) *
                                 Eigen::AngleAxisd(-0.5 * M_PI, Eigen::Vector3d::UnitZ())),
              Eigen::Vector3d(0.05, 0.0, 0.01));
  return rig;
}

}  // namespace viosfm

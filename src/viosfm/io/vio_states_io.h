// states.csv of a VIO run (`viosfm vio`, OUT/vio/ of `viosfm run`): one row
// per frame, with a header line:
//   #timestamp [ns],status,px,py,pz,qw,qx,qy,qz,vx,vy,vz,bgx,bgy,bgz,bax,bay,baz,
//   sigma_roll,sigma_pitch,sigma_yaw,sigma_px,sigma_py,sigma_pz,segment,has_pose
// p: world_from_body translation (m), q: its rotation (Hamilton), v: velocity
// in world (m/s), bg: gyro bias (rad/s), ba: accel bias (m/s^2), sigma: the
// pose's marginal standard deviations (rad, m), segment: the VIO segment,
// has_pose: 1 if the frame has a pose. Numbers with 17 significant digits.
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <string>
#include <vector>

#include "viosfm/geometry/rigid3.h"
#include "viosfm/util/timestamp.h"

namespace viosfm {

struct VioStateRecord {
  timestamp_ns_t timestamp_ns = 0;
  std::string status;  // "tracking", "initializing", ...
  Rigid3d world_from_body;
  Eigen::Vector3d velocity_in_world = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_bias = Eigen::Vector3d::Zero();
  Eigen::Matrix<double, 6, 1> pose_sigma = Eigen::Matrix<double, 6, 1>::Zero();
  int segment = 0;
  bool has_pose = false;
};

// Writes the rows atomically. Throws InputError naming `path` if it cannot.
void WriteVioStatesCsv(const std::filesystem::path& path,
                       const std::vector<VioStateRecord>& records);

}  // namespace viosfm

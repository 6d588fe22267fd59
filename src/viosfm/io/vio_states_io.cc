#include "viosfm/io/vio_states_io.h"

#include <iomanip>

#include "viosfm/util/file_util.h"

namespace viosfm {

void WriteVioStatesCsv(const std::filesystem::path& path,
                       const std::vector<VioStateRecord>& records) {
  WriteFileAtomically(path, [&](std::ostream& out) {
    out << "#timestamp [ns],status,px,py,pz,qw,qx,qy,qz,vx,vy,vz,bgx,bgy,bgz,bax,bay,baz,"
           "sigma_roll,sigma_pitch,sigma_yaw,sigma_px,sigma_py,sigma_pz,segment,has_pose\n";
    out << std::setprecision(17);
    for (const VioStateRecord& r : records) {
      const Eigen::Quaterniond q = r.world_from_body.rotation.normalized();
      const Eigen::Vector3d& p = r.world_from_body.translation;
      out << r.timestamp_ns << "," << r.status << "," << p.x() << "," << p.y() << "," << p.z()
          << "," << q.w() << "," << q.x() << "," << q.y() << "," << q.z();
      for (const Eigen::Vector3d* v : {&r.velocity_in_world, &r.gyro_bias, &r.accel_bias}) {
        out << "," << v->x() << "," << v->y() << "," << v->z();
      }
      for (int i = 0; i < 6; ++i) out << "," << r.pose_sigma[i];
      out << "," << r.segment << "," << (r.has_pose ? 1 : 0) << "\n";
    }
  });
}

}  // namespace viosfm

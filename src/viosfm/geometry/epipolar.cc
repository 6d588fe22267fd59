#include "viosfm/geometry/epipolar.h"

#include <cmath>
#include <limits>

#include "viosfm/geometry/lie.h"

namespace viosfm {
namespace {

// Distance of the homogeneous point x from the line l.
double PointLineDistance(const Eigen::Vector3d& line, const Eigen::Vector2d& x) {
  const double normal_sq = line.head<2>().squaredNorm();
  if (!(normal_sq > 0.0)) return std::numeric_limits<double>::infinity();
  return std::abs(line.dot(x.homogeneous())) / std::sqrt(normal_sq);
}

}  // namespace

Eigen::Matrix3d EssentialFromRelativePose(const Rigid3d& cam2_from_cam1) {
  return Hat(cam2_from_cam1.translation) * cam2_from_cam1.rotation.toRotationMatrix();
}

Eigen::Matrix3d FundamentalFromEssential(const Eigen::Matrix3d& essential,
                                         const Eigen::Matrix3d& calibration1,
                                         const Eigen::Matrix3d& calibration2) {
  return calibration2.inverse().transpose() * essential * calibration1.inverse();
}

Eigen::Matrix3d FundamentalFromRelativePose(const Rigid3d& cam2_from_cam1,
                                            const Eigen::Matrix3d& calibration1,
                                            const Eigen::Matrix3d& calibration2) {
  return FundamentalFromEssential(EssentialFromRelativePose(cam2_from_cam1), calibration1,
                                  calibration2);
}

double EpipolarLineDistance(const Eigen::Matrix3d& fundamental, const Eigen::Vector2d& x1,
                            const Eigen::Vector2d& x2) {
  return PointLineDistance(fundamental * x1.homogeneous(), x2);
}

double SymmetricEpipolarDistance(const Eigen::Matrix3d& fundamental, const Eigen::Vector2d& x1,
                                 const Eigen::Vector2d& x2) {
  return 0.5 * (PointLineDistance(fundamental * x1.homogeneous(), x2) +
                PointLineDistance(fundamental.transpose() * x2.homogeneous(), x1));
}

double SampsonError(const Eigen::Matrix3d& fundamental, const Eigen::Vector2d& x1,
                    const Eigen::Vector2d& x2) {
  const Eigen::Vector3d line2 = fundamental * x1.homogeneous();
  const Eigen::Vector3d line1 = fundamental.transpose() * x2.homogeneous();
  const double numerator = x2.homogeneous().dot(line2);
  const double denominator = line2.head<2>().squaredNorm() + line1.head<2>().squaredNorm();
  if (!(denominator > 0.0)) return std::numeric_limits<double>::infinity();
  return numerator * numerator / denominator;
}

Eigen::Matrix3d Matrix3FromRowMajor(const Eigen::Ref<const Eigen::VectorXd>& entries) {
  Eigen::Matrix3d matrix;
  matrix << entries(0), entries(1), entries(2), entries(3), entries(4), entries(5), entries(6),
      entries(7), entries(8);
  return matrix;
}

}  // namespace viosfm

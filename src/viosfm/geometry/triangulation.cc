#include "viosfm/geometry/triangulation.h"

#include <Eigen/SVD>
#include <cmath>
#include <limits>

namespace viosfm {
namespace {

// The DLT solution is rejected when the second smallest singular value of the
// (row-normalised) system is below this fraction of the largest: the null
// space is then (numerically) two-dimensional and the point undetermined.
constexpr double kDltRankTolerance = 1e-10;
// Homogeneous solutions with |w| below this fraction of |xyz| are points at
// infinity.
constexpr double kDltInfinityTolerance = 1e-12;
// Rays whose directions have |sin(angle)|^2 below this are parallel.
constexpr double kParallelTolerance = 1e-20;

}  // namespace

std::optional<Eigen::Vector3d> TriangulateDlt(
    const std::vector<Matrix3x4d>& cams_from_world,
    const std::vector<Eigen::Vector2d>& points_normalized) {
  const size_t num_views = cams_from_world.size();
  if (num_views < 2 || points_normalized.size() != num_views) return std::nullopt;
  Eigen::MatrixXd system(2 * num_views, 4);
  for (size_t i = 0; i < num_views; ++i) {
    const Matrix3x4d& proj = cams_from_world[i];
    const Eigen::Vector2d& x = points_normalized[i];
    system.row(2 * i) = x.x() * proj.row(2) - proj.row(0);
    system.row(2 * i + 1) = x.y() * proj.row(2) - proj.row(1);
  }
  for (Eigen::Index r = 0; r < system.rows(); ++r) {
    const double norm = system.row(r).norm();
    if (norm == 0.0 || !std::isfinite(norm)) return std::nullopt;
    system.row(r) /= norm;
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(system, Eigen::ComputeFullV);
  const Eigen::VectorXd& singular = svd.singularValues();
  if (singular.size() < 4 || !(singular[2] > kDltRankTolerance * singular[0])) {
    return std::nullopt;
  }
  const Eigen::Vector4d homogeneous = svd.matrixV().col(3);
  if (!(std::abs(homogeneous[3]) > kDltInfinityTolerance * homogeneous.head<3>().norm())) {
    return std::nullopt;
  }
  return Eigen::Vector3d(homogeneous.head<3>() / homogeneous[3]);
}

std::optional<Eigen::Vector3d> TriangulateMidpoint(const Rigid3d& cam1_from_world,
                                                   const Rigid3d& cam2_from_world,
                                                   const Eigen::Vector2d& point1_normalized,
                                                   const Eigen::Vector2d& point2_normalized) {
  const Eigen::Vector3d center1 = ProjectionCenter(cam1_from_world);
  const Eigen::Vector3d center2 = ProjectionCenter(cam2_from_world);
  // Ray directions in the world frame.
  const Eigen::Vector3d dir1 =
      (cam1_from_world.rotation.inverse() * point1_normalized.homogeneous()).normalized();
  const Eigen::Vector3d dir2 =
      (cam2_from_world.rotation.inverse() * point2_normalized.homogeneous()).normalized();
  // Minimise |center1 + s dir1 - center2 - t dir2|^2 over s, t (unit dirs).
  const double b = dir1.dot(dir2);
  // sin^2 of the angle between the rays (= 1 - b^2, without its cancellation).
  const double denominator = dir1.cross(dir2).squaredNorm();
  if (!(denominator > kParallelTolerance)) return std::nullopt;
  const Eigen::Vector3d offset = center1 - center2;
  const double d = dir1.dot(offset);
  const double e = dir2.dot(offset);
  const double s = (b * e - d) / denominator;
  const double t = (e - b * d) / denominator;
  return Eigen::Vector3d(0.5 * ((center1 + s * dir1) + (center2 + t * dir2)));
}

double TriangulationAngle(const Eigen::Vector3d& center1, const Eigen::Vector3d& center2,
                          const Eigen::Vector3d& point) {
  const Eigen::Vector3d ray1 = point - center1;
  const Eigen::Vector3d ray2 = point - center2;
  return std::atan2(ray1.cross(ray2).norm(), ray1.dot(ray2));
}

bool HasPositiveDepth(const Rigid3d& cam_from_world, const Eigen::Vector3d& point_in_world) {
  return (cam_from_world * point_in_world).z() > std::numeric_limits<double>::epsilon();
}

bool HasPositiveDepth(const Matrix3x4d& cam_from_world, const Eigen::Vector3d& point_in_world) {
  return cam_from_world.row(2).dot(point_in_world.homogeneous()) >
         std::numeric_limits<double>::epsilon();
}

}  // namespace viosfm

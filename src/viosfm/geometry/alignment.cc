#include "viosfm/geometry/alignment.h"

#include <Eigen/SVD>
#include <cmath>

namespace viosfm {
namespace {

Eigen::Vector3d Mean(const std::vector<Eigen::Vector3d>& points) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& point : points) sum += point;
  return sum / static_cast<double>(points.size());
}

}  // namespace

std::optional<Sim3d> AlignPointsUmeyama(const std::vector<Eigen::Vector3d>& src,
                                        const std::vector<Eigen::Vector3d>& dst, bool with_scale) {
  if (src.size() != dst.size() || src.size() < 3) return std::nullopt;
  const double n = static_cast<double>(src.size());
  const Eigen::Vector3d mean_src = Mean(src);
  const Eigen::Vector3d mean_dst = Mean(dst);

  double variance_src = 0.0;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (size_t i = 0; i < src.size(); ++i) {
    const Eigen::Vector3d centred_src = src[i] - mean_src;
    variance_src += centred_src.squaredNorm();
    covariance += (dst[i] - mean_dst) * centred_src.transpose();
  }
  variance_src /= n;
  covariance /= n;

  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(covariance,
                                              Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Vector3d singular_values = svd.singularValues();
  if (!(singular_values(0) > 0.0) || !(singular_values(1) > 1e-12 * singular_values(0))) {
    return std::nullopt;
  }
  Eigen::Vector3d s_diagonal = Eigen::Vector3d::Ones();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0.0) s_diagonal(2) = -1.0;
  const Eigen::Matrix3d rotation =
      svd.matrixU() * s_diagonal.asDiagonal() * svd.matrixV().transpose();
  const double scale = with_scale ? singular_values.dot(s_diagonal) / variance_src : 1.0;
  const Eigen::Vector3d translation = mean_dst - scale * (rotation * mean_src);
  return Sim3d(scale, Eigen::Quaterniond(rotation).normalized(), translation);
}

std::optional<Sim3d> AlignPointsPositionYaw(const std::vector<Eigen::Vector3d>& src,
                                            const std::vector<Eigen::Vector3d>& dst) {
  if (src.size() != dst.size() || src.size() < 2) return std::nullopt;
  const Eigen::Vector3d mean_src = Mean(src);
  const Eigen::Vector3d mean_dst = Mean(dst);
  double cos_term = 0.0;  // sum b_x a_x + b_y a_y
  double sin_term = 0.0;  // sum b_y a_x - b_x a_y
  double magnitude = 0.0;
  for (size_t i = 0; i < src.size(); ++i) {
    const Eigen::Vector3d a = src[i] - mean_src;
    const Eigen::Vector3d b = dst[i] - mean_dst;
    cos_term += b.x() * a.x() + b.y() * a.y();
    sin_term += b.y() * a.x() - b.x() * a.y();
    magnitude += a.head<2>().norm() * b.head<2>().norm();
  }
  if (!(magnitude > 0.0) || !(std::hypot(cos_term, sin_term) > 1e-12 * magnitude)) {
    return std::nullopt;
  }
  const double yaw = std::atan2(sin_term, cos_term);
  const Eigen::Quaterniond rotation(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()));
  return Sim3d(1.0, rotation, mean_dst - rotation * mean_src);
}

}  // namespace viosfm

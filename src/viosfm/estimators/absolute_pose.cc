#include "viosfm/estimators/absolute_pose.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <array>
#include <cmath>
#include <complex>
#include <optional>

#include "viosfm/geometry/alignment.h"
#include "viosfm/util/errors.h"

namespace viosfm {
namespace {

constexpr double kBehindCamera = 1e12;

// Polynomial coefficients, lowest degree first.
using Poly = std::vector<double>;

Poly Multiply(const Poly& a, const Poly& b) {
  Poly result(a.size() + b.size() - 1, 0.0);
  for (size_t i = 0; i < a.size(); ++i) {
    for (size_t j = 0; j < b.size(); ++j) result[i + j] += a[i] * b[j];
  }
  return result;
}

Poly Add(const Poly& a, const Poly& b, double b_factor = 1.0) {
  Poly result(std::max(a.size(), b.size()), 0.0);
  for (size_t i = 0; i < a.size(); ++i) result[i] += a[i];
  for (size_t i = 0; i < b.size(); ++i) result[i] += b_factor * b[i];
  return result;
}

double Evaluate(const Poly& p, double x) {
  double value = 0.0;
  for (size_t i = p.size(); i-- > 0;) value = value * x + p[i];
  return value;
}

// Real roots of a polynomial of degree <= 4 (companion matrix eigenvalues,
// polished by Newton steps).
std::vector<double> RealRoots(Poly p) {
  while (!p.empty() && std::abs(p.back()) < 1e-14 * (1.0 + std::abs(p.front()))) p.pop_back();
  const int degree = static_cast<int>(p.size()) - 1;
  std::vector<double> roots;
  if (degree < 1) return roots;
  Eigen::MatrixXd companion = Eigen::MatrixXd::Zero(degree, degree);
  for (int i = 0; i < degree; ++i) companion(0, i) = -p[degree - 1 - i] / p[degree];
  for (int i = 1; i < degree; ++i) companion(i, i - 1) = 1.0;
  const Eigen::EigenSolver<Eigen::MatrixXd> solver(companion, false);
  Poly derivative(degree);
  for (int i = 1; i <= degree; ++i) derivative[i - 1] = i * p[i];
  for (int i = 0; i < degree; ++i) {
    const std::complex<double> root = solver.eigenvalues()[i];
    if (std::abs(root.imag()) > 1e-6 * (1.0 + std::abs(root.real()))) continue;
    double x = root.real();
    for (int step = 0; step < 3; ++step) {
      const double slope = Evaluate(derivative, x);
      if (slope == 0.0) break;
      x -= Evaluate(p, x) / slope;
    }
    roots.push_back(x);
  }
  return roots;
}

Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return m;
}

}  // namespace

std::vector<Rigid3d> P3PEstimator::Estimate(const std::vector<X_t>& x, const std::vector<Y_t>& y) {
  VIOSFM_CHECK_EQ(x.size(), 3u);
  VIOSFM_CHECK_EQ(y.size(), 3u);
  std::array<Eigen::Vector3d, 3> f;
  for (int i = 0; i < 3; ++i) f[i] = x[i].homogeneous().normalized();
  const double a2 = (y[1] - y[2]).squaredNorm();
  const double b2 = (y[0] - y[2]).squaredNorm();
  const double c2 = (y[0] - y[1]).squaredNorm();
  if (a2 < 1e-20 || b2 < 1e-20 || c2 < 1e-20) return {};
  const double cos_alpha = f[1].dot(f[2]);
  const double cos_beta = f[0].dot(f[2]);
  const double cos_gamma = f[0].dot(f[1]);
  const double k1 = a2 / b2;
  const double k2 = c2 / b2;
  // q(v) = 1 + v^2 - 2 v cos_beta; s1^2 q(v) = b^2.
  const Poly q = {1.0, -2.0 * cos_beta, 1.0};
  // u = N(v) / D(v).
  const Poly n = Add({-1.0, 0.0, 1.0}, q, -(k1 - k2));
  const Poly d = {-2.0 * cos_gamma, 2.0 * cos_alpha};
  // N^2 - 2 cos_gamma N D + (1 - k2 q) D^2 = 0.
  const Poly one_minus_k2q = Add({1.0}, q, -k2);
  Poly quartic = Multiply(n, n);
  quartic = Add(quartic, Multiply(n, d), -2.0 * cos_gamma);
  quartic = Add(quartic, Multiply(one_minus_k2q, Multiply(d, d)));

  std::vector<Rigid3d> models;
  const std::vector<Eigen::Vector3d> world(y.begin(), y.end());
  for (const double v : RealRoots(quartic)) {
    if (!(v > 0.0)) continue;
    const double qv = Evaluate(q, v);
    const double dv = Evaluate(d, v);
    if (!(qv > 1e-12) || std::abs(dv) < 1e-12) continue;
    const double u = Evaluate(n, v) / dv;
    if (!(u > 0.0)) continue;
    const double s1 = std::sqrt(b2 / qv);
    const std::vector<Eigen::Vector3d> camera = {s1 * f[0], u * s1 * f[1], v * s1 * f[2]};
    const std::optional<Sim3d> aligned = AlignPointsUmeyama(world, camera, false);
    if (!aligned) continue;
    models.emplace_back(aligned->rotation, aligned->translation);
  }
  return models;
}

void P3PEstimator::Residuals(const std::vector<X_t>& x, const std::vector<Y_t>& y, const M_t& model,
                             std::vector<double>* squared_residuals) {
  squared_residuals->resize(x.size());
  const Eigen::Matrix3d rotation = model.rotation.toRotationMatrix();
  for (size_t i = 0; i < x.size(); ++i) {
    const Eigen::Vector3d point = rotation * y[i] + model.translation;
    (*squared_residuals)[i] =
        point.z() > 1e-9 ? (point.hnormalized() - x[i]).squaredNorm() : kBehindCamera;
  }
}

std::vector<Rigid3d> AbsolutePoseDltEstimator::Estimate(const std::vector<X_t>& x,
                                                        const std::vector<Y_t>& y) {
  VIOSFM_CHECK_EQ(x.size(), y.size());
  if (x.size() < static_cast<size_t>(kMinNumSamples)) return {};
  // Normalise the world points (centre, mean distance sqrt(3)) for conditioning.
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& point : y) mean += point;
  mean /= static_cast<double>(y.size());
  double spread = 0.0;
  for (const Eigen::Vector3d& point : y) spread += (point - mean).norm();
  spread /= static_cast<double>(y.size());
  if (!(spread > 1e-12)) return {};
  const double scale = std::sqrt(3.0) / spread;
  Eigen::MatrixXd a(2 * x.size(), 12);
  for (size_t i = 0; i < x.size(); ++i) {
    const Eigen::Vector4d p = (scale * (y[i] - mean)).homogeneous();
    a.row(2 * i) << p.transpose(), Eigen::RowVector4d::Zero(), -x[i].x() * p.transpose();
    a.row(2 * i + 1) << Eigen::RowVector4d::Zero(), p.transpose(), -x[i].y() * p.transpose();
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeFullV);
  const Eigen::Matrix<double, 12, 1> h = svd.matrixV().col(11);
  Eigen::Matrix<double, 3, 4> projection;
  projection.row(0) = h.segment<4>(0).transpose();
  projection.row(1) = h.segment<4>(4).transpose();
  projection.row(2) = h.segment<4>(8).transpose();
  Eigen::Matrix3d m = projection.leftCols<3>();
  Eigen::Vector3d p = projection.col(3);
  if (m.determinant() < 0.0) {
    m = -m;
    p = -p;
  }
  // (A dynamic-size SVD: the fixed 3x3 one trips g++ 12's -Wmaybe-uninitialized.)
  const Eigen::MatrixXd m_dynamic = m;
  const Eigen::JacobiSVD<Eigen::MatrixXd> m_svd(m_dynamic,
                                                Eigen::ComputeFullU | Eigen::ComputeFullV);
  const double lambda = m_svd.singularValues().mean();
  if (!(lambda > 1e-12)) return {};
  Eigen::Matrix3d rotation = m_svd.matrixU() * m_svd.matrixV().transpose();
  if (rotation.determinant() < 0.0) return {};
  // P = [lambda R | p] in normalised world coordinates X' = scale (X - mean):
  // x ~ R scale (X - mean) + p / lambda, i.e. t = (p / lambda - scale R mean) / scale.
  const Eigen::Vector3d translation = (p / lambda - scale * rotation * mean) / scale;
  Rigid3d pose(Eigen::Quaterniond(rotation).normalized(), translation);
  // Most points must be in front of the camera.
  int in_front = 0;
  for (const Eigen::Vector3d& point : y) in_front += (pose * point).z() > 0.0 ? 1 : 0;
  if (2 * in_front < static_cast<int>(y.size())) return {};
  return {RefineAbsolutePose(x, y, pose, 10)};
}

void AbsolutePoseDltEstimator::Residuals(const std::vector<X_t>& x, const std::vector<Y_t>& y,
                                         const M_t& model, std::vector<double>* squared_residuals) {
  P3PEstimator::Residuals(x, y, model, squared_residuals);
}

Rigid3d RefineAbsolutePose(const std::vector<Eigen::Vector2d>& points_normalized,
                           const std::vector<Eigen::Vector3d>& points_in_world,
                           const Rigid3d& initial, int max_iterations, double huber_normalized) {
  VIOSFM_CHECK_EQ(points_normalized.size(), points_in_world.size());
  Rigid3d pose = initial;
  const auto cost_of = [&](const Rigid3d& candidate) {
    double cost = 0.0;
    for (size_t i = 0; i < points_in_world.size(); ++i) {
      const Eigen::Vector3d point = candidate * points_in_world[i];
      if (point.z() <= 1e-9) {
        cost += 1.0;
        continue;
      }
      const double r2 = (points_normalized[i] - point.hnormalized()).squaredNorm();
      if (huber_normalized > 0.0 && r2 > huber_normalized * huber_normalized) {
        cost += 2.0 * huber_normalized * std::sqrt(r2) - huber_normalized * huber_normalized;
      } else {
        cost += r2;
      }
    }
    return cost;
  };
  double cost = cost_of(pose);
  double lambda = 1e-4;
  for (int iteration = 0; iteration < max_iterations; ++iteration) {
    Eigen::Matrix<double, 6, 6> jtj = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> jtr = Eigen::Matrix<double, 6, 1>::Zero();
    for (size_t i = 0; i < points_in_world.size(); ++i) {
      const Eigen::Vector3d point = pose * points_in_world[i];
      if (point.z() <= 1e-9) continue;
      const double inverse_z = 1.0 / point.z();
      const Eigen::Vector2d residual = points_normalized[i] - point.hnormalized();
      Eigen::Matrix<double, 2, 3> d_projection;
      d_projection << inverse_z, 0.0, -point.x() * inverse_z * inverse_z, 0.0, inverse_z,
          -point.y() * inverse_z * inverse_z;
      // Left perturbation of cam_from_world: point' = Exp(w) point + dt.
      Eigen::Matrix<double, 3, 6> d_point;
      d_point.leftCols<3>() = -Skew(point);
      d_point.rightCols<3>() = Eigen::Matrix3d::Identity();
      const Eigen::Matrix<double, 2, 6> jacobian = d_projection * d_point;
      double weight = 1.0;
      if (huber_normalized > 0.0) {
        const double norm = residual.norm();
        if (norm > huber_normalized) weight = huber_normalized / norm;
      }
      jtj += weight * jacobian.transpose() * jacobian;
      jtr += weight * jacobian.transpose() * residual;
    }
    bool improved = false;
    for (int attempt = 0; attempt < 8 && !improved; ++attempt) {
      Eigen::Matrix<double, 6, 6> damped = jtj;
      damped.diagonal() *= 1.0 + lambda;
      damped.diagonal().array() += 1e-12;
      const Eigen::Matrix<double, 6, 1> step = damped.ldlt().solve(jtr);
      if (!step.allFinite()) break;
      const Eigen::Vector3d w = step.head<3>();
      const Eigen::Quaterniond rotation_step =
          w.norm() > 0.0 ? Eigen::Quaterniond(Eigen::AngleAxisd(w.norm(), w.normalized()))
                         : Eigen::Quaterniond::Identity();
      Rigid3d candidate((rotation_step * pose.rotation).normalized(),
                        rotation_step * pose.translation + step.tail<3>());
      const double candidate_cost = cost_of(candidate);
      if (candidate_cost < cost) {
        const bool converged = cost - candidate_cost < 1e-12 * (1.0 + cost);
        pose = candidate;
        cost = candidate_cost;
        lambda = std::max(1e-8, lambda / 10.0);
        improved = true;
        if (converged) return pose;
      } else {
        lambda *= 10.0;
      }
    }
    if (!improved) break;
  }
  return pose;
}

std::string AbsolutePoseOptions::Validate() const {
  if (!(max_error_px > 0.0)) return "max_error_px must be > 0";
  if (min_num_inliers < 3) return "min_num_inliers must be >= 3";
  if (!(confidence > 0.0 && confidence < 1.0)) return "confidence must be in (0, 1)";
  if (min_num_trials < 0) return "min_num_trials must be >= 0";
  if (max_num_trials < 1 || max_num_trials < min_num_trials) {
    return "max_num_trials must be >= 1 and >= min_num_trials";
  }
  return "";
}

size_t CountAbsolutePoseInliers(const std::vector<Eigen::Vector2d>& points_normalized,
                                const std::vector<Eigen::Vector3d>& points_in_world,
                                const Rigid3d& cam_from_world, double focal_length_px,
                                double max_error_px) {
  std::vector<double> residuals;
  P3PEstimator::Residuals(points_normalized, points_in_world, cam_from_world, &residuals);
  const double max_error = max_error_px / focal_length_px;
  size_t count = 0;
  for (const double r2 : residuals) count += r2 <= max_error * max_error ? 1 : 0;
  return count;
}

AbsolutePoseResult EstimateAbsolutePose(const std::vector<Eigen::Vector2d>& points_normalized,
                                        const std::vector<Eigen::Vector3d>& points_in_world,
                                        double focal_length_px, const AbsolutePoseOptions& options,
                                        const std::optional<Rigid3d>& predicted) {
  VIOSFM_CHECK(options.Check()) << options.Validate();
  VIOSFM_CHECK_EQ(points_normalized.size(), points_in_world.size());
  VIOSFM_CHECK_GT(focal_length_px, 0.0);
  AbsolutePoseResult result;
  if (predicted) {
    result.num_predicted_inliers = CountAbsolutePoseInliers(
        points_normalized, points_in_world, *predicted, focal_length_px, options.max_error_px);
  }
  if (points_normalized.size() < static_cast<size_t>(options.min_num_inliers)) return result;
  RansacOptions ransac_options;
  ransac_options.max_error = options.max_error_px / focal_length_px;
  ransac_options.confidence = options.confidence;
  ransac_options.min_num_trials = options.min_num_trials;
  ransac_options.max_num_trials = options.max_num_trials;
  ransac_options.seed = options.seed;
  const Ransac<P3PEstimator, AbsolutePoseDltEstimator> ransac(ransac_options);
  std::vector<Rigid3d> initial;
  if (predicted) initial.push_back(*predicted);
  const auto report = ransac.Estimate(points_normalized, points_in_world, initial);
  result.num_trials = report.num_trials;
  if (!report.success) return result;
  Rigid3d pose = report.model;
  std::vector<char> mask = report.inlier_mask;
  if (options.refine) {
    for (int round = 0; round < 2; ++round) {
      std::vector<Eigen::Vector2d> inlier_points;
      std::vector<Eigen::Vector3d> inlier_world;
      for (size_t i = 0; i < mask.size(); ++i) {
        if (!mask[i]) continue;
        inlier_points.push_back(points_normalized[i]);
        inlier_world.push_back(points_in_world[i]);
      }
      if (inlier_points.size() < 6) break;
      pose =
          RefineAbsolutePose(inlier_points, inlier_world, pose, 20, 0.5 * ransac_options.max_error);
      std::vector<double> residuals;
      P3PEstimator::Residuals(points_normalized, points_in_world, pose, &residuals);
      for (size_t i = 0; i < mask.size(); ++i) {
        mask[i] = residuals[i] <= ransac_options.max_error * ransac_options.max_error ? 1 : 0;
      }
    }
  }
  result.cam_from_world = pose;
  result.inlier_mask = mask;
  for (const char inlier : mask) result.num_inliers += inlier ? 1 : 0;
  result.success = result.num_inliers >= static_cast<size_t>(options.min_num_inliers);
  return result;
}

}  // namespace viosfm

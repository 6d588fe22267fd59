#include "viosfm/estimators/essential_matrix.h"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <array>
#include <cmath>
#include <complex>
#include <cstdint>

#include "viosfm/geometry/epipolar.h"
#include "viosfm/geometry/lie.h"
#include "viosfm/util/errors.h"

namespace viosfm {
namespace {

// Polynomials of degree <= 3 in (x, y, z), as coefficients of 20 monomials in
// graded order: the ten cubic monomials first, then the ten of degree <= 2
// that form the basis of the quotient ring used by the action matrix.
constexpr int kNumMonomials = 20;
constexpr int kExponents[kNumMonomials][3] = {
    {3, 0, 0}, {2, 1, 0}, {2, 0, 1}, {1, 2, 0}, {1, 1, 1}, {1, 0, 2}, {0, 3, 0},
    {0, 2, 1}, {0, 1, 2}, {0, 0, 3}, {2, 0, 0}, {1, 1, 0}, {1, 0, 1}, {0, 2, 0},
    {0, 1, 1}, {0, 0, 2}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0, 0, 0}};
constexpr int kX = 16;
constexpr int kY = 17;
constexpr int kZ = 18;
constexpr int kOne = 19;

using Polynomial = Eigen::Matrix<double, kNumMonomials, 1>;

// product[i][j]: the index of monomial i times monomial j, -1 if its degree
// exceeds 3.
struct MonomialProductTable {
  int8_t product[kNumMonomials][kNumMonomials];
  MonomialProductTable() {
    int index[4][4][4];
    for (auto& plane : index)
      for (auto& row : plane)
        for (int& value : row) value = -1;
    for (int i = 0; i < kNumMonomials; ++i) {
      index[kExponents[i][0]][kExponents[i][1]][kExponents[i][2]] = i;
    }
    for (int i = 0; i < kNumMonomials; ++i) {
      for (int j = 0; j < kNumMonomials; ++j) {
        const int a = kExponents[i][0] + kExponents[j][0];
        const int b = kExponents[i][1] + kExponents[j][1];
        const int c = kExponents[i][2] + kExponents[j][2];
        product[i][j] = static_cast<int8_t>(a + b + c <= 3 ? index[a][b][c] : -1);
      }
    }
  }
};

Polynomial Multiply(const Polynomial& p, const Polynomial& q) {
  static const MonomialProductTable table;
  Polynomial result = Polynomial::Zero();
  for (int i = 0; i < kNumMonomials; ++i) {
    if (p[i] == 0.0) continue;
    for (int j = 0; j < kNumMonomials; ++j) {
      if (q[j] == 0.0) continue;
      const int k = table.product[i][j];
      VIOSFM_CHECK(k >= 0) << "product of degree > 3";
      result[k] += p[i] * q[j];
    }
  }
  return result;
}

// Rows of the epipolar constraints x2^T E x1 = 0 on the row-major entries of E.
Eigen::MatrixXd EpipolarConstraints(const std::vector<Eigen::Vector2d>& points1,
                                    const std::vector<Eigen::Vector2d>& points2) {
  Eigen::MatrixXd constraints(points1.size(), 9);
  for (size_t i = 0; i < points1.size(); ++i) {
    const Eigen::Vector3d x1 = points1[i].homogeneous();
    const Eigen::Vector3d x2 = points2[i].homogeneous();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) constraints(i, 3 * r + c) = x2[r] * x1[c];
    }
  }
  return constraints;
}

}  // namespace

std::vector<Eigen::Matrix3d> EssentialMatrixFivePoint(const std::vector<Eigen::Vector2d>& points1,
                                                      const std::vector<Eigen::Vector2d>& points2) {
  VIOSFM_CHECK_EQ(points1.size(), points2.size());
  if (points1.size() < 5) return {};

  // Basis X, Y, Z, W of the (least-squares) null space: E = x X + y Y + z Z + W.
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(EpipolarConstraints(points1, points2),
                                              Eigen::ComputeFullV);
  const Eigen::MatrixXd& v = svd.matrixV();
  std::array<Eigen::Matrix3d, 4> basis;
  for (int k = 0; k < 4; ++k) basis[k] = Matrix3FromRowMajor(v.col(5 + k));

  // Entries of E as linear polynomials.
  Polynomial e[3][3];
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      e[r][c] = Polynomial::Zero();
      e[r][c][kX] = basis[0](r, c);
      e[r][c][kY] = basis[1](r, c);
      e[r][c][kZ] = basis[2](r, c);
      e[r][c][kOne] = basis[3](r, c);
    }
  }

  // E E^T (degree 2) and its trace.
  Polynomial eet[3][3];
  for (int r = 0; r < 3; ++r) {
    for (int c = r; c < 3; ++c) {
      eet[r][c] = Polynomial::Zero();
      for (int k = 0; k < 3; ++k) eet[r][c] += Multiply(e[r][k], e[c][k]);
      eet[c][r] = eet[r][c];
    }
  }
  const Polynomial trace = eet[0][0] + eet[1][1] + eet[2][2];

  // Ten cubic constraints: det(E) and the nine entries of 2 E E^T E - tr(E E^T) E.
  Eigen::Matrix<double, 10, kNumMonomials> constraints;
  const Polynomial det =
      Multiply(e[0][0], Multiply(e[1][1], e[2][2]) - Multiply(e[1][2], e[2][1])) -
      Multiply(e[0][1], Multiply(e[1][0], e[2][2]) - Multiply(e[1][2], e[2][0])) +
      Multiply(e[0][2], Multiply(e[1][0], e[2][1]) - Multiply(e[1][1], e[2][0]));
  constraints.row(0) = det.transpose();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      Polynomial entry = -Multiply(trace, e[r][c]);
      for (int k = 0; k < 3; ++k) entry += 2.0 * Multiply(eet[r][k], e[k][c]);
      constraints.row(1 + 3 * r + c) = entry.transpose();
    }
  }

  // Gauss-Jordan: cubic monomial k = -reduced.row(k) . basis, where basis is
  // (x^2, xy, xz, y^2, yz, z^2, x, y, z, 1).
  const Eigen::FullPivLU<Eigen::Matrix<double, 10, 10>> lu(constraints.leftCols<10>());
  if (!lu.isInvertible()) return {};
  const Eigen::Matrix<double, 10, 10> reduced = lu.solve(constraints.rightCols<10>());

  // Action matrix of multiplication by x on the basis: x * basis = action * basis.
  Eigen::Matrix<double, 10, 10> action = Eigen::Matrix<double, 10, 10>::Zero();
  // x * (x^2, xy, xz, y^2, yz, z^2) = (x^3, x^2y, x^2z, xy^2, xyz, xz^2): rows 0..5.
  action.topRows<6>() = -reduced.topRows<6>();
  action(6, 0) = 1.0;  // x * x = x^2
  action(7, 1) = 1.0;  // x * y = xy
  action(8, 2) = 1.0;  // x * z = xz
  action(9, 6) = 1.0;  // x * 1 = x

  const Eigen::EigenSolver<Eigen::Matrix<double, 10, 10>> eigen(action);
  if (eigen.info() != Eigen::Success) return {};
  // eigenvectors() computes a new matrix on each call: keep one copy.
  const Eigen::Matrix<std::complex<double>, 10, 10> eigenvectors = eigen.eigenvectors();
  std::vector<Eigen::Matrix3d> solutions;
  for (int i = 0; i < 10; ++i) {
    const std::complex<double> value = eigen.eigenvalues()[i];
    if (std::abs(value.imag()) > 1e-8 * std::max(1.0, std::abs(value.real()))) continue;
    const auto vector = eigenvectors.col(i);
    if (std::abs(vector[9]) < 1e-14) continue;
    const double x = (vector[6] / vector[9]).real();
    const double y = (vector[7] / vector[9]).real();
    const double z = (vector[8] / vector[9]).real();
    Eigen::Matrix3d essential = x * basis[0] + y * basis[1] + z * basis[2] + basis[3];
    const double norm = essential.norm();
    if (!(norm > 0.0) || !std::isfinite(norm)) continue;
    solutions.push_back(essential / norm);
  }
  return solutions;
}

std::vector<Eigen::Matrix3d> EssentialMatrixEightPoint(
    const std::vector<Eigen::Vector2d>& points1, const std::vector<Eigen::Vector2d>& points2) {
  VIOSFM_CHECK_EQ(points1.size(), points2.size());
  if (points1.size() < 8) return {};
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(EpipolarConstraints(points1, points2),
                                              Eigen::ComputeFullV);
  const Eigen::Matrix3d linear = Matrix3FromRowMajor(svd.matrixV().col(8));
  const Eigen::JacobiSVD<Eigen::Matrix3d> projection(linear,
                                                     Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix3d essential = projection.matrixU() * Eigen::Vector3d(1, 1, 0).asDiagonal() *
                                    projection.matrixV().transpose();
  return {essential / essential.norm()};
}

std::array<Rigid3d, 4> DecomposeEssentialMatrix(const Eigen::Matrix3d& essential) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(essential, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d u = svd.matrixU();
  Eigen::Matrix3d v = svd.matrixV();
  if (u.determinant() < 0.0) u = -u;
  if (v.determinant() < 0.0) v = -v;
  Eigen::Matrix3d w;
  w << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  const Eigen::Matrix3d r1 = u * w * v.transpose();
  const Eigen::Matrix3d r2 = u * w.transpose() * v.transpose();
  const Eigen::Vector3d t = u.col(2).normalized();
  return {Rigid3d(r1, t), Rigid3d(r1, Eigen::Vector3d(-t)), Rigid3d(r2, t),
          Rigid3d(r2, Eigen::Vector3d(-t))};
}

bool TriangulateDepths(const Rigid3d& cam2_from_cam1, const Eigen::Vector2d& point1,
                       const Eigen::Vector2d& point2, double* depth1, double* depth2) {
  // d1 a - d2 b = -t with a = R x1, b = x2, in the least-squares sense.
  const Eigen::Vector3d a = cam2_from_cam1.rotation * point1.homogeneous();
  const Eigen::Vector3d b = point2.homogeneous();
  const Eigen::Vector3d& t = cam2_from_cam1.translation;
  const double aa = a.squaredNorm();
  const double bb = b.squaredNorm();
  const double ab = a.dot(b);
  const double det = aa * bb - ab * ab;
  if (!(det > 1e-12 * aa * bb)) return false;
  const double at = a.dot(t);
  const double bt = b.dot(t);
  *depth1 = (ab * bt - at * bb) / det;
  *depth2 = (aa * bt - ab * at) / det;
  return true;
}

Rigid3d RelativePoseFromEssential(const Eigen::Matrix3d& essential,
                                  const std::vector<Eigen::Vector2d>& points1,
                                  const std::vector<Eigen::Vector2d>& points2, int* num_in_front) {
  VIOSFM_CHECK_EQ(points1.size(), points2.size());
  const std::array<Rigid3d, 4> candidates = DecomposeEssentialMatrix(essential);
  int best = 0;
  int best_count = -1;
  for (int k = 0; k < 4; ++k) {
    const double max_depth = kMaxCheiralityDepth * candidates[k].translation.norm();
    int count = 0;
    for (size_t i = 0; i < points1.size(); ++i) {
      double depth1 = 0.0;
      double depth2 = 0.0;
      if (!TriangulateDepths(candidates[k], points1[i], points2[i], &depth1, &depth2)) continue;
      if (depth1 > 0.0 && depth2 > 0.0 && depth1 < max_depth && depth2 < max_depth) ++count;
    }
    if (count > best_count) {
      best_count = count;
      best = k;
    }
  }
  if (num_in_front != nullptr) *num_in_front = best_count;
  return candidates[best];
}

namespace {

// Orthonormal basis of the plane tangent to t (|t| = 1).
std::pair<Eigen::Vector3d, Eigen::Vector3d> TangentBasis(const Eigen::Vector3d& t) {
  const Eigen::Vector3d axis =
      std::abs(t.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d tangent1 = t.cross(axis).normalized();
  const Eigen::Vector3d tangent2 = t.cross(tangent1).normalized();
  return {tangent1, tangent2};
}

}  // namespace

Eigen::Matrix<double, 3, 2> DirectionTangentBasis(const Eigen::Vector3d& t) {
  const auto [tangent1, tangent2] = TangentBasis(t);
  Eigen::Matrix<double, 3, 2> basis;
  basis << tangent1, tangent2;
  return basis;
}

Rigid3d RelativePosePlus(const Rigid3d& pose, const Eigen::Matrix<double, 5, 1>& delta) {
  const Eigen::Vector3d& t = pose.translation;
  const auto [tangent1, tangent2] = TangentBasis(t);
  const Eigen::Vector3d moved = t + delta[3] * tangent1 + delta[4] * tangent2;
  return Rigid3d((So3Exp(delta.head<3>()) * pose.rotation).normalized(), moved.normalized());
}

void RelativePoseSampsonResiduals(const Rigid3d& cam2_from_cam1,
                                  const std::vector<Eigen::Vector2d>& points1,
                                  const std::vector<Eigen::Vector2d>& points2,
                                  Eigen::VectorXd* residuals,
                                  Eigen::Matrix<double, Eigen::Dynamic, 5>* jacobian) {
  VIOSFM_CHECK_EQ(points1.size(), points2.size());
  const Eigen::Matrix3d rotation = cam2_from_cam1.rotation.toRotationMatrix();
  const Eigen::Matrix3d essential = Hat(cam2_from_cam1.translation) * rotation;
  // dE/d delta_k at delta = 0: the rotation increment turns R into
  // Exp(delta) R, so dE/d delta_k = [t]x [e_k]x R (k < 3); the tangent step
  // moves t along the tangent basis (normalising changes nothing to first
  // order), so dE/d delta_{3,4} = [tangent]x R.
  std::array<Eigen::Matrix3d, 5> d_essential;
  if (jacobian != nullptr) {
    for (int k = 0; k < 3; ++k) {
      d_essential[k] = Hat(cam2_from_cam1.translation) * Hat(Eigen::Vector3d::Unit(k)) * rotation;
    }
    const auto [tangent1, tangent2] = TangentBasis(cam2_from_cam1.translation);
    d_essential[3] = Hat(tangent1) * rotation;
    d_essential[4] = Hat(tangent2) * rotation;
    jacobian->resize(static_cast<Eigen::Index>(points1.size()), 5);
  }
  residuals->resize(static_cast<Eigen::Index>(points1.size()));
  for (size_t i = 0; i < points1.size(); ++i) {
    const Eigen::Vector3d x1 = points1[i].homogeneous();
    const Eigen::Vector3d x2 = points2[i].homogeneous();
    const Eigen::Vector3d line2 = essential * x1;
    const Eigen::Vector3d line1 = essential.transpose() * x2;
    const double numerator = x2.dot(line2);
    const double denominator = line2.head<2>().squaredNorm() + line1.head<2>().squaredNorm();
    if (!(denominator > 0.0)) {
      (*residuals)[i] = 0.0;
      if (jacobian != nullptr) jacobian->row(static_cast<Eigen::Index>(i)).setZero();
      continue;
    }
    const double inverse_sqrt = 1.0 / std::sqrt(denominator);
    (*residuals)[i] = numerator * inverse_sqrt;
    if (jacobian == nullptr) continue;
    // r = n / sqrt(d): dr = dn / sqrt(d) - n dd / (2 d^(3/2)), with
    // dn = x2^T dE x1 and dd = 2 (l2_12 . (dE x1)_12 + l1_12 . (dE^T x2)_12).
    for (int k = 0; k < 5; ++k) {
      const Eigen::Vector3d d_line2 = d_essential[k] * x1;
      const Eigen::Vector3d d_line1 = d_essential[k].transpose() * x2;
      const double d_numerator = x2.dot(d_line2);
      const double d_denominator =
          2.0 * (line2.head<2>().dot(d_line2.head<2>()) + line1.head<2>().dot(d_line1.head<2>()));
      (*jacobian)(static_cast<Eigen::Index>(i), k) =
          d_numerator * inverse_sqrt -
          0.5 * numerator * d_denominator * inverse_sqrt * inverse_sqrt * inverse_sqrt;
    }
  }
}

Rigid3d RefineRelativePose(const Rigid3d& cam2_from_cam1,
                           const std::vector<Eigen::Vector2d>& points1,
                           const std::vector<Eigen::Vector2d>& points2, int max_iterations) {
  VIOSFM_CHECK_EQ(points1.size(), points2.size());
  if (points1.size() < 5) return cam2_from_cam1;
  Rigid3d pose(cam2_from_cam1.rotation.normalized(), cam2_from_cam1.translation.normalized());
  Eigen::VectorXd residuals;
  Eigen::Matrix<double, Eigen::Dynamic, 5> jacobian;
  double lambda = 1e-4;
  Eigen::VectorXd candidate_residuals;
  for (int iteration = 0; iteration < max_iterations; ++iteration) {
    RelativePoseSampsonResiduals(pose, points1, points2, &residuals, &jacobian);
    const double cost = residuals.squaredNorm();
    const Eigen::Matrix<double, 5, 5> normal = jacobian.transpose() * jacobian;
    const Eigen::Matrix<double, 5, 1> gradient = jacobian.transpose() * residuals;
    bool improved = false;
    for (int attempt = 0; attempt < 10 && !improved; ++attempt) {
      Eigen::Matrix<double, 5, 5> damped = normal;
      damped.diagonal() *= 1.0 + lambda;
      const Eigen::Matrix<double, 5, 1> step = damped.ldlt().solve(-gradient);
      if (!step.allFinite()) break;
      const Rigid3d candidate = RelativePosePlus(pose, step);
      RelativePoseSampsonResiduals(candidate, points1, points2, &candidate_residuals, nullptr);
      const double candidate_cost = candidate_residuals.squaredNorm();
      if (candidate_cost < cost) {
        const double relative_decrease = (cost - candidate_cost) / std::max(cost, 1e-300);
        pose = candidate;
        lambda = std::max(lambda * 0.1, 1e-12);
        improved = true;
        if (relative_decrease < 1e-10) return pose;
      } else {
        lambda *= 10.0;
      }
    }
    if (!improved) break;
  }
  return pose;
}

}  // namespace viosfm

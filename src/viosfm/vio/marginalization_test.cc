#include "viosfm/vio/marginalization.h"

#include <ceres/gradient_checker.h>
#include <ceres/problem.h>
#include <ceres/solver.h>
#include <gtest/gtest.h>

#include <memory>

#include "viosfm/geometry/lie.h"
#include "viosfm/util/random.h"
#include "viosfm/vio/imu_factor.h"

namespace viosfm {
namespace {

// r = A [x_1; ...; x_n] - c over Euclidean blocks.
class LinearCost : public ceres::CostFunction {
 public:
  LinearCost(Eigen::MatrixXd A, Eigen::VectorXd c, const std::vector<int>& sizes)
      : A_(std::move(A)), c_(std::move(c)) {
    for (int size : sizes) mutable_parameter_block_sizes()->push_back(size);
    set_num_residuals(static_cast<int>(c_.size()));
  }
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    Eigen::VectorXd x(A_.cols());
    int offset = 0;
    for (size_t k = 0; k < parameter_block_sizes().size(); ++k) {
      const int size = parameter_block_sizes()[k];
      x.segment(offset, size) = Eigen::Map<const Eigen::VectorXd>(parameters[k], size);
      if (jacobians != nullptr && jacobians[k] != nullptr) {
        Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
            jacobians[k], num_residuals(), size) = A_.middleCols(offset, size);
      }
      offset += size;
    }
    Eigen::Map<Eigen::VectorXd>(residuals, num_residuals()) = A_ * x - c_;
    return true;
  }

 private:
  Eigen::MatrixXd A_;
  Eigen::VectorXd c_;
};

Eigen::MatrixXd RandomMatrix(Random& random, int rows, int cols) {
  Eigen::MatrixXd matrix(rows, cols);
  for (int i = 0; i < rows; ++i) {
    for (int j = 0; j < cols; ++j) matrix(i, j) = random.Normal();
  }
  return matrix;
}

Eigen::VectorXd RandomVector(Random& random, int size) {
  return RandomMatrix(random, size, 1);
}

// Blocks x1 (2), x2 (3), x3 (1); the factors f1(x1), f2(x1, x2), f3(x1, x3)
// touch x1, f4(x2, x3) and f5(x2) do not.
struct LinearProblem {
  std::vector<Eigen::MatrixXd> A;
  std::vector<Eigen::VectorXd> c;
  std::vector<std::vector<int>> blocks;  // block indices per factor
  std::vector<int> sizes{2, 3, 1};
  std::vector<int> offsets{0, 2, 5};

  explicit LinearProblem(Random& random) {
    blocks = {{0}, {0, 1}, {0, 2}, {1, 2}, {1}};
    const std::vector<int> rows = {2, 3, 2, 3, 2};
    for (size_t f = 0; f < blocks.size(); ++f) {
      int cols = 0;
      for (int block : blocks[f]) cols += sizes[block];
      A.push_back(RandomMatrix(random, rows[f], cols));
      c.push_back(RandomVector(random, rows[f]));
    }
  }
  ceres::CostFunction* Cost(size_t f) const {
    std::vector<int> block_sizes;
    for (int block : blocks[f]) block_sizes.push_back(sizes[block]);
    return new LinearCost(A[f], c[f], block_sizes);
  }
  // The stacked Jacobian of the given factors over all 6 variables.
  Eigen::MatrixXd StackedJacobian(const std::vector<size_t>& factors) const {
    int rows = 0;
    for (size_t f : factors) rows += static_cast<int>(A[f].rows());
    Eigen::MatrixXd J = Eigen::MatrixXd::Zero(rows, 6);
    int row = 0;
    for (size_t f : factors) {
      int col = 0;
      for (int block : blocks[f]) {
        J.block(row, offsets[block], A[f].rows(), sizes[block]) =
            A[f].middleCols(col, sizes[block]);
        col += sizes[block];
      }
      row += static_cast<int>(A[f].rows());
    }
    return J;
  }
};

TEST(Marginalization, PriorIsTheSchurComplementAndKeepsTheSolution) {
  Random random(11);
  const LinearProblem problem(random);
  // The linearisation point is arbitrary for a linear problem.
  std::vector<Eigen::VectorXd> x = {RandomVector(random, 2), RandomVector(random, 3),
                                    RandomVector(random, 1)};

  Marginalizer marginalizer;
  for (int k = 0; k < 3; ++k) marginalizer.AddParameterBlock(x[k].data(), problem.sizes[k]);
  for (size_t f = 0; f < 3; ++f) {
    std::vector<double*> blocks;
    for (int block : problem.blocks[f]) blocks.push_back(x[block].data());
    marginalizer.AddResidualBlock(problem.Cost(f), nullptr, blocks);
  }
  marginalizer.MarkMarginalized(x[0].data());
  const std::shared_ptr<LinearPrior> prior = marginalizer.Marginalize();
  ASSERT_NE(prior, nullptr);
  ASSERT_EQ(prior->blocks.size(), 2u);
  EXPECT_EQ(prior->blocks[0].values, x[1].data());
  EXPECT_EQ(prior->blocks[1].values, x[2].data());

  // Exact conditional: information H_rr - H_rm H_mm^-1 H_mr of the factors
  // that touch x1.
  const Eigen::MatrixXd J = problem.StackedJacobian({0, 1, 2});
  const Eigen::MatrixXd H = J.transpose() * J;
  const Eigen::MatrixXd schur = H.bottomRightCorner(4, 4) - H.bottomLeftCorner(4, 2) *
                                                                H.topLeftCorner(2, 2).inverse() *
                                                                H.topRightCorner(2, 4);
  EXPECT_LT((prior->Information() - schur).norm(), 1e-9 * schur.norm());

  // Full solve of all five factors.
  auto solve = [](ceres::Problem& ceres_problem) {
    ceres::Solver::Options options;
    options.max_num_iterations = 10;
    options.function_tolerance = 1e-16;
    options.gradient_tolerance = 1e-16;
    options.parameter_tolerance = 1e-16;
    ceres::Solver::Summary summary;
    ceres::Solve(options, &ceres_problem, &summary);
    EXPECT_TRUE(summary.IsSolutionUsable());
  };
  std::vector<Eigen::VectorXd> full = x;
  {
    ceres::Problem ceres_problem;
    for (size_t f = 0; f < 5; ++f) {
      std::vector<double*> blocks;
      for (int block : problem.blocks[f]) blocks.push_back(full[block].data());
      ceres_problem.AddResidualBlock(problem.Cost(f), nullptr, blocks);
    }
    solve(ceres_problem);
  }
  // The prior with the factors that do not touch x1.
  {
    ceres::Problem ceres_problem;
    ceres_problem.AddResidualBlock(new LinearPriorFactor(prior), nullptr, prior->ParameterBlocks());
    for (size_t f = 3; f < 5; ++f) {
      std::vector<double*> blocks;
      for (int block : problem.blocks[f]) blocks.push_back(x[block].data());
      ceres_problem.AddResidualBlock(problem.Cost(f), nullptr, blocks);
    }
    solve(ceres_problem);
  }
  EXPECT_LT((x[1] - full[1]).norm(), 1e-8) << x[1].transpose() << " vs " << full[1].transpose();
  EXPECT_LT((x[2] - full[2]).norm(), 1e-8);

  // Cross-check with the normal equations of the full problem.
  const Eigen::MatrixXd J_all = problem.StackedJacobian({0, 1, 2, 3, 4});
  Eigen::VectorXd c_all(J_all.rows());
  int row = 0;
  for (size_t f = 0; f < 5; ++f) {
    c_all.segment(row, problem.c[f].size()) = problem.c[f];
    row += static_cast<int>(problem.c[f].size());
  }
  const Eigen::VectorXd x_all = (J_all.transpose() * J_all).ldlt().solve(J_all.transpose() * c_all);
  EXPECT_LT((x_all.segment(2, 3) - full[1]).norm(), 1e-8);
}

TEST(Marginalization, GaussianPriorOnPoseHasConsistentJacobians) {
  std::shared_ptr<const ceres::Manifold> manifold(CreatePoseManifold());
  ImuState state;
  state.world_from_body =
      Rigid3d(So3Exp(Eigen::Vector3d(0.3, -0.2, 1.0)), Eigen::Vector3d(1.0, 2.0, 3.0));
  ImuStateParameters parameters = ImuStateParameters::FromState(state);
  Eigen::Matrix<double, 15, 1> diagonal;
  diagonal << 10, 20, 30, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12;
  Eigen::MatrixXd sqrt_information = Eigen::MatrixXd::Zero(15, 15);
  sqrt_information.diagonal() = diagonal;
  const std::shared_ptr<LinearPrior> prior =
      MakeGaussianPrior({parameters.pose.data(), parameters.speed_bias.data()}, {7, 9},
                        {manifold, nullptr}, sqrt_information);
  LinearPriorFactor factor(prior);
  ASSERT_EQ(factor.num_residuals(), 15);

  // Zero at the centre.
  const double* at_centre[] = {parameters.pose.data(), parameters.speed_bias.data()};
  double residuals[15];
  ASSERT_TRUE(factor.Evaluate(at_centre, residuals, nullptr));
  EXPECT_LT(Eigen::Map<Eigen::VectorXd>(residuals, 15).norm(), 1e-12);

  // Jacobians away from the centre.
  ImuStateParameters moved = parameters;
  ImuState moved_state = state;
  moved_state.world_from_body.rotation =
      So3Exp(Eigen::Vector3d(0.02, -0.01, 0.03)) * state.world_from_body.rotation;
  moved_state.world_from_body.translation += Eigen::Vector3d(0.1, 0.2, -0.1);
  moved = ImuStateParameters::FromState(moved_state);
  moved.speed_bias[4] = 0.5;
  const std::vector<const ceres::Manifold*> manifolds = {manifold.get(), nullptr};
  ceres::NumericDiffOptions numeric_options;
  ceres::GradientChecker checker(&factor, &manifolds, numeric_options);
  // Exact at the linearisation point; away from it the tangent Jacobian is
  // held at J0 (first-order accurate in the distance to x0). Compared in
  // absolute terms (exact zeros against numeric noise make relative errors
  // meaningless).
  auto max_difference = [](const ceres::GradientChecker::ProbeResults& results) {
    double worst = 0.0;
    for (size_t k = 0; k < results.local_jacobians.size(); ++k) {
      worst = std::max(
          worst,
          (results.local_jacobians[k] - results.local_numeric_jacobians[k]).cwiseAbs().maxCoeff());
    }
    return worst;
  };
  ceres::GradientChecker::ProbeResults results;
  checker.Probe(at_centre, 1e-7, &results);
  EXPECT_LT(max_difference(results), 1e-6);
  const double* away[] = {moved.pose.data(), moved.speed_bias.data()};
  checker.Probe(away, 1e-7, &results);
  EXPECT_LT(max_difference(results), 0.05 * 30.0);
  EXPECT_GT(max_difference(results), 1e-6);

  // Minimising the prior alone returns to its centre: move the blocks it acts
  // on and solve.
  const ImuStateParameters centre = parameters;
  parameters = moved;
  ceres::Problem problem;
  problem.AddResidualBlock(new LinearPriorFactor(prior), nullptr, prior->ParameterBlocks());
  problem.SetManifold(parameters.pose.data(), CreatePoseManifold());
  ceres::Solver::Options options;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  for (int k = 0; k < 7; ++k) EXPECT_NEAR(parameters.pose[k], centre.pose[k], 1e-8);
  for (int k = 0; k < 9; ++k) EXPECT_NEAR(parameters.speed_bias[k], centre.speed_bias[k], 1e-8);
}

}  // namespace
}  // namespace viosfm

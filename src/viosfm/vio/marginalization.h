// Marginalisation of variables of a nonlinear least-squares problem into a
// linear-Gaussian prior on the variables they are connected to (the Schur
// complement), and the Ceres cost that applies that prior (as in sliding-window
// estimators: VINS-Mono, OKVIS).
//
// Linearisation: every factor that touches a marginalised block is evaluated
// at the current values; its Jacobians are taken in the tangent space of each
// block (the ambient Jacobian times the manifold's PlusJacobian) and, for a
// robust loss rho, residual and Jacobians are scaled by sqrt(rho'(|r|^2))
// (the first-order part of the Triggs correction). With all blocks ordered
// marginalised (m) first, kept (r) second:
//   H = sum J^T J,   b = sum J^T r
//   H* = H_rr - H_rm H_mm^+ H_mr,   b* = b_r - H_rm H_mm^+ b_m
// (H_mm^+ the pseudo-inverse over eigenvalues above a threshold). The prior
// is the linear residual r_p(x) = r0 + J0 * (x [-] x0) with J0^T J0 = H*,
// J0^T r0 = b*, where x0 are the kept blocks' values at marginalisation and
// [-] the manifold's Minus: 0.5 |r_p|^2 equals, up to a constant, the
// quadratic model of the eliminated factors minimised over the marginalised
// variables.
#pragma once

#include <ceres/cost_function.h>
#include <ceres/loss_function.h>
#include <ceres/manifold.h>

#include <Eigen/Core>
#include <memory>
#include <unordered_map>
#include <unordered_set>
#include <vector>

namespace viosfm {

// A linear-Gaussian prior on parameter blocks (see above).
struct LinearPrior {
  struct Block {
    double* values = nullptr;  // the block the prior acts on (must outlive its use)
    int size = 0;              // ambient size
    int tangent_size = 0;
    int tangent_offset = 0;  // first column of the block in `jacobian`
    // Null for a Euclidean block.
    std::shared_ptr<const ceres::Manifold> manifold;
    Eigen::VectorXd linearization_point;  // x0, ambient
  };
  std::vector<Block> blocks;
  Eigen::MatrixXd jacobian;  // J0: rows x total tangent size
  Eigen::VectorXd residual;  // r0

  int num_residuals() const { return static_cast<int>(residual.size()); }
  int tangent_size() const { return static_cast<int>(jacobian.cols()); }
  std::vector<double*> ParameterBlocks() const;
  // The information matrix J0^T J0 and gradient J0^T r0 in tangent space.
  Eigen::MatrixXd Information() const { return jacobian.transpose() * jacobian; }
};

// A Gaussian prior centred at the blocks' current values with the given
// square-root information (rows x total tangent size): r = L (x [-] x0).
std::shared_ptr<LinearPrior> MakeGaussianPrior(
    const std::vector<double*>& values, const std::vector<int>& sizes,
    const std::vector<std::shared_ptr<const ceres::Manifold>>& manifolds,
    const Eigen::MatrixXd& sqrt_information);

// Ceres cost applying a LinearPrior; its parameter blocks are
// prior->ParameterBlocks(), in that order. The Jacobian with respect to the
// ambient block is J0_k * MinusJacobian(x_k), so the tangent-space Jacobian
// Ceres uses is J0_k (fixed at the linearisation point).
class LinearPriorFactor : public ceres::CostFunction {
 public:
  explicit LinearPriorFactor(std::shared_ptr<const LinearPrior> prior);
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  std::shared_ptr<const LinearPrior> prior_;
};

class Marginalizer {
 public:
  // Declares a block: its ambient size and manifold (null: Euclidean).
  void AddParameterBlock(double* values, int size,
                         std::shared_ptr<const ceres::Manifold> manifold = nullptr);
  // A factor on declared blocks (in the cost's order); takes ownership of
  // `cost` and `loss` (loss may be null).
  void AddResidualBlock(ceres::CostFunction* cost, ceres::LossFunction* loss,
                        const std::vector<double*>& blocks);
  // Marks a declared block for elimination.
  void MarkMarginalized(double* values);

  // Eliminates the marked blocks from the factors added; returns the prior on
  // the other blocks these factors touch, or null when none remains or a
  // factor fails to evaluate. Eigenvalues of H_mm and H* below
  // `eigenvalue_threshold` (relative to the largest) are treated as zero.
  std::shared_ptr<LinearPrior> Marginalize(double eigenvalue_threshold = 1e-10) const;

  int num_residual_blocks() const { return static_cast<int>(factors_.size()); }

 private:
  struct ParameterInfo {
    int size = 0;
    std::shared_ptr<const ceres::Manifold> manifold;
  };
  struct Factor {
    std::unique_ptr<ceres::CostFunction> cost;
    std::unique_ptr<ceres::LossFunction> loss;
    std::vector<double*> blocks;
  };
  struct Layout;
  struct Linearization;

  // Marginalize's steps: the blocks in elimination order, the system H dx = b
  // of the factors (false when a plus-Jacobian or a factor fails to
  // evaluate), and the prior from the kept blocks' information H*, b*.
  Layout OrderBlocks() const;
  bool ComputePlusJacobians(const Layout& layout, Linearization* linearization) const;
  bool AddFactor(const Factor& factor, const Layout& layout, Linearization* linearization) const;
  std::shared_ptr<LinearPrior> PriorFromInformation(const Layout& layout,
                                                    const Eigen::MatrixXd& H_star,
                                                    const Eigen::VectorXd& b_star,
                                                    double eigenvalue_threshold) const;

  std::unordered_map<double*, ParameterInfo> parameters_;
  std::vector<double*> parameter_order_;  // declaration order
  std::unordered_set<double*> marginalized_;
  std::vector<Factor> factors_;
};

}  // namespace viosfm

#include "viosfm/vio/marginalization.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "viosfm/util/errors.h"
#include "viosfm/util/logging.h"

namespace viosfm {
namespace {

using RowMajorMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

int TangentSize(int size, const ceres::Manifold* manifold) {
  return manifold == nullptr ? size : manifold->TangentSize();
}

// The tangent increment x [-] x0.
Eigen::VectorXd TangentDifference(const LinearPrior::Block& block, const double* x) {
  Eigen::VectorXd delta(block.tangent_size);
  if (block.manifold == nullptr) {
    delta = Eigen::Map<const Eigen::VectorXd>(x, block.size) - block.linearization_point;
  } else {
    block.manifold->Minus(x, block.linearization_point.data(), delta.data());
  }
  return delta;
}

// H* and b* of the last rows of H dx = b once its first m are eliminated
// (the Schur complement), H* made exactly symmetric.
void SchurComplement(const Eigen::MatrixXd& H, const Eigen::VectorXd& b, int m,
                     double eigenvalue_threshold, Eigen::MatrixXd* H_star,
                     Eigen::VectorXd* b_star) {
  const int r = static_cast<int>(H.rows()) - m;
  if (m == 0) {
    *H_star = H;
    *b_star = b;
  } else {
    const Eigen::MatrixXd H_mm = 0.5 * (H.topLeftCorner(m, m) + H.topLeftCorner(m, m).transpose());
    Eigen::MatrixXd H_mm_inverse;
    // Cholesky when H_mm is well conditioned (the usual case), else the
    // eigenvalue pseudo-inverse.
    const Eigen::LLT<Eigen::MatrixXd> llt(H_mm);
    const double max_diagonal = H_mm.diagonal().maxCoeff();
    if (llt.info() == Eigen::Success && llt.matrixLLT().diagonal().cwiseAbs2().minCoeff() >
                                            1e3 * eigenvalue_threshold * max_diagonal) {
      H_mm_inverse = llt.solve(Eigen::MatrixXd::Identity(m, m));
    } else {
      const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen_mm(H_mm);
      const double max_eigenvalue = std::max(eigen_mm.eigenvalues().maxCoeff(), 0.0);
      const Eigen::VectorXd inverse_eigenvalues =
          (eigen_mm.eigenvalues().array() > eigenvalue_threshold * max_eigenvalue)
              .select(eigen_mm.eigenvalues().array().inverse(), 0.0);
      H_mm_inverse = eigen_mm.eigenvectors() * inverse_eigenvalues.asDiagonal() *
                     eigen_mm.eigenvectors().transpose();
    }
    const Eigen::MatrixXd H_rm = H.bottomLeftCorner(r, m);
    *H_star = H.bottomRightCorner(r, r) - H_rm * H_mm_inverse * H_rm.transpose();
    *b_star = b.tail(r) - H_rm * H_mm_inverse * b.head(m);
  }
  *H_star = 0.5 * (*H_star + H_star->transpose());
}

}  // namespace

std::vector<double*> LinearPrior::ParameterBlocks() const {
  std::vector<double*> values;
  values.reserve(blocks.size());
  for (const Block& block : blocks) values.push_back(block.values);
  return values;
}

std::shared_ptr<LinearPrior> MakeGaussianPrior(
    const std::vector<double*>& values, const std::vector<int>& sizes,
    const std::vector<std::shared_ptr<const ceres::Manifold>>& manifolds,
    const Eigen::MatrixXd& sqrt_information) {
  VIOSFM_CHECK_EQ(values.size(), sizes.size());
  VIOSFM_CHECK_EQ(values.size(), manifolds.size());
  auto prior = std::make_shared<LinearPrior>();
  int offset = 0;
  for (size_t k = 0; k < values.size(); ++k) {
    LinearPrior::Block block;
    block.values = values[k];
    block.size = sizes[k];
    block.manifold = manifolds[k];
    block.tangent_size = TangentSize(sizes[k], manifolds[k].get());
    block.tangent_offset = offset;
    block.linearization_point = Eigen::Map<const Eigen::VectorXd>(values[k], sizes[k]);
    offset += block.tangent_size;
    prior->blocks.push_back(std::move(block));
  }
  VIOSFM_CHECK_EQ(sqrt_information.cols(), offset);
  prior->jacobian = sqrt_information;
  prior->residual = Eigen::VectorXd::Zero(sqrt_information.rows());
  return prior;
}

LinearPriorFactor::LinearPriorFactor(std::shared_ptr<const LinearPrior> prior)
    : prior_(std::move(prior)) {
  VIOSFM_CHECK(prior_ != nullptr);
  for (const LinearPrior::Block& block : prior_->blocks) {
    mutable_parameter_block_sizes()->push_back(block.size);
  }
  set_num_residuals(prior_->num_residuals());
}

bool LinearPriorFactor::Evaluate(double const* const* parameters, double* residuals,
                                 double** jacobians) const {
  const int num_residuals = prior_->num_residuals();
  Eigen::VectorXd delta(prior_->tangent_size());
  for (size_t k = 0; k < prior_->blocks.size(); ++k) {
    const LinearPrior::Block& block = prior_->blocks[k];
    delta.segment(block.tangent_offset, block.tangent_size) =
        TangentDifference(block, parameters[k]);
  }
  Eigen::Map<Eigen::VectorXd>(residuals, num_residuals) =
      prior_->residual + prior_->jacobian * delta;
  if (jacobians == nullptr) return true;
  for (size_t k = 0; k < prior_->blocks.size(); ++k) {
    if (jacobians[k] == nullptr) continue;
    const LinearPrior::Block& block = prior_->blocks[k];
    Eigen::Map<RowMajorMatrix> jacobian(jacobians[k], num_residuals, block.size);
    const auto j_tangent = prior_->jacobian.middleCols(block.tangent_offset, block.tangent_size);
    if (block.manifold == nullptr) {
      jacobian = j_tangent;
    } else {
      RowMajorMatrix minus_jacobian(block.tangent_size, block.size);
      if (!block.manifold->MinusJacobian(parameters[k], minus_jacobian.data())) return false;
      jacobian = j_tangent * minus_jacobian;
    }
  }
  return true;
}

void Marginalizer::AddParameterBlock(double* values, int size,
                                     std::shared_ptr<const ceres::Manifold> manifold) {
  VIOSFM_CHECK(values != nullptr);
  VIOSFM_CHECK_GT(size, 0);
  const auto [it, inserted] = parameters_.emplace(values, ParameterInfo{size, std::move(manifold)});
  if (inserted) {
    parameter_order_.push_back(values);
  } else {
    VIOSFM_CHECK_EQ(it->second.size, size) << "block declared twice with different sizes";
  }
}

void Marginalizer::AddResidualBlock(ceres::CostFunction* cost, ceres::LossFunction* loss,
                                    const std::vector<double*>& blocks) {
  VIOSFM_CHECK(cost != nullptr);
  VIOSFM_CHECK_EQ(cost->parameter_block_sizes().size(), blocks.size());
  for (size_t k = 0; k < blocks.size(); ++k) {
    const auto it = parameters_.find(blocks[k]);
    VIOSFM_CHECK(it != parameters_.end()) << "undeclared parameter block";
    VIOSFM_CHECK_EQ(it->second.size, cost->parameter_block_sizes()[k]);
  }
  Factor factor;
  factor.cost.reset(cost);
  factor.loss.reset(loss);
  factor.blocks = blocks;
  factors_.push_back(std::move(factor));
}

void Marginalizer::MarkMarginalized(double* values) {
  VIOSFM_CHECK(parameters_.count(values) > 0) << "undeclared parameter block";
  marginalized_.insert(values);
}

// The blocks the factors touch, marginalised first, then kept, each in
// declaration order, with their offsets in the tangent space.
struct Marginalizer::Layout {
  std::vector<double*> order;
  size_t num_marginalized_blocks = 0;
  std::unordered_map<double*, int> offsets;
  int total = 0;              // tangent size of all blocks
  int marginalized_size = 0;  // tangent size of the marginalised blocks
};

// The Gauss-Newton system H dx = b over a layout's tangent space, with the
// plus-Jacobians at the current values that the factors share.
struct Marginalizer::Linearization {
  explicit Linearization(int total)
      : H(Eigen::MatrixXd::Zero(total, total)), b(Eigen::VectorXd::Zero(total)) {}
  std::unordered_map<double*, RowMajorMatrix> plus_jacobians;
  Eigen::MatrixXd H;
  Eigen::VectorXd b;
};

std::shared_ptr<LinearPrior> Marginalizer::Marginalize(double eigenvalue_threshold) const {
  const Layout layout = OrderBlocks();
  if (layout.order.size() == layout.num_marginalized_blocks) return nullptr;
  Linearization linearization(layout.total);
  if (!ComputePlusJacobians(layout, &linearization)) return nullptr;
  for (const Factor& factor : factors_) {
    if (!AddFactor(factor, layout, &linearization)) return nullptr;
  }
  Eigen::MatrixXd H_star;
  Eigen::VectorXd b_star;
  SchurComplement(linearization.H, linearization.b, layout.marginalized_size, eigenvalue_threshold,
                  &H_star, &b_star);
  return PriorFromInformation(layout, H_star, b_star, eigenvalue_threshold);
}

Marginalizer::Layout Marginalizer::OrderBlocks() const {
  Layout layout;
  std::unordered_set<double*> used;
  for (const Factor& factor : factors_) used.insert(factor.blocks.begin(), factor.blocks.end());
  std::vector<double*>& order = layout.order;
  for (double* block : parameter_order_) {
    if (used.count(block) > 0 && marginalized_.count(block) > 0) order.push_back(block);
  }
  layout.num_marginalized_blocks = order.size();
  for (double* block : parameter_order_) {
    if (used.count(block) > 0 && marginalized_.count(block) == 0) order.push_back(block);
  }
  for (size_t k = 0; k < order.size(); ++k) {
    const ParameterInfo& info = parameters_.at(order[k]);
    layout.offsets[order[k]] = layout.total;
    layout.total += TangentSize(info.size, info.manifold.get());
    if (k + 1 == layout.num_marginalized_blocks) layout.marginalized_size = layout.total;
  }
  return layout;
}

bool Marginalizer::ComputePlusJacobians(const Layout& layout, Linearization* linearization) const {
  for (double* block : layout.order) {
    const ParameterInfo& info = parameters_.at(block);
    if (info.manifold == nullptr) continue;
    RowMajorMatrix plus(info.size, info.manifold->TangentSize());
    if (!info.manifold->PlusJacobian(block, plus.data())) return false;
    linearization->plus_jacobians.emplace(block, std::move(plus));
  }
  return true;
}

bool Marginalizer::AddFactor(const Factor& factor, const Layout& layout,
                             Linearization* linearization) const {
  const int num_residuals = factor.cost->num_residuals();
  const std::vector<int32_t>& sizes = factor.cost->parameter_block_sizes();
  Eigen::VectorXd residual(num_residuals);
  std::vector<RowMajorMatrix> jacobians(sizes.size());
  std::vector<double*> jacobian_pointers(sizes.size());
  for (size_t k = 0; k < sizes.size(); ++k) {
    jacobians[k].resize(num_residuals, sizes[k]);
    jacobian_pointers[k] = jacobians[k].data();
  }
  if (!factor.cost->Evaluate(factor.blocks.data(), residual.data(), jacobian_pointers.data())) {
    VIOSFM_LOG(WARNING) << "marginalisation: a factor failed to evaluate";
    return false;
  }
  if (!residual.allFinite()) return false;
  double scale = 1.0;
  if (factor.loss != nullptr) {
    double rho[3];
    factor.loss->Evaluate(residual.squaredNorm(), rho);
    scale = std::sqrt(std::max(rho[1], 0.0));
  }
  residual *= scale;
  // Tangent Jacobians.
  std::vector<Eigen::MatrixXd> tangent(sizes.size());
  for (size_t k = 0; k < sizes.size(); ++k) {
    const auto it = linearization->plus_jacobians.find(factor.blocks[k]);
    tangent[k] = it == linearization->plus_jacobians.end()
                     ? Eigen::MatrixXd(jacobians[k] * scale)
                     : Eigen::MatrixXd(jacobians[k] * it->second * scale);
  }
  Eigen::MatrixXd& H = linearization->H;
  for (size_t k = 0; k < sizes.size(); ++k) {
    const int offset_k = layout.offsets.at(factor.blocks[k]);
    const int size_k = static_cast<int>(tangent[k].cols());
    linearization->b.segment(offset_k, size_k) += tangent[k].transpose() * residual;
    for (size_t l = k; l < sizes.size(); ++l) {
      const int offset_l = layout.offsets.at(factor.blocks[l]);
      const int size_l = static_cast<int>(tangent[l].cols());
      const Eigen::MatrixXd block = tangent[k].transpose() * tangent[l];
      H.block(offset_k, offset_l, size_k, size_l) += block;
      if (l != k) H.block(offset_l, offset_k, size_l, size_k) += block.transpose();
    }
  }
  return true;
}

std::shared_ptr<LinearPrior> Marginalizer::PriorFromInformation(const Layout& layout,
                                                                const Eigen::MatrixXd& H_star,
                                                                const Eigen::VectorXd& b_star,
                                                                double eigenvalue_threshold) const {
  const int r = layout.total - layout.marginalized_size;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(H_star);
  const double max_eigenvalue = std::max(eigen.eigenvalues().maxCoeff(), 0.0);
  std::vector<int> kept;
  for (int k = 0; k < r; ++k) {
    if (eigen.eigenvalues()[k] > eigenvalue_threshold * max_eigenvalue &&
        eigen.eigenvalues()[k] > 0.0) {
      kept.push_back(k);
    }
  }
  if (kept.empty()) return nullptr;

  auto prior = std::make_shared<LinearPrior>();
  int tangent_offset = 0;
  for (size_t k = layout.num_marginalized_blocks; k < layout.order.size(); ++k) {
    double* values = layout.order[k];
    const ParameterInfo& info = parameters_.at(values);
    LinearPrior::Block block;
    block.values = values;
    block.size = info.size;
    block.manifold = info.manifold;
    block.tangent_size = TangentSize(info.size, info.manifold.get());
    block.tangent_offset = tangent_offset;
    block.linearization_point = Eigen::Map<const Eigen::VectorXd>(values, info.size);
    tangent_offset += block.tangent_size;
    prior->blocks.push_back(std::move(block));
  }
  const int rows = static_cast<int>(kept.size());
  prior->jacobian.resize(rows, r);
  prior->residual.resize(rows);
  for (int row = 0; row < rows; ++row) {
    const double lambda = eigen.eigenvalues()[kept[row]];
    const Eigen::VectorXd v = eigen.eigenvectors().col(kept[row]);
    prior->jacobian.row(row) = std::sqrt(lambda) * v.transpose();
    prior->residual[row] = v.dot(b_star) / std::sqrt(lambda);
  }
  return prior;
}

}  // namespace viosfm

#include "viosfm/ba/bundle_adjustment.h"

#include <ceres/ceres.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <memory>
#include <sstream>
#include <unordered_map>
#include <unordered_set>

#include "viosfm/ba/cost_functions.h"
#include "viosfm/sensor/camera_models.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/logging.h"
#include "viosfm/util/timer.h"

namespace viosfm {
namespace {

// Parameter indices of `camera` held constant when intrinsics are refined.
std::vector<int> ConstantIntrinsicIndices(const Camera& camera,
                                          const BundleAdjustmentOptions& options) {
  if (options.refine_principal_point) return {};
  return PrincipalPointIndices(camera);
}

// The problem's cost functions, which it does not own: a problem that owns
// them keeps a tree node for each, an allocation and an insertion per
// observation. Declared before the problem, so deleted after it.
class OwnedCostFunctions {
 public:
  ceres::CostFunction* Add(ceres::CostFunction* cost) {
    owned_.emplace_back(cost);
    return cost;
  }
  // The cost functions of the residual blocks added to `problem` from the
  // `first` on: a caller's terms, added as to a problem that owns them.
  void TakeFrom(const ceres::Problem& problem, size_t first) {
    std::vector<ceres::ResidualBlockId> blocks;
    problem.GetResidualBlocks(&blocks);
    std::vector<const ceres::CostFunction*> costs;
    for (size_t k = first; k < blocks.size(); ++k) {
      costs.push_back(problem.GetCostFunctionForResidualBlock(blocks[k]));
    }
    std::sort(costs.begin(), costs.end());
    costs.erase(std::unique(costs.begin(), costs.end()), costs.end());
    for (const ceres::CostFunction* cost : costs) Add(const_cast<ceres::CostFunction*>(cost));
  }

 private:
  std::vector<std::unique_ptr<ceres::CostFunction>> owned_;
};

}  // namespace

const char* BaLinearSolverName(BaLinearSolver solver) {
  switch (solver) {
    case BaLinearSolver::kSparseSchur: return "SPARSE_SCHUR";
    case BaLinearSolver::kDenseSchur: return "DENSE_SCHUR";
    case BaLinearSolver::kIterativeSchur: return "ITERATIVE_SCHUR";
    default: break;
  }
  return "auto";
}

BaLinearSolver ParseBaLinearSolver(const std::string& name) {
  for (const BaLinearSolver solver :
       {BaLinearSolver::kAuto, BaLinearSolver::kSparseSchur, BaLinearSolver::kDenseSchur,
        BaLinearSolver::kIterativeSchur}) {
    if (name == BaLinearSolverName(solver)) return solver;
  }
  throw InputError("linear solver '" + name +
                   "': expected auto, SPARSE_SCHUR, DENSE_SCHUR or ITERATIVE_SCHUR");
}

const char* PriorWeightingName(PriorWeighting weighting) {
  return weighting == PriorWeighting::kPaper ? "paper" : "covariance";
}

PriorWeighting ParsePriorWeighting(const std::string& name) {
  if (name == "covariance") return PriorWeighting::kCovariance;
  if (name == "paper") return PriorWeighting::kPaper;
  throw InputError("prior weighting '" + name + "': expected 'covariance' or 'paper'");
}

std::string BundleAdjustmentOptions::Validate() const {
  if (!(loss_scale_px >= 0.0)) return "loss_scale_px must be >= 0";
  if (!(prior_alpha >= 0.0)) return "prior_alpha must be >= 0";
  if (!(prior_beta >= 0.0)) return "prior_beta must be >= 0";
  if (!(prior_rotation_sigma_rad > 0.0)) return "prior_rotation_sigma_rad must be > 0";
  if (!(prior_translation_sigma_m > 0.0)) return "prior_translation_sigma_m must be > 0";
  if (!(prior_loss_scale >= 0.0)) return "prior_loss_scale must be >= 0";
  if (!(image_noise_px > 0.0)) return "image_noise_px must be > 0";
  if (max_num_iterations < 0) return "max_num_iterations must be >= 0";
  if (num_threads < 1) return "num_threads must be >= 1";
  if (max_images_for_sparse_schur < 0) return "max_images_for_sparse_schur must be >= 0";
  if (!(function_tolerance >= 0.0)) return "function_tolerance must be >= 0";
  if (max_linear_solver_iterations < 1) return "max_linear_solver_iterations must be >= 1";
  if (!(gradient_tolerance >= 0.0)) return "gradient_tolerance must be >= 0";
  if (!(parameter_tolerance >= 0.0)) return "parameter_tolerance must be >= 0";
  return "";
}

std::string BundleAdjustmentSummary::ToString() const {
  std::ostringstream out;
  out << std::fixed << std::setprecision(3) << "bundle adjustment: " << num_images << " images, "
      << num_points << " points, " << num_observations << " observations, " << num_priors
      << " relative-pose priors; reprojection error " << mean_reprojection_error_before_px << " -> "
      << mean_reprojection_error_after_px << " px; cost " << std::setprecision(6) << initial_cost
      << " -> " << final_cost << "; " << num_iterations << " iterations, " << std::setprecision(3)
      << time_s << " s (" << BaLinearSolverName(linear_solver) << "); " << termination;
  return out.str();
}

ceres::LossFunction* CreateWhitenedLoss(double prior_loss_scale, double image_noise_px) {
  ceres::LossFunction* loss = nullptr;
  if (prior_loss_scale > 0.0) loss = new ceres::TukeyLoss(prior_loss_scale);
  if (image_noise_px != 1.0) {
    // Against reprojection errors in units of image_noise_px; the loss still
    // acts in the term's own sigmas.
    loss = new ceres::ScaledLoss(loss, image_noise_px * image_noise_px, ceres::TAKE_OWNERSHIP);
  }
  return loss;
}

namespace {

// One adjustment: its problem built, solved and written back in named steps
// (BundleAdjust). Each registered image's pose is one parameter block
// (cost_functions.h) and each point's position another, copied into arrays
// in the order they enter the problem and back after the solve; the
// caller's terms' blocks live in the poses' array, after them. The arrays
// never grow past their reserved size, so the blocks' addresses are stable,
// and they increase in that order: Ceres orders the blocks of each group of
// linear_solver_ordering by address, so the solve does not depend on where
// the reconstruction's or the caller's memory happens to be.
class BundleAdjuster {
 public:
  BundleAdjuster(Reconstruction* reconstruction, const std::vector<image_t>& constant_poses,
                 const BundleAdjustmentOptions& options, BundleAdjustmentTerms* terms)
      : reconstruction_(reconstruction),
        options_(options),
        terms_(terms),
        constant_(constant_poses.begin(), constant_poses.end()),
        problem_(ProblemOptions()),
        max_num_poses_(reconstruction->NumRegImages()),
        pose_and_term_values_(max_num_poses_ * kPoseSize +
                              (terms != nullptr ? terms->NumParameters() : 0)) {}

  // The constant poses checked, the rotations normalised, the error before.
  void Prepare() {
    for (const image_t image_id : constant_) {
      VIOSFM_CHECK(reconstruction_->ExistsImage(image_id))
          << "constant pose of unknown image " << image_id;
      VIOSFM_CHECK(reconstruction_->GetImage(image_id).registered)
          << "constant pose of unregistered image " << image_id;
    }
    for (const image_t image_id : reconstruction_->RegImageIds()) {
      reconstruction_->GetImage(image_id).cam_from_world.rotation.normalize();
    }
    summary_.mean_reprojection_error_before_px =
        MeanReprojectionError(*reconstruction_, options_.num_threads);
  }

  // Every point's observations in registered images.
  void AddObservations();
  // The relative-pose priors between registered images, not both constant.
  void AddPriors(const std::vector<RelativePosePrior>& priors);
  // The caller's terms, their blocks in the poses' array.
  void AddTerms();
  // The poses' manifold and the constant ones; the intrinsics held.
  void SetManifolds();

  bool Empty() const { return problem_.NumResidualBlocks() == 0; }
  // Solves, and writes the poses, points and terms back.
  void Solve();
  // The summary, the errors after and the time.
  BundleAdjustmentSummary Finish(const std::string& termination);

 private:
  static constexpr size_t kPoseSize = std::tuple_size_v<PoseParameters>;

  // The shared loss and the manifolds are owned by the problem, the cost
  // functions by cost_functions_.
  static ceres::Problem::Options ProblemOptions() {
    ceres::Problem::Options options;
    options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    return options;
  }
  double* PoseData(size_t k) { return pose_and_term_values_.data() + k * kPoseSize; }
  double* TermStorage() { return pose_and_term_values_.data() + max_num_poses_ * kPoseSize; }
  // The image's pose block, added on first use.
  double* PoseBlock(const Image& image);
  Rigid3d PoseOfBlock(size_t k) {
    PoseParameters values;
    std::copy(PoseData(k), PoseData(k) + kPoseSize, values.begin());
    return FromPoseParameters(values);
  }
  ceres::Solver::Options SolverOptions();

  Reconstruction* const reconstruction_;
  const BundleAdjustmentOptions& options_;
  BundleAdjustmentTerms* const terms_;
  const std::unordered_set<image_t> constant_;
  const Timer timer_;
  BundleAdjustmentSummary summary_;
  OwnedCostFunctions cost_functions_;  // before problem_: deleted after it
  ceres::Problem problem_;
  const size_t max_num_poses_;
  std::vector<double> pose_and_term_values_;
  size_t num_poses_ = 0;
  std::vector<image_t> pose_image_ids_;
  std::unordered_map<image_t, size_t> pose_index_;
  std::vector<Eigen::Vector3d> point_parameters_;
  std::vector<point3D_t> point_ids_in_problem_;
  std::unordered_set<camera_t> cameras_in_problem_;
  std::vector<double*> term_blocks_;
  double seconds_before_solve_ = 0.0;
  std::string solve_times_;  // Ceres' times, for the log
};

double* BundleAdjuster::PoseBlock(const Image& image) {
  auto [it, inserted] = pose_index_.try_emplace(image.image_id, num_poses_);
  if (inserted) {
    VIOSFM_CHECK_LT(num_poses_, max_num_poses_);
    const PoseParameters values = ToPoseParameters(image.cam_from_world);
    std::copy(values.begin(), values.end(), PoseData(num_poses_));
    pose_image_ids_.push_back(image.image_id);
    ++num_poses_;
  }
  return PoseData(it->second);
}

void BundleAdjuster::AddObservations() {
  ceres::LossFunction* loss =
      options_.loss_scale_px > 0.0 ? new ceres::CauchyLoss(options_.loss_scale_px) : nullptr;
  bool loss_used = false;
  const std::vector<point3D_t> all_point_ids = reconstruction_->Point3DIds();
  point_parameters_.reserve(all_point_ids.size());
  for (const point3D_t point3D_id : all_point_ids) {
    const Point3D& point3D = reconstruction_->GetPoint3D(point3D_id);
    bool point_used = false;
    double* xyz = nullptr;
    for (const TrackElement& element : point3D.track) {
      Image& image = reconstruction_->GetImage(element.image_id);
      if (!image.registered) continue;
      Camera& camera = reconstruction_->GetCamera(image.camera_id);
      const Point2D& point2D = image.points2D.at(element.point2D_idx);
      if (xyz == nullptr) {
        point_parameters_.push_back(point3D.xyz);
        xyz = point_parameters_.back().data();
      }
      if (options_.refine_intrinsics) {
        problem_.AddResidualBlock(
            cost_functions_.Add(CreateReprojectionCost(camera.model_id, point2D.xy)), loss,
            PoseBlock(image), xyz, camera.params.data());
        cameras_in_problem_.insert(camera.camera_id);
      } else {
        problem_.AddResidualBlock(
            cost_functions_.Add(CreateConstantCameraReprojectionCost(camera, point2D.xy)), loss,
            PoseBlock(image), xyz);
      }
      loss_used = true;
      point_used = true;
      ++summary_.num_observations;
    }
    if (point_used) {
      ++summary_.num_points;
      point_ids_in_problem_.push_back(point3D_id);
    }
  }
  if (loss != nullptr && !loss_used) delete loss;
}

void BundleAdjuster::AddPriors(const std::vector<RelativePosePrior>& priors) {
  if (!options_.use_relative_pose_priors) return;
  for (const RelativePosePrior& prior : priors) {
    if (!reconstruction_->ExistsImage(prior.image_id1) ||
        !reconstruction_->ExistsImage(prior.image_id2)) {
      continue;
    }
    Image& image1 = reconstruction_->GetImage(prior.image_id1);
    Image& image2 = reconstruction_->GetImage(prior.image_id2);
    if (!image1.registered || !image2.registered) continue;
    if (constant_.count(prior.image_id1) > 0 && constant_.count(prior.image_id2) > 0) continue;
    Eigen::Matrix<double, 6, 6> sqrt_information;
    ceres::LossFunction* prior_loss = nullptr;
    // The loss of a whitened prior (covariance-weighted or the gyro's).
    const auto whitened_loss = [this]() {
      return CreateWhitenedLoss(options_.prior_loss_scale, options_.image_noise_px);
    };
    if (prior.from_gyro) {
      VIOSFM_CHECK(prior.sqrt_information.has_value());
      sqrt_information = *prior.sqrt_information;
      prior_loss = whitened_loss();
    } else if (options_.prior_weighting == PriorWeighting::kCovariance && prior.sqrt_information) {
      // The connectivity factor exp(-beta c) scales the information.
      const double factor =
          std::sqrt(prior.weight_scale *
                    RelativePoseWeight(prior.num_verified_matches, 1.0, options_.prior_beta));
      sqrt_information = factor * *prior.sqrt_information;
      if (prior.rotation_only) {
        // The rotation's marginal information: whiten the rotation block alone.
        sqrt_information.setZero();
        const Eigen::Matrix<double, 6, 6> information =
            prior.sqrt_information->transpose() * *prior.sqrt_information;
        const Eigen::Matrix3d rotation_covariance = information.inverse().topLeftCorner<3, 3>();
        const Eigen::Matrix3d rotation_sqrt =
            rotation_covariance.llt().matrixL().solve(Eigen::Matrix3d::Identity());
        sqrt_information.topLeftCorner<3, 3>() = factor * rotation_sqrt;
      }
      prior_loss = whitened_loss();
    } else {
      const double weight =
          prior.weight_scale *
          RelativePoseWeight(prior.num_verified_matches, options_.prior_alpha, options_.prior_beta);
      sqrt_information = RelativePoseSqrtInformation(weight, options_.prior_rotation_sigma_rad,
                                                     options_.prior_translation_sigma_m);
      if (prior.rotation_only) sqrt_information.bottomRightCorner<3, 3>().setZero();
    }
    problem_.AddResidualBlock(
        cost_functions_.Add(RelativePoseError::Create(prior.cam2_from_cam1, sqrt_information)),
        prior_loss, PoseBlock(image1), PoseBlock(image2));
    ++summary_.num_priors;
  }
}

void BundleAdjuster::AddTerms() {
  if (terms_ == nullptr) return;
  const size_t first_term = static_cast<size_t>(problem_.NumResidualBlocks());
  term_blocks_ = terms_->AddTo(
      &problem_,
      [this](image_t image_id) -> double* {
        if (!reconstruction_->ExistsImage(image_id)) return nullptr;
        const Image& image = reconstruction_->GetImage(image_id);
        return image.registered ? PoseBlock(image) : nullptr;
      },
      TermStorage());
  cost_functions_.TakeFrom(problem_, first_term);
}

void BundleAdjuster::SetManifolds() {
  summary_.num_images = static_cast<int>(num_poses_);
  for (size_t k = 0; k < num_poses_; ++k) {
    problem_.SetManifold(PoseData(k), CreatePoseManifold());
    if (constant_.count(pose_image_ids_[k]) > 0) problem_.SetParameterBlockConstant(PoseData(k));
  }
  // (Only with refine_intrinsics are cameras parameter blocks.)
  for (const camera_t camera_id : cameras_in_problem_) {
    Camera& camera = reconstruction_->GetCamera(camera_id);
    const std::vector<int> held = ConstantIntrinsicIndices(camera, options_);
    if (!held.empty()) {
      problem_.SetManifold(camera.params.data(),
                           new ceres::SubsetManifold(static_cast<int>(camera.params.size()), held));
    }
  }
}

ceres::Solver::Options BundleAdjuster::SolverOptions() {
  ceres::Solver::Options solver_options;
  solver_options.max_num_iterations = options_.max_num_iterations;
  solver_options.num_threads = options_.num_threads;
  solver_options.function_tolerance = options_.function_tolerance;
  solver_options.gradient_tolerance = options_.gradient_tolerance;
  solver_options.parameter_tolerance = options_.parameter_tolerance;
  solver_options.minimizer_progress_to_stdout = options_.print_progress;
  solver_options.logging_type =
      options_.print_progress ? ceres::PER_MINIMIZER_ITERATION : ceres::SILENT;
  const bool sparse_available =
      ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::SUITE_SPARSE) ||
      ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::EIGEN_SPARSE);
  BaLinearSolver solver = options_.linear_solver;
  if (solver == BaLinearSolver::kAuto) {
    solver = summary_.num_images > options_.max_images_for_sparse_schur
                 ? BaLinearSolver::kIterativeSchur
                 : BaLinearSolver::kSparseSchur;
  }
  if (solver == BaLinearSolver::kSparseSchur && !sparse_available) {
    solver = BaLinearSolver::kDenseSchur;
  }
  summary_.linear_solver = solver;
  switch (solver) {
    case BaLinearSolver::kIterativeSchur:
      solver_options.linear_solver_type = ceres::ITERATIVE_SCHUR;
      solver_options.preconditioner_type = ceres::SCHUR_JACOBI;
      solver_options.max_linear_solver_iterations = options_.max_linear_solver_iterations;
      break;
    case BaLinearSolver::kDenseSchur: solver_options.linear_solver_type = ceres::DENSE_SCHUR; break;
    default: solver_options.linear_solver_type = ceres::SPARSE_SCHUR; break;
  }
  if (!options_.refine_intrinsics) {
    // The points first (eliminated), then the poses and the caller's
    // blocks: the ordering Ceres finds for a bundle adjustment problem,
    // given instead of searched for in the problem's graph, a large part of
    // Ceres' preprocessing. (With intrinsics, whose blocks live elsewhere,
    // Ceres searches.)
    auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
    for (Eigen::Vector3d& xyz : point_parameters_) ordering->AddElementToGroup(xyz.data(), 0);
    for (size_t k = 0; k < num_poses_; ++k) {
      if (constant_.count(pose_image_ids_[k]) == 0) ordering->AddElementToGroup(PoseData(k), 1);
    }
    for (double* block : term_blocks_) ordering->AddElementToGroup(block, 1);
    if (ordering->NumGroups() == 2) solver_options.linear_solver_ordering = ordering;
  }
  std::string error;
  VIOSFM_CHECK(solver_options.IsValid(&error)) << error;
  return solver_options;
}

void BundleAdjuster::Solve() {
  const ceres::Solver::Options solver_options = SolverOptions();
  seconds_before_solve_ = timer_.ElapsedSeconds();
  ceres::Solver::Summary ceres_summary;
  ceres::Solve(solver_options, &problem_, &ceres_summary);

  for (size_t k = 0; k < num_poses_; ++k) {
    if (constant_.count(pose_image_ids_[k]) > 0) continue;
    reconstruction_->GetImage(pose_image_ids_[k]).cam_from_world = PoseOfBlock(k);
  }
  if (terms_ != nullptr) terms_->TakeSolution(TermStorage());
  for (size_t k = 0; k < point_ids_in_problem_.size(); ++k) {
    reconstruction_->GetPoint3D(point_ids_in_problem_[k]).xyz = point_parameters_[k];
  }
  summary_.initial_cost = ceres_summary.initial_cost;
  summary_.final_cost = ceres_summary.final_cost;
  summary_.num_iterations = std::max(0, static_cast<int>(ceres_summary.iterations.size()) - 1);
  summary_.termination =
      std::string(ceres::TerminationTypeToString(ceres_summary.termination_type)) + ": " +
      ceres_summary.message;
  summary_.usable = ceres_summary.IsSolutionUsable();
  std::ostringstream times;
  times << "; before the solve (errors, problem built) " << seconds_before_solve_
        << " s; Ceres: in all " << ceres_summary.total_time_in_seconds << " s, linear solver "
        << ceres_summary.linear_solver_time_in_seconds << " s, Jacobians "
        << ceres_summary.jacobian_evaluation_time_in_seconds << " s, residuals "
        << ceres_summary.residual_evaluation_time_in_seconds << " s, preprocessing "
        << ceres_summary.preprocessor_time_in_seconds << " s";
  solve_times_ = times.str();
}

BundleAdjustmentSummary BundleAdjuster::Finish(const std::string& termination) {
  if (!termination.empty()) summary_.termination = termination;
  summary_.mean_reprojection_error_after_px =
      UpdateReprojectionErrors(reconstruction_, options_.num_threads);
  summary_.time_s = timer_.ElapsedSeconds();
  if (!solve_times_.empty()) VIOSFM_LOG(DEBUG) << summary_.ToString() << solve_times_;
  return summary_;
}

}  // namespace

BundleAdjustmentSummary BundleAdjust(Reconstruction* reconstruction,
                                     const std::vector<RelativePosePrior>& priors,
                                     const std::vector<image_t>& constant_poses,
                                     const BundleAdjustmentOptions& options,
                                     BundleAdjustmentTerms* terms) {
  VIOSFM_CHECK(reconstruction != nullptr);
  VIOSFM_CHECK(options.Check()) << options.Validate();
  BundleAdjuster adjuster(reconstruction, constant_poses, options, terms);
  adjuster.Prepare();
  adjuster.AddObservations();
  adjuster.AddPriors(priors);
  adjuster.AddTerms();
  adjuster.SetManifolds();
  if (adjuster.Empty()) return adjuster.Finish("nothing to adjust");
  adjuster.Solve();
  return adjuster.Finish("");
}

}  // namespace viosfm

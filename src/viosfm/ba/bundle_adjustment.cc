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

BundleAdjustmentSummary BundleAdjust(Reconstruction* reconstruction,
                                     const std::vector<RelativePosePrior>& priors,
                                     const std::vector<image_t>& constant_poses,
                                     const BundleAdjustmentOptions& options,
                                     BundleAdjustmentTerms* terms) {
  VIOSFM_CHECK(reconstruction != nullptr);
  VIOSFM_CHECK(options.Check()) << options.Validate();
  const Timer timer;
  BundleAdjustmentSummary summary;

  const std::unordered_set<image_t> constant(constant_poses.begin(), constant_poses.end());
  for (const image_t image_id : constant) {
    VIOSFM_CHECK(reconstruction->ExistsImage(image_id))
        << "constant pose of unknown image " << image_id;
    VIOSFM_CHECK(reconstruction->GetImage(image_id).registered)
        << "constant pose of unregistered image " << image_id;
  }
  for (const image_t image_id : reconstruction->RegImageIds()) {
    reconstruction->GetImage(image_id).cam_from_world.rotation.normalize();
  }
  summary.mean_reprojection_error_before_px =
      MeanReprojectionError(*reconstruction, options.num_threads);

  ceres::Problem::Options problem_options;
  // Cost functions, the shared loss and the manifolds are owned by the problem.
  ceres::Problem problem(problem_options);
  ceres::LossFunction* loss =
      options.loss_scale_px > 0.0 ? new ceres::CauchyLoss(options.loss_scale_px) : nullptr;
  bool loss_used = false;

  // Each registered image's pose as one parameter block (cost_functions.h)
  // and each point's position, copied into arrays in the order they enter
  // the problem and back after the solve; the caller's terms' blocks in
  // the poses' array, after them. The arrays never grow past their
  // reserved size, so the blocks' addresses are stable, and they increase
  // in that order: Ceres orders the blocks of each group of
  // linear_solver_ordering by address, so the solve does not depend on
  // where the reconstruction's or the caller's memory happens to be.
  constexpr size_t kPoseSize = std::tuple_size_v<PoseParameters>;
  const size_t max_num_poses = reconstruction->NumRegImages();
  std::vector<double> pose_and_term_values(max_num_poses * kPoseSize +
                                           (terms != nullptr ? terms->NumParameters() : 0));
  double* const term_storage = pose_and_term_values.data() + max_num_poses * kPoseSize;
  size_t num_poses = 0;
  const auto pose_data = [&](size_t k) { return pose_and_term_values.data() + k * kPoseSize; };
  const auto pose_of_block = [&](size_t k) {
    PoseParameters values;
    std::copy(pose_data(k), pose_data(k) + kPoseSize, values.begin());
    return FromPoseParameters(values);
  };
  std::vector<image_t> pose_image_ids;
  std::unordered_map<image_t, size_t> pose_index;
  const auto pose_block = [&](const Image& image) {
    auto [it, inserted] = pose_index.try_emplace(image.image_id, num_poses);
    if (inserted) {
      VIOSFM_CHECK_LT(num_poses, max_num_poses);
      const PoseParameters values = ToPoseParameters(image.cam_from_world);
      std::copy(values.begin(), values.end(), pose_data(num_poses));
      pose_image_ids.push_back(image.image_id);
      ++num_poses;
    }
    return pose_data(it->second);
  };
  const std::vector<point3D_t> all_point_ids = reconstruction->Point3DIds();
  std::vector<Eigen::Vector3d> point_parameters;
  point_parameters.reserve(all_point_ids.size());
  std::unordered_set<camera_t> cameras_in_problem;
  std::vector<point3D_t> point_ids_in_problem;
  for (const point3D_t point3D_id : all_point_ids) {
    const Point3D& point3D = reconstruction->GetPoint3D(point3D_id);
    bool point_used = false;
    double* xyz = nullptr;
    for (const TrackElement& element : point3D.track) {
      Image& image = reconstruction->GetImage(element.image_id);
      if (!image.registered) continue;
      Camera& camera = reconstruction->GetCamera(image.camera_id);
      const Point2D& point2D = image.points2D.at(element.point2D_idx);
      if (xyz == nullptr) {
        point_parameters.push_back(point3D.xyz);
        xyz = point_parameters.back().data();
      }
      if (options.refine_intrinsics) {
        problem.AddResidualBlock(CreateReprojectionCost(camera.model_id, point2D.xy), loss,
                                 pose_block(image), xyz, camera.params.data());
        cameras_in_problem.insert(camera.camera_id);
      } else {
        problem.AddResidualBlock(CreateConstantCameraReprojectionCost(camera, point2D.xy), loss,
                                 pose_block(image), xyz);
      }
      loss_used = true;
      point_used = true;
      ++summary.num_observations;
    }
    if (point_used) {
      ++summary.num_points;
      point_ids_in_problem.push_back(point3D_id);
    }
  }
  if (loss != nullptr && !loss_used) delete loss;

  if (options.use_relative_pose_priors) {
    for (const RelativePosePrior& prior : priors) {
      if (!reconstruction->ExistsImage(prior.image_id1) ||
          !reconstruction->ExistsImage(prior.image_id2)) {
        continue;
      }
      Image& image1 = reconstruction->GetImage(prior.image_id1);
      Image& image2 = reconstruction->GetImage(prior.image_id2);
      if (!image1.registered || !image2.registered) continue;
      if (constant.count(prior.image_id1) > 0 && constant.count(prior.image_id2) > 0) continue;
      Eigen::Matrix<double, 6, 6> sqrt_information;
      ceres::LossFunction* prior_loss = nullptr;
      // The loss of a whitened prior (covariance-weighted or the gyro's).
      const auto whitened_loss = [&options]() {
        return CreateWhitenedLoss(options.prior_loss_scale, options.image_noise_px);
      };
      if (prior.from_gyro) {
        VIOSFM_CHECK(prior.sqrt_information.has_value());
        sqrt_information = *prior.sqrt_information;
        prior_loss = whitened_loss();
      } else if (options.prior_weighting == PriorWeighting::kCovariance && prior.sqrt_information) {
        // The connectivity factor exp(-beta c) scales the information.
        const double factor =
            std::sqrt(prior.weight_scale *
                      RelativePoseWeight(prior.num_verified_matches, 1.0, options.prior_beta));
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
            RelativePoseWeight(prior.num_verified_matches, options.prior_alpha, options.prior_beta);
        sqrt_information = RelativePoseSqrtInformation(weight, options.prior_rotation_sigma_rad,
                                                       options.prior_translation_sigma_m);
        if (prior.rotation_only) sqrt_information.bottomRightCorner<3, 3>().setZero();
      }
      problem.AddResidualBlock(RelativePoseError::Create(prior.cam2_from_cam1, sqrt_information),
                               prior_loss, pose_block(image1), pose_block(image2));
      ++summary.num_priors;
    }
  }
  std::vector<double*> term_blocks;
  if (terms != nullptr) {
    term_blocks = terms->AddTo(
        &problem,
        [&](image_t image_id) -> double* {
          if (!reconstruction->ExistsImage(image_id)) return nullptr;
          const Image& image = reconstruction->GetImage(image_id);
          return image.registered ? pose_block(image) : nullptr;
        },
        term_storage);
  }
  summary.num_images = static_cast<int>(num_poses);

  for (size_t k = 0; k < num_poses; ++k) {
    problem.SetManifold(pose_data(k), CreatePoseManifold());
    if (constant.count(pose_image_ids[k]) > 0) problem.SetParameterBlockConstant(pose_data(k));
  }
  // (Only with refine_intrinsics are cameras parameter blocks.)
  for (const camera_t camera_id : cameras_in_problem) {
    Camera& camera = reconstruction->GetCamera(camera_id);
    const std::vector<int> held = ConstantIntrinsicIndices(camera, options);
    if (!held.empty()) {
      problem.SetManifold(camera.params.data(),
                          new ceres::SubsetManifold(static_cast<int>(camera.params.size()), held));
    }
  }

  if (problem.NumResidualBlocks() == 0) {
    summary.termination = "nothing to adjust";
    summary.mean_reprojection_error_after_px =
        UpdateReprojectionErrors(reconstruction, options.num_threads);
    summary.time_s = timer.ElapsedSeconds();
    return summary;
  }

  ceres::Solver::Options solver_options;
  solver_options.max_num_iterations = options.max_num_iterations;
  solver_options.num_threads = options.num_threads;
  solver_options.function_tolerance = options.function_tolerance;
  solver_options.gradient_tolerance = options.gradient_tolerance;
  solver_options.parameter_tolerance = options.parameter_tolerance;
  solver_options.minimizer_progress_to_stdout = options.print_progress;
  solver_options.logging_type =
      options.print_progress ? ceres::PER_MINIMIZER_ITERATION : ceres::SILENT;
  const bool sparse_available =
      ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::SUITE_SPARSE) ||
      ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::EIGEN_SPARSE);
  BaLinearSolver solver = options.linear_solver;
  if (solver == BaLinearSolver::kAuto) {
    solver = summary.num_images > options.max_images_for_sparse_schur
                 ? BaLinearSolver::kIterativeSchur
                 : BaLinearSolver::kSparseSchur;
  }
  if (solver == BaLinearSolver::kSparseSchur && !sparse_available) {
    solver = BaLinearSolver::kDenseSchur;
  }
  summary.linear_solver = solver;
  switch (solver) {
    case BaLinearSolver::kIterativeSchur:
      solver_options.linear_solver_type = ceres::ITERATIVE_SCHUR;
      solver_options.preconditioner_type = ceres::SCHUR_JACOBI;
      solver_options.max_linear_solver_iterations = options.max_linear_solver_iterations;
      break;
    case BaLinearSolver::kDenseSchur: solver_options.linear_solver_type = ceres::DENSE_SCHUR; break;
    default: solver_options.linear_solver_type = ceres::SPARSE_SCHUR; break;
  }
  if (!options.refine_intrinsics) {
    // The points first (eliminated), then the poses and the caller's
    // blocks: the ordering Ceres finds for a bundle adjustment problem,
    // given instead of searched for in the problem's graph, a large part of
    // Ceres' preprocessing. (With intrinsics, whose blocks live elsewhere,
    // Ceres searches.)
    auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
    for (Eigen::Vector3d& xyz : point_parameters) ordering->AddElementToGroup(xyz.data(), 0);
    for (size_t k = 0; k < num_poses; ++k) {
      if (constant.count(pose_image_ids[k]) == 0) ordering->AddElementToGroup(pose_data(k), 1);
    }
    for (double* block : term_blocks) ordering->AddElementToGroup(block, 1);
    if (ordering->NumGroups() == 2) solver_options.linear_solver_ordering = ordering;
  }
  std::string error;
  VIOSFM_CHECK(solver_options.IsValid(&error)) << error;

  const double seconds_before_solve = timer.ElapsedSeconds();
  ceres::Solver::Summary ceres_summary;
  ceres::Solve(solver_options, &problem, &ceres_summary);

  for (size_t k = 0; k < num_poses; ++k) {
    if (constant.count(pose_image_ids[k]) > 0) continue;
    reconstruction->GetImage(pose_image_ids[k]).cam_from_world = pose_of_block(k);
  }
  if (terms != nullptr) terms->TakeSolution(term_storage);
  for (size_t k = 0; k < point_ids_in_problem.size(); ++k) {
    reconstruction->GetPoint3D(point_ids_in_problem[k]).xyz = point_parameters[k];
  }
  summary.initial_cost = ceres_summary.initial_cost;
  summary.final_cost = ceres_summary.final_cost;
  summary.num_iterations = std::max(0, static_cast<int>(ceres_summary.iterations.size()) - 1);
  summary.termination =
      std::string(ceres::TerminationTypeToString(ceres_summary.termination_type)) + ": " +
      ceres_summary.message;
  summary.usable = ceres_summary.IsSolutionUsable();
  summary.mean_reprojection_error_after_px =
      UpdateReprojectionErrors(reconstruction, options.num_threads);
  summary.time_s = timer.ElapsedSeconds();
  VIOSFM_LOG(DEBUG) << summary.ToString() << "; before the solve (errors, problem built) "
                    << seconds_before_solve << " s; Ceres: in all "
                    << ceres_summary.total_time_in_seconds << " s, linear solver "
                    << ceres_summary.linear_solver_time_in_seconds << " s, Jacobians "
                    << ceres_summary.jacobian_evaluation_time_in_seconds << " s, residuals "
                    << ceres_summary.residual_evaluation_time_in_seconds << " s, preprocessing "
                    << ceres_summary.preprocessor_time_in_seconds << " s";
  return summary;
}

}  // namespace viosfm

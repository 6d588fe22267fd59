// Bundle adjustment of a Reconstruction with the paper's joint objective
// (section "Bundle Adjustment with Relative Pose Constraints"):
//
//   sum_ij rho(|z_ij - pi(p_i, X_j, K)|^2) + sum_i w_i,i+1 E_r(p_i, p_i+1 | p_hat_i,i+1)
//
// rho is the Cauchy loss, E_r the relative-pose error of RelativePoseError
// (cost_functions.h) and w = alpha exp(-beta c). The cameras' poses
// (cam_from_world), the 3D points and optionally the intrinsics are refined
// in place; per-point reprojection errors are written to Point3D::error.
//
// Gauge: the caller holds poses constant (e.g. the first image's, from VIO)
// through `constant_poses`. With relative-pose priors the scale is that of
// the priors (metric for VIO); without priors and with only one pose held the
// scale is free (the solver keeps it near its starting value).
#pragma once

#include <Eigen/Core>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "viosfm/geometry/rigid3.h"
#include "viosfm/scene/reconstruction.h"
#include "viosfm/scene/reprojection.h"
#include "viosfm/util/option_fields.h"
#include "viosfm/util/types.h"

namespace ceres {
class LossFunction;
class Problem;
}  // namespace ceres

namespace viosfm {

// The linear solver of the Levenberg-Marquardt steps. kAuto in BundleAdjust:
// SPARSE_SCHUR up to max_images_for_sparse_schur images, ITERATIVE_SCHUR
// (with the SCHUR_JACOBI preconditioner) above; the batched mapper chooses
// from the problem's structure instead (sfm/linear_solver_chooser.h).
enum class BaLinearSolver { kAuto, kSparseSchur, kDenseSchur, kIterativeSchur };

// How a relative-pose prior is weighted.
//  kCovariance: by the square-root information of the VIO's relative pose
//    (RelativePosePrior::sqrt_information, from the VIO uncertainty model of
//    scene/vio_uncertainty.h: the longer, farther and more turning the way
//    between the two frames, the weaker), times sqrt(exp(-beta c)), the
//    paper's connectivity factor normalised to 1 at c = 0 (the VIO keeps
//    its full information where the images do not connect the frames and
//    yields to them where they do), under Tukey's biweight loss of scale
//    prior_loss_scale (in standard deviations), so that a VIO jump or reset
//    cannot drag the model: a prior that far off pulls with no force at all.
//  kPaper: the paper's w = alpha exp(-beta c) on residuals divided by fixed
//    sigmas (prior_rotation_sigma_rad, prior_translation_sigma_m), no loss.
// A prior without sqrt_information is weighted as kPaper either way.
enum class PriorWeighting { kCovariance, kPaper };
// "covariance", "paper"; ParsePriorWeighting throws InputError otherwise.
const char* PriorWeightingName(PriorWeighting weighting);
PriorWeighting ParsePriorWeighting(const std::string& name);
// The option texts (util/option_fields.h).
inline std::string OptionText(PriorWeighting value) {
  return PriorWeightingName(value);
}
inline void ParseOptionText(const std::string& text, PriorWeighting* value) {
  *value = ParsePriorWeighting(text);
}

struct BundleAdjustmentOptions {
  // Cauchy loss scale on the reprojection error, pixels (default 1.0): an
  // observation r px off costs s^2 log(1 + r^2 / s^2) / 2. 0 = plain squares.
  double loss_scale_px = 1.0;
  // Refine the focal length(s) and distortion parameters of the cameras
  // (default false); the principal point too if refine_principal_point
  // (default false; weakly observable, usually best kept).
  bool refine_intrinsics = false;
  bool refine_principal_point = false;

  // The paper's relative-pose constraints (default true); false is the
  // paper's "w/o RPC" ablation (plain bundle adjustment).
  bool use_relative_pose_priors = true;
  // w = alpha exp(-beta c), c = verified matches between the two frames
  // (the paper's alpha = 1e3 and beta = 0.003, dimensionless and per match).
  double prior_alpha = 1e3;
  double prior_beta = 0.003;
  // The units of E_r: its residual is [Log R_E / rotation_sigma; t_E /
  // translation_sigma], rotation (rad) and translation (m) weighed alike as
  // in the paper's ||Log(p_i,i+1 p_hat_i,i+1^-1)||^2. Defaults 0.1 rad and
  // 0.1 m: with w = alpha exp(-beta c) the effective per-frame sigmas are
  // sigma / sqrt(w), 3 mm / 3 mrad at c = 0 (a frame without matches
  // follows the VIO: nothing else acts on it) and 5 mm / 5 mrad at c = 300,
  // the size of a VIO's frame-to-frame noise, so that where matches are many
  // the images correct the VIO. Tighter sigmas keep the VIO's noise, looser
  // ones lose the priors where the images are weak (a textureless corridor).
  double prior_rotation_sigma_rad = 0.1;
  double prior_translation_sigma_m = 0.1;
  // See PriorWeighting. Default kCovariance.
  PriorWeighting prior_weighting = PriorWeighting::kCovariance;
  // Tukey biweight loss scale on the whitened prior residual (kCovariance),
  // in standard deviations; 0: plain squares. Default 10: a correct 6-D
  // prior (expected squared norm 6) keeps 88 % of its weight, one more than
  // 10 sigma off (a VIO jump, a reset, a drift far beyond the model) exerts
  // no force, as if it were absent: a corrupted prior moves the solution no
  // more than removing it would (sfm/frame_registration_test.cc).
  double prior_loss_scale = 10.0;
  // px, the standard deviation of a keypoint's position that the
  // reprojection errors (in pixels, unweighted) stand for when they are
  // combined with the covariance-weighted priors (kCovariance): each prior's
  // cost is multiplied by its square, so that a prior whitened by the VIO's
  // covariance and a reprojection error whitened by the image noise weigh
  // as their uncertainties say. Default 1.
  double image_noise_px = 1.0;

  // Solver.
  int max_num_iterations = 50;  // Levenberg-Marquardt iterations (default 50)
  int num_threads = 2;          // Jacobian evaluation and linear solver threads (default 2)
  // Up to this number of images in the problem SPARSE_SCHUR is used; above
  // it, see BaLinearSolver (default 100). Neither solver wins everywhere:
  // where the cameras see each other (a room) the reduced camera matrix is
  // nearly dense and its factorisation dominates SPARSE_SCHUR; along a weakly
  // textured corridor the conjugate gradients need many steps.
  // See docs/benchmarks.md, section "Bundle adjustment: choosing the linear solver".
  int max_images_for_sparse_schur = 100;
  BaLinearSolver linear_solver = BaLinearSolver::kAuto;  // (default kAuto)
  // Relative cost change to stop. Default 1e-5: a tighter tolerance costs
  // the final adjustment many more iterations for no better model.
  // See docs/history/benchmarks-2026.md, section "Real time: where a 100 s recording's time goes".
  double function_tolerance = 1e-5;
  // ITERATIVE_SCHUR: the conjugate gradients' steps per iteration at most.
  // Default 500 (Ceres'). With the IMU's factors (sfm/inertial_terms.h) the
  // reduced system holds a stiff frame-to-frame chain that the Schur-Jacobi
  // preconditioner does not see, so the steps run to the cap; the real-time
  // preset takes 100, most of the factors' gain for a third of their time.
  // See docs/benchmarks.md, section "Scaling: 300 to 2400 frames".
  int max_linear_solver_iterations = 500;
  double gradient_tolerance = 1e-10;  // (default 1e-10)
  double parameter_tolerance = 1e-8;  // relative step size to stop (default 1e-8)
  bool print_progress = false;        // Ceres' per-iteration lines to stdout (default false)

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }

  template <class Self, class Visitor>
  static void VisitFields(Self& self, Visitor&& visit) {
    visit({"loss_scale_px", "px, scale of the reprojection errors' robust loss", kRunOnly},
          self.loss_scale_px);
    visit({"refine_intrinsics", "refine the focal length and distortion", kRunOnly},
          self.refine_intrinsics);
    visit({"refine_principal_point", "refine the principal point as well", kRunOnly},
          self.refine_principal_point);
    visit({"use_relative_pose_priors", "the VIO's relative-pose priors", kRunOnly},
          self.use_relative_pose_priors);
    visit({"prior_alpha", "the paper's prior weight alpha", kRunOnly}, self.prior_alpha);
    visit({"prior_beta", "the paper's connectivity decay beta", kRunOnly}, self.prior_beta);
    visit({"prior_rotation_sigma_rad", "rad, fixed prior sigma (paper weighting)", kRunOnly},
          self.prior_rotation_sigma_rad);
    visit({"prior_translation_sigma_m", "m, fixed prior sigma (paper weighting)", kRunOnly},
          self.prior_translation_sigma_m);
    visit({"prior_weighting", "covariance or paper", kRunOnly}, self.prior_weighting);
    visit({"prior_loss_scale", "Tukey loss on the whitened priors, in standard deviations; 0: none",
           kRunOnly},
          self.prior_loss_scale);
    visit({"image_noise_px", "px, keypoint noise the priors are weighed against (covariance)",
           kRunOnly},
          self.image_noise_px);
    visit({"max_num_iterations", "Levenberg-Marquardt iterations", kRunOnly},
          self.max_num_iterations);
    visit({"num_threads", "Jacobian and linear solver threads", kRunOnly}, self.num_threads);
    visit({"max_images_for_sparse_schur", "images up to which auto uses SPARSE_SCHUR", kRunOnly},
          self.max_images_for_sparse_schur);
    visit({"linear_solver", "auto, SPARSE_SCHUR, DENSE_SCHUR or ITERATIVE_SCHUR", kRunOnly},
          self.linear_solver);
    visit({"function_tolerance", "relative cost change to stop", kRunOnly},
          self.function_tolerance);
    visit({"max_linear_solver_iterations",
           "ITERATIVE_SCHUR: conjugate-gradient steps per iteration at most", kRunOnly},
          self.max_linear_solver_iterations);
    visit({"gradient_tolerance", "gradient tolerance to stop", kRunOnly}, self.gradient_tolerance);
    visit({"parameter_tolerance", "relative step size to stop", kRunOnly},
          self.parameter_tolerance);
  }
};

// "SPARSE_SCHUR", "DENSE_SCHUR", "ITERATIVE_SCHUR" or "auto".
const char* BaLinearSolverName(BaLinearSolver solver);
// The inverse of BaLinearSolverName; InputError for another name.
BaLinearSolver ParseBaLinearSolver(const std::string& name);
// The option texts (util/option_fields.h).
inline std::string OptionText(BaLinearSolver value) {
  return BaLinearSolverName(value);
}
inline void ParseOptionText(const std::string& text, BaLinearSolver* value) {
  *value = ParseBaLinearSolver(text);
}

// The VIO's relative pose between two (normally consecutive) frames.
struct RelativePosePrior {
  image_t image_id1 = kInvalidImageId;
  image_t image_id2 = kInvalidImageId;
  Rigid3d cam2_from_cam1;
  int num_verified_matches = 0;  // c in w = alpha exp(-beta c)
  // Multiplies w (default 1).
  double weight_scale = 1.0;
  // Only the rotation residual counts (the translation rows get weight 0).
  bool rotation_only = false;
  // A relative rotation from the gyro (sfm/gyro_priors.h), not from the
  // VIO: whitened by its sqrt_information as given (rotation rows only),
  // whatever the weighting, without the connectivity factor.
  bool from_gyro = false;
  // The square-root information of the VIO's relative pose (S with S^T S =
  // covariance^-1 of the residual [Log R_E; t_E], scene/vio_uncertainty.h),
  // used with PriorWeighting::kCovariance; unset: weighted as kPaper.
  std::optional<Eigen::Matrix<double, 6, 6>> sqrt_information;
};

struct BundleAdjustmentSummary {
  // Ceres' cost (half the sum of squared, robustified residuals).
  double initial_cost = 0.0;
  double final_cost = 0.0;
  // Mean reprojection error over all observations in registered images, px.
  double mean_reprojection_error_before_px = 0.0;
  double mean_reprojection_error_after_px = 0.0;
  int num_iterations = 0;
  double time_s = 0.0;
  std::string termination;                               // Ceres' termination type and message
  BaLinearSolver linear_solver = BaLinearSolver::kAuto;  // the one used
  // Whether Ceres returned a usable solution (converged or hit the
  // iteration limit); the reconstruction is updated either way.
  bool usable = false;
  // Problem size.
  int num_images = 0;
  int num_points = 0;
  int num_observations = 0;
  int num_priors = 0;  // relative-pose terms added

  std::string ToString() const;  // one summary line
};

// Terms beyond the reprojection errors and the relative-pose priors that a
// caller adds to an adjustment (sfm/inertial_terms.h: the IMU's): residual
// blocks on the images' pose blocks and on parameter blocks of the caller's
// own, which are solved with the poses (not eliminated with the points).
//
// The caller's blocks live in `storage`, which BundleAdjust gives them in
// the array that holds the poses' blocks, after those: Ceres orders the
// blocks of a group of its linear_solver_ordering by address, so blocks of
// arrays of their own would be ordered by wherever the allocator put them,
// and the sums of the solve with them (one run's model unlike the next).
class BundleAdjustmentTerms {
 public:
  virtual ~BundleAdjustmentTerms() = default;
  // The number of doubles of the caller's own parameter blocks, at most.
  virtual size_t NumParameters() const = 0;
  // Adds the terms to `problem`, the caller's own parameter blocks laid out
  // in `storage` (NumParameters() doubles) and set to their current values.
  // The cost functions, losses and manifolds it adds are deleted with the
  // adjustment, as by a problem that owns them.
  // pose_block(image_id) is the pose block (geometry/pose_parameters.h) of
  // a registered image, nullptr for any other image. Returns the caller's
  // own parameter blocks.
  virtual std::vector<double*> AddTo(ceres::Problem* problem,
                                     const std::function<double*(image_t)>& pose_block,
                                     double* storage) = 0;
  // Takes the values of its parameters from `storage` (the one AddTo was
  // given), once the solve is done: they are the solution once BundleAdjust
  // returns.
  virtual void TakeSolution(const double* storage) = 0;
};

// The loss of a whitened term (a covariance-weighted prior, the gyro's, a
// caller's): Tukey's biweight of scale `prior_loss_scale` sigmas (none if 0),
// its cost multiplied by image_noise_px^2 so that it weighs against
// reprojection errors in units of image_noise_px (BundleAdjustmentOptions).
// Null when neither applies; the caller owns it (ceres::Problem does once
// it is given to a residual block).
ceres::LossFunction* CreateWhitenedLoss(double prior_loss_scale, double image_noise_px);

// Refines `reconstruction` in place (see the top of this file). Priors whose
// images are not both registered, or both constant, are skipped; every id in
// `constant_poses` must be a registered image (CHECK). Observations of
// unregistered images are ignored. `terms`, if given, adds its own.
BundleAdjustmentSummary BundleAdjust(Reconstruction* reconstruction,
                                     const std::vector<RelativePosePrior>& priors,
                                     const std::vector<image_t>& constant_poses,
                                     const BundleAdjustmentOptions& options,
                                     BundleAdjustmentTerms* terms = nullptr);

}  // namespace viosfm

#include "viosfm/sfm/vio_drift_terms.h"

#include <ceres/crs_matrix.h>
#include <ceres/manifold.h>
#include <ceres/problem.h>
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <memory>
#include <vector>

#include "viosfm/ba/cost_functions.h"

namespace viosfm {
namespace {

// A walk at 0.5 m/s along the world's x axis, 10 Hz, the camera turned
// against the world (so that camera and world axes differ).
struct Walk {
  std::vector<VioSample> frames;
};

Walk StraightWalk(int num_frames) {
  Walk walk;
  const Eigen::Quaterniond world_from_cam =
      Eigen::Quaterniond(Eigen::AngleAxisd(1.2, Eigen::Vector3d(0.3, -0.5, 0.8).normalized()));
  for (int k = 0; k < num_frames; ++k) {
    VioSample sample;
    sample.timestamp_ns = static_cast<timestamp_ns_t>(k) * 100'000'000;
    sample.world_from_cam = Rigid3d(world_from_cam, Eigen::Vector3d(0.05 * k, 0.0, 1.0));
    sample.odometer.distance_m = 0.05 * k;
    walk.frames.push_back(sample);
  }
  return walk;
}

// The covariance the terms imply for the residual of the VIO's relative pose
// between the first and the last frame (RelativePoseResidual), the first
// frame's pose held, the images absent: the inverse of the problem's
// Gauss-Newton information, carried through the residual's Jacobian.
// `add_terms` adds the VIO's terms on the poses' blocks.
template <class AddTerms>
Eigen::Matrix<double, 6, 6> ImpliedEndToEndCovariance(const Walk& walk, AddTerms&& add_terms) {
  const int n = static_cast<int>(walk.frames.size());
  std::vector<PoseParameters> poses;
  for (const VioSample& frame : walk.frames) {
    poses.push_back(ToPoseParameters(frame.world_from_cam.Inverse()));
  }
  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  for (PoseParameters& pose : poses) {
    problem.AddParameterBlock(pose.data(), 7, CreatePoseManifold());
  }
  std::vector<double*> extra = add_terms(&problem, poses);
  problem.SetParameterBlockConstant(poses[0].data());

  ceres::Problem::EvaluateOptions evaluate;
  for (int k = 1; k < n; ++k) evaluate.parameter_blocks.push_back(poses[k].data());
  evaluate.parameter_blocks.insert(evaluate.parameter_blocks.end(), extra.begin(), extra.end());
  ceres::CRSMatrix crs;
  problem.Evaluate(evaluate, nullptr, nullptr, nullptr, &crs);
  Eigen::MatrixXd jacobian = Eigen::MatrixXd::Zero(crs.num_rows, crs.num_cols);
  for (int row = 0; row < crs.num_rows; ++row) {
    for (int k = crs.rows[row]; k < crs.rows[row + 1]; ++k) {
      jacobian(row, crs.cols[k]) = crs.values[k];
    }
  }
  const Eigen::MatrixXd covariance =
      (jacobian.transpose() * jacobian)
          .ldlt()
          .solve(Eigen::MatrixXd::Identity(crs.num_cols, crs.num_cols));
  // The last pose's tangent block (poses 1..n-1, 6 each).
  const Eigen::Matrix<double, 6, 6> pose_covariance =
      covariance.block<6, 6>(6 * (n - 2), 6 * (n - 2));

  // d residual / d tangent of the last pose, by central differences.
  const Rigid3d cam1_from_world = FromPoseParameters(poses[0]);
  const Rigid3d vio_cam2_from_cam1 =
      walk.frames.back().world_from_cam.Inverse() * walk.frames.front().world_from_cam;
  std::unique_ptr<ceres::Manifold> manifold(CreatePoseManifold());
  Eigen::Matrix<double, 6, 6> residual_jacobian;
  const double h = 1e-6;
  for (int d = 0; d < 6; ++d) {
    Eigen::Matrix<double, 6, 1> delta = Eigen::Matrix<double, 6, 1>::Zero();
    PoseParameters plus, minus;
    delta[d] = h;
    manifold->Plus(poses[n - 1].data(), delta.data(), plus.data());
    delta[d] = -h;
    manifold->Plus(poses[n - 1].data(), delta.data(), minus.data());
    residual_jacobian.col(d) =
        (RelativePoseResidual(cam1_from_world, FromPoseParameters(plus), vio_cam2_from_cam1) -
         RelativePoseResidual(cam1_from_world, FromPoseParameters(minus), vio_cam2_from_cam1)) /
        (2 * h);
  }
  return residual_jacobian * pose_covariance * residual_jacobian.transpose();
}

VioUncertaintyModel TestModel() {
  VioUncertaintyModel model;
  // The within-segment scale variation is a per-pair error that no chain
  // composes; off here, so that the drift and the noise are compared alone.
  model.relative_scale_sigma = 1e-9;
  return model;
}

Eigen::Matrix<double, 6, 1> Sigmas(const Eigen::Matrix<double, 6, 6>& covariance) {
  return covariance.diagonal().cwiseSqrt();
}

// Over 10 s (100 frames at 10 Hz) the drift states trust the VIO's relative
// pose between the ends as the model's closed form says (the drift over the
// way plus the two frames' noise), where the chain of consecutive priors
// counts each frame's noise twice and trusts it far less.
TEST(VioDriftTerms, TheVioIsTrustedOverSecondsAsItsModelSays) {
  const Walk walk = StraightWalk(101);
  const VioUncertaintyModel model = TestModel();
  VioDriftTermsOptions options;
  options.vio_uncertainty = model;
  options.prior_loss_scale = 0.0;

  std::vector<VioDriftFrame> frames;
  std::vector<VioDriftLink> links;
  for (size_t k = 0; k < walk.frames.size(); ++k) {
    frames.push_back({static_cast<image_t>(k + 1), walk.frames[k]});
    if (k > 0) links.push_back({k - 1, k, 0});
  }
  VioDriftTerms terms(frames, links, options);
  std::vector<double> storage(terms.NumParameters());
  const Eigen::Matrix<double, 6, 6> drift_states = ImpliedEndToEndCovariance(
      walk, [&](ceres::Problem* problem, std::vector<PoseParameters>& poses) {
        return terms.AddTo(
            problem, [&](image_t image_id) { return poses[image_id - 1].data(); }, storage.data());
      });
  EXPECT_EQ(terms.num_frame_terms(), 101);
  EXPECT_EQ(terms.num_drift_terms(), 100);

  const Eigen::Matrix<double, 6, 6> chain = ImpliedEndToEndCovariance(
      walk, [&](ceres::Problem* problem, std::vector<PoseParameters>& poses) {
        for (size_t k = 1; k < walk.frames.size(); ++k) {
          const Rigid3d cam2_from_cam1 =
              walk.frames[k].world_from_cam.Inverse() * walk.frames[k - 1].world_from_cam;
          problem->AddResidualBlock(
              RelativePoseError::Create(
                  cam2_from_cam1, SqrtInformationFromCovariance(RelativePoseCovariance(
                                      model.WithinSegment(), walk.frames[k - 1], walk.frames[k]))),
              nullptr, poses[k - 1].data(), poses[k].data());
        }
        return std::vector<double*>{};
      });

  const Eigen::Matrix<double, 6, 6> truth =
      RelativePoseCovariance(model.WithinSegment(), walk.frames.front(), walk.frames.back());
  // In the world's axes (the covariances are in the last camera's).
  Eigen::Matrix<double, 6, 6> world_from_cam = Eigen::Matrix<double, 6, 6>::Zero();
  const Eigen::Matrix3d rotation = walk.frames.back().world_from_cam.rotation.toRotationMatrix();
  world_from_cam.topLeftCorner<3, 3>() = rotation;
  world_from_cam.bottomRightCorner<3, 3>() = rotation;
  const auto in_world = [&](const Eigen::Matrix<double, 6, 6>& covariance) {
    return Sigmas(world_from_cam * covariance * world_from_cam.transpose());
  };
  const Eigen::Matrix<double, 6, 1> truth_sigmas = in_world(truth);
  const Eigen::Matrix<double, 6, 1> drift_sigmas = in_world(drift_states);
  const Eigen::Matrix<double, 6, 1> chain_sigmas = in_world(chain);
  std::cout << "sigmas (roll, pitch, yaw rad; x, y, z m) over 10 s:\n  model   "
            << truth_sigmas.transpose() << "\n  states  " << drift_sigmas.transpose()
            << "\n  chain   " << chain_sigmas.transpose() << "\n";
  for (int d = 0; d < 6; ++d) {
    EXPECT_NEAR(drift_sigmas[d] / truth_sigmas[d], 1.0, 0.05) << "axis " << d;
  }
  // The chain: roll and pitch (which barely drift) trusted many times less,
  // and yaw and position less.
  EXPECT_GT(chain_sigmas[0] / truth_sigmas[0], 4.0);
  EXPECT_GT(chain_sigmas[1] / truth_sigmas[1], 4.0);
  EXPECT_GT(chain_sigmas[2] / truth_sigmas[2], 1.3);
  EXPECT_GT(chain_sigmas[3] / truth_sigmas[3], 1.2);
}

}  // namespace
}  // namespace viosfm

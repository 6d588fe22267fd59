#include "viosfm/sfm/vio_drift_terms.h"

#include <ceres/autodiff_cost_function.h>
#include <ceres/problem.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <utility>

#include "viosfm/ba/cost_functions.h"
#include "viosfm/geometry/lie.h"
#include "viosfm/util/errors.h"

namespace viosfm {
namespace {

template <typename T>
using QuaternionT = Eigen::Quaternion<T>;
template <typename T>
using Vector3T = Eigen::Matrix<T, 3, 1>;

// A rigid transform (rotation, translation) and its algebra on Jets.
template <typename T>
struct Pose {
  QuaternionT<T> q;
  Vector3T<T> t;
  Pose operator*(const Pose& other) const { return {q * other.q, q * other.t + t}; }
  Pose Inverse() const {
    const QuaternionT<T> q_inverse = q.conjugate();
    return {q_inverse, -(q_inverse * t)};
  }
};

template <typename T>
Pose<T> PoseOfBlock(const T* block) {
  return {Eigen::Map<const QuaternionT<T>>(block), Eigen::Map<const Vector3T<T>>(block + 4)};
}

template <typename T>
Pose<T> ConstantPose(const Rigid3d& pose) {
  return {pose.rotation.cast<T>(), pose.translation.cast<T>()};
}

template <typename T>
void WhitenedResidual(const Pose<T>& error, const Eigen::Matrix<double, 6, 6>& sqrt_information,
                      T* residuals) {
  Eigen::Matrix<T, 6, 1> r;
  r.template head<3>() = QuaternionLog(error.q);
  r.template tail<3>() = error.t;
  Eigen::Map<Eigen::Matrix<T, 6, 1>> weighted(residuals);
  weighted = sqrt_information.cast<T>() * r;
}

// The frame's VIO pose against the model's: E = P G V^-1 (see the header).
class FrameCost {
 public:
  FrameCost(const Rigid3d& vio_cam_from_vio_world, const Eigen::Matrix<double, 6, 6>& sqrt_info)
      : vio_world_from_cam_(vio_cam_from_vio_world.Inverse()), sqrt_information_(sqrt_info) {}
  template <typename T>
  bool operator()(const T* cam_from_world, const T* world_from_vio_world, T* residuals) const {
    const Pose<T> error = PoseOfBlock(cam_from_world) * PoseOfBlock(world_from_vio_world) *
                          ConstantPose<T>(vio_world_from_cam_);
    WhitenedResidual(error, sqrt_information_, residuals);
    return true;
  }

 private:
  Rigid3d vio_world_from_cam_;
  Eigen::Matrix<double, 6, 6> sqrt_information_;
};

// The drift between two frames' states, seen at the second frame: E = V
// G2^-1 G1 V^-1 (see the header).
class DriftCost {
 public:
  DriftCost(const Rigid3d& vio_cam_from_vio_world, const Eigen::Matrix<double, 6, 6>& sqrt_info)
      : vio_cam_from_vio_world_(vio_cam_from_vio_world), sqrt_information_(sqrt_info) {}
  template <typename T>
  bool operator()(const T* world_from_vio_world1, const T* world_from_vio_world2,
                  T* residuals) const {
    const Pose<T> v = ConstantPose<T>(vio_cam_from_vio_world_);
    const Pose<T> error = v * PoseOfBlock(world_from_vio_world2).Inverse() *
                          PoseOfBlock(world_from_vio_world1) * v.Inverse();
    WhitenedResidual(error, sqrt_information_, residuals);
    return true;
  }

 private:
  Rigid3d vio_cam_from_vio_world_;
  Eigen::Matrix<double, 6, 6> sqrt_information_;
};

}  // namespace

Eigen::Matrix<double, 6, 6> VioDriftTerms::FrameSqrtInformation(const VioUncertaintyModel& model) {
  const double rotation_sigma =
      std::hypot(model.rotation_noise_rad, model.correlated_rotation_noise_rad);
  const double position_sigma =
      std::hypot(model.position_noise_m, model.correlated_position_noise_m);
  Eigen::Matrix<double, 6, 1> diagonal;
  diagonal << Eigen::Vector3d::Constant(1.0 / rotation_sigma),
      Eigen::Vector3d::Constant(1.0 / position_sigma);
  return diagonal.asDiagonal();
}

Eigen::Matrix<double, 6, 6> VioDriftTerms::DriftSqrtInformation(const VioUncertaintyModel& model,
                                                                const VioSample& frame1,
                                                                const VioSample& frame2) {
  // A floor of 1 micro-radian and micrometre: two frames at one time and
  // place have no drift between them, and their states are then one.
  constexpr double kFloor = 1e-6;
  Eigen::Matrix<double, 6, 6> covariance = RelativePoseDriftCovariance(model, frame1, frame2);
  covariance.diagonal().array() += kFloor * kFloor;
  return SqrtInformationFromCovariance(covariance);
}

VioDriftTerms::VioDriftTerms(std::vector<VioDriftFrame> frames, std::vector<VioDriftLink> links,
                             const VioDriftTermsOptions& options)
    : frames_(std::move(frames)), links_(std::move(links)), options_(options) {
  VIOSFM_CHECK(options_.vio_uncertainty.Check()) << options_.vio_uncertainty.Validate();
  for (const VioDriftLink& link : links_) {
    VIOSFM_CHECK(link.first < frames_.size() && link.second < frames_.size() &&
                 link.first != link.second)
        << "link " << link.first << "-" << link.second << " of " << frames_.size() << " frames";
    VIOSFM_CHECK_EQ(frames_[link.first].vio.odometer.segment,
                    frames_[link.second].vio.odometer.segment)
        << "a drift link across VIO segments";
  }
}

size_t VioDriftTerms::NumParameters() const {
  return frames_.size() * std::tuple_size_v<PoseParameters>;
}

std::vector<double*> VioDriftTerms::AddTo(ceres::Problem* problem,
                                          const std::function<double*(image_t)>& pose_block,
                                          double* storage) {
  const VioUncertaintyModel model = options_.vio_uncertainty.WithinSegment();
  const Eigen::Matrix<double, 6, 6> frame_sqrt_information = FrameSqrtInformation(model);
  std::vector<bool> added(frames_.size(), false);
  std::vector<double*> blocks;
  num_frame_terms_ = 0;
  num_drift_terms_ = 0;
  const auto state = [&](size_t k) { return storage + k * std::tuple_size_v<PoseParameters>; };
  // A frame's state and its frame term, once; false if its image has no
  // pose block.
  const auto add_frame = [&](size_t k) {
    if (added[k]) return true;
    double* pose = pose_block(frames_[k].image_id);
    if (pose == nullptr) return false;
    PoseParameters pose_values;
    std::copy(pose, pose + pose_values.size(), pose_values.begin());
    const Rigid3d cam_from_world = FromPoseParameters(pose_values);
    const Rigid3d vio_cam_from_vio_world = frames_[k].vio.world_from_cam.Inverse();
    // G = P^-1 V: the frame term starts at zero.
    const PoseParameters start =
        ToPoseParameters(cam_from_world.Inverse() * vio_cam_from_vio_world);
    std::copy(start.begin(), start.end(), state(k));
    problem->AddResidualBlock(
        new ceres::AutoDiffCostFunction<FrameCost, 6, 7, 7>(
            new FrameCost(vio_cam_from_vio_world, frame_sqrt_information)),
        CreateWhitenedLoss(options_.prior_loss_scale, options_.image_noise_px), pose, state(k));
    problem->SetManifold(state(k), CreatePoseManifold());
    blocks.push_back(state(k));
    added[k] = true;
    ++num_frame_terms_;
    return true;
  };
  for (const VioDriftLink& link : links_) {
    if (!add_frame(link.first) || !add_frame(link.second)) continue;
    const VioSample& first = frames_[link.first].vio;
    const VioSample& second = frames_[link.second].vio;
    // The connectivity factor exp(-beta c) on the information.
    const double factor =
        std::sqrt(RelativePoseWeight(link.num_verified_matches, 1.0, options_.prior_beta));
    const Eigen::Matrix<double, 6, 6> sqrt_information =
        factor * DriftSqrtInformation(model, first, second);
    problem->AddResidualBlock(
        new ceres::AutoDiffCostFunction<DriftCost, 6, 7, 7>(
            new DriftCost(second.world_from_cam.Inverse(), sqrt_information)),
        CreateWhitenedLoss(options_.prior_loss_scale, options_.image_noise_px), state(link.first),
        state(link.second));
    ++num_drift_terms_;
  }
  return blocks;
}

// The states are the adjustment's own: nothing reads them after it.
void VioDriftTerms::TakeSolution(const double* /*storage*/) {}

}  // namespace viosfm

// The IMU in the final bundle adjustment: a preintegrated IMU factor
// (vio/imu_factor.h) between every two consecutive registered frames, with
// each frame's velocity, the biases of every second, one scale and the
// gravity's tilt as unknowns beside the poses and the points.
//
// The relative-pose priors carry the VIO's lengths only as far as its
// covariance allows, and where the images are strong the connectivity
// factor hands the shape to them; but images never see a length, so over a
// long walk the model's local scale drifts with the images' while the VIO's
// stays put. The accelerometer sees lengths everywhere:
// its factors keep every stretch of the model at one metric scale, and
// with the gyro's rotations in them they also hold what the gyro's priors
// held (sfm/gyro_priors.h), which they replace.
//
// Frames: the body (IMU) pose of frame i is world_from_cam_i * cam_from_body
// (SensorRig::body_from_cam), at the frame's stamp on the IMU's clock
// (SensorRig::CamToImuTime). The factor sees it as
//   world'_from_body_i = [R_tilt * R_i, s * R_tilt * p_i],
// with s the model's metric scale (the model keeps the VIO's scale, which the
// priors and the gauge fix; s is what the IMU says of it: metric lengths
// are s times the model's) and R_tilt = Exp([a, b, 0]) the small rotation
// that levels the model's world (its z axis is the VIO's estimate of the
// vertical; yaw is not observable). The velocities are metric, in the
// levelled world.
//
// Before the adjustment, the velocities, biases, scale and tilt are solved
// with the poses held (Initialise); where the model and the IMU disagree
// by more than the preintegration's covariance says (the median whitened
// residual over the chi-square median; a real rig's timing, rolling shutter
// and calibration), every factor's covariance is inflated by the ratio, as
// the gyro's priors do.
#pragma once

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "viosfm/ba/bundle_adjustment.h"
#include "viosfm/geometry/rigid3.h"
#include "viosfm/scene/reconstruction.h"
#include "viosfm/sensor/imu.h"
#include "viosfm/sensor/sensor_rig.h"
#include "viosfm/util/option_fields.h"
#include "viosfm/util/timestamp.h"
#include "viosfm/util/types.h"
#include "viosfm/vio/imu_preintegration.h"

namespace viosfm {

struct InertialTermOptions {
  // IMU factors in the final bundle adjustment, when the dataset has an IMU,
  // in place of the gyro's rotation priors and of the bridging priors
  // (without relative-pose priors, ba.use_relative_pose_priors = false,
  // neither). Default true: the factors lowered the error of every simulated
  // trust sequence and keep a long walk at one metric scale.
  // See docs/history/benchmarks-2026.md, section "The IMU in the final adjustment".
  bool enabled = true;
  // s: no factor between consecutive frames further apart. Default 10.
  double max_gap_s = 10.0;
  // s, one pair of biases (gyro, accelerometer) per window that holds a
  // frame, joined to the next one's by their random walk over the time
  // between them; 0: a pair per frame. A window holds the biases still
  // while they walk, and over a frame gap of seconds what it misses goes
  // into the velocities and the positions. Default 1: about as good as a
  // pair per frame, far better than 10 s windows, in the same time.
  // See docs/history/benchmarks-2026.md, section "The IMU's biases every second".
  double bias_window_s = 1.0;
  // The factors are not used (the gyro's priors are, which allow for a
  // floor of unmodelled rotation error) when the model's rotations disagree
  // with the gyro's by more than this many times the preintegration's
  // covariance (Initialise's sigma_factor): the rig's timing, rolling shutter
  // or calibration is then further from the IMU model than the factors can
  // take. Default 12: above what the simulated trust sequences show, where
  // the inflated factors still help, and below the real rolling-shutter
  // recording's, where they broke the metric scale; max_scale_change is the
  // check behind it. See docs/history/benchmarks-2026.md, section "Three seeds: the comparison is
  // not settled".
  double max_sigma_factor = 12.0;
  // After the final adjustment, the factors' metric scale of the model
  // (scale()) further from 1 than this (relative; the model has the VIO's
  // scale, a few per cent off) means the rig is further from the IMU model
  // than their start showed: the adjustment is done again from where it
  // started, with the gyro's priors. Default 0.1.
  double max_scale_change = 0.1;

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }

  template <class Self, class Visitor>
  static void VisitFields(Self& self, Visitor&& visit) {
    visit({"enabled", "IMU factors in the final bundle adjustment (replace the gyro's priors)",
           kRunOnly},
          self.enabled);
    visit({"max_gap_s", "s, no IMU factor between frames further apart", kRunOnly}, self.max_gap_s);
    visit({"bias_window_s", "s, one pair of IMU biases per window (0: per frame)", kRunOnly},
          self.bias_window_s);
    visit({"max_sigma_factor",
           "not used (the gyro's priors are) where the rotations disagree with the gyro by more "
           "than this times the covariance",
           kRunOnly},
          self.max_sigma_factor);
    visit({"max_scale_change",
           "relative; the factors' adjustment is undone where it puts the model's metric scale "
           "further from 1",
           kRunOnly},
          self.max_scale_change);
  }
};

// A registered frame: its image, time on the camera's clock and pose.
struct InertialFrame {
  image_t image_id = kInvalidImageId;
  timestamp_ns_t timestamp_ns = 0;
  Rigid3d cam_from_world;
};

class InertialTerms : public BundleAdjustmentTerms {
 public:
  // `frames` in strictly increasing time, `imu` in increasing time;
  // `initial_gyro_bias` the gyro bias the factors start from (rad/s, e.g.
  // the gyro priors' fit).
  InertialTerms(const std::vector<InertialFrame>& frames, const std::vector<ImuSample>& imu,
                const SensorRig& rig, const Eigen::Vector3d& initial_gyro_bias,
                const InertialTermOptions& options);
  ~InertialTerms() override;

  // Solves the velocities, biases, scale and tilt with the frames' poses
  // held, then inflates the factors' covariance where the poses and the
  // IMU disagree (see the top). Returns false (and the terms add nothing)
  // with fewer than two factors or an inflation beyond
  // InertialTermOptions::max_sigma_factor (Message() says which).
  // `num_threads`: Ceres' threads for that solve. The inflation is at least
  // `min_sigma_factor` (>= 1; see MakeGyroPriors: a later adjustment keeps
  // the first one's).
  bool Initialise(int num_threads = 2, double min_sigma_factor = 1.0);

  size_t NumParameters() const override;
  std::vector<double*> AddTo(ceres::Problem* problem,
                             const std::function<double*(image_t)>& pose_block,
                             double* storage) override;
  void TakeSolution(const double* storage) override;

  int num_factors() const { return static_cast<int>(factors_.size()); }
  // Metric lengths are scale() times the model's.
  double scale() const { return scale_[0]; }
  // rad, the levelling rotation's angle.
  double tilt_rad() const;
  // Frame k's velocity (m/s, metric, in the levelled world) and biases
  // (gyro rad/s, accelerometer m/s^2): those its window's factors integrate
  // with, or for a frame whose window starts no factor (the last frame, one
  // before a gap beyond max_gap_s) the previous such window's.
  Eigen::Vector3d velocity(size_t k) const;
  Eigen::Vector3d gyro_bias(size_t k) const;
  Eigen::Vector3d accel_bias(size_t k) const;
  // The factors' covariance inflation (>= 1) and the median whitened
  // residual (9-D: rotation, velocity, position) at Initialise.
  double sigma_factor() const { return sigma_factor_; }
  double median_whitened_residual() const { return median_whitened_residual_; }
  // The median whitened residual at the current values (after the
  // adjustment: at its solution), the frames' poses from `reconstruction`.
  double MedianWhitenedResidual(const Reconstruction& reconstruction) const;
  std::string Message() const;  // one line for the log

 private:
  double MedianWhitenedResidual(const std::vector<Rigid3d>& cam_from_world) const;
  // The same for the rotation residual alone (3-D, its own covariance).
  double MedianWhitenedRotationResidual(const std::vector<Rigid3d>& cam_from_world) const;

  struct Factor;
  std::vector<InertialFrame> frames_;
  SensorRig rig_;
  InertialTermOptions options_;
  // The bias walks between consecutive windows in `problem`, the biases
  // of window w at biases(w).
  void AddBiasWalks(ceres::Problem* problem, const std::function<double*(int)>& biases) const;
  // Where AddTo lays out the parameters in its storage: every frame's
  // velocity, every window's biases, the scale, the tilt.
  size_t VelocityOffset(size_t k) const { return 3 * k; }
  size_t BiasesOffset(int w) const { return 3 * velocity_.size() + 6 * static_cast<size_t>(w); }
  size_t ScaleOffset() const { return 3 * velocity_.size() + 6 * biases_.size(); }
  size_t TiltOffset() const { return ScaleOffset() + 1; }
  // Calls visit(own values, size, offset in that storage) for every array.
  template <typename Visit>
  void ForEachParameterArray(Visit&& visit);
  // The window whose biases stand for frame k (see gyro_bias).
  int BiasWindowOfFrame(size_t k) const;

  std::vector<std::array<double, 3>> velocity_;  // per frame
  std::vector<int> window_;                      // per frame, its biases' window
  std::vector<std::array<double, 6>> biases_;    // per window: bg, ba
  std::vector<double> window_start_s_;           // per window, s after the first frame
  std::vector<bool> used_;                       // frame has a factor
  std::vector<std::unique_ptr<Factor>> factors_;
  std::array<double, 1> scale_{1.0};
  std::array<double, 2> tilt_{0.0, 0.0};
  double sigma_factor_ = 1.0;
  double median_whitened_residual_ = 0.0;
  double median_whitened_rotation_residual_ = 0.0;
  bool initialised_ = false;
  std::string refusal_;  // why Initialise returned false
};

}  // namespace viosfm

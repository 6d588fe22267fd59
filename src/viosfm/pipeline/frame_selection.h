// Frame selection before matching, as the paper prepares its sequences: the
// static frames at the beginning and the end are removed and the rest is
// downsampled to 10 Hz.
//
// Static detection, on sliding windows of static_window_s:
//  - IMU: the IMU is low-passed (centred moving average over imu_lowpass_s,
//    which removes rotor vibration: a MAV on the ground with spinning rotors
//    shows ~1 m/s^2 of raw accelerometer spread but ~0.1 m/s^2 after it);
//    a window is static if the spread (RMS deviation from the window mean)
//    of the low-passed gyro and accelerometer and the norm of the mean
//    angular rate are all below their thresholds;
//  - trajectory (VIO or ground truth): a window is static if no pose in it
//    is farther than max_static_translation_m / max_static_rotation_rad
//    from the window's first pose.
// The window of an image ends at the image (for the start; for the end it
// begins at the image) and is shifted to lie inside the data near the data's
// ends; a window without enough data is "unknown" and counts as moving, so
// missing data never trims frames. Only the two ends are trimmed: a pause
// in the middle is kept.
//
// With the IMU, the start of motion is then refined within the first moving
// window: it is where the low-passed signal last left the static reference
// (the mean of the previous, static, window) by more than a threshold, not
// the end of the window that first noticed it. The same happens, mirrored,
// at the end.
//
// Downsampling keeps, for each point of a regular grid at target_rate_hz
// starting at the first kept frame, the frame nearest to it.
#pragma once

#include <string>
#include <vector>

#include "viosfm/scene/sequence.h"
#include "viosfm/scene/trajectory.h"
#include "viosfm/util/option_fields.h"

namespace viosfm {

enum class StaticSource {
  kAuto,              // the IMU if the sequence has one, else the trajectory
  kImu,               // the IMU only
  kTrajectory,        // the trajectory only (given, else the sequence's ground truth)
  kImuAndTrajectory,  // static only where both agree
};
// "auto", "imu", "trajectory", "imu_and_trajectory"; InputError otherwise.
StaticSource ParseStaticSource(const std::string& name);
std::string StaticSourceName(StaticSource source);
// The option texts (util/option_fields.h).
inline std::string OptionText(StaticSource value) {
  return StaticSourceName(value);
}
inline void ParseOptionText(const std::string& text, StaticSource* value) {
  *value = ParseStaticSource(text);
}

struct FrameSelectionOptions {
  // Remove the static frames at the beginning and the end. Default true (the paper).
  bool trim_static = true;
  StaticSource static_source = StaticSource::kAuto;  // default: auto
  double static_window_s = 1.0;                      // s, length of the sliding window. Default 1.0
  double imu_lowpass_s = 0.1;  // s, moving-average length applied to the IMU first. Default 0.1
  // Static if the low-passed gyro's spread is below this (rad/s). Default 0.02.
  double max_static_gyro_stddev_rad_s = 0.02;
  // Static if the norm of the mean angular rate (gyro bias included) is
  // below this (rad/s). Default 0.25.
  double max_static_gyro_mean_rad_s = 0.25;
  // Static if the low-passed accelerometer's spread is below this (m/s^2). Default 0.2.
  double max_static_accel_stddev_m_s2 = 0.2;
  // Trajectory: static if every position in the window is within this of
  // the window's first one (m). Default 0.02.
  double max_static_translation_m = 0.02;
  // Trajectory: static if every orientation in the window is within this of
  // the window's first one (rad). Default 0.05.
  double max_static_rotation_rad = 0.05;
  // Downsample to this rate (Hz); 0 keeps every frame. Sequences at or
  // below the rate are kept whole. Default 10 (the paper).
  double target_rate_hz = 10.0;

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }

  template <class Self, class Visitor>
  static void VisitFields(Self& self, Visitor&& visit) {
    visit(
        {"trim_static", "remove the static frames at the beginning and the end", kShapesStoredData},
        self.trim_static);
    visit({"static_source",
           "what detects the static frames: auto, imu, trajectory, imu_and_trajectory",
           kShapesStoredData},
          self.static_source);
    visit({"static_window_s", "s, length of the sliding window", kShapesStoredData},
          self.static_window_s);
    visit({"imu_lowpass_s", "s, moving-average length applied to the IMU", kShapesStoredData},
          self.imu_lowpass_s);
    visit(
        {"max_static_gyro_stddev_rad_s", "rad/s, static below this gyro spread", kShapesStoredData},
        self.max_static_gyro_stddev_rad_s);
    visit({"max_static_gyro_mean_rad_s", "rad/s, static below this mean angular rate",
           kShapesStoredData},
          self.max_static_gyro_mean_rad_s);
    visit({"max_static_accel_stddev_m_s2", "m/s^2, static below this accelerometer spread",
           kShapesStoredData},
          self.max_static_accel_stddev_m_s2);
    visit({"max_static_translation_m", "m, trajectory: static within this of the window's start",
           kShapesStoredData},
          self.max_static_translation_m);
    visit({"max_static_rotation_rad", "rad, trajectory: static within this of the window's start",
           kShapesStoredData},
          self.max_static_rotation_rad);
    visit({"target_rate_hz", "Hz, downsample to this rate; 0 keeps every frame", kShapesStoredData},
          self.target_rate_hz);
  }
};

enum class FrameDecision {
  kKept,
  kStaticStart,  // before the motion starts
  kStaticEnd,    // after the motion ends
  kStatic,       // the whole sequence is static
  kDownsampled,  // between the kept frames of the target rate
};
std::string FrameDecisionName(FrameDecision decision);

enum class FrameSelectionStatus {
  kOk,
  kNoImages,        // the sequence has no images
  kNoMovingFrames,  // static from start to end: nothing to reconstruct
};

struct FrameSelection {
  FrameSelectionStatus status = FrameSelectionStatus::kOk;
  // A line for the user: "static: no moving frames", "kept 300 of 1200 ...".
  std::string message;
  // Indices into sequence.images, increasing.
  std::vector<size_t> kept;
  // One per image of the sequence.
  std::vector<FrameDecision> decisions;
  // Estimated start and end of the motion (ns); the first and last image
  // stamps when nothing is trimmed; 0 unless status is kOk.
  timestamp_ns_t motion_start_ns = 0;
  timestamp_ns_t motion_end_ns = 0;

  bool ok() const { return status == FrameSelectionStatus::kOk; }
  size_t Count(FrameDecision decision) const;
};

// Whether SelectFrames on `sequence` with `options` reads the trajectory
// (static trimming from it); if not, the selection is known before any VIO
// runs.
bool FrameSelectionUsesTrajectory(const Sequence& sequence, const FrameSelectionOptions& options);

// `trajectory` (any world_from_body or world_from_cam trajectory, e.g. VIO)
// is used by the trajectory source; null: the sequence's ground truth. A
// source that is asked for but absent (kImu without IMU, kTrajectory without
// trajectory or ground truth) and invalid options throw InputError.
FrameSelection SelectFrames(const Sequence& sequence, const FrameSelectionOptions& options,
                            const Trajectory* trajectory = nullptr);

// The frames of a recording that grows (`viosfm run --follow`), selected as
// SelectFrames selects them from the whole recording: a frame is decided
// once the images and the IMU go on `Lag()` beyond it (two static windows,
// the IMU's low-pass and two frame periods of the target rate: what its
// static-start, static-end and downsampling decisions look at), SelectFrames
// then running on the recording so far. A pause that may yet be the
// recording's static end is held until the motion goes on or the
// recording ends.
class GrowingFrameSelection {
 public:
  // InputError for invalid options.
  explicit GrowingFrameSelection(const FrameSelectionOptions& options);

  // The recording so far (every image and IMU sample up to now). Returns
  // the frames selected since the last call (indices into its images, in
  // order), and in `decided_until` how many of its first images are
  // decided (selected or not).
  std::vector<size_t> Update(const Sequence& so_far, size_t* decided_until);
  // The whole recording: the frames selected since the last call, and in
  // `selection` SelectFrames' selection of it, its `kept` those taken as it
  // grew and these (SelectFrames of the whole recording takes the same; a
  // frame taken as it grew that the whole would not keep stays, with a
  // warning naming how many).
  std::vector<size_t> Finish(const Sequence& whole, FrameSelection* selection);

  timestamp_ns_t Lag() const { return lag_ns_; }

 private:
  FrameSelectionOptions options_;
  timestamp_ns_t lag_ns_ = 0;
  size_t decided_ = 0;         // images [0, decided_) decided
  std::vector<size_t> taken_;  // the frames selected so far
};

}  // namespace viosfm

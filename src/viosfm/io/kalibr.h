// Kalibr calibration files, the form in which camera-IMU users have their
// calibration (https://github.com/ethz-asl/kalibr/wiki/yaml-formats):
//
// camchain.yaml (or Kalibr's camchain-imucam.yaml), one map per camera; the
// first camera, cam0, is read:
//   cam0:
//     camera_model: pinhole              (the only supported projection; optional)
//     intrinsics: [fu, fv, pu, pv]
//     distortion_model: radtan | equidistant | none
//     distortion_coeffs: [4 numbers]     (radtan: k1 k2 p1 p2; equidistant: k1 k2 k3 k4)
//     resolution: [width, height]
//     T_cam_imu: 4x4 (rows of 4)         cam_from_imu: maps a point in the IMU frame
//                                        into the camera frame
//     timeshift_cam_imu: 0.0021          seconds; t_imu = t_cam + timeshift (optional, 0)
//     cam_overlaps, rostopic, ...        ignored
// T_cam_imu is required. The intrinsics (intrinsics, resolution and the
// distortion keys) are optional as a group: a camchain with extrinsics only
// (as the DM-VIO recordings ship theirs) leaves the dataset's camera as it is.
// cam0 may also hold the IMU noise keys below (the DM-VIO camchain does).
//
// imu.yaml: the four noise figures of Kalibr's IMU model, at the top level or
// in an "imu0:" map (Kalibr's imu-output form):
//   accelerometer_noise_density: 1.86e-03   m / s^2 / sqrt(Hz)
//   accelerometer_random_walk:   4.33e-04   m / s^3 / sqrt(Hz)
//   gyroscope_noise_density:     1.87e-04   rad / s / sqrt(Hz)
//   gyroscope_random_walk:       2.66e-05   rad / s^2 / sqrt(Hz)
//   update_rate:                 200.0      Hz (optional)
// Other keys (rostopic, integration_sigma, T_i_b, ...) are ignored.
//
// Frames: viosfm's body frame is the IMU frame, so body_from_cam is the
// inverse of T_cam_imu. Time: Kalibr's timeshift_cam_imu is the camera-IMU
// clock offset t_imu = t_cam + shift, which is SensorRig::cam_time_offset_ns
// (rounded to 1 ns; at most kMaxKalibrTimeshiftS in magnitude).
//
// Errors throw InputError naming the file, the line of the offending key and
// what was expected.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "viosfm/geometry/rigid3.h"
#include "viosfm/scene/sequence.h"
#include "viosfm/sensor/camera.h"
#include "viosfm/sensor/imu.h"
#include "viosfm/util/timestamp.h"

namespace viosfm {

// The largest |timeshift_cam_imu| accepted, seconds: Kalibr estimates
// offsets of milliseconds; a shift of seconds is a different clock, not a
// calibration.
inline constexpr double kMaxKalibrTimeshiftS = 1.0;

// The four noise figures and the optional rate of a Kalibr IMU description.
struct KalibrImuNoise {
  double gyro_noise_density = 0.0;   // rad / s / sqrt(Hz)
  double gyro_random_walk = 0.0;     // rad / s^2 / sqrt(Hz)
  double accel_noise_density = 0.0;  // m / s^2 / sqrt(Hz)
  double accel_random_walk = 0.0;    // m / s^3 / sqrt(Hz)
  std::optional<double> update_rate_hz;
};

struct KalibrCalibration {
  // cam0's intrinsics (camera_id 1), if the camchain gives them.
  std::optional<Camera> camera;
  // The inverse of cam0's T_cam_imu.
  Rigid3d body_from_cam;
  // timeshift_cam_imu in ns: t_imu = t_cam + cam_time_offset_ns (0 if absent).
  timestamp_ns_t cam_time_offset_ns = 0;
  // From the IMU file if given, else from noise keys in cam0 (if any).
  std::optional<KalibrImuNoise> imu_noise;
  // Where each part came from (for log lines and errors).
  std::filesystem::path camchain_path;
  std::filesystem::path imu_noise_path;
};

// Reads cam0 of `camchain` and, if `imu_yaml` is not empty, the IMU noise of
// `imu_yaml` (which then takes precedence over noise keys in cam0; a
// difference is logged as a warning).
KalibrCalibration ReadKalibrCalibration(const std::filesystem::path& camchain,
                                        const std::filesystem::path& imu_yaml = {});

// Reads a Kalibr IMU noise file (format above).
KalibrImuNoise ReadKalibrImuYaml(const std::filesystem::path& imu_yaml);

// The calibration files given on the command line (--calibration,
// --imu-calibration). Both empty: the dataset's own sensor.yaml holds.
struct CalibrationFiles {
  std::filesystem::path camchain;  // Kalibr camchain.yaml; default none
  std::filesystem::path imu;       // Kalibr imu.yaml; default none (needs camchain)

  bool empty() const { return camchain.empty() && imu.empty(); }
  // Empty if valid; otherwise names the bad field (an IMU file without a camchain).
  std::string Validate() const;
  bool Check() const { return Validate().empty(); }
};

// Replaces the sequence's calibration by `calibration` where it gives one:
// body_from_cam and the camera-IMU time offset always; the camera when the
// camchain has intrinsics (the camera keeps camera_id 1); the IMU noise
// densities and random walks when given (and the IMU rate when given).
// Logs what it replaced. Throws InputError naming the camchain if the
// resulting rig is invalid (SensorRig::Validate).
void ApplyCalibration(const KalibrCalibration& calibration, Sequence* sequence);

// ReadKalibrCalibration + ApplyCalibration; does nothing if `files` is empty.
void ApplyCalibrationFiles(const CalibrationFiles& files, Sequence* sequence);

}  // namespace viosfm

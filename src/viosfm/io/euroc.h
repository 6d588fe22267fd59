// The EuRoC MAV / ASL dataset layout (Burri et al., IJRR 2016), also used by
// TUM-VI, UZH-FPV and Kalibr:
//
//   <root>/mav0/cam0/data.csv       "#timestamp [ns],filename"
//   <root>/mav0/cam0/data/<filename>
//   <root>/mav0/cam0/sensor.yaml    Kalibr camera calibration (see below)
//   <root>/mav0/imu0/data.csv       "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y,w_RS_S_z,
//                                    a_RS_S_x [m s^-2],a_RS_S_y,a_RS_S_z"
//   <root>/mav0/imu0/sensor.yaml    gyroscope_noise_density, gyroscope_random_walk,
//                                    accelerometer_noise_density, accelerometer_random_walk,
//                                    rate_hz, T_BS
//   <root>/mav0/state_groundtruth_estimate0/data.csv   (optional, see ReadEurocGroundTruth)
//
// CSV files: one record a line, comma-separated, fields trimmed; lines that
// are blank or start with '#' are skipped; timestamps are integer ns and must
// strictly increase.
//
// Camera sensor.yaml (OpenCV-style "%YAML:1.0" first line accepted):
//   T_BS: {cols: 4, rows: 4, data: [16 numbers, row-major]}   body_from_cam
//   rate_hz: 20
//   resolution: [width, height]
//   camera_model: pinhole                     (the only supported projection)
//   intrinsics: [fu, fv, cu, cv]
//   distortion_model: radial-tangential       -> OPENCV        fx fy cx cy k1 k2 p1 p2
//                     equidistant             -> OPENCV_FISHEYE fx fy cx cy k1 k2 k3 k4
//                     none (or key absent)    -> PINHOLE        fx fy cx cy
//   distortion_coefficients: [4 numbers]      ([] or absent for none)
//
// Frames: viosfm's body frame is the IMU frame. EuRoC's imu0 T_BS is the
// identity; if a dataset's is not, body_from_cam is re-expressed as
// imu_from_cam and ground-truth poses as world_from_imu (velocities are left
// as the file states them, for the EuRoC body origin).
//
// IMU coverage: an IMU stream that does not overlap the image time span at all
// is an InputError; one that starts after the first image or ends before the
// last is logged as a warning by default (the frames outside cannot be
// IMU-constrained) and is an InputError with options.require_imu_coverage.
//
// All reading errors throw InputError naming the file, the line (where there
// is one) and what was expected.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "viosfm/io/dataset_checks.h"
#include "viosfm/scene/sequence.h"

namespace viosfm {

// GroundTruthState is defined in sequence.h (a Sequence holds them).

// Reads a EuRoC ground-truth state file (state_groundtruth_estimate0/data.csv):
//   "#timestamp [ns], p_RS_R_x [m], p_RS_R_y, p_RS_R_z, q_RS_w [], q_RS_x, q_RS_y, q_RS_z,
//    v_RS_R_x [m s^-1], v_RS_R_y, v_RS_R_z, b_w_RS_S_x [rad s^-1], .._y, .._z,
//    b_a_RS_S_x [m s^-2], .._y, .._z"
// The quaternion is w first and is world_from_body (R = world, S = body).
// Each row has either the first 8 columns or all 17. A quaternion whose norm
// is off 1 by more than kFileRotationTolerance (1e-3, io/rotation_checks.h)
// is an error; others are normalised. Throws
// InputError (file and line) on a wrong column count, a non-numeric field, a
// non-increasing timestamp, a non-unit quaternion or a file without rows.
std::vector<GroundTruthState> ReadEurocGroundTruth(const std::filesystem::path& csv);

// For ground truth that is optional (a dataset's, used only to evaluate):
// the states, or the InputError's message ("path:line: what") in `error`
// with no states. Never throws InputError.
struct GroundTruthReadResult {
  std::vector<GroundTruthState> states;
  std::string error;  // empty if the file was read
  bool ok() const { return error.empty(); }
};
GroundTruthReadResult TryReadEurocGroundTruth(const std::filesystem::path& csv);

// Camera calibration from a Kalibr/EuRoC camera sensor.yaml (format above).
struct EurocCameraCalibration {
  Camera camera;  // camera_id 1
  Rigid3d body_from_cam;
  double rate_hz = 0.0;  // 0 if the key is absent
};
EurocCameraCalibration ReadEurocCameraYaml(const std::filesystem::path& yaml);

// The T_BS entry (body_from_sensor) of any Kalibr/EuRoC sensor.yaml. Throws
// InputError naming the file and line if it is absent or not a rigid transform.
Rigid3d ReadEurocSensorTransform(const std::filesystem::path& yaml);

// IMU calibration from a Kalibr/EuRoC imu sensor.yaml. The four noise keys
// are required; rate_hz keeps ImuNoise's default and T_BS the identity when
// absent.
struct EurocImuCalibration {
  ImuNoise noise;
  Rigid3d body_from_imu;
};
EurocImuCalibration ReadEurocImuYaml(const std::filesystem::path& yaml);

// Reads "#timestamp [ns],filename" rows; paths are image_folder/filename.
// A filename must stay inside image_folder: an absolute path or one with a
// '..' component is an error (a dataset cannot make viosfm open files
// elsewhere), and so is a filename listed twice (one image under two
// stamps). With check_images_exist, a listed file that does not exist is an
// error.
std::vector<SequenceImage> ReadEurocImageList(const std::filesystem::path& csv,
                                              const std::filesystem::path& image_folder,
                                              bool check_images_exist);
// Reads imu0/data.csv rows (7 columns, see above), each checked against
// `checks`' bounds (dataset_checks.h): a value beyond them is an InputError
// naming the file and line. Gaps are left as they are (FindImuGaps).
std::vector<ImuSample> ReadEurocImu(const std::filesystem::path& csv,
                                    const DatasetChecks& checks = {});

// One data row of each list, as the readers above parse it (`fields`: the
// line split at commas, trimmed; InputError naming csv and line). The
// order of the stamps is the caller's to check (CheckEurocStampIncreasing).
SequenceImage ParseEurocImageRow(const std::filesystem::path& csv, int64_t line,
                                 const std::vector<std::string_view>& fields,
                                 const std::filesystem::path& image_folder);
ImuSample ParseEurocImuRow(const std::filesystem::path& csv, int64_t line,
                           const std::vector<std::string_view>& fields,
                           const DatasetChecks& checks = {});
// InputError naming csv and line unless `stamp` follows `previous` (of
// previous_line), as the readers above require.
void CheckEurocStampIncreasing(const std::filesystem::path& csv, int64_t line, timestamp_ns_t stamp,
                               const std::optional<timestamp_ns_t>& previous,
                               int64_t previous_line);

struct EurocReadOptions {
  // The camera sub-folder of mav0/. Default "cam0".
  std::string cam_name = "cam0";
  // The IMU sub-folder of mav0/. Default "imu0".
  std::string imu_name = "imu0";
  // Check that every image listed in data.csv exists (no decoding). Default true.
  bool check_images_exist = true;
  // Without an IMU folder: error (true) or a sequence without IMU (false). Default true.
  bool require_imu = true;
  // Partial IMU coverage of the image time span is an error (true) or a
  // warning (false). Default false.
  bool require_imu_coverage = false;
  // Read state_groundtruth_estimate0/data.csv when present. Default true.
  bool read_ground_truth = true;
  // A malformed ground-truth file is an InputError (true), or (false) a
  // warning naming its file and line, and the sequence has no ground truth:
  // it only serves evaluation, so a run goes on without it. Default false.
  bool strict_ground_truth = false;
  // The IMU's bounds and whether links may leave the dataset's folder
  // (dataset_checks.h): ReadEurocDataset checks every IMU sample, every
  // image (inside the folder, once, its header's size) and reports IMU gaps.
  DatasetChecks checks;

  // Empty if valid; otherwise names the bad field.
  std::string Validate() const;
  bool Check() const { return Validate().empty(); }
};

// The mav0 folder of `root` (root/mav0, or root itself when it is mav0 and
// holds options.cam_name): InputError naming root otherwise.
std::filesystem::path EurocMav0Folder(const std::filesystem::path& root,
                                      const EurocReadOptions& options);
// The camera and IMU calibration of a EuRoC folder as ReadEurocDataset
// reads them (the camera's sensor.yaml, the IMU's when its folder exists
// or options.require_imu; the body frame is the IMU's): a rig whose
// camera_rate_hz is the yaml's rate_hz or 0. `body_from_imu`: the IMU's
// T_BS (identity without IMU).
SensorRig ReadEurocRig(const std::filesystem::path& mav0, const EurocReadOptions& options,
                       Rigid3d* body_from_imu);

// The ground truth of a EuRoC folder as ReadEurocDataset reads it (none
// without the file or with read_ground_truth false; a file that cannot be
// read is an InputError with strict_ground_truth, else a warning and none),
// re-expressed for the IMU's T_BS `body_from_imu`.
std::vector<GroundTruthState> ReadEurocGroundTruthOf(const std::filesystem::path& mav0,
                                                     const EurocReadOptions& options,
                                                     const Rigid3d& body_from_imu);

// `root` is the folder that contains mav0/, or the mav0 folder itself.
Sequence ReadEurocDataset(const std::filesystem::path& root, const EurocReadOptions& options = {});

// The files besides the images that ReadEurocDataset(root, options) reads,
// those present, in a fixed order: <cam>/sensor.yaml, <cam>/data.csv,
// <imu>/sensor.yaml, <imu>/data.csv, state_groundtruth_estimate0/data.csv
// (with read_ground_truth), each relative to `root` (e.g.
// "mav0/imu0/data.csv"). Empty if `root` is not a EuRoC folder.
std::vector<std::filesystem::path> EurocDatasetFiles(const std::filesystem::path& root,
                                                     const EurocReadOptions& options = {});

}  // namespace viosfm

#include "viosfm/io/euroc.h"

#include <Eigen/Geometry>
#include <cmath>
#include <fstream>
#include <functional>
#include <optional>
#include <sstream>
#include <string_view>
#include <unordered_map>

#include "viosfm/io/kalibr_yaml.h"
#include "viosfm/io/rotation_checks.h"
#include "viosfm/io/text_lines.h"
#include "viosfm/io/yaml_util.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/logging.h"
#include "viosfm/util/string_util.h"

namespace viosfm {
namespace fs = std::filesystem;

namespace {

// Calls `row(line_number, fields)` for each data line of a comma-separated
// file: blank lines and lines starting with '#' are skipped, fields trimmed.
void ForEachCsvRow(const fs::path& path, const std::string& what,
                   const std::function<void(int64_t, const std::vector<std::string_view>&)>& row) {
  ForEachDataLine(path, what,
                  [&](int64_t line, std::string_view text) { row(line, SplitFields(text, ",")); });
}

std::string Quoted(std::string_view text) {
  return "'" + std::string(text) + "'";
}

timestamp_ns_t ParseStampField(const fs::path& path, int64_t line, std::string_view field) {
  const std::optional<timestamp_ns_t> stamp = ParseNs(field);
  if (!stamp) {
    throw InputError(
        path.string(), line,
        "expected an integer timestamp in nanoseconds in the first column, got " + Quoted(field));
  }
  if (!IsTimestampInRange(*stamp)) {
    throw InputError(path.string(), line,
                     "timestamp " + Quoted(field) +
                         " is out of range: expected nanoseconds within +-2^62 (146 years) of "
                         "the epoch");
  }
  return *stamp;
}

double ParseNumberField(const fs::path& path, int64_t line, size_t column, std::string_view field) {
  const std::optional<double> value = ParseDouble(field);
  if (!value || !std::isfinite(*value)) {
    throw InputError(path.string(), line,
                     "expected a finite number in column " + std::to_string(column + 1) + ", got " +
                         Quoted(field));
  }
  return *value;
}

void CheckIncreasing(const fs::path& path, int64_t line, timestamp_ns_t stamp,
                     const std::optional<timestamp_ns_t>& previous, int64_t previous_line) {
  if (previous && stamp <= *previous) {
    throw InputError(path.string(), line,
                     "timestamps must strictly increase: " + std::to_string(stamp) +
                         " ns is not after " + std::to_string(*previous) + " ns (line " +
                         std::to_string(previous_line) + ")");
  }
}

bool IsIdentity(const Rigid3d& transform) {
  return transform.rotation.angularDistance(Eigen::Quaterniond::Identity()) < 1e-9 &&
         transform.translation.norm() < 1e-9;
}

// A relative path without '..' components (nor a NUL, which would end the
// name early): joined to a folder it stays inside that folder.
bool IsPathInsideFolder(std::string_view name) {
  if (name.find('\0') != std::string_view::npos) return false;
  const fs::path path{std::string(name)};
  if (path.has_root_path()) return false;
  for (const fs::path& part : path) {
    if (part == "..") return false;
  }
  return true;
}

}  // namespace

Rigid3d ReadEurocSensorTransform(const fs::path& yaml_path) {
  return ReadRigidTransform(YamlMap::Load(yaml_path), "T_BS");
}

std::vector<GroundTruthState> ReadEurocGroundTruth(const fs::path& csv) {
  std::vector<GroundTruthState> states;
  std::optional<timestamp_ns_t> previous;
  int64_t previous_line = 0;
  ForEachCsvRow(csv, "EuRoC ground-truth file", [&](int64_t line, const auto& fields) {
    if (fields.size() != 8 && fields.size() != 17) {
      throw InputError(csv.string(), line,
                       "expected 8 comma-separated fields (timestamp [ns], p_x, p_y, p_z, q_w, "
                       "q_x, q_y, q_z) or 17 (those, then v_xyz, gyro bias xyz, accel bias xyz), "
                       "got " +
                           std::to_string(fields.size()));
    }
    GroundTruthState state;
    state.timestamp_ns = ParseStampField(csv, line, fields[0]);
    CheckIncreasing(csv, line, state.timestamp_ns, previous, previous_line);
    double values[17];
    for (size_t i = 1; i < fields.size(); ++i)
      values[i] = ParseNumberField(csv, line, i, fields[i]);
    Eigen::Quaterniond rotation(values[4], values[5], values[6], values[7]);
    if (const std::string problem = CheckFileQuaternion(rotation); !problem.empty()) {
      throw InputError(
          csv.string(), line,
          "expected a unit quaternion (q_w, q_x, q_y, q_z in columns 5-8): " + problem);
    }
    // A quaternion already unit to rounding is kept bit for bit, so that
    // write -> read is lossless (as the TUM reader does).
    if (std::abs(rotation.squaredNorm() - 1.0) > 2e-15) rotation.normalize();
    state.world_from_body = Rigid3d(rotation, Eigen::Vector3d(values[1], values[2], values[3]));
    if (fields.size() == 17) {
      state.velocity_in_world = Eigen::Vector3d(values[8], values[9], values[10]);
      state.gyro_bias = Eigen::Vector3d(values[11], values[12], values[13]);
      state.accel_bias = Eigen::Vector3d(values[14], values[15], values[16]);
      state.has_velocity_and_biases = true;
    }
    states.push_back(state);
    previous = state.timestamp_ns;
    previous_line = line;
  });
  if (states.empty()) throw InputError(csv.string(), 0, "expected ground-truth rows, found none");
  return states;
}

GroundTruthReadResult TryReadEurocGroundTruth(const fs::path& csv) {
  GroundTruthReadResult result;
  try {
    result.states = ReadEurocGroundTruth(csv);
  } catch (const InputError& error) {
    result.error = error.what();
  }
  return result;
}

EurocCameraCalibration ReadEurocCameraYaml(const fs::path& yaml_path) {
  const YamlMap yaml = YamlMap::Load(yaml_path);
  EurocCameraCalibration calibration;
  calibration.camera = ReadKalibrCameraIntrinsics(yaml, "distortion_coefficients");
  calibration.camera.camera_id = 1;
  calibration.body_from_cam = ReadRigidTransform(yaml, "T_BS");
  if (yaml.Has("rate_hz")) {
    calibration.rate_hz = yaml.GetDouble("rate_hz");
    if (calibration.rate_hz <= 0.0) yaml.Fail("rate_hz", "expected a positive rate in Hz");
  }
  return calibration;
}

EurocImuCalibration ReadEurocImuYaml(const fs::path& yaml_path) {
  const YamlMap yaml = YamlMap::Load(yaml_path);
  EurocImuCalibration calibration;
  ImuNoise& noise = calibration.noise;
  const auto positive = [&](const std::string& key) {
    const double value = yaml.GetDouble(key);
    if (value <= 0.0) yaml.Fail(key, "expected a positive number");
    return value;
  };
  noise.gyro_noise_density = positive("gyroscope_noise_density");
  noise.gyro_random_walk = positive("gyroscope_random_walk");
  noise.accel_noise_density = positive("accelerometer_noise_density");
  noise.accel_random_walk = positive("accelerometer_random_walk");
  if (yaml.Has("rate_hz")) noise.rate_hz = positive("rate_hz");
  if (yaml.Has("T_BS")) calibration.body_from_imu = ReadRigidTransform(yaml, "T_BS");
  if (const std::string problem = noise.Validate(); !problem.empty()) {
    throw InputError(yaml_path.string(), 0, "invalid IMU noise model: " + problem);
  }
  return calibration;
}

SequenceImage ParseEurocImageRow(const fs::path& csv, int64_t line,
                                 const std::vector<std::string_view>& fields,
                                 const fs::path& image_folder) {
  if (fields.size() != 2) {
    throw InputError(csv.string(), line,
                     "expected 2 comma-separated fields (timestamp [ns], filename), got " +
                         std::to_string(fields.size()));
  }
  SequenceImage image;
  image.timestamp_ns = ParseStampField(csv, line, fields[0]);
  if (fields[1].empty()) throw InputError(csv.string(), line, "expected a filename in column 2");
  if (!IsPathInsideFolder(fields[1])) {
    throw InputError(csv.string(), line,
                     "image filename " + Quoted(fields[1]) +
                         " must be a relative path inside the image folder " +
                         image_folder.string() + " (not absolute, no '..')");
  }
  image.path = image_folder / std::string(fields[1]);
  return image;
}

ImuSample ParseEurocImuRow(const fs::path& csv, int64_t line,
                           const std::vector<std::string_view>& fields,
                           const DatasetChecks& checks) {
  if (fields.size() != 7) {
    throw InputError(csv.string(), line,
                     "expected 7 comma-separated fields (timestamp [ns], w_x, w_y, w_z [rad/s], "
                     "a_x, a_y, a_z [m/s^2]), got " +
                         std::to_string(fields.size()));
  }
  ImuSample sample;
  sample.timestamp_ns = ParseStampField(csv, line, fields[0]);
  for (int i = 0; i < 3; ++i) {
    sample.gyro[i] = ParseNumberField(csv, line, 1 + i, fields[1 + i]);
    sample.accel[i] = ParseNumberField(csv, line, 4 + i, fields[4 + i]);
  }
  CheckImuSample(sample, checks, csv, line);
  return sample;
}

void CheckEurocStampIncreasing(const fs::path& csv, int64_t line, timestamp_ns_t stamp,
                               const std::optional<timestamp_ns_t>& previous,
                               int64_t previous_line) {
  CheckIncreasing(csv, line, stamp, previous, previous_line);
}

std::vector<SequenceImage> ReadEurocImageList(const fs::path& csv, const fs::path& image_folder,
                                              bool check_images_exist) {
  std::vector<SequenceImage> images;
  std::optional<timestamp_ns_t> previous;
  int64_t previous_line = 0;
  // Each image once: one image under two stamps is not a recording.
  std::unordered_map<std::string, int64_t> line_of_name;
  ForEachCsvRow(csv, "EuRoC image list", [&](int64_t line, const auto& fields) {
    SequenceImage image = ParseEurocImageRow(csv, line, fields, image_folder);
    CheckIncreasing(csv, line, image.timestamp_ns, previous, previous_line);
    const auto [it, inserted] =
        line_of_name.emplace(fs::path(std::string(fields[1])).lexically_normal().string(), line);
    if (!inserted) {
      throw InputError(csv.string(), line,
                       "image " + Quoted(fields[1]) + " is already listed on line " +
                           std::to_string(it->second) +
                           ": one image under two stamps (expected each image once)");
    }
    if (check_images_exist && !fs::is_regular_file(image.path)) {
      throw InputError(
          csv.string(), line,
          "listed image " + Quoted(fields[1]) + " does not exist: " + image.path.string());
    }
    images.push_back(std::move(image));
    previous = images.back().timestamp_ns;
    previous_line = line;
  });
  if (images.empty()) throw InputError(csv.string(), 0, "expected image rows, found none");
  return images;
}

std::vector<ImuSample> ReadEurocImu(const fs::path& csv, const DatasetChecks& checks) {
  std::vector<ImuSample> samples;
  std::optional<timestamp_ns_t> previous;
  int64_t previous_line = 0;
  ForEachCsvRow(csv, "EuRoC IMU file", [&](int64_t line, const auto& fields) {
    const ImuSample sample = ParseEurocImuRow(csv, line, fields, checks);
    CheckIncreasing(csv, line, sample.timestamp_ns, previous, previous_line);
    samples.push_back(sample);
    previous = sample.timestamp_ns;
    previous_line = line;
  });
  if (samples.empty()) throw InputError(csv.string(), 0, "expected IMU rows, found none");
  return samples;
}

std::string EurocReadOptions::Validate() const {
  const auto is_plain_name = [](const std::string& name) {
    return !name.empty() && name.find('/') == std::string::npos && name != "." && name != "..";
  };
  if (!is_plain_name(cam_name)) return "cam_name must be a folder name such as 'cam0'";
  if (!is_plain_name(imu_name)) return "imu_name must be a folder name such as 'imu0'";
  if (const std::string problem = checks.Validate(); !problem.empty()) return "checks." + problem;
  return "";
}

std::vector<fs::path> EurocDatasetFiles(const fs::path& root, const EurocReadOptions& options) {
  fs::path mav0;
  if (fs::is_directory(root / "mav0")) {
    mav0 = "mav0";
  } else if (!fs::is_directory(root / options.cam_name)) {
    return {};
  }
  std::vector<fs::path> candidates = {
      mav0 / options.cam_name / "sensor.yaml", mav0 / options.cam_name / "data.csv",
      mav0 / options.imu_name / "sensor.yaml", mav0 / options.imu_name / "data.csv"};
  if (options.read_ground_truth) {
    candidates.push_back(mav0 / "state_groundtruth_estimate0" / "data.csv");
  }
  std::vector<fs::path> files;
  for (const fs::path& candidate : candidates) {
    if (fs::is_regular_file(root / candidate)) files.push_back(candidate);
  }
  return files;
}

fs::path EurocMav0Folder(const fs::path& root, const EurocReadOptions& options) {
  if (fs::is_directory(root / "mav0")) return root / "mav0";
  if (fs::is_directory(root / options.cam_name)) return root;
  throw InputError(root.string(), 0,
                   "expected a EuRoC ASL folder: one containing mav0/, or mav0/ itself (with " +
                       options.cam_name + "/)");
}

SensorRig ReadEurocRig(const fs::path& mav0, const EurocReadOptions& options,
                       Rigid3d* body_from_imu) {
  SensorRig rig;
  const fs::path cam_folder = mav0 / options.cam_name;
  RequireFolder(cam_folder, "camera folder");
  const EurocCameraCalibration camera = ReadEurocCameraYaml(cam_folder / "sensor.yaml");
  rig.camera = camera.camera;
  rig.body_from_cam = camera.body_from_cam;
  rig.camera_rate_hz = camera.rate_hz;
  *body_from_imu = Rigid3d();
  const fs::path imu_folder = mav0 / options.imu_name;
  if (fs::exists(imu_folder) || options.require_imu) {
    RequireFolder(imu_folder, "IMU folder");
    const EurocImuCalibration imu = ReadEurocImuYaml(imu_folder / "sensor.yaml");
    rig.imu_noise = imu.noise;
    *body_from_imu = imu.body_from_imu;
    if (!IsIdentity(*body_from_imu)) {
      VIOSFM_LOG(WARNING) << imu_folder / "sensor.yaml"
                          << ": T_BS is not the identity; camera extrinsics and ground-truth "
                             "poses are re-expressed in the IMU frame";
      rig.body_from_cam = body_from_imu->Inverse() * rig.body_from_cam;
    }
  }
  return rig;
}

std::vector<GroundTruthState> ReadEurocGroundTruthOf(const fs::path& mav0,
                                                     const EurocReadOptions& options,
                                                     const Rigid3d& body_from_imu) {
  const fs::path ground_truth_csv = mav0 / "state_groundtruth_estimate0" / "data.csv";
  if (!options.read_ground_truth || !fs::exists(ground_truth_csv)) return {};
  std::vector<GroundTruthState> states;
  if (options.strict_ground_truth) {
    states = ReadEurocGroundTruth(ground_truth_csv);
  } else {
    GroundTruthReadResult ground_truth = TryReadEurocGroundTruth(ground_truth_csv);
    if (!ground_truth.ok()) {
      VIOSFM_LOG(WARNING) << "ignoring the dataset's ground truth, which cannot be read (no "
                             "evaluation): "
                          << ground_truth.error;
    }
    states = std::move(ground_truth.states);
  }
  if (!IsIdentity(body_from_imu)) {
    for (GroundTruthState& state : states) {
      state.world_from_body = state.world_from_body * body_from_imu;
    }
  }
  return states;
}

Sequence ReadEurocDataset(const fs::path& root, const EurocReadOptions& options) {
  if (const std::string problem = options.Validate(); !problem.empty()) {
    throw InputError("EuRoC read options: " + problem);
  }
  RequireFolder(root, "EuRoC dataset folder");
  const fs::path mav0 = EurocMav0Folder(root, options);

  // The lists and calibrations too stay inside the dataset.
  for (const fs::path& file : EurocDatasetFiles(root, options)) {
    CheckInsideDataset(root, root / file, options.checks, "");
  }
  Sequence sequence;
  sequence.root = root;
  // The body frame of a Sequence is the IMU frame.
  Rigid3d body_from_imu;
  sequence.rig = ReadEurocRig(mav0, options, &body_from_imu);

  const fs::path cam_folder = mav0 / options.cam_name;
  if (options.check_images_exist) RequireFolder(cam_folder / "data", "image folder");
  sequence.images =
      ReadEurocImageList(cam_folder / "data.csv", cam_folder / "data", options.check_images_exist);
  if (options.check_images_exist) CheckSequenceImages(sequence, root, options.checks);
  if (!(sequence.rig.camera_rate_hz > 0)) {
    sequence.rig.camera_rate_hz = EstimateFrameRateHz(sequence.images);  // no rate_hz in the yaml
  }

  const fs::path imu_folder = mav0 / options.imu_name;
  if (fs::exists(imu_folder) || options.require_imu) {
    const fs::path imu_csv = imu_folder / "data.csv";
    sequence.imu = ReadEurocImu(imu_csv, options.checks);
    // Reported, never bridged here: what uses the IMU decides.
    ReportImuGaps(sequence.imu, imu_csv);
    const ImuCoverage coverage = CheckImuCoverage(sequence);
    if (!coverage.overlaps) {
      throw InputError(
          imu_csv.string(), 0,
          "expected IMU samples over the time span of the images, found none: " + coverage.spans);
    }
    if (!coverage.complete) {
      const std::string message =
          "the IMU does not cover the whole image time span: " + coverage.spans;
      if (options.require_imu_coverage) throw InputError(imu_csv.string(), 0, message);
      VIOSFM_LOG(WARNING) << imu_csv.string() << ": " << message;
    }
  }

  sequence.ground_truth = ReadEurocGroundTruthOf(mav0, options, body_from_imu);

  VIOSFM_LOG(INFO) << "EuRoC " << mav0.string() << ": " << sequence.images.size() << " images ("
                   << sequence.rig.camera.ModelName() << " " << sequence.rig.camera.width << "x"
                   << sequence.rig.camera.height << "), " << sequence.imu.size() << " IMU samples, "
                   << sequence.ground_truth.size() << " ground-truth states";
  return sequence;
}

}  // namespace viosfm

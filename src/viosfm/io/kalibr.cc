#include "viosfm/io/kalibr.h"

#include <cmath>
#include <sstream>

#include "viosfm/io/kalibr_yaml.h"
#include "viosfm/io/yaml_util.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/logging.h"

namespace viosfm {
namespace fs = std::filesystem;

namespace {

constexpr const char* kNoiseKeys[4] = {"accelerometer_noise_density", "accelerometer_random_walk",
                                       "gyroscope_noise_density", "gyroscope_random_walk"};

bool HasAnyNoiseKey(const YamlMap& yaml) {
  for (const char* key : kNoiseKeys) {
    if (yaml.Has(key)) return true;
  }
  return false;
}

// The four noise keys (all required once one is there) and update_rate.
KalibrImuNoise ReadNoiseKeys(const YamlMap& yaml) {
  const auto positive = [&](const std::string& key) {
    const double value = yaml.GetDouble(key);
    if (!(value > 0.0)) yaml.Fail(key, "expected a positive number");
    return value;
  };
  KalibrImuNoise noise;
  noise.accel_noise_density = positive(kNoiseKeys[0]);
  noise.accel_random_walk = positive(kNoiseKeys[1]);
  noise.gyro_noise_density = positive(kNoiseKeys[2]);
  noise.gyro_random_walk = positive(kNoiseKeys[3]);
  if (yaml.Has("update_rate")) noise.update_rate_hz = positive("update_rate");
  return noise;
}

bool SameNoise(const KalibrImuNoise& a, const KalibrImuNoise& b) {
  return a.accel_noise_density == b.accel_noise_density &&
         a.accel_random_walk == b.accel_random_walk &&
         a.gyro_noise_density == b.gyro_noise_density && a.gyro_random_walk == b.gyro_random_walk;
}

}  // namespace

KalibrImuNoise ReadKalibrImuYaml(const fs::path& imu_yaml) {
  const YamlMap file = YamlMap::Load(imu_yaml);
  if (!HasAnyNoiseKey(file) && file.Has("imu0")) return ReadNoiseKeys(file.GetMap("imu0"));
  if (!HasAnyNoiseKey(file)) {
    file.Fail(kNoiseKeys[0],
              "expected a Kalibr IMU file: accelerometer_noise_density, "
              "accelerometer_random_walk, gyroscope_noise_density and gyroscope_random_walk at "
              "the top level or in an 'imu0:' map");
  }
  return ReadNoiseKeys(file);
}

KalibrCalibration ReadKalibrCalibration(const fs::path& camchain, const fs::path& imu_yaml) {
  const YamlMap file = YamlMap::Load(camchain);
  if (!file.Has("cam0")) {
    file.Fail("cam0", "expected a Kalibr camchain with a 'cam0:' map (T_cam_imu, intrinsics, ...)");
  }
  const YamlMap cam0 = file.GetMap("cam0");

  KalibrCalibration calibration;
  calibration.camchain_path = camchain;
  // T_cam_imu maps IMU-frame points into the camera frame: cam_from_imu.
  calibration.body_from_cam = ReadRigidTransform(cam0, "T_cam_imu").Inverse();

  const bool has_intrinsics = cam0.Has("intrinsics") || cam0.Has("resolution") ||
                              cam0.Has("distortion_model") || cam0.Has("distortion_coeffs");
  if (has_intrinsics) {
    calibration.camera = ReadKalibrCameraIntrinsics(cam0, "distortion_coeffs");
    calibration.camera->camera_id = 1;
  }

  if (cam0.Has("timeshift_cam_imu")) {
    const double shift_s = cam0.GetDouble("timeshift_cam_imu");
    if (!(std::abs(shift_s) <= kMaxKalibrTimeshiftS)) {
      std::ostringstream message;
      message << "expected a camera-IMU time offset of at most " << kMaxKalibrTimeshiftS
              << " s in magnitude, got " << shift_s << " s";
      cam0.Fail("timeshift_cam_imu", message.str());
    }
    calibration.cam_time_offset_ns = SecondsToNs(shift_s);
  }

  std::optional<KalibrImuNoise> cam0_noise;
  if (HasAnyNoiseKey(cam0)) cam0_noise = ReadNoiseKeys(cam0);
  if (!imu_yaml.empty()) {
    calibration.imu_noise = ReadKalibrImuYaml(imu_yaml);
    calibration.imu_noise_path = imu_yaml;
    if (cam0_noise && !SameNoise(*cam0_noise, *calibration.imu_noise)) {
      VIOSFM_LOG(WARNING) << camchain.string() << ": the IMU noise in cam0 differs from "
                          << imu_yaml.string() << "'s; using " << imu_yaml.string() << "'s";
    }
  } else if (cam0_noise) {
    calibration.imu_noise = cam0_noise;
    calibration.imu_noise_path = camchain;
  }
  return calibration;
}

std::string CalibrationFiles::Validate() const {
  if (!imu.empty() && camchain.empty()) {
    return "imu: an IMU calibration needs the camchain calibration too (--calibration)";
  }
  return "";
}

void ApplyCalibration(const KalibrCalibration& calibration, Sequence* sequence) {
  VIOSFM_CHECK(sequence != nullptr);
  SensorRig rig = sequence->rig;
  rig.body_from_cam = calibration.body_from_cam;
  rig.cam_time_offset_ns = calibration.cam_time_offset_ns;
  std::ostringstream replaced;
  replaced << "body_from_cam (inverse of cam0's T_cam_imu), camera-IMU time offset "
           << FormatNsAsSeconds(calibration.cam_time_offset_ns) << " s";
  if (calibration.camera) {
    rig.camera = *calibration.camera;
    rig.camera.camera_id = sequence->rig.camera.camera_id;
    replaced << ", camera " << rig.camera.ModelName() << " " << rig.camera.width << "x"
             << rig.camera.height;
  }
  if (calibration.imu_noise) {
    const KalibrImuNoise& noise = *calibration.imu_noise;
    rig.imu_noise.accel_noise_density = noise.accel_noise_density;
    rig.imu_noise.accel_random_walk = noise.accel_random_walk;
    rig.imu_noise.gyro_noise_density = noise.gyro_noise_density;
    rig.imu_noise.gyro_random_walk = noise.gyro_random_walk;
    if (noise.update_rate_hz) rig.imu_noise.rate_hz = *noise.update_rate_hz;
    replaced << ", IMU noise (from " << calibration.imu_noise_path.string() << ")";
  }
  if (const std::string problem = rig.Validate(); !problem.empty()) {
    throw InputError(calibration.camchain_path.string(), 0,
                     "the calibration gives an invalid sensor rig: " + problem);
  }
  sequence->rig = rig;
  VIOSFM_LOG(INFO) << "calibration " << calibration.camchain_path.filename().string()
                   << " replaces the dataset's extrinsics, time offset"
                   << (calibration.camera ? ", camera" : "")
                   << (calibration.imu_noise ? ", IMU noise" : "") << LogDetails() << " ("
                   << calibration.camchain_path.string() << ": " << replaced.str()
                   << (calibration.camera ? ")" : "; the camera intrinsics stay the dataset's)");
}

void ApplyCalibrationFiles(const CalibrationFiles& files, Sequence* sequence) {
  if (files.empty()) return;
  if (const std::string problem = files.Validate(); !problem.empty()) {
    throw InputError("calibration files: " + problem);
  }
  ApplyCalibration(ReadKalibrCalibration(files.camchain, files.imu), sequence);
}

}  // namespace viosfm

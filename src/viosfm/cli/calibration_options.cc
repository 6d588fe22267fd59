// The calibration and dataset-check options shared by the subcommands that
// read a dataset, and the cap on thread counts.
#include <algorithm>
#include <string>
#include <thread>

#include "viosfm/cli/commands.h"
#include "viosfm/util/logging.h"

namespace viosfm::cli {

void AddCalibrationOptions(CLI::App* command, CalibrationFiles* files) {
  command->add_option("--calibration", files->camchain,
                      "Kalibr camchain.yaml: cam0's T_cam_imu, timeshift_cam_imu and (if given) "
                      "intrinsics replace the dataset's sensor.yaml");
  command->add_option("--imu-calibration", files->imu,
                      "Kalibr imu.yaml: IMU noise densities and random walks (needs "
                      "--calibration)");
}

void AddDatasetCheckOptions(CLI::App* command, DatasetChecks* checks) {
  command->add_flag("--allow-external-links", checks->allow_links_outside,
                    "Follow symbolic links that lead out of the dataset's folder (refused by "
                    "default; option dataset_checks.allow_links_outside)");
  command
      ->add_option("--imu-max-accel", checks->imu_max_accel_m_s2,
                   "The largest acceleration an IMU sample may state on an axis, m/s^2 (default "
                   "50 g; larger values are refused as corrupt; option "
                   "dataset_checks.imu_max_accel_m_s2)")
      ->capture_default_str();
  command
      ->add_option("--imu-max-gyro", checks->imu_max_gyro_rad_s,
                   "The largest angular rate an IMU sample may state on an axis, rad/s (option "
                   "dataset_checks.imu_max_gyro_rad_s)")
      ->capture_default_str();
}

int CapNumThreads(int requested, const std::string& flag) {
  const int hardware = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  const int cap = std::max(kMinThreadCap, kMaxThreadsPerHardwareThread * hardware);
  if (requested <= cap) return requested;
  VIOSFM_LOG(WARNING) << flag << " " << requested << ": capped at " << cap << " ("
                      << kMaxThreadsPerHardwareThread << " per hardware thread of this machine's "
                      << hardware << "; more only take memory)";
  return cap;
}

}  // namespace viosfm::cli

// The calibration options shared by the subcommands that read a dataset.
#include "viosfm/cli/commands.h"

namespace viosfm::cli {

void AddCalibrationOptions(CLI::App* command, CalibrationFiles* files) {
  command->add_option("--calibration", files->camchain,
                      "Kalibr camchain.yaml: cam0's T_cam_imu, timeshift_cam_imu and (if given) "
                      "intrinsics replace the dataset's sensor.yaml");
  command->add_option("--imu-calibration", files->imu,
                      "Kalibr imu.yaml: IMU noise densities and random walks (needs "
                      "--calibration)");
}

}  // namespace viosfm::cli

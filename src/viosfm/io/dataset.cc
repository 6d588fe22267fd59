#include "viosfm/io/dataset.h"

#include "viosfm/io/euroc.h"
#include "viosfm/util/errors.h"

namespace viosfm {

namespace fs = std::filesystem;

bool IsEurocDatasetFolder(const fs::path& folder) {
  return fs::is_directory(folder / "mav0") ||
         (folder.filename() == "mav0" && fs::is_directory(folder / "cam0"));
}

void CheckDatasetExists(const fs::path& path) {
  if (HasBagExtension(path)) {
    if (!fs::is_regular_file(path)) throw InputError(path.string(), 0, "bag file not found");
  } else if (!fs::is_directory(path)) {
    throw InputError(path.string(), 0, "dataset folder not found");
  }
}

Sequence ReadDataset(const fs::path& path, const DatasetReadOptions& options) {
  CheckDatasetExists(path);
  Sequence sequence;
  if (IsBagPath(path)) {
    RosbagDatasetOptions rosbag = options.rosbag;
    rosbag.require_imu = rosbag.require_imu || options.require_imu;
    sequence = ReadRosbagDataset(path, rosbag);
    CheckImuSamples(sequence.imu, options.checks, path);
    ReportImuGaps(sequence.imu, path);
  } else if (IsEurocDatasetFolder(path)) {
    EurocReadOptions euroc;
    euroc.require_imu = options.require_imu;
    euroc.checks = options.checks;
    sequence = ReadEurocDataset(path, euroc);
  } else {
    if (options.require_imu) {
      throw InputError(path.string(), 0,
                       "not a EuRoC dataset (no mav0/) nor a bag: an image folder has no IMU");
    }
    if (const std::string error = options.image_folder.Validate(); !error.empty()) {
      throw InputError(path.string(), 0,
                       "not a EuRoC dataset (no mav0/), so read as an image folder: " + error +
                           " (give the camera: --camera-yaml or --camera)");
    }
    sequence = ReadImageFolder(path, options.image_folder, options.checks);
  }
  if (sequence.images.empty()) throw InputError(path.string(), 0, "the dataset has no images");
  ApplyCalibrationFiles(options.calibration, &sequence);
  return sequence;
}

}  // namespace viosfm

// Reading any dataset viosfm takes, by what it is: a EuRoC ASL folder (one
// holding mav0/, or mav0/ itself), a bag (rosbag_dataset.h: a ROS 1 ".bag",
// a ROS 2 ".db3" or ".mcap", or a rosbag2 folder holding metadata.yaml)
// or a folder of images with a camera (image_folder.h); then the Kalibr or
// EuRoC calibration files, if given, replace what the dataset says
// (kalibr.h). Every command that takes a dataset reads it here.
#pragma once

#include <filesystem>

#include "viosfm/io/dataset_checks.h"
#include "viosfm/io/image_folder.h"
#include "viosfm/io/kalibr.h"
#include "viosfm/io/rosbag_dataset.h"
#include "viosfm/scene/sequence.h"

namespace viosfm {

struct DatasetReadOptions {
  // Used only for a folder of images (neither EuRoC nor a bag): its stamps
  // and camera.
  ImageFolderOptions image_folder;
  // Used only for a bag: topics, calibration and where its images are
  // extracted (rosbag.extract_folder, required for a bag).
  RosbagDatasetOptions rosbag;
  // Calibration files replacing the dataset's (default none).
  CalibrationFiles calibration;
  // The dataset must have an IMU (the VIO). Default false: the IMU only
  // helps (frame selection, metric scale).
  bool require_imu = false;
  // What the sensors may say and where the dataset's files may lie
  // (dataset_checks.h).
  DatasetChecks checks;
};

// Whether `folder` is a EuRoC dataset: it holds mav0/, or is mav0/ with cam0/.
bool IsEurocDatasetFolder(const std::filesystem::path& folder);

// Throws InputError naming `path` when no dataset can be there: a bag
// file (".bag", ".db3", ".mcap") that is not a file, or anything else that is
// not a folder. A run
// checks it before it creates its output folder.
void CheckDatasetExists(const std::filesystem::path& path);

// The dataset at `path` (see the top of this file). Throws InputError
// naming the path when it does not exist, is a folder that is neither EuRoC
// nor readable as an image folder with `options.image_folder`, has no
// images, or lacks an IMU that `require_imu` asks for; the readers' own
// errors name the file and line.
Sequence ReadDataset(const std::filesystem::path& path, const DatasetReadOptions& options);

}  // namespace viosfm

// The options of a bag (ROS 1 or 2) given as a dataset (io/rosbag_dataset.h), shared
// by the subcommands that take one: topics and calibration files.
#pragma once

#include <CLI/CLI.hpp>
#include <filesystem>
#include <string>

#include "viosfm/io/rosbag_dataset.h"

namespace viosfm::cli {

struct BagArguments {
  std::string image_topic;
  std::string imu_topic;
  std::string groundtruth_topic;
  // A bag's, and an image folder's: the subcommands that read image
  // folders give it to both.
  std::string camera_yaml;
  std::string imu_yaml;
};

// Adds --image-topic, --imu-topic, --groundtruth-topic, --camera-yaml and
// --imu-yaml.
void AddBagOptions(CLI::App* command, BagArguments* args);

// The read options of a bag whose images go to `extract_folder`.
RosbagDatasetOptions MakeRosbagOptions(const BagArguments& args,
                                       const std::filesystem::path& extract_folder);

}  // namespace viosfm::cli

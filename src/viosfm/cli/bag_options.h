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
  std::string camera_yaml;
  std::string imu_yaml;
};

// Adds --image-topic, --imu-topic, --groundtruth-topic, --imu-yaml and, with
// add_camera_yaml, --camera-yaml (subcommands that read image folders
// already have it: it then serves both).
void AddBagOptions(CLI::App* command, BagArguments* args, bool add_camera_yaml);

// The read options of a bag whose images go to `extract_folder`.
RosbagDatasetOptions MakeRosbagOptions(const BagArguments& args,
                                       const std::filesystem::path& extract_folder);

}  // namespace viosfm::cli

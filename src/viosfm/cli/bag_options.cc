#include "viosfm/cli/bag_options.h"

namespace viosfm::cli {

void AddBagOptions(CLI::App* command, BagArguments* args) {
  command->add_option("--image-topic", args->image_topic,
                      "Bag: sensor_msgs/Image or CompressedImage topic (default: the only one, "
                      "or /cam0/image_raw)");
  command->add_option("--imu-topic", args->imu_topic,
                      "Bag: sensor_msgs/Imu topic (default: the only one, or /imu0)");
  command->add_option("--groundtruth-topic", args->groundtruth_topic,
                      "Bag: geometry_msgs/PoseStamped or TransformStamped ground truth "
                      "(default: /groundtruth/pose when present)");
  command->add_option("--camera-yaml", args->camera_yaml,
                      "Bag or image folder: the camera's EuRoC/Kalibr sensor.yaml (a bag's "
                      "default: the calibration in the bag, or mav0/ beside it; an image "
                      "folder's: a camera guessed from the image size)");
  command->add_option("--imu-yaml", args->imu_yaml,
                      "Bag: Kalibr/EuRoC IMU sensor.yaml (with --camera-yaml)");
}

RosbagDatasetOptions MakeRosbagOptions(const BagArguments& args,
                                       const std::filesystem::path& extract_folder) {
  RosbagDatasetOptions options;
  options.image_topic = args.image_topic;
  options.imu_topic = args.imu_topic;
  options.groundtruth_topic = args.groundtruth_topic;
  options.camera_yaml = args.camera_yaml;
  options.imu_yaml = args.imu_yaml;
  options.extract_folder = extract_folder;
  return options;
}

}  // namespace viosfm::cli

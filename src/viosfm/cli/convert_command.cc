// `viosfm convert IN OUT`: a EuRoC folder to a bag (ROS 1 .bag, ROS 2 .db3 or
// .mcap), a bag to a EuRoC folder, or a bag to a bag of another container,
// by what IN and OUT are (see io/rosbag_dataset.h).
#include <unistd.h>

#include <filesystem>
#include <memory>
#include <string>

#include "viosfm/cli/bag_options.h"
#include "viosfm/cli/commands.h"
#include "viosfm/io/bag_container.h"
#include "viosfm/io/euroc.h"
#include "viosfm/io/rosbag_dataset.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/logging.h"
#include "viosfm/util/string_util.h"

namespace viosfm::cli {
namespace {

namespace fs = std::filesystem;

struct ConvertArguments {
  std::string in;
  std::string out;
  BagArguments bag;
  std::string compression = "default";
  bool compressed_images = false;
  bool no_calibration = false;
};

BagCompression ParseCompression(const std::string& name) {
  if (ToLower(name) == "default") return BagCompression::kDefault;
  try {
    return ParseBagCompression(name);
  } catch (const InputError&) {
    throw InputError("--compression '" + name + "': expected default, none, bz2, lz4 or zstd");
  }
}

// Writes `sequence` as the bag `out` with the options of `args`; the
// calibration as the sensor.yaml files of `euroc_folder` when it is given
// (the folder the sequence was read from).
void WriteBag(const Sequence& sequence, const ConvertArguments& args,
              const fs::path& euroc_folder = {}) {
  const fs::path out = args.out;
  RosbagWriteOptions options;
  if (!args.bag.image_topic.empty()) options.image_topic = args.bag.image_topic;
  if (!args.bag.imu_topic.empty()) options.imu_topic = args.bag.imu_topic;
  if (!args.bag.groundtruth_topic.empty()) options.groundtruth_topic = args.bag.groundtruth_topic;
  options.compressed_images = args.compressed_images;
  options.embed_calibration = !args.no_calibration;
  if (!euroc_folder.empty()) UseEurocCalibrationTexts(euroc_folder, &options);
  options.writer.compression = ParseCompression(args.compression);
  if (const std::string error = options.Validate(); !error.empty()) {
    throw InputError("invalid convert options: " + error);
  }
  if (const std::string error = options.writer.Validate(out); !error.empty()) {
    throw InputError(args.out, 0, "--compression " + args.compression + ": " + error);
  }
  if (out.has_parent_path()) fs::create_directories(out.parent_path());
  WriteRosbagDataset(sequence, out, options);
}

// Reads the bag `in`, its images extracted to `extract_folder`.
Sequence ReadBag(const fs::path& in, const ConvertArguments& args, const fs::path& extract_folder) {
  {
    const std::unique_ptr<BagReader> reader = OpenBag(in);
    VIOSFM_LOG(INFO) << "convert: " << in.string() << " (" << reader->Describe() << ") holds\n"
                     << DescribeBagTopics(*reader);
  }
  return ReadRosbagDataset(in, MakeRosbagOptions(args.bag, extract_folder));
}

void RunConvert(const ConvertArguments& args) {
  const fs::path in = args.in;
  const fs::path out = args.out;
  const bool in_is_bag = IsBagPath(in);
  const bool out_is_bag = HasBagExtension(out);
  if (in_is_bag && !out_is_bag) {
    const Sequence sequence = ReadBag(in, args, out);
    VIOSFM_LOG(INFO) << "convert: wrote the EuRoC folder " << out.string() << " ("
                     << sequence.images.size() << " images, " << sequence.imu.size()
                     << " IMU samples, " << sequence.ground_truth.size() << " ground-truth poses)";
    return;
  }
  if (!in_is_bag && out_is_bag) {
    if (!fs::is_directory(in)) throw InputError(args.in, 0, "dataset folder not found");
    EurocReadOptions read_options;
    read_options.require_imu = false;
    WriteBag(ReadEurocDataset(in, read_options), args, in);
    return;
  }
  if (in_is_bag && out_is_bag) {
    // Bag to bag (ROS 1 to ROS 2, sqlite3 to MCAP, ...): the images pass
    // through a temporary EuRoC folder of our own.
    std::error_code error;
    if (fs::exists(out, error) && fs::equivalent(in, out, error)) {
      throw InputError(args.out, 0, "the bag to write is the bag to read");
    }
    const fs::path temp =
        fs::temp_directory_path() / ("viosfm-convert-" + std::to_string(::getpid()));
    fs::remove_all(temp, error);
    struct RemoveTemp {
      fs::path folder;
      ~RemoveTemp() {
        std::error_code ignored;
        fs::remove_all(folder, ignored);
      }
    } remove_temp{temp};
    WriteBag(ReadBag(in, args, temp), args);
    return;
  }
  throw InputError("convert " + args.in + " " + args.out +
                   ": expected a EuRoC folder or a bag (.bag, .db3, .mcap, or a rosbag2 folder "
                   "with metadata.yaml) to read, and a folder or a bag file to write");
}

}  // namespace

void RegisterConvert(CLI::App& app) {
  auto args = std::make_shared<ConvertArguments>();
  CLI::App* command = app.add_subcommand(
      "convert",
      "Convert between a EuRoC folder and a bag, by extension: FOLDER -> X.bag (ROS 1), X.db3 "
      "(ROS 2, rosbag2 sqlite3) or X.mcap (ROS 2, MCAP) writes sensor_msgs/Image mono8 on "
      "/cam0/image_raw, sensor_msgs/Imu on /imu0, the ground truth on /groundtruth/pose and the "
      "calibration; BAG -> FOLDER writes what viosfm reads from the bag as a EuRoC folder; BAG "
      "-> X.bag, X.db3 or X.mcap writes what viosfm reads from the first bag into the second");
  command->add_option("in", args->in, "EuRoC folder, or a bag (.bag, .db3, .mcap, rosbag2 folder)")
      ->required();
  command->add_option("out", args->out, ".bag, .db3, .mcap or folder (written)")->required();
  AddBagOptions(command, &args->bag, /*add_camera_yaml=*/true);
  command
      ->add_option("--compression", args->compression,
                   "Writing a bag: default (.bag none, .mcap zstd, .db3 none), none, bz2 or lz4 "
                   "(.bag chunks), zstd or lz4 (.mcap chunks), zstd (.db3: each message)")
      ->capture_default_str();
  command->add_flag("--compressed-images", args->compressed_images,
                    "Writing a bag: sensor_msgs/CompressedImage holding the image files' bytes");
  command->add_flag("--no-calibration", args->no_calibration,
                    "Writing a bag: leave out the calibration (/viosfm/cam0/sensor_yaml, "
                    "/viosfm/imu0/sensor_yaml)");
  command->callback([args] { RunConvert(*args); });
}

}  // namespace viosfm::cli

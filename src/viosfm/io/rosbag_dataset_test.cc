#include "viosfm/io/rosbag_dataset.h"

#include <gtest/gtest.h>

#include <cmath>

#include "viosfm/io/euroc.h"
#include "viosfm/io/euroc_writer.h"
#include "viosfm/io/image_io.h"
#include "viosfm/io/ros_messages.h"
#include "viosfm/sensor/camera_models.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/random.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {
namespace fs = std::filesystem;

constexpr timestamp_ns_t kStart = 1'403'715'273'262'142'976;

// A small recording: 6 images of 40x30 at 20 Hz (noise patterns), IMU at
// 200 Hz with values no decimal text would keep exactly, ground truth at the
// image stamps, an OPENCV camera with a non-trivial body_from_cam.
Sequence MakeSequence(const fs::path& folder) {
  Sequence sequence;
  sequence.root = folder;
  sequence.rig.camera = MakeCamera(CameraModelId::kOpenCV, 40, 30,
                                   {45.5, 44.25, 19.75, 14.5, -0.28, 0.07, 1e-4, -2e-4});
  sequence.rig.body_from_cam = Rigid3d(Eigen::Quaterniond(0.7, 0.1, -0.7, 0.1).normalized(),
                                       Eigen::Vector3d(0.01, -0.065, 0.002));
  sequence.rig.camera_rate_hz = 20;
  sequence.rig.imu_noise.rate_hz = 200;
  sequence.rig.imu_noise.gyro_noise_density = 1.1e-4;
  Random random(3);
  fs::create_directories(folder / "mav0" / "cam0" / "data");
  for (int i = 0; i < 6; ++i) {
    const timestamp_ns_t stamp = kStart + 50'000'000LL * i;
    GreyImage image(40, 30);
    for (uint8_t& pixel : image.pixels) pixel = static_cast<uint8_t>(random.UniformInt(0, 255));
    const fs::path path = folder / "mav0" / "cam0" / "data" / (std::to_string(stamp) + ".png");
    WriteGreyPng(path, image);
    sequence.images.push_back({stamp, path});
    GroundTruthState state;
    state.timestamp_ns = stamp;
    state.world_from_body = Rigid3d(Eigen::Quaterniond(1, 0.01 * i, 0.02, -0.03 * i).normalized(),
                                    Eigen::Vector3d(0.1 * i + 1.0 / 3.0, -0.2 * i, 1.5));
    sequence.ground_truth.push_back(state);
  }
  for (int k = -4; k < 60; ++k) {
    ImuSample sample;
    sample.timestamp_ns = kStart + 5'000'000LL * k;
    sample.gyro = Eigen::Vector3d(std::sin(0.1 * k), 1.0 / 3.0, -0.2 * k);
    sample.accel = Eigen::Vector3d(0.3, std::cos(0.05 * k), 9.81 + 1.0 / 7.0);
    sequence.imu.push_back(sample);
  }
  return sequence;
}

void ExpectSameSequence(const Sequence& a, const Sequence& b) {
  ASSERT_EQ(a.images.size(), b.images.size());
  for (size_t i = 0; i < a.images.size(); ++i) {
    EXPECT_EQ(a.images[i].timestamp_ns, b.images[i].timestamp_ns);
    EXPECT_EQ(a.images[i].path.filename(), b.images[i].path.filename());
    EXPECT_EQ(ReadGreyImage(a.images[i].path).pixels, ReadGreyImage(b.images[i].path).pixels);
  }
  EXPECT_EQ(a.rig.camera.model_id, b.rig.camera.model_id);
  EXPECT_EQ(a.rig.camera.params, b.rig.camera.params);
  EXPECT_EQ(a.rig.camera.width, b.rig.camera.width);
  EXPECT_EQ(a.rig.camera.height, b.rig.camera.height);
  EXPECT_EQ(a.rig.body_from_cam.translation, b.rig.body_from_cam.translation);
  EXPECT_LT(a.rig.body_from_cam.rotation.angularDistance(b.rig.body_from_cam.rotation), 1e-15);
  EXPECT_EQ(a.rig.camera_rate_hz, b.rig.camera_rate_hz);
  EXPECT_EQ(a.rig.imu_noise.gyro_noise_density, b.rig.imu_noise.gyro_noise_density);
  EXPECT_EQ(a.rig.imu_noise.rate_hz, b.rig.imu_noise.rate_hz);
  ASSERT_EQ(a.imu.size(), b.imu.size());
  for (size_t i = 0; i < a.imu.size(); ++i) {
    EXPECT_EQ(a.imu[i].timestamp_ns, b.imu[i].timestamp_ns);
    EXPECT_EQ(a.imu[i].gyro, b.imu[i].gyro);
    EXPECT_EQ(a.imu[i].accel, b.imu[i].accel);
  }
  ASSERT_EQ(a.ground_truth.size(), b.ground_truth.size());
  for (size_t i = 0; i < a.ground_truth.size(); ++i) {
    EXPECT_EQ(a.ground_truth[i].timestamp_ns, b.ground_truth[i].timestamp_ns);
    EXPECT_EQ(a.ground_truth[i].world_from_body.translation,
              b.ground_truth[i].world_from_body.translation);
    EXPECT_LT(a.ground_truth[i].world_from_body.rotation.angularDistance(
                  b.ground_truth[i].world_from_body.rotation),
              1e-15);
  }
}

RosbagDatasetOptions Extract(const fs::path& folder) {
  RosbagDatasetOptions options;
  options.extract_folder = folder;
  return options;
}

// Written with the EuRoC topics and the embedded calibration, a bag is read
// back without any option: same pixels, stamps, IMU values, ground truth and
// calibration. The same for CompressedImage (PNG bytes), in every container
// (ROS 1 .bag, rosbag2 .db3, MCAP) and compression.
TEST(RosbagDataset, RoundTripsWithoutOptions) {
  const fs::path folder = testing::MakeScratchFolder("rosbag_dataset_roundtrip");
  const Sequence original = MakeSequence(folder / "original");
  struct Case {
    const char* name;
    bool compressed_images;
    BagCompression compression;
  };
  for (const Case& c :
       {Case{"r.bag", false, BagCompression::kDefault}, Case{"c.bag", true, BagCompression::kLz4},
        Case{"r.db3", false, BagCompression::kDefault}, Case{"c.db3", true, BagCompression::kZstd},
        Case{"r.mcap", false, BagCompression::kDefault}, Case{"c.mcap", true, BagCompression::kLz4},
        Case{"n.mcap", false, BagCompression::kNone}}) {
    SCOPED_TRACE(std::string(c.name) + ", " + BagCompressionName(c.compression));
    RosbagWriteOptions write;
    write.compressed_images = c.compressed_images;
    write.writer.compression = c.compression;
    write.writer.chunk_threshold_bytes = 4096;  // several chunks
    const fs::path bag = folder / c.name;
    const fs::path extract = folder / ("x_" + std::string(c.name));
    WriteRosbagDataset(original, bag, write);
    const Sequence read = ReadRosbagDataset(bag, Extract(extract));
    ExpectSameSequence(original, read);
    EXPECT_EQ(read.root, bag);
    for (size_t i = 0; i < read.ground_truth.size(); ++i) {  // bit for bit
      EXPECT_EQ(read.ground_truth[i].world_from_body.rotation.coeffs(),
                original.ground_truth[i].world_from_body.rotation.coeffs());
    }
    // The extract folder is a EuRoC folder of the same recording.
    EurocReadOptions euroc;
    ExpectSameSequence(original, ReadEurocDataset(extract, euroc));
  }
}

// ROS 2 bags recorded by others: the topics chosen as for a ROS 1 bag, the
// reasons given when they cannot be.
TEST(RosbagDataset, ReadsRos2BagsRecordedElsewhere) {
  VIOSFM_REQUIRE_DATASET(root, "ros2_bags");
  const fs::path folder = testing::MakeScratchFolder("rosbag_dataset_ros2");
  const fs::path sample = root / "image_imu" / "rosbag2js_sample.db3";
  RosbagDatasetOptions options = Extract(folder / "x");
  const std::string two = testing::InputErrorMessage([&] { ReadRosbagDataset(sample, options); });
  EXPECT_NE(two.find("2 image topics (/image, /image/compressed): choose one with --image-topic"),
            std::string::npos)
      << two;
  options.image_topic = "/image";
  options.rig = SensorRig();
  options.rig->camera = MakeCamera(CameraModelId::kPinhole, 640, 480, {500, 500, 320, 240});
  // One image stamped 0 (so stamped with its record time), one IMU sample
  // three days later: the IMU does not cover the image.
  const std::string coverage =
      testing::InputErrorMessage([&] { ReadRosbagDataset(sample, options); });
  EXPECT_NE(coverage.find("no IMU sample over the images"), std::string::npos) << coverage;
  options.imu_topic = "/image/compressed";
  const std::string wrong = testing::InputErrorMessage([&] { ReadRosbagDataset(sample, options); });
  EXPECT_NE(wrong.find("topic '/image/compressed' (--imu-topic) has type "
                       "sensor_msgs/CompressedImage, expected sensor_msgs/msg/Imu"),
            std::string::npos)
      << wrong;

  // The MCAP sample: one rgb8 image and one IMU sample at the same stamp.
  options = Extract(folder / "y");
  options.image_topic = "/image";
  options.rig = SensorRig();
  options.rig->camera = MakeCamera(CameraModelId::kPinhole, 640, 480, {500, 500, 320, 240});
  const Sequence sequence = ReadRosbagDataset(root / "image_imu" / "rerun_sensors.mcap", options);
  ASSERT_EQ(sequence.images.size(), 1u);
  EXPECT_EQ(sequence.images[0].timestamp_ns, 1757502238482648699);
  EXPECT_EQ(sequence.images[0].path.filename(), "1757502238482648699.png");
  const GreyImage grey = ReadGreyImage(sequence.images[0].path);
  EXPECT_EQ(grey.width, 640);
  EXPECT_EQ(grey.height, 480);
  ASSERT_EQ(sequence.imu.size(), 1u);
  EXPECT_EQ(sequence.imu[0].gyro, Eigen::Vector3d(0.1, 0.2, 0.3));
  EXPECT_EQ(sequence.imu[0].accel, Eigen::Vector3d(0, 0, 9.81));

  // A bag whose messages are not CDR, one without images.
  const fs::path wrong_rmw = root / "format" / "wrong_rmw_mcap";
  const std::string rmw =
      testing::InputErrorMessage([&] { ReadRosbagDataset(wrong_rmw, Extract(folder / "z")); });
  EXPECT_NE(rmw.find("wrong_format"), std::string::npos) << rmw;
  const fs::path imu_only = root / "broken" / "ros2_imu.mcap";
  const std::string no_image =
      testing::InputErrorMessage([&] { ReadRosbagDataset(imu_only, Extract(folder / "w")); });
  EXPECT_NE(no_image.find(imu_only.string() + ": no image topic"), std::string::npos) << no_image;
  EXPECT_NE(no_image.find("/vehicle/imu/data_raw (sensor_msgs/msg/Imu, 3 messages)"),
            std::string::npos)
      << no_image;
}

// A bag in EuRoC's conventions without embedded calibration (as EuRoC ships
// them) takes the calibration from the EuRoC folder beside it.
TEST(RosbagDataset, TakesTheCalibrationFromTheEurocFolderBesideTheBag) {
  const fs::path folder = testing::MakeScratchFolder("rosbag_dataset_beside");
  const Sequence original = MakeSequence(folder / "data");
  RosbagWriteOptions write;
  write.embed_calibration = false;
  const fs::path bag = folder / "data" / "seq.bag";
  WriteRosbagDataset(original, bag, write);
  const std::string no_calibration =
      testing::InputErrorMessage([&] { ReadRosbagDataset(bag, Extract(folder / "x1")); });
  EXPECT_NE(no_calibration.find("no camera calibration"), std::string::npos) << no_calibration;
  WriteEurocCameraYaml(folder / "data" / "mav0" / "cam0" / "sensor.yaml", original.rig.camera,
                       original.rig.body_from_cam, original.rig.camera_rate_hz);
  WriteEurocImuYaml(folder / "data" / "mav0" / "imu0" / "sensor.yaml", original.rig.imu_noise);
  ExpectSameSequence(original, ReadRosbagDataset(bag, Extract(folder / "x2")));

  // The calibration given in code wins (the hook for other calibration readers).
  RosbagDatasetOptions options = Extract(folder / "x3");
  options.rig = original.rig;
  options.rig->camera.params[0] = 50.0;
  EXPECT_EQ(ReadRosbagDataset(bag, options).rig.camera.params[0], 50.0);
}

TEST(RosbagDataset, ChoosesTopicsAndSaysWhyItCannot) {
  const fs::path folder = testing::MakeScratchFolder("rosbag_dataset_topics");
  const Sequence original = MakeSequence(folder / "data");
  // Two image topics, neither named /cam0/image_raw.
  const fs::path bag = folder / "two.bag";
  {
    RosbagWriter writer(bag);
    const uint32_t left = writer.AddConnection("/left/image", kRosImageType.name,
                                               kRosImageType.md5sum, kRosImageType.definition);
    const uint32_t right = writer.AddConnection("/right/image", kRosImageType.name,
                                                kRosImageType.md5sum, kRosImageType.definition);
    for (size_t i = 0; i < original.images.size(); ++i) {
      const GreyImage grey = ReadGreyImage(original.images[i].path);
      RosImage image;
      image.header.stamp_ns = original.images[i].timestamp_ns;
      image.width = 40;
      image.height = 30;
      image.step = 40;
      image.encoding = "mono8";
      image.data = grey.pixels;
      writer.Write(left, image.header.stamp_ns, SerializeRosImage(image));
      writer.Write(right, image.header.stamp_ns, SerializeRosImage(image));
    }
    writer.Close();
  }
  const std::string ambiguous =
      testing::InputErrorMessage([&] { ReadRosbagDataset(bag, Extract(folder / "x")); });
  EXPECT_NE(ambiguous.find("2 image topics (/left/image, /right/image): choose one with "
                           "--image-topic"),
            std::string::npos)
      << ambiguous;

  RosbagDatasetOptions options = Extract(folder / "x");
  options.image_topic = "/left/imag";
  const std::string missing = testing::InputErrorMessage([&] { ReadRosbagDataset(bag, options); });
  EXPECT_NE(missing.find("no topic '/left/imag' (--image-topic); the bag has:"), std::string::npos)
      << missing;
  EXPECT_NE(missing.find("/right/image (sensor_msgs/Image, 6 messages)"), std::string::npos)
      << missing;

  options.image_topic = "/left/image";
  options.imu_topic = "/right/image";
  const std::string wrong_type =
      testing::InputErrorMessage([&] { ReadRosbagDataset(bag, options); });
  EXPECT_NE(wrong_type.find("topic '/right/image' (--imu-topic) has type sensor_msgs/Image, "
                            "expected sensor_msgs/Imu"),
            std::string::npos)
      << wrong_type;

  options.imu_topic.clear();
  options.require_imu = true;
  const std::string no_imu = testing::InputErrorMessage([&] { ReadRosbagDataset(bag, options); });
  EXPECT_NE(no_imu.find("no IMU topic (sensor_msgs/Imu)"), std::string::npos) << no_imu;

  // With the topic and a calibration: camera only, no IMU.
  options.require_imu = false;
  WriteEurocCameraYaml(folder / "cam.yaml", original.rig.camera, original.rig.body_from_cam, 20);
  options.camera_yaml = folder / "cam.yaml";
  const Sequence read = ReadRosbagDataset(bag, options);
  EXPECT_EQ(read.images.size(), 6u);
  EXPECT_FALSE(read.has_imu());
}

// One-message bags with a bad image: the error names the bag, the byte
// offset, the topic and what is wrong.
std::string ReadOneImage(const fs::path& folder, const std::string& name, const RosImage& image,
                         const char* md5 = kRosImageType.md5sum) {
  const fs::path bag = folder / name;
  {
    RosbagWriter writer(bag);
    const uint32_t id =
        writer.AddConnection("/cam0/image_raw", kRosImageType.name, md5, kRosImageType.definition);
    writer.Write(id, image.header.stamp_ns, SerializeRosImage(image));
    writer.Close();
  }
  RosbagDatasetOptions options = Extract(folder / "x");
  options.rig = SensorRig();
  options.rig->camera = MakeCamera(CameraModelId::kPinhole, 4, 2, {5, 5, 2, 1});
  return testing::InputErrorMessage([&] { ReadRosbagDataset(bag, options); });
}

TEST(RosbagDataset, BadImagesGiveClearErrors) {
  const fs::path folder = testing::MakeScratchFolder("rosbag_dataset_bad_images");
  RosImage image;
  image.header.stamp_ns = kStart;
  image.width = 4;
  image.height = 2;
  image.encoding = "16UC1";
  image.step = 8;
  image.data.assign(16, 0);
  const std::string encoding = ReadOneImage(folder, "enc.bag", image);
  EXPECT_NE(encoding.find("enc.bag: byte offset "), std::string::npos) << encoding;
  EXPECT_NE(encoding.find("(/cam0/image_raw): sensor_msgs/Image encoding '16UC1' is not "
                          "supported (expected mono8, bgr8, rgb8, bgra8 or rgba8)"),
            std::string::npos)
      << encoding;

  image.encoding = "mono8";
  image.step = 4;
  image.data.assign(7, 0);
  const std::string size = ReadOneImage(folder, "size.bag", image);
  EXPECT_NE(size.find("data has 7 bytes, expected step x height = 4 x 2"), std::string::npos)
      << size;

  image.data.assign(8, 0);
  const std::string md5 =
      ReadOneImage(folder, "md5.bag", image, "0123456789abcdef0123456789abcdef");
  EXPECT_NE(md5.find("sensor_msgs/Image with MD5 sum 0123456789abcdef0123456789abcdef"),
            std::string::npos)
      << md5;

  image.width = 3;
  image.step = 3;
  image.data.assign(6, 0);
  const std::string calibration = ReadOneImage(folder, "calib.bag", image);
  EXPECT_NE(calibration.find("have 3x2 pixels, the calibration (the calibration given in code) "
                             "states 4x2"),
            std::string::npos)
      << calibration;
}

// Colour images become grey with the ITU-R 601 weights (0.299 R + 0.587 G +
// 0.114 B), in either channel order.
TEST(RosbagDataset, ConvertsColourImagesToGrey) {
  const fs::path folder = testing::MakeScratchFolder("rosbag_dataset_colour");
  const uint8_t r = 200, g = 100, b = 30;
  const double expected = 0.299 * r + 0.587 * g + 0.114 * b;
  for (const std::string encoding : {"rgb8", "bgr8"}) {
    RosImage image;
    image.header.stamp_ns = kStart;
    image.width = 4;
    image.height = 2;
    image.encoding = encoding;
    image.step = 12;
    for (int i = 0; i < 8; ++i) {
      if (encoding == "rgb8") {
        image.data.insert(image.data.end(), {r, g, b});
      } else {
        image.data.insert(image.data.end(), {b, g, r});
      }
    }
    const fs::path bag = folder / (encoding + ".bag");
    RosbagWriter writer(bag);
    const uint32_t id = writer.AddConnection("/cam0/image_raw", kRosImageType.name,
                                             kRosImageType.md5sum, kRosImageType.definition);
    writer.Write(id, kStart, SerializeRosImage(image));
    writer.Close();
    RosbagDatasetOptions options = Extract(folder / encoding);
    options.rig = SensorRig();
    options.rig->camera = MakeCamera(CameraModelId::kPinhole, 4, 2, {5, 5, 2, 1});
    const Sequence sequence = ReadRosbagDataset(bag, options);
    const GreyImage grey = ReadGreyImage(sequence.images[0].path);
    for (const uint8_t pixel : grey.pixels) EXPECT_NEAR(pixel, expected, 0.51) << encoding;
  }
}

TEST(RosbagDataset, DuplicateStampsAreAnError) {
  const fs::path folder = testing::MakeScratchFolder("rosbag_dataset_duplicates");
  Sequence sequence = MakeSequence(folder / "data");
  sequence.imu[5].timestamp_ns = sequence.imu[4].timestamp_ns;
  WriteRosbagDataset(sequence, folder / "dup.bag");
  const std::string message = testing::InputErrorMessage(
      [&] { ReadRosbagDataset(folder / "dup.bag", Extract(folder / "x")); });
  EXPECT_NE(message.find("topic '/imu0': two messages with the stamp"), std::string::npos)
      << message;
  EXPECT_NE(message.find("byte offset"), std::string::npos) << message;
}

// The real EuRoC excerpt, folder -> bag -> sequence: identical to reading
// the folder (pixels, stamps, IMU, calibration; ground-truth poses).
TEST(RosbagDataset, RealEurocExcerptRoundTrips) {
  VIOSFM_REQUIRE_DATASET(root, "euroc_v101_static_micro");
  const Sequence original = ReadEurocDataset(root);
  const fs::path folder = testing::MakeScratchFolder("rosbag_dataset_euroc");
  WriteRosbagDataset(original, folder / "v101.bag");
  const Sequence read = ReadRosbagDataset(folder / "v101.bag", Extract(folder / "x"));
  ExpectSameSequence(original, read);
}

// The real RealSense recording (JPEG images) as sensor_msgs/CompressedImage
// holding the JPEG files, in every container: read back, each image is the
// recording's JPEG file itself, under its name, and the grey pixels are the
// ones OpenCV decodes from the files (first 30 images, to stay fast).
TEST(RosbagDataset, RealJpegRecordingAsCompressedImages) {
  VIOSFM_REQUIRE_DATASET(root, "realsense_room_30s");
  Sequence original = ReadEurocDataset(root);
  original.images.resize(30);
  const fs::path folder = testing::MakeScratchFolder("rosbag_dataset_realsense");
  for (const char* name : {"rs.bag", "rs.db3", "rs.mcap"}) {
    SCOPED_TRACE(name);
    RosbagWriteOptions write;
    write.compressed_images = true;
    write.writer.compression =
        std::string(name) == "rs.db3" ? BagCompression::kZstd : BagCompression::kLz4;
    WriteRosbagDataset(original, folder / name, write);
    const Sequence read =
        ReadRosbagDataset(folder / name, Extract(folder / ("x_" + std::string(name))));
    ASSERT_EQ(read.images.size(), 30u);
    for (size_t i = 0; i < read.images.size(); ++i) {
      EXPECT_EQ(read.images[i].timestamp_ns, original.images[i].timestamp_ns);
      EXPECT_EQ(read.images[i].path.filename(), original.images[i].path.filename());
      EXPECT_TRUE(ReadTextFile(read.images[i].path) == ReadTextFile(original.images[i].path));
    }
    EXPECT_EQ(ReadGreyImage(read.images[29].path).pixels,
              ReadGreyImage(original.images[29].path).pixels);
    EXPECT_EQ(read.imu.size(), original.imu.size());
    EXPECT_EQ(read.rig.camera.params, original.rig.camera.params);
  }
}

// The real recording's calibration was written by others (a rotation
// matrix of 10 digits, not quite orthonormal): written from the rig and read
// again, its rotation changes in the last bit, and a run of the bag drifts
// from the folder's. Its own sensor.yaml files embedded as they are give the
// folder's rig bit for bit, in every container.
TEST(RosbagDataset, RealRecordingKeepsTheFolderCalibrationBitForBit) {
  VIOSFM_REQUIRE_DATASET(root, "realsense_room_30s");
  Sequence original = ReadEurocDataset(root);
  original.images.resize(10);
  const fs::path folder = testing::MakeScratchFolder("rosbag_dataset_calibration");
  RosbagWriteOptions write;
  UseEurocCalibrationTexts(root, &write);
  EXPECT_EQ(write.camera_yaml_text, ReadTextFile(root / "mav0" / "cam0" / "sensor.yaml"));
  EXPECT_EQ(write.imu_yaml_text, ReadTextFile(root / "mav0" / "imu0" / "sensor.yaml"));
  for (const char* name : {"rs.bag", "rs.db3", "rs.mcap"}) {
    SCOPED_TRACE(name);
    WriteRosbagDataset(original, folder / name, write);
    const Sequence read =
        ReadRosbagDataset(folder / name, Extract(folder / ("x_" + std::string(name))));
    EXPECT_EQ(read.rig.body_from_cam.rotation.coeffs(),
              original.rig.body_from_cam.rotation.coeffs());
    EXPECT_EQ(read.rig.body_from_cam.translation, original.rig.body_from_cam.translation);
    EXPECT_EQ(read.rig.camera.params, original.rig.camera.params);
    EXPECT_EQ(read.rig.camera_rate_hz, original.rig.camera_rate_hz);
    EXPECT_EQ(read.rig.imu_noise.gyro_noise_density, original.rig.imu_noise.gyro_noise_density);
    EXPECT_EQ(read.rig.imu_noise.gyro_random_walk, original.rig.imu_noise.gyro_random_walk);
    EXPECT_EQ(read.rig.imu_noise.accel_noise_density, original.rig.imu_noise.accel_noise_density);
    EXPECT_EQ(read.rig.imu_noise.accel_random_walk, original.rig.imu_noise.accel_random_walk);
    EXPECT_EQ(read.rig.imu_noise.rate_hz, original.rig.imu_noise.rate_hz);
    ASSERT_EQ(read.images.size(), 10u);
    EXPECT_EQ(ReadGreyImage(read.images[9].path).pixels,
              ReadGreyImage(original.images[9].path).pixels);
  }
}

}  // namespace
}  // namespace viosfm

#include "viosfm/io/ros_messages.h"

#include <gtest/gtest.h>

#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

// The layout of ROS 1 serialization written out by hand for a 2x1 mono8
// image: header (seq, sec, nsec, frame_id), height, width, encoding,
// is_bigendian, step, data.
TEST(RosMessages, ImageBytesFollowRosSerialization) {
  RosImage image;
  image.header = {7, 3'000'000'005, "c"};
  image.height = 1;
  image.width = 2;
  image.encoding = "mono8";
  image.step = 2;
  image.data = {0xAA, 0xBB};
  // clang-format off
  const std::vector<uint8_t> expected = {
      7,    0,    0,    0,                                  // seq
      3,    0,    0,    0,    5, 0, 0, 0,                   // stamp 3 s 5 ns
      1,    0,    0,    0,    'c',                          // frame_id
      1,    0,    0,    0,                                  // height
      2,    0,    0,    0,                                  // width
      5,    0,    0,    0,    'm', 'o', 'n', 'o', '8',      // encoding
      0,                                                    // is_bigendian
      2,    0,    0,    0,                                  // step
      2,    0,    0,    0,    0xAA, 0xBB};                  // data
  // clang-format on
  EXPECT_EQ(SerializeRosImage(image), expected);
  const RosImage back = DeserializeRosImage(expected, "test");
  EXPECT_EQ(back.header.stamp_ns, 3'000'000'005);
  EXPECT_EQ(back.header.frame_id, "c");
  EXPECT_EQ(back.data, image.data);
}

TEST(RosMessages, RoundTripEveryType) {
  RosImu imu;
  imu.header = {1, 12'345'678'901, "imu"};
  imu.angular_velocity = {0.1, -0.2, 0.3};
  imu.linear_acceleration = {1.0 / 3.0, 9.81, -1e-300};
  imu.orientation = Eigen::Quaterniond(0.5, -0.5, 0.5, -0.5);
  imu.angular_velocity_covariance(1, 2) = 4.0;
  const RosImu imu_back = DeserializeRosImu(SerializeRosImu(imu), "test");
  EXPECT_EQ(imu_back.angular_velocity, imu.angular_velocity);
  EXPECT_EQ(imu_back.linear_acceleration, imu.linear_acceleration);
  EXPECT_EQ(imu_back.orientation.coeffs(), imu.orientation.coeffs());
  EXPECT_EQ(imu_back.angular_velocity_covariance, imu.angular_velocity_covariance);
  EXPECT_EQ(SerializeRosImu(imu).size(), 4 + 8 + 4 + 3 + 4 * 8 + 3 * 9 * 8 + 2 * 3 * 8u);

  RosCompressedImage compressed;
  compressed.format = "jpeg";
  compressed.data = {1, 2, 3};
  const RosCompressedImage compressed_back =
      DeserializeRosCompressedImage(SerializeRosCompressedImage(compressed), "test");
  EXPECT_EQ(compressed_back.format, "jpeg");
  EXPECT_EQ(compressed_back.data, compressed.data);

  RosTransformStamped transform;
  transform.child_frame_id = "body";
  transform.transform = Rigid3d(Eigen::Quaterniond(0, 1, 0, 0), Eigen::Vector3d(1, 2, 3));
  const RosTransformStamped transform_back =
      DeserializeRosTransformStamped(SerializeRosTransformStamped(transform), "test");
  EXPECT_EQ(transform_back.child_frame_id, "body");
  EXPECT_EQ(transform_back.transform.translation, transform.transform.translation);
  EXPECT_EQ(transform_back.transform.rotation.coeffs(), transform.transform.rotation.coeffs());

  EXPECT_EQ(DeserializeRosString(SerializeRosString("a: b\nc"), "test"), "a: b\nc");
}

TEST(RosMessages, MalformedBytesNameTheFieldAndWhere) {
  RosImage image;
  image.encoding = "mono8";
  image.data.assign(100, 1);
  std::vector<uint8_t> bytes = SerializeRosImage(image);
  bytes.resize(bytes.size() - 10);
  const std::string short_message =
      testing::InputErrorMessage([&] { DeserializeRosImage(bytes, "x.bag: byte offset 9"); });
  EXPECT_NE(short_message.find("x.bag: byte offset 9: sensor_msgs/Image: data needs 100 bytes"),
            std::string::npos)
      << short_message;

  std::vector<uint8_t> longer = SerializeRosString("abc");
  longer.push_back(0);
  const std::string long_message =
      testing::InputErrorMessage([&] { DeserializeRosString(longer, "w"); });
  EXPECT_NE(long_message.find("1 bytes left after the message"), std::string::npos) << long_message;

  // An Imu read as an Image: the encoding length runs past the end.
  const std::vector<uint8_t> imu = SerializeRosImu(RosImu());
  EXPECT_NE(testing::InputErrorMessage([&] {
              DeserializeRosPoseStamped(imu, "w");
            }).find("geometry_msgs/PoseStamped"),
            std::string::npos);
}

}  // namespace
}  // namespace viosfm

#include "viosfm/io/cdr.h"

#include <gtest/gtest.h>

#include "viosfm/io/ros_messages.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

// Bytes spelled out by hand from the XCDR1 rules: a sensor_msgs/Image whose
// frame_id leaves `height` needing 3 bytes of padding.
std::vector<uint8_t> HandWrittenImage(bool big_endian) {
  const auto u32 = [big_endian](uint32_t v) {
    return big_endian ? std::vector<uint8_t>{uint8_t(v >> 24), uint8_t(v >> 16), uint8_t(v >> 8),
                                             uint8_t(v)}
                      : std::vector<uint8_t>{uint8_t(v), uint8_t(v >> 8), uint8_t(v >> 16),
                                             uint8_t(v >> 24)};
  };
  std::vector<uint8_t> bytes = {0x00, uint8_t(big_endian ? 0x00 : 0x01), 0x00, 0x00};
  const auto add = [&bytes](const std::vector<uint8_t>& more) {
    bytes.insert(bytes.end(), more.begin(), more.end());
  };
  add(u32(1700000000));  // stamp.sec (int32)        offset 0
  add(u32(123456789));   // stamp.nanosec             offset 4
  add(u32(2));           // frame_id length with NUL  offset 8
  add({'c', 0});         //                           offset 12
  add({0, 0});           // padding to 16
  add(u32(2));           // height                    offset 16
  add(u32(3));           // width                     offset 20
  add(u32(6));           // encoding "mono8" + NUL    offset 24
  add({'m', 'o', 'n', 'o', '8', 0});
  add({1});     // is_bigendian (uint8)      offset 34
  add({0});     // padding to 36
  add(u32(3));  // step                      offset 36
  add(u32(6));  // data length               offset 40
  add({1, 2, 3, 4, 5, 6});
  add({0, 0});  // the message padded to a multiple of 4
  return bytes;
}

TEST(Cdr, ReadsHandWrittenBytesInBothByteOrders) {
  for (const bool big_endian : {false, true}) {
    SCOPED_TRACE(big_endian ? "big-endian" : "little-endian");
    const RosImage image = DeserializeCdrImage(HandWrittenImage(big_endian), "hand");
    EXPECT_EQ(image.header.stamp_ns, 1700000000123456789);
    EXPECT_EQ(image.header.frame_id, "c");
    EXPECT_EQ(image.height, 2u);
    EXPECT_EQ(image.width, 3u);
    EXPECT_EQ(image.encoding, "mono8");
    EXPECT_EQ(image.is_bigendian, 1);
    EXPECT_EQ(image.step, 3u);
    EXPECT_EQ(image.data, (std::vector<uint8_t>{1, 2, 3, 4, 5, 6}));
  }
  // The writer gives the same bytes (little-endian, padded to 4).
  const RosImage image = DeserializeCdrImage(HandWrittenImage(false), "hand");
  EXPECT_EQ(SerializeCdrImage(image), HandWrittenImage(false));
}

// Doubles are aligned to 8 from the end of the encapsulation header: with
// frame_ids of every length mod 8, an Imu survives a round trip, and its
// size is the one the alignment rule gives.
TEST(Cdr, AlignsDoublesToEightAfterStringsOfEveryLength) {
  for (size_t length = 0; length < 9; ++length) {
    RosImu imu;
    imu.header.stamp_ns = 1553411909072940288;
    imu.header.frame_id = std::string(length, 'f');
    imu.orientation = Eigen::Quaterniond(0.9, 0.1, -0.2, 0.3);
    imu.angular_velocity = Eigen::Vector3d(1.0 / 3.0, -2, 3e-9);
    imu.linear_acceleration = Eigen::Vector3d(0, 0, 9.81);
    imu.orientation_covariance(0, 0) = -1;
    imu.angular_velocity_covariance(1, 2) = 0.25;
    const std::vector<uint8_t> bytes = SerializeCdrImu(imu);
    const size_t string_end = 12 + length + 1;  // stamp 8, length 4, chars and NUL
    const size_t doubles_start = (string_end + 7) / 8 * 8;
    EXPECT_EQ(bytes.size(), 4 + doubles_start + (4 + 9 + 3 + 9 + 3 + 9) * 8) << length;
    const RosImu back = DeserializeCdrImu(bytes, "imu");
    EXPECT_EQ(back.header.frame_id, imu.header.frame_id);
    EXPECT_EQ(back.header.stamp_ns, imu.header.stamp_ns);
    EXPECT_EQ(back.orientation.coeffs(), imu.orientation.coeffs());
    EXPECT_EQ(back.angular_velocity, imu.angular_velocity);
    EXPECT_EQ(back.linear_acceleration, imu.linear_acceleration);
    EXPECT_EQ(back.orientation_covariance, imu.orientation_covariance);
    EXPECT_EQ(back.angular_velocity_covariance, imu.angular_velocity_covariance);
  }
}

TEST(Cdr, RoundTripsEveryMessage) {
  RosCompressedImage compressed;
  compressed.header = {0, 5'000'000'001, "cam"};
  compressed.format = "jpeg";
  compressed.data = {0xff, 0xd8, 0xff};
  const RosCompressedImage compressed_back =
      DeserializeCdrCompressedImage(SerializeCdrCompressedImage(compressed), "c");
  EXPECT_EQ(compressed_back.format, "jpeg");
  EXPECT_EQ(compressed_back.data, compressed.data);
  EXPECT_EQ(compressed_back.header.stamp_ns, 5'000'000'001);

  RosPoseStamped pose;
  pose.header = {0, 7, "world"};
  pose.pose = Rigid3d(Eigen::Quaterniond(0.5, 0.5, -0.5, 0.5), Eigen::Vector3d(1, 2.5, -3));
  const RosPoseStamped pose_back = DeserializeCdrPoseStamped(SerializeCdrPoseStamped(pose), "p");
  EXPECT_EQ(pose_back.pose.translation, pose.pose.translation);
  EXPECT_EQ(pose_back.pose.rotation.coeffs(), pose.pose.rotation.coeffs());

  RosTransformStamped transform;
  transform.header = {0, 9, "odom"};
  transform.child_frame_id = "base_link";
  transform.transform.translation = Eigen::Vector3d(-1, 0, 4);
  const RosTransformStamped transform_back =
      DeserializeCdrTransformStamped(SerializeCdrTransformStamped(transform), "t");
  EXPECT_EQ(transform_back.child_frame_id, "base_link");
  EXPECT_EQ(transform_back.transform.translation, transform.transform.translation);

  for (const std::string text : {"", "a", "abc", "abcd", "hello world"}) {
    const std::vector<uint8_t> bytes = SerializeCdrString(text);
    EXPECT_EQ(bytes.size() % 4, 0u);
    EXPECT_EQ(DeserializeCdrString(bytes, "s"), text);
  }
}

TEST(Cdr, MalformedBytesNameTheFieldAndWhere) {
  std::vector<uint8_t> image = HandWrittenImage(false);
  // Cut inside data.
  const std::string cut = testing::InputErrorMessage([&] {
    DeserializeCdrImage(std::span<const uint8_t>(image).subspan(0, 40), "bag.db3, message 7");
  });
  EXPECT_NE(cut.find("bag.db3, message 7: sensor_msgs/msg/Image: step needs 4 bytes at message "
                     "offset 40, only 0 left"),
            std::string::npos)
      << cut;
  // An XCDR2 encapsulation.
  std::vector<uint8_t> xcdr2 = image;
  xcdr2[1] = 0x07;
  const std::string encapsulation =
      testing::InputErrorMessage([&] { DeserializeCdrImage(xcdr2, "w"); });
  EXPECT_NE(encapsulation.find("CDR encapsulation 00 07 (CDR2_LE, XCDR2) is not read"),
            std::string::npos)
      << encapsulation;
  // A string without its NUL.
  std::vector<uint8_t> no_nul = image;
  no_nul[13 + 4] = 'x';
  EXPECT_NE(testing::InputErrorMessage([&] {
              DeserializeCdrImage(no_nul, "w");
            }).find("header.frame_id: a string of 2 bytes without its terminating NUL"),
            std::string::npos);
  // Bytes beyond the padding.
  std::vector<uint8_t> longer = image;
  longer.insert(longer.end(), {0, 0, 0, 0});
  EXPECT_NE(testing::InputErrorMessage([&] {
              DeserializeCdrImage(longer, "w");
            }).find("6 bytes left after the message"),
            std::string::npos);
  // Nanoseconds of a second or more.
  std::vector<uint8_t> nanoseconds = image;
  nanoseconds[4 + 4 + 3] = 0x7f;
  EXPECT_NE(testing::InputErrorMessage([&] {
              DeserializeCdrImage(nanoseconds, "w");
            }).find("header.stamp.nanosec"),
            std::string::npos);
  // Too short for the encapsulation.
  EXPECT_NE(testing::InputErrorMessage([&] {
              DeserializeCdrString(std::vector<uint8_t>{0, 1}, "w");
            }).find("fewer than the 4 of a CDR encapsulation header"),
            std::string::npos);
}

TEST(Cdr, NormalizesRos2TypeNames) {
  EXPECT_EQ(NormalizeRos2TypeName("sensor_msgs/Image"), "sensor_msgs/msg/Image");
  EXPECT_EQ(NormalizeRos2TypeName("sensor_msgs/msg/Image"), "sensor_msgs/msg/Image");
  EXPECT_EQ(NormalizeRos2TypeName("Image"), "Image");
}

}  // namespace
}  // namespace viosfm

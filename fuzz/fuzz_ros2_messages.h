// The ROS 2 messages viosfm decodes (io/ros_messages.h, CDR), read from a
// fuzzed bag: every message of a known type is deserialised, and an
// accepted one must survive a serialise-deserialise round trip.
#pragma once

#include <span>
#include <string>

#include "fuzz_util.h"
#include "viosfm/io/ros_messages.h"

namespace viosfm::fuzz {

inline void ReadCdrMessage(const std::string& type, std::span<const uint8_t> data,
                           const std::string& where) {
  const std::string name = NormalizeRos2TypeName(type);
  if (name == kRos2ImageType.name) {
    RosImage image;
    if (!AcceptsInput([&] { image = DeserializeCdrImage(data, where); })) return;
    const RosImage again = DeserializeCdrImage(SerializeCdrImage(image), where);
    Require(again.data == image.data && again.encoding == image.encoding &&
                again.width == image.width && again.height == image.height &&
                again.step == image.step && again.header.stamp_ns == image.header.stamp_ns &&
                again.header.frame_id == image.header.frame_id,
            "an Image survives a round trip");
  } else if (name == kRos2CompressedImageType.name) {
    RosCompressedImage image;
    if (!AcceptsInput([&] { image = DeserializeCdrCompressedImage(data, where); })) return;
    const RosCompressedImage again =
        DeserializeCdrCompressedImage(SerializeCdrCompressedImage(image), where);
    Require(again.data == image.data && again.format == image.format,
            "a CompressedImage survives a round trip");
  } else if (name == kRos2ImuType.name) {
    RosImu imu;
    if (!AcceptsInput([&] { imu = DeserializeCdrImu(data, where); })) return;
    const RosImu again = DeserializeCdrImu(SerializeCdrImu(imu), where);
    Require(again.header.stamp_ns == imu.header.stamp_ns &&
                again.header.frame_id == imu.header.frame_id,
            "an Imu survives a round trip");
  } else if (name == kRos2PoseStampedType.name) {
    AcceptsInput([&] { DeserializeCdrPoseStamped(data, where); });
  } else if (name == kRos2TransformStampedType.name) {
    AcceptsInput([&] { DeserializeCdrTransformStamped(data, where); });
  } else if (name == kRos2StringType.name) {
    std::string text;
    if (!AcceptsInput([&] { text = DeserializeCdrString(data, where); })) return;
    Require(DeserializeCdrString(SerializeCdrString(text), where) == text,
            "a String survives a round trip");
  }
}

}  // namespace viosfm::fuzz

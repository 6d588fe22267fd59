// libFuzzer target: ROS 1 bags (io/rosbag.h) and the messages viosfm reads
// from them (io/ros_messages.h). The input is the bag file; every message
// of a known type is deserialised, and an accepted one must survive a
// serialise-deserialise round trip.
#include "fuzz_util.h"
#include "viosfm/io/ros_messages.h"
#include "viosfm/io/rosbag.h"

namespace {

using namespace viosfm;
using namespace viosfm::fuzz;

void ReadMessage(const RosbagMessage& message) {
  const std::string& type = message.connection->type;
  const std::string where = "fuzz.bag: " + message.location;
  if (type == "sensor_msgs/Image") {
    RosImage image;
    if (!AcceptsInput([&] { image = DeserializeRosImage(message.data, where); })) return;
    const RosImage again = DeserializeRosImage(SerializeRosImage(image), where);
    Require(again.data == image.data && again.encoding == image.encoding &&
                again.width == image.width && again.height == image.height &&
                again.step == image.step && again.header.stamp_ns == image.header.stamp_ns,
            "an Image survives a round trip");
  } else if (type == "sensor_msgs/CompressedImage") {
    RosCompressedImage image;
    if (!AcceptsInput([&] { image = DeserializeRosCompressedImage(message.data, where); })) return;
    const RosCompressedImage again =
        DeserializeRosCompressedImage(SerializeRosCompressedImage(image), where);
    Require(again.data == image.data && again.format == image.format,
            "a CompressedImage survives a round trip");
  } else if (type == "sensor_msgs/Imu") {
    RosImu imu;
    if (!AcceptsInput([&] { imu = DeserializeRosImu(message.data, where); })) return;
    const RosImu again = DeserializeRosImu(SerializeRosImu(imu), where);
    Require(again.header.stamp_ns == imu.header.stamp_ns, "an Imu survives a round trip");
  } else if (type == "geometry_msgs/PoseStamped") {
    AcceptsInput([&] { DeserializeRosPoseStamped(message.data, where); });
  } else if (type == "geometry_msgs/TransformStamped") {
    AcceptsInput([&] { DeserializeRosTransformStamped(message.data, where); });
  } else if (type == "std_msgs/String") {
    AcceptsInput([&] { DeserializeRosString(message.data, where); });
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::filesystem::path bag = ScratchFolder() / "fuzz.bag";
  WriteBytes(bag, AsText(data, size));
  AcceptsInput([&] {
    RosbagReader reader(bag);
    reader.ReadMessages([](const RosbagConnection&) { return true; },
                        [&](const RosbagMessage& message) {
                          Require(message.connection != nullptr, "a message has a connection");
                          ReadMessage(message);
                        });
  });
  return 0;
}

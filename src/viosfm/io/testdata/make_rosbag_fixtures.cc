// Writes the reference bags of io/rosbag_test.cc with ROS's own librosbag_storage
// and message types (Debian: librosbag-storage-dev, libsensor-msgs-dev,
// libgeometry-msgs-dev, libstd-msgs-dev), and reads any bag back through
// librosbag_storage to check bags viosfm writes.
//
//   write:  make_rosbag_fixtures write OUT_DIR
//   read:   make_rosbag_fixtures read BAG     (prints one line a message)
//
// The generated ROS 1 message headers need C++17 (they use
// std::allocator<void>::rebind, removed in C++20); build with the command in
// io/testdata/README.md.
#include <geometry_msgs/PoseStamped.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/Imu.h>
#include <std_msgs/String.h>

#include <cstdio>
#include <iostream>
#include <string>

namespace {

void Write(const std::string& path, rosbag::compression::CompressionType compression) {
  rosbag::Bag bag;
  bag.open(path, rosbag::bagmode::Write);
  bag.setCompression(compression);
  bag.setChunkThreshold(200);  // several chunks even for a few small messages
  std_msgs::String text;
  text.data = "hello bag";
  bag.write("/note", ros::Time(100, 0), text);
  for (int i = 0; i < 5; ++i) {
    const ros::Time stamp(100, 5000000 * i + 1);
    sensor_msgs::Imu imu;
    imu.header.seq = i;
    imu.header.stamp = stamp;
    imu.header.frame_id = "imu0";
    imu.angular_velocity.x = 0.1 * i;
    imu.angular_velocity.y = -0.25;
    imu.angular_velocity.z = 1.0 / 3.0;
    imu.linear_acceleration.x = 0.5;
    imu.linear_acceleration.y = -0.125 * i;
    imu.linear_acceleration.z = 9.81;
    imu.orientation_covariance[0] = -1;
    bag.write("/imu0", stamp, imu);
    if (i % 2 == 0) {
      sensor_msgs::Image image;
      image.header.seq = i / 2;
      image.header.stamp = stamp;
      image.header.frame_id = "cam0";
      image.height = 3;
      image.width = 4;
      image.encoding = "mono8";
      image.step = 4;
      for (int k = 0; k < 12; ++k) image.data.push_back(static_cast<uint8_t>(20 * i + k));
      bag.write("/cam0/image_raw", stamp, image);
    }
  }
  geometry_msgs::PoseStamped pose;
  pose.header.stamp = ros::Time(100, 7);
  pose.header.frame_id = "world";
  pose.pose.position.x = 1.5;
  pose.pose.position.y = -2.0;
  pose.pose.position.z = 0.25;
  pose.pose.orientation.w = 0.5;
  pose.pose.orientation.x = 0.5;
  pose.pose.orientation.y = 0.5;
  pose.pose.orientation.z = 0.5;
  bag.write("/groundtruth/pose", ros::Time(100, 7), pose);
  bag.close();
}

int Read(const std::string& path) {
  rosbag::Bag bag;
  bag.open(path, rosbag::bagmode::Read);
  rosbag::View view(bag);
  for (const rosbag::MessageInstance& m : view) {
    std::cout << m.getTopic() << " " << m.getDataType() << " " << m.getMD5Sum() << " "
              << m.getTime().sec << "." << m.getTime().nsec << " " << m.size();
    if (sensor_msgs::Image::ConstPtr image = m.instantiate<sensor_msgs::Image>()) {
      std::cout << " image " << image->width << "x" << image->height << " " << image->encoding
                << " stamp " << image->header.stamp << " sum ";
      unsigned long sum = 0;
      for (uint8_t v : image->data) sum += v;
      std::cout << sum;
    }
    if (sensor_msgs::Imu::ConstPtr imu = m.instantiate<sensor_msgs::Imu>()) {
      std::printf(" imu stamp %u.%09u gyro %.17g %.17g %.17g accel %.17g %.17g %.17g",
                  imu->header.stamp.sec, imu->header.stamp.nsec, imu->angular_velocity.x,
                  imu->angular_velocity.y, imu->angular_velocity.z, imu->linear_acceleration.x,
                  imu->linear_acceleration.y, imu->linear_acceleration.z);
      std::fflush(stdout);
    }
    if (std_msgs::String::ConstPtr text = m.instantiate<std_msgs::String>()) {
      std::cout << " string of " << text->data.size() << " chars";
    }
    if (geometry_msgs::PoseStamped::ConstPtr pose = m.instantiate<geometry_msgs::PoseStamped>()) {
      std::printf(" pose %.17g %.17g %.17g", pose->pose.position.x, pose->pose.position.y,
                  pose->pose.position.z);
      std::fflush(stdout);
    }
    std::cout << "\n";
  }
  bag.close();
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::cerr << "usage: make_rosbag_fixtures write OUT_DIR | read BAG\n";
    return 2;
  }
  const std::string mode = argv[1];
  try {
    if (mode == "write") {
      const std::string out = argv[2];
      Write(out + "/librosbag_none.bag", rosbag::compression::Uncompressed);
      Write(out + "/librosbag_bz2.bag", rosbag::compression::BZ2);
      Write(out + "/librosbag_lz4.bag", rosbag::compression::LZ4);
      return 0;
    }
    if (mode == "read") return Read(argv[2]);
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  }
  std::cerr << "unknown mode " << mode << "\n";
  return 2;
}

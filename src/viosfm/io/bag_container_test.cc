#include "viosfm/io/bag_container.h"

#include <gtest/gtest.h>

#include "viosfm/io/rosbag2.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {
namespace fs = std::filesystem;

TEST(BagContainer, TellsBagsByExtensionOrMetadataYaml) {
  const fs::path folder = testing::MakeScratchFolder("bag_container_paths");
  for (const char* name : {"a.bag", "a.BAG", "a.db3", "a.mcap", "a.db3.zstd", "a.mcap.zstd"}) {
    EXPECT_TRUE(HasBagExtension(name)) << name;
    EXPECT_TRUE(IsBagPath(folder / name)) << name;
  }
  for (const char* name : {"a.zstd", "a.db", "mav0", "a.bag.txt"}) {
    EXPECT_FALSE(HasBagExtension(name)) << name;
  }
  fs::create_directories(folder / "rosbag2");
  EXPECT_FALSE(IsBagPath(folder / "rosbag2"));
  testing::WriteTextFile(folder / "rosbag2" / "metadata.yaml",
                         "rosbag2_bagfile_information:\n  storage_identifier: mcap\n"
                         "  relative_file_paths: [r_0.mcap, r_1.mcap]\n");
  testing::WriteTextFile(folder / "rosbag2" / "r_0.mcap", "x");
  EXPECT_TRUE(IsBagPath(folder / "rosbag2"));
  // The files that make up the bag (the missing r_1.mcap is left out).
  const std::vector<fs::path> files = BagFiles(folder / "rosbag2");
  ASSERT_EQ(files.size(), 2u);
  EXPECT_EQ(files[0].filename(), "metadata.yaml");
  EXPECT_EQ(files[1].filename(), "r_0.mcap");
  EXPECT_EQ(BagFiles(folder / "x.db3"), std::vector<fs::path>{folder / "x.db3"});
}

// The container is told by the first bytes, whatever the name says.
TEST(BagContainer, OpensByContent) {
  const fs::path folder = testing::MakeScratchFolder("bag_container_content");
  {
    Rosbag2SqliteWriter writer(folder / "sqlite.db3", false);
    writer.AddTopic("/text", kRos2StringType);
    writer.Close();
  }
  fs::copy_file(folder / "sqlite.db3", folder / "named_mcap.mcap");
  fs::copy_file(folder / "sqlite.db3", folder / "named_ros1.bag");
  for (const char* name : {"sqlite.db3", "named_mcap.mcap", "named_ros1.bag"}) {
    const std::unique_ptr<BagReader> reader = OpenBag(folder / name);
    EXPECT_EQ(reader->format(), BagFormat::kRos2) << name;
    EXPECT_EQ(reader->Describe(), "ROS 2 bag (sqlite3, 1 file)") << name;
    ASSERT_EQ(reader->connections().size(), 1u);
    EXPECT_EQ(reader->connections()[0].type, "std_msgs/msg/String");
  }
  testing::WriteTextFile(folder / "text.bag", "hello, not a bag");
  EXPECT_NE(
      testing::InputErrorMessage([&] { OpenBag(folder / "text.bag"); }).find("not a ROS 1 bag"),
      std::string::npos);
  EXPECT_NE(testing::InputErrorMessage([&] {
              OpenBag(folder / "missing.mcap");
            }).find("bag file not found"),
            std::string::npos);
}

TEST(BagContainer, WriterOptionsNameWhatTheContainerTakes) {
  BagWriterOptions options;
  EXPECT_EQ(options.Validate("a.bag"), "");
  EXPECT_EQ(options.Validate("a.mcap"), "");
  EXPECT_NE(options.Validate("a.txt").find("a bag is written as .bag"), std::string::npos);
  EXPECT_NE(options.Validate("a.db3.zstd").find("a bag is written as .bag"), std::string::npos);
  options.compression = BagCompression::kZstd;
  EXPECT_NE(options.Validate("a.bag").find("none, bz2 or lz4"), std::string::npos);
  EXPECT_EQ(options.Validate("a.mcap"), "");
  EXPECT_EQ(options.Validate("a.db3"), "");
  options.compression = BagCompression::kLz4;
  EXPECT_NE(options.Validate("a.db3").find("zstd, or not at all"), std::string::npos);
  options.compression = BagCompression::kBz2;
  EXPECT_NE(options.Validate("a.mcap").find("none, zstd or lz4"), std::string::npos);
  EXPECT_EQ(ParseBagCompression("ZSTD"), BagCompression::kZstd);
  EXPECT_NE(testing::InputErrorMessage([] { ParseBagCompression("gzip"); }).find("gzip"),
            std::string::npos);
}

}  // namespace
}  // namespace viosfm

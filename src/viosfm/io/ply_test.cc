#include "viosfm/io/ply.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {
namespace fs = std::filesystem;
using ::testing::HasSubstr;

const char kBinaryHeader[] =
    "ply\n"
    "format binary_little_endian 1.0\n"
    "element vertex 3\n"
    "property double x\n"
    "property double y\n"
    "property double z\n"
    "property uchar red\n"
    "property uchar green\n"
    "property uchar blue\n"
    "end_header\n";

std::vector<Eigen::Vector3d> Points() {
  return {Eigen::Vector3d(1.5, -2.25, 3e10), Eigen::Vector3d(0.1, 1.0 / 3.0, -7e-12),
          Eigen::Vector3d(0, 0, 0)};
}
std::vector<Vector3ub> Colors() {
  return {Vector3ub(255, 0, 7), Vector3ub(1, 2, 3), Vector3ub(9, 8, 128)};
}

void WriteBytes(const fs::path& path, const std::string& bytes) {
  std::ofstream stream(path, std::ios::binary | std::ios::trunc);
  stream.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

std::string ReadError(const fs::path& path) {
  try {
    ReadPly(path);
  } catch (const InputError& error) {
    return error.what();
  }
  ADD_FAILURE() << "no InputError for " << path;
  return "";
}

TEST(PlyTest, BinaryRoundTripAndExactHeader) {
  const fs::path path = viosfm::testing::MakeScratchFolder("ply") / "points.ply";
  WritePlyPoints(path, Points(), Colors());
  const std::string bytes = ReadTextFile(path);
  const std::string header = kBinaryHeader;
  ASSERT_EQ(bytes.substr(0, header.size()), header);
  EXPECT_EQ(bytes.size(), header.size() + 3 * 27);
  // First vertex: x = 1.5 as a little-endian double, then the colour bytes.
  EXPECT_EQ(bytes.substr(header.size(), 8), std::string("\0\0\0\0\0\0\xf8\x3f", 8));
  EXPECT_EQ(bytes.substr(header.size() + 24, 3), std::string("\xff\x00\x07", 3));
  const PlyPoints read = ReadPly(path);
  EXPECT_EQ(read.xyz, Points());
  EXPECT_EQ(read.rgb, Colors());
}

TEST(PlyTest, AsciiRoundTripIsExact) {
  const fs::path path = viosfm::testing::MakeScratchFolder("ply") / "points.ply";
  WritePlyPoints(path, Points(), Colors(), /*binary=*/false);
  EXPECT_EQ(ReadTextFile(path),
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\n"
            "property double z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
            "end_header\n"
            "1.5 -2.25 30000000000 255 0 7\n"
            "0.10000000000000001 0.33333333333333331 -7.0000000000000001e-12 1 2 3\n"
            "0 0 0 9 8 128\n");
  const PlyPoints read = ReadPly(path);
  EXPECT_EQ(read.xyz, Points());
  EXPECT_EQ(read.rgb, Colors());
}

TEST(PlyTest, WithoutColours) {
  const fs::path path = viosfm::testing::MakeScratchFolder("ply") / "points.ply";
  WritePlyPoints(path, Points(), {});
  EXPECT_THAT(ReadTextFile(path), HasSubstr("property double z\nend_header\n"));
  const PlyPoints read = ReadPly(path);
  EXPECT_EQ(read.xyz, Points());
  EXPECT_TRUE(read.rgb.empty());
  EXPECT_THROW(WritePlyPoints(path, Points(), {Vector3ub(1, 2, 3)}), InternalError);
}

TEST(PlyTest, WritesReconstructionPoints) {
  Reconstruction reconstruction;
  reconstruction.AddPoint3DWithId(
      5, Point3D{Eigen::Vector3d(1, 2, 3), Vector3ub(10, 20, 30), 0.5, {}});
  reconstruction.AddPoint3DWithId(
      2, Point3D{Eigen::Vector3d(-1, 0, 4), Vector3ub(0, 0, 255), 0.5, {}});
  const fs::path path = viosfm::testing::MakeScratchFolder("ply") / "points.ply";
  WritePly(path, reconstruction);
  const PlyPoints read = ReadPly(path);
  ASSERT_EQ(read.xyz.size(), 2u);
  EXPECT_EQ(read.xyz[0], Eigen::Vector3d(1, 2, 3));  // point order
  EXPECT_EQ(read.rgb[1], Vector3ub(0, 0, 255));
}

// COLMAP's fused.ply layout: float positions and normals, uchar colours.
TEST(PlyTest, ReadsColmapFusedLayout) {
  const fs::path path = viosfm::testing::MakeScratchFolder("ply") / "fused.ply";
  std::string bytes =
      "ply\nformat binary_little_endian 1.0\ncomment written by a test\nelement vertex 1\n"
      "property float x\nproperty float y\nproperty float z\nproperty float nx\n"
      "property float ny\nproperty float nz\nproperty uchar red\nproperty uchar green\n"
      "property uchar blue\nend_header\n";
  for (const float value : {1.5f, -2.0f, 0.25f, 0.0f, 0.0f, 1.0f}) {
    const uint32_t bits = std::bit_cast<uint32_t>(value);
    for (int i = 0; i < 4; ++i) bytes.push_back(static_cast<char>((bits >> (8 * i)) & 0xff));
  }
  bytes += std::string("\x0a\x14\x1e", 3);
  WriteBytes(path, bytes);
  const PlyPoints read = ReadPly(path);
  ASSERT_EQ(read.xyz.size(), 1u);
  EXPECT_EQ(read.xyz[0], Eigen::Vector3d(1.5, -2.0, 0.25));
  EXPECT_EQ(read.rgb[0], Vector3ub(10, 20, 30));
}

TEST(PlyTest, Errors) {
  const fs::path folder = viosfm::testing::MakeScratchFolder("ply");
  const fs::path path = folder / "bad.ply";
  WritePlyPoints(path, Points(), Colors());
  const std::string bytes = ReadTextFile(path);
  WriteBytes(path, bytes.substr(0, bytes.size() - 5));
  EXPECT_THAT(ReadError(path), HasSubstr("bad.ply: truncated: 3 vertices of 27 bytes"));

  WriteBytes(path,
             "ply\nformat ascii 1.0\nelement vertex 1\nproperty double x\nproperty double y\n"
             "property double z\nend_header\n1 2 abc\n");
  EXPECT_THAT(ReadError(path),
              HasSubstr("bad.ply:8: expected a number for property z, found 'abc'"));

  WriteBytes(path,
             "ply\nformat ascii 1.0\nelement vertex 1\nproperty double x\nproperty double y\n"
             "end_header\n1 2\n");
  EXPECT_THAT(ReadError(path), HasSubstr("the vertex element has no property z"));

  WriteBytes(path, "solid cube\n");
  EXPECT_THAT(ReadError(path), HasSubstr("bad.ply:1: expected 'ply'"));
}

}  // namespace
}  // namespace viosfm

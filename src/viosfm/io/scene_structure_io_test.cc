#include "viosfm/io/scene_structure_io.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>

#include "viosfm/util/errors.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {
namespace fs = std::filesystem;
using ::testing::HasSubstr;

SceneStructure Example() {
  SceneStructureQuad a;
  a.id = 0;
  a.region = "floor1";
  a.floor = 0;
  a.texture_id = 3;
  a.origin = Eigen::Vector3d(-4, -4, 0);
  a.axis_u = Eigen::Vector3d(8, 0, 0);
  a.axis_v = Eigen::Vector3d(0, 0, 3);
  SceneStructureQuad b;
  b.id = 1;
  b.region = "none";
  b.floor = -1;
  b.texture_id = 0;
  b.origin = Eigen::Vector3d(0.1, 1.0 / 3.0, -7e-12);
  b.axis_u = Eigen::Vector3d(1e-3, 2.0 / 7.0, 0);
  b.axis_v = Eigen::Vector3d(0, 0, 3.5);
  return {a, b};
}

TEST(SceneStructureIoTest, RoundTripIsExact) {
  const fs::path folder = testing::MakeScratchFolder("scene_structure_io");
  const SceneStructure written = Example();
  WriteSceneStructure(folder / "scene.csv", written);
  const SceneStructure read = ReadSceneStructure(folder / "scene.csv");
  ASSERT_EQ(read.size(), written.size());
  for (size_t k = 0; k < read.size(); ++k) {
    EXPECT_EQ(read[k].id, written[k].id);
    EXPECT_EQ(read[k].region, written[k].region);
    EXPECT_EQ(read[k].floor, written[k].floor);
    EXPECT_EQ(read[k].texture_id, written[k].texture_id);
    EXPECT_EQ(read[k].origin, written[k].origin);
    EXPECT_EQ(read[k].axis_u, written[k].axis_u);
    EXPECT_EQ(read[k].axis_v, written[k].axis_v);
  }
}

TEST(SceneStructureIoTest, BadRowNamesFileLineAndColumn) {
  const fs::path folder = testing::MakeScratchFolder("scene_structure_io_bad");
  const fs::path path = folder / "scene.csv";
  {
    std::ofstream stream(path);
    stream << "# header\n0,room,0,1,0,0,0,1,0,0,0,1,0\n1,room,0,1,0,0,x,1,0,0,0,1,0\n";
  }
  try {
    ReadSceneStructure(path);
    FAIL() << "expected InputError";
  } catch (const InputError& error) {
    EXPECT_THAT(error.what(), HasSubstr("scene.csv"));
    EXPECT_THAT(error.what(), HasSubstr(":3"));
    EXPECT_THAT(error.what(), HasSubstr("origin_z"));
  }
  {
    std::ofstream stream(path);
    stream << "0,room,0,1,0,0,0\n";
  }
  EXPECT_THROW(ReadSceneStructure(path), InputError);
  EXPECT_THROW(ReadSceneStructure(folder / "missing.csv"), InputError);
}

}  // namespace
}  // namespace viosfm

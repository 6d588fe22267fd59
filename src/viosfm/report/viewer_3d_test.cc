#include "viosfm/report/viewer_3d.h"

#include <gtest/gtest.h>

#include "viosfm/util/testing.h"

namespace viosfm {
namespace {
namespace fs = std::filesystem;

TEST(Viewer3d, DecimationKeepsEveryKthPoint) {
  EXPECT_EQ(DecimationIndices(10, 3), (std::vector<size_t>{0, 4, 8}));
  EXPECT_EQ(DecimationIndices(4, 10), (std::vector<size_t>{0, 1, 2, 3}));
  EXPECT_EQ(DecimationIndices(1'000'001, 200'000).size(), 166'667u);  // k = 6
  EXPECT_TRUE(DecimationIndices(0, 5).empty());
}

// With a stand-in three.js: the scripts are embedded (a "</script" inside
// one is neutralised), the data is there, and at most max_points points.
TEST(Viewer3d, EmbedsScriptsAndData) {
  const fs::path folder = testing::MakeScratchFolder("viewer3d");
  fs::create_directories(folder / "examples" / "js" / "controls");
  testing::WriteTextFile(folder / "three.min.js", "var THREE={};var s='</script>';");
  testing::WriteTextFile(folder / "examples" / "js" / "controls" / "OrbitControls.js", "// oc");
  Viewer3dOptions options;
  options.three_js_dir = folder;
  options.max_points = 3;
  ASSERT_TRUE(HasThreeJs(options));
  Viewer3dScene scene;
  for (int i = 0; i < 10; ++i) scene.points.push_back(Eigen::Vector3d(1e6 + i, 2e6, 3.0));
  scene.path = {Eigen::Vector3d(1e6, 2e6, 3.0), Eigen::Vector3d(1e6 + 1, 2e6, 3.0)};
  scene.path_errors_m = {0.0, 0.02};
  const std::string html = RenderViewer3d(scene, options);
  EXPECT_NE(html.find("var s='<\\/script>';"), std::string::npos);
  EXPECT_EQ(html.find("var s='</script>'"), std::string::npos);
  EXPECT_NE(html.find("total_points: 10, num_points: 3, num_path: 2"), std::string::npos);
  EXPECT_NE(html.find("0 to 0.02 m"), std::string::npos);
  // The centre is the median of the kept points (1e6 + 4, 2e6, 3).
  EXPECT_NE(html.find("center: [1e+06, 2e+06, 3]"), std::string::npos);

  options.three_js_dir = folder / "absent";
  EXPECT_FALSE(HasThreeJs(options));
}

}  // namespace
}  // namespace viosfm

#include "viosfm/sim/pair_truth.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "viosfm/io/colmap_database.h"
#include "viosfm/sensor/camera_models.h"
#include "viosfm/sim/sequence_simulator.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

constexpr double kDegToRad = M_PI / 180.0;

Camera TestCamera() {
  return MakeCamera(CameraModelId::kPinhole, 752, 480, {458.654, 457.296, 367.215, 248.375});
}

SceneStructureQuad Quad(const Eigen::Vector3d& origin, const Eigen::Vector3d& u,
                        const Eigen::Vector3d& v) {
  SceneStructureQuad quad;
  quad.origin = origin;
  quad.axis_u = u;
  quad.axis_v = v;
  return quad;
}

// A closed 8 x 8 x 3 m room with its floor at height z0.
void AddRoom(double z0, SceneStructure* structure) {
  const Eigen::Vector3d ex(8, 0, 0), ey(0, 8, 0), ez(0, 0, 3);
  const Eigen::Vector3d corner(-4, -4, z0);
  structure->push_back(Quad(corner, ex, ey));       // floor
  structure->push_back(Quad(corner + ez, ex, ey));  // ceiling
  structure->push_back(Quad(corner, ex, ez));       // y = -4
  structure->push_back(Quad(corner + ey, ex, ez));  // y = +4
  structure->push_back(Quad(corner, ey, ez));       // x = -4
  structure->push_back(Quad(corner + ex, ey, ez));  // x = +4
  for (size_t k = 0; k < structure->size(); ++k) (*structure)[k].id = static_cast<int>(k);
}

// cam_from_world of a level camera at `position` looking along +y rotated by
// `yaw` about the vertical.
Rigid3d LevelCamFromWorld(const Eigen::Vector3d& position, double yaw) {
  Eigen::Matrix3d world_from_level;
  world_from_level << 1, 0, 0, 0, 0, 1, 0, -1, 0;  // columns: right, down, forward
  const Eigen::Matrix3d rotation =
      Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix() * world_from_level;
  return Rigid3d(rotation, position).Inverse();
}

PairTruthFrame Frame(const std::string& name, const Rigid3d& cam_from_world) {
  PairTruthFrame frame;
  frame.name = name;
  frame.cam_from_world = cam_from_world;
  return frame;
}

TEST(SceneRayCaster, NearestHitAndOcclusion) {
  SceneStructure structure;
  AddRoom(0.0, &structure);
  const SceneRayCaster caster(structure);
  const auto hit = caster.Cast(Eigen::Vector3d(0, 0, 1.5), Eigen::Vector3d(0, 1, 0));
  ASSERT_TRUE(hit);
  EXPECT_NEAR(*hit, 4.0, 1e-12);
  const auto down = caster.Cast(Eigen::Vector3d(1, 2, 1.5), Eigen::Vector3d(0, 0, -1));
  ASSERT_TRUE(down);
  EXPECT_NEAR(*down, 1.5, 1e-12);
  EXPECT_FALSE(caster.Cast(Eigen::Vector3d(0, 0, 10), Eigen::Vector3d(0, 0, 1)));
  const PairTruthOptions options;
  // A wall point seen from inside, and from outside the room through a wall.
  EXPECT_TRUE(caster.Unoccluded(Eigen::Vector3d(0, 0, 1.5), Eigen::Vector3d(1, 4, 1), options));
  EXPECT_FALSE(caster.Unoccluded(Eigen::Vector3d(0, 0, 1.5), Eigen::Vector3d(1, 6, 1), options));
}

TEST(PairTruthLabeller, CovisibilityOfSameOppositeAndStackedViews) {
  SceneStructure structure;
  AddRoom(0.0, &structure);
  AddRoom(3.65, &structure);  // an identical room one floor up
  const Eigen::Vector3d position(0.5, -1.0, 1.5);
  const Eigen::Vector3d floor_offset(0, 0, 3.65);
  std::vector<PairTruthFrame> frames = {
      Frame("a", LevelCamFromWorld(position, 0.0)),
      Frame("a_again", LevelCamFromWorld(position, 0.0)),
      Frame("back", LevelCamFromWorld(position, M_PI)),
      Frame("upstairs", LevelCamFromWorld(position + floor_offset, 0.0)),
      Frame("turned", LevelCamFromWorld(position, 30.0 * kDegToRad))};
  const PairTruthLabeller labeller(structure, TestCamera(), frames, PairTruthOptions());
  ASSERT_EQ(labeller.FindFrame("back"), 2u);
  EXPECT_FALSE(labeller.FindFrame("missing"));
  EXPECT_GT(labeller.Covisibility(0, 1), 0.99);
  EXPECT_EQ(labeller.Covisibility(0, 2), 0.0);  // opposite walls
  EXPECT_EQ(labeller.Covisibility(0, 3), 0.0);  // identical view, other floor
  // Turned by 30 degrees of a 78 degree field of view: about 60 % shared.
  const double turned = labeller.Covisibility(0, 4);
  EXPECT_GT(turned, 0.45);
  EXPECT_LT(turned, 0.75);
  EXPECT_NEAR(labeller.DirectedCovisibility(0, 4), labeller.DirectedCovisibility(4, 0), 0.1);
}

// Points on the far wall projected exactly into two views: every match
// agrees; the same keypoints paired with the wrong partners do not.
TEST(PairTruthLabeller, MatchAgreementOfExactAndWrongMatches) {
  SceneStructure structure;
  AddRoom(0.0, &structure);
  const Camera camera = TestCamera();
  const Rigid3d cam1_from_world = LevelCamFromWorld(Eigen::Vector3d(0, -1, 1.5), 0.0);
  const Rigid3d cam2_from_world =
      LevelCamFromWorld(Eigen::Vector3d(0.6, -0.5, 1.4), 8.0 * kDegToRad);
  const PairTruthLabeller labeller(structure, camera,
                                   {Frame("1", cam1_from_world), Frame("2", cam2_from_world)},
                                   PairTruthOptions());
  FeatureKeypoints keypoints1, keypoints2;
  FeatureMatches matches;
  for (double x = -2.0; x <= 2.0; x += 0.5) {
    for (double z = 0.5; z <= 2.5; z += 0.5) {
      const Eigen::Vector3d point(x, 4.0, z);
      const auto pixel1 = Project(camera, cam1_from_world * point);
      const auto pixel2 = Project(camera, cam2_from_world * point);
      ASSERT_TRUE(pixel1 && pixel2);
      const auto index = static_cast<point2D_t>(keypoints1.size());
      keypoints1.push_back(FeatureKeypoint::FromScaleOrientation(
          static_cast<float>(pixel1->x()), static_cast<float>(pixel1->y()), 2.0f, 0.0f));
      keypoints2.push_back(FeatureKeypoint::FromScaleOrientation(
          static_cast<float>(pixel2->x()), static_cast<float>(pixel2->y()), 2.0f, 0.0f));
      matches.push_back({index, index});
    }
  }
  ASSERT_EQ(matches.size(), 45u);
  EXPECT_EQ(labeller.MatchAgreement(0, 1, keypoints1, keypoints2, matches), 1.0);
  FeatureMatches wrong = matches;
  for (size_t i = 0; i < wrong.size(); ++i) {
    wrong[i].point2D_idx2 = matches[(i + 3) % matches.size()].point2D_idx2;
  }
  EXPECT_EQ(labeller.MatchAgreement(0, 1, keypoints1, keypoints2, wrong), 0.0);
  EXPECT_TRUE(std::isnan(labeller.MatchAgreement(0, 1, keypoints1, keypoints2, {})));
}

// Three frames: 1 and 2 on the ground floor, 3 exactly above 1 one floor up.
// Run "ransac" accepted (1, 2) with exact inliers and (1, 3) with
// zero-motion matches (identical views, which disagree with the truth); run
// "vio" accepted only (1, 2).
TEST(EvaluateVerificationRuns, CountsCorrectWrongAndRecall) {
  SceneStructure structure;
  AddRoom(0.0, &structure);
  AddRoom(3.65, &structure);
  const Camera camera = TestCamera();
  const Rigid3d cam1 = LevelCamFromWorld(Eigen::Vector3d(0, -1, 1.5), 0.0);
  const Rigid3d cam2 = LevelCamFromWorld(Eigen::Vector3d(0.5, -0.8, 1.5), 5.0 * kDegToRad);
  const Rigid3d cam3 = LevelCamFromWorld(Eigen::Vector3d(0, -1, 5.15), 0.0);
  const PairTruthLabeller labeller(
      structure, camera, {Frame("1.png", cam1), Frame("2.png", cam2), Frame("3.png", cam3)},
      PairTruthOptions());

  FeatureKeypoints keypoints1, keypoints2;
  FeatureMatches matches;
  for (double x = -2.0; x <= 2.0; x += 0.25) {
    for (double z = 0.5; z <= 2.5; z += 0.25) {
      const Eigen::Vector3d point(x, 4.0, z);
      const auto pixel1 = Project(camera, cam1 * point);
      const auto pixel2 = Project(camera, cam2 * point);
      if (!pixel1 || !pixel2) continue;
      const auto index = static_cast<point2D_t>(keypoints1.size());
      keypoints1.push_back(FeatureKeypoint::FromScaleOrientation(
          static_cast<float>(pixel1->x()), static_cast<float>(pixel1->y()), 2.0f, 0.0f));
      keypoints2.push_back(FeatureKeypoint::FromScaleOrientation(
          static_cast<float>(pixel2->x()), static_cast<float>(pixel2->y()), 2.0f, 0.0f));
      matches.push_back({index, index});
    }
  }
  ASSERT_GE(matches.size(), 100u);

  const auto folder = testing::MakeScratchFolder("pair_truth_evaluate");
  const auto make_database = [&](const std::string& name, bool accept_wrong) {
    const auto path = folder / name;
    ColmapDatabase database = ColmapDatabase::Open(path);
    const camera_t camera_id = database.WriteCamera(camera);
    const image_t id1 = database.WriteImage("1.png", camera_id);
    const image_t id2 = database.WriteImage("2.png", camera_id);
    const image_t id3 = database.WriteImage("3.png", camera_id);
    database.WriteKeypoints(id1, keypoints1);
    database.WriteKeypoints(id2, keypoints2);
    database.WriteKeypoints(id3, keypoints1);  // the same view one floor up
    TwoViewGeometry geometry;
    geometry.config = TwoViewGeometryConfig::kCalibrated;
    geometry.inlier_matches = matches;
    database.WriteTwoViewGeometry(id1, id2, geometry);
    if (accept_wrong) database.WriteTwoViewGeometry(id1, id3, geometry);
    return path;
  };
  const auto decision = [](image_t id2, const std::string& name2, bool accepted) {
    PairDecision d;
    d.image_id1 = 1;
    d.image_id2 = id2;
    d.name1 = "1.png";
    d.name2 = name2;
    d.accepted = accepted;
    return d;
  };
  const std::vector<VerificationRunInput> runs = {
      {"ransac",
       {decision(2, "2.png", true), decision(3, "3.png", true)},
       make_database("ransac.db", true)},
      {"vio",
       {decision(2, "2.png", true), decision(3, "3.png", false)},
       make_database("vio.db", false)}};
  const std::vector<VerificationTruthSummary> summaries = EvaluateVerificationRuns(labeller, runs);
  ASSERT_EQ(summaries.size(), 2u);
  EXPECT_EQ(summaries[0].num_candidates, 2u);
  EXPECT_EQ(summaries[0].num_correct_candidates, 1u);
  EXPECT_EQ(summaries[0].num_accepted, 2u);
  EXPECT_EQ(summaries[0].num_accepted_correct, 1u);
  EXPECT_EQ(summaries[0].num_accepted_wrong, 1u);
  ASSERT_EQ(summaries[0].wrong_pairs.size(), 1u);
  EXPECT_EQ(summaries[0].wrong_pairs[0].second, "3.png");
  EXPECT_EQ(summaries[0].recall_vs_baseline, 1.0);
  EXPECT_EQ(summaries[1].num_accepted, 1u);
  EXPECT_EQ(summaries[1].num_accepted_correct, 1u);
  EXPECT_EQ(summaries[1].num_accepted_wrong, 0u);
  EXPECT_EQ(summaries[1].num_baseline_correct, 1u);
  EXPECT_EQ(summaries[1].num_baseline_correct_kept, 1u);
  EXPECT_EQ(summaries[1].recall_vs_baseline, 1.0);
  const std::string table = FormatVerificationTruthTable(summaries);
  EXPECT_NE(table.find("| vio | 2 | 1 | 1 | 1 | 0 | 0 | 1/1 (100.0 %) |"), std::string::npos)
      << table;

  std::vector<VerificationRunInput> unknown = runs;
  unknown[1].decisions[0].name2 = "9.png";
  EXPECT_THROW(EvaluateVerificationRuns(labeller, unknown), InputError);
}

// A simulated two_floors sequence (motion and scene only) read back from its
// folder:
// consecutive frames share most of their view, and frames are named by
// their image file names.
TEST(PairTruthLabeller, FromSimulatedSequence) {
  SimulationOptions options;
  options.scenario = "two_floors";
  options.duration_s = 20.0;
  options.camera_rate_hz = 2.0;
  options.render_images = false;
  const SimulatedSequence simulated = SimulateSequence(options);
  const auto folder = testing::MakeScratchFolder("pair_truth_simulation");
  WriteSimulatedSequence(folder, simulated, options);
  // Without rendered images the simulator writes no image list; the labeller
  // needs only the stamps and names.
  WriteFileAtomically(folder / "mav0/cam0/data.csv", [&](std::ostream& out) {
    out << "#timestamp [ns],filename\n";
    for (const SequenceImage& image : simulated.sequence.images) {
      out << image.timestamp_ns << ',' << image.path.filename().string() << '\n';
    }
  });
  const PairTruthLabeller labeller = PairTruthLabeller::FromSimulation(folder, PairTruthOptions());
  ASSERT_EQ(labeller.frames().size(), simulated.sequence.images.size());
  const std::string first = simulated.sequence.images.front().path.filename().string();
  EXPECT_EQ(labeller.FindFrame(first), 0u);
  // The static start: identical poses.
  EXPECT_GT(labeller.Covisibility(0, 1), 0.99);
  int overlapping = 0;
  for (size_t k = 4; k + 1 < labeller.frames().size(); ++k) {
    if (labeller.Covisibility(k, k + 1) > 0.3) ++overlapping;
  }
  EXPECT_GE(overlapping, static_cast<int>(labeller.frames().size() - 5) * 8 / 10);
  EXPECT_THROW(PairTruthLabeller::FromSimulation(folder / "missing", PairTruthOptions()),
               InputError);
}

}  // namespace
}  // namespace viosfm

#include "viosfm/sfm/triangulator.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "viosfm/sensor/camera_models.h"
#include "viosfm/sfm/synthetic_test_scene.h"
#include "viosfm/sfm/tracks.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/random.h"

namespace viosfm {
namespace {

using ::testing::ElementsAre;
using testing::MakeSyntheticReconstruction;
using testing::MakeSyntheticScene;
using testing::ProjectToPixel;
using testing::SyntheticScene;

std::vector<TriangulationView> ExactViews(const SyntheticScene& scene,
                                          const Eigen::Vector3d& point) {
  std::vector<TriangulationView> views;
  for (const Rigid3d& cam_from_world : scene.cams_from_world) {
    views.push_back(
        {&scene.camera, cam_from_world, ProjectToPixel(scene.camera, cam_from_world, point)});
  }
  return views;
}

TEST(TriangulatorTest, ExactWithoutNoise) {
  const SyntheticScene scene = MakeSyntheticScene(5, 50, 1);
  for (const bool refine : {false, true}) {
    TriangulationOptions options;
    options.refine = refine;
    for (const Eigen::Vector3d& point : scene.points) {
      const std::optional<TrackTriangulation> result =
          TriangulateTrack(ExactViews(scene, point), options);
      ASSERT_TRUE(result.has_value());
      EXPECT_LT((result->point_in_world - point).norm(), 1e-9);
      EXPECT_THAT(result->inlier_views, ElementsAre(0, 1, 2, 3, 4));
      EXPECT_LT(result->mean_error_px, 1e-6);
      EXPECT_GE(result->max_angle_deg, 1.5);
    }
  }
}

// 0.5 px Gaussian noise, 5 views over a 2 m baseline, points 5 to 9 m away.
// First-order depth uncertainty of one point: z^2 / (f b_eff) * sigma with
// the views' spread b_eff ~ 1.6 m (rms over 5 views, sqrt(5)*0.71 m): at most
// 81 / (500 * 1.6) * 0.5 ~ 0.05 m at 9 m. Bounds: every point within 0.25 m
// (5 sigma at the far end), RMS over points below 0.06 m; refinement must
// not be worse than plain DLT in RMS pixel error.
TEST(TriangulatorTest, AccurateWithHalfPixelNoise) {
  const SyntheticScene scene = MakeSyntheticScene(5, 200, 2);
  Random random(3);
  double sum_sq_refined = 0.0;
  double sum_sq_dlt = 0.0;
  double sum_px_refined = 0.0;
  double sum_px_dlt = 0.0;
  for (const Eigen::Vector3d& point : scene.points) {
    std::vector<TriangulationView> views = ExactViews(scene, point);
    for (TriangulationView& view : views) {
      view.pixel += Eigen::Vector2d(random.Normal(0.0, 0.5), random.Normal(0.0, 0.5));
    }
    TriangulationOptions options;
    const std::optional<TrackTriangulation> refined = TriangulateTrack(views, options);
    options.refine = false;
    const std::optional<TrackTriangulation> dlt = TriangulateTrack(views, options);
    ASSERT_TRUE(refined.has_value());
    ASSERT_TRUE(dlt.has_value());
    EXPECT_EQ(refined->inlier_views.size(), 5u);
    const double error = (refined->point_in_world - point).norm();
    EXPECT_LT(error, 0.25);
    sum_sq_refined += error * error;
    sum_sq_dlt += (dlt->point_in_world - point).squaredNorm();
    for (double e : refined->errors_px) sum_px_refined += e * e;
    for (double e : dlt->errors_px) sum_px_dlt += e * e;
  }
  const double rms_refined = std::sqrt(sum_sq_refined / scene.points.size());
  EXPECT_LT(rms_refined, 0.06);
  EXPECT_LE(sum_px_refined, sum_px_dlt + 1e-9);
  RecordProperty("rms_refined_m", std::to_string(rms_refined));
  RecordProperty("rms_dlt_m", std::to_string(std::sqrt(sum_sq_dlt / scene.points.size())));
}

TEST(TriangulatorTest, RejectsTinyBaseline) {
  const Camera camera = testing::MakeDistortedTestCamera();
  const Eigen::Vector3d point(0.2, -0.1, 5.0);
  // 1 mm baseline at 5 m: 0.011 degrees.
  std::vector<TriangulationView> views;
  for (const double x : {0.0, 0.001}) {
    const Rigid3d cam_from_world = testing::CamFromWorldAt(Eigen::Vector3d(x, 0, 0), {0, 0, 0});
    views.push_back({&camera, cam_from_world, ProjectToPixel(camera, cam_from_world, point)});
  }
  EXPECT_FALSE(TriangulateTrack(views).has_value());
  TriangulationOptions options;
  options.min_angle_deg = 0.005;
  const std::optional<TrackTriangulation> result = TriangulateTrack(views, options);
  ASSERT_TRUE(result.has_value());
  EXPECT_NEAR(result->max_angle_deg, 0.001 / 5.0 * 180.0 / M_PI, 1e-4);
}

// The observation of a point behind a camera: the pinhole formula applied to
// a negative depth (a point on the same line of sight, mirrored).
Eigen::Vector2d PixelOfPointBehind(const Camera& camera, const Rigid3d& cam_from_world,
                                   const Eigen::Vector3d& point) {
  const Eigen::Vector3d point_in_cam = cam_from_world * point;
  EXPECT_LT(point_in_cam.z(), 0.0);
  return CamToImage(camera, point_in_cam.hnormalized());
}

TEST(TriangulatorTest, RejectsPointBehindTheCameras) {
  const SyntheticScene scene = MakeSyntheticScene(3, 0, 4);
  const Eigen::Vector3d point(0.3, 0.2, -6.0);  // behind all three cameras
  std::vector<TriangulationView> views;
  for (const Rigid3d& cam_from_world : scene.cams_from_world) {
    views.push_back(
        {&scene.camera, cam_from_world, PixelOfPointBehind(scene.camera, cam_from_world, point)});
  }
  EXPECT_FALSE(TriangulateTrack(views).has_value());
}

TEST(TriangulatorTest, DropsTheViewThatSeesThePointBehind) {
  SyntheticScene scene = MakeSyntheticScene(4, 0, 5);
  // A fifth camera beyond the point, looking along +z: the point is behind it.
  scene.cams_from_world.push_back(testing::CamFromWorldAt({0.0, 0.0, 12.0}, {0, 0, 0}));
  const Eigen::Vector3d point(0.1, 0.2, 7.0);
  std::vector<TriangulationView> views;
  for (size_t i = 0; i < 4; ++i) {
    views.push_back({&scene.camera, scene.cams_from_world[i],
                     ProjectToPixel(scene.camera, scene.cams_from_world[i], point)});
  }
  views.push_back({&scene.camera, scene.cams_from_world[4],
                   PixelOfPointBehind(scene.camera, scene.cams_from_world[4], point)});
  const std::optional<TrackTriangulation> result = TriangulateTrack(views);
  ASSERT_TRUE(result.has_value());
  EXPECT_THAT(result->inlier_views, ElementsAre(0, 1, 2, 3));
  EXPECT_LT((result->point_in_world - point).norm(), 1e-9);
}

TEST(TriangulatorTest, FallbackDropsOneGrossOutlierView) {
  const SyntheticScene scene = MakeSyntheticScene(6, 30, 6);
  for (size_t j = 0; j < scene.points.size(); ++j) {
    std::vector<TriangulationView> views = ExactViews(scene, scene.points[j]);
    const size_t bad = j % views.size();
    views[bad].pixel += Eigen::Vector2d(40.0, -25.0);
    const std::optional<TrackTriangulation> result = TriangulateTrack(views);
    ASSERT_TRUE(result.has_value()) << "point " << j;
    EXPECT_EQ(result->inlier_views.size(), 5u);
    EXPECT_EQ(std::count(result->inlier_views.begin(), result->inlier_views.end(), bad), 0);
    EXPECT_LT((result->point_in_world - scene.points[j]).norm(), 1e-9);
  }
}

TEST(TriangulatorTest, ReachesTriangulationAngleAgreesWithTheLargestAngle) {
  // Random camera centres around points near and far, thresholds around
  // their largest angles (and exactly at them): the early answer is the
  // comparison with MaxTriangulationAngle.
  Random random(31);
  int num_reached = 0;
  int num_cases = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const int num_centers = random.UniformInt(0, 40);
    std::vector<Eigen::Vector3d> centers;
    const double spread = random.Uniform(0.001, 2.0);
    for (int k = 0; k < num_centers; ++k) {
      centers.emplace_back(random.Uniform(-spread, spread), random.Uniform(-spread, spread),
                           random.Uniform(-spread, spread));
    }
    const Eigen::Vector3d point(random.Uniform(-1.0, 1.0), random.Uniform(-1.0, 1.0),
                                random.Uniform(1.0, 200.0));
    const double largest = MaxTriangulationAngle(centers, point);
    for (const double threshold : {0.0, 0.5 * largest, largest, largest * (1.0 + 1e-9),
                                   std::min(2.0 * largest + 1e-6, M_PI), 0.0261799}) {
      const bool reached = ReachesTriangulationAngle(centers, point, threshold);
      EXPECT_EQ(reached, largest >= threshold)
          << "trial " << trial << ", " << num_centers << " centres, threshold " << threshold;
      num_reached += reached ? 1 : 0;
      ++num_cases;
    }
  }
  // Both answers occur.
  EXPECT_GT(num_reached, num_cases / 4);
  EXPECT_LT(num_reached, num_cases);
}

TEST(TriangulatorTest, OptionsValidate) {
  TriangulationOptions options;
  EXPECT_TRUE(options.Check());
  options.max_reprojection_error_px = 0.0;
  EXPECT_THAT(options.Validate(), ::testing::HasSubstr("max_reprojection_error_px"));
  options = {};
  options.min_angle_deg = -1.0;
  EXPECT_THAT(options.Validate(), ::testing::HasSubstr("min_angle_deg"));
  EXPECT_THROW(TriangulateTrack({}, options), InternalError);
}

// Tracks of a synthetic scene: point j is keypoint j in every image, matched
// between consecutive images and images two apart.
std::vector<Track> SceneTracks(const SyntheticScene& scene) {
  std::vector<ImagePairMatches> pairs;
  const image_t num_images = static_cast<image_t>(scene.cams_from_world.size());
  for (image_t a = 1; a <= num_images; ++a) {
    for (image_t b = a + 1; b <= std::min(num_images, a + 2); ++b) {
      ImagePairMatches pair{a, b, {}};
      for (size_t j = 0; j < scene.points.size(); ++j) {
        pair.matches.push_back({static_cast<point2D_t>(j), static_cast<point2D_t>(j)});
      }
      pairs.push_back(std::move(pair));
    }
  }
  return BuildTracks(pairs).tracks;
}

TEST(TriangulatorTest, TriangulateReconstructionAddsPointsThenExtendsThem) {
  const SyntheticScene scene = MakeSyntheticScene(10, 200, 8);
  Reconstruction reconstruction = MakeSyntheticReconstruction(scene, 8);
  const std::vector<Track> tracks = SceneTracks(scene);
  ASSERT_EQ(tracks.size(), 200u);

  const TriangulationStatistics first =
      TriangulateReconstruction(&reconstruction, tracks, reconstruction.RegImageIds());
  EXPECT_EQ(first.num_tracks_tried, 200u);
  EXPECT_EQ(first.num_points_added, 200u);
  EXPECT_EQ(first.num_new_point_observations, 200u * 8);
  EXPECT_EQ(first.num_rejected_observations, 0u);
  ASSERT_EQ(reconstruction.NumPoints3D(), 200u);
  EXPECT_EQ(first.changed_point_ids, reconstruction.Point3DIds());  // the points added
  for (const point3D_t point3D_id : reconstruction.Point3DIds()) {
    const Point3D& point3D = reconstruction.GetPoint3D(point3D_id);
    ASSERT_EQ(point3D.track.size(), 8u);
    const point2D_t j = point3D.track.front().point2D_idx;
    EXPECT_LT((point3D.xyz - scene.points[j]).norm(), 1e-8);
    EXPECT_LT(point3D.error, 1e-6);
  }

  // A second call with the same images changes nothing.
  const TriangulationStatistics again =
      TriangulateReconstruction(&reconstruction, tracks, reconstruction.RegImageIds());
  EXPECT_EQ(again.num_points_added + again.num_extension_observations, 0u);
  EXPECT_TRUE(again.changed_point_ids.empty());

  // Register images 9 and 10: every point gains their two observations.
  reconstruction.GetImage(9).registered = true;
  reconstruction.GetImage(10).registered = true;
  const TriangulationStatistics second =
      TriangulateReconstruction(&reconstruction, tracks, reconstruction.RegImageIds());
  EXPECT_EQ(second.num_tracks_tried, 0u);
  EXPECT_EQ(second.num_points_added, 0u);
  EXPECT_EQ(second.num_points_extended, 200u);
  EXPECT_EQ(second.num_extension_observations, 400u);
  EXPECT_EQ(second.changed_point_ids, reconstruction.Point3DIds());  // the points extended
  EXPECT_EQ(reconstruction.NumPoints3D(), 200u);
  for (const point3D_t point3D_id : reconstruction.Point3DIds()) {
    EXPECT_EQ(reconstruction.GetPoint3D(point3D_id).track.size(), 10u);
  }
  EXPECT_EQ(reconstruction.ComputeNumObservations(), 2000u);
}

TEST(TriangulatorTest, TriangulateReconstructionSkipsBadObservations) {
  const SyntheticScene scene = MakeSyntheticScene(10, 40, 9);
  Reconstruction reconstruction = MakeSyntheticReconstruction(scene, 6);
  // Keypoint 0 of image 2 is a gross outlier; keypoint 1 of image 8 too (it
  // must not be attached when image 8 is registered).
  reconstruction.GetImage(2).points2D[0].xy += Eigen::Vector2d(30.0, 30.0);
  reconstruction.GetImage(8).points2D[1].xy += Eigen::Vector2d(-30.0, 20.0);
  const std::vector<Track> tracks = SceneTracks(scene);

  const TriangulationStatistics first =
      TriangulateReconstruction(&reconstruction, tracks, reconstruction.RegImageIds());
  EXPECT_EQ(first.num_points_added, 40u);
  EXPECT_EQ(first.num_rejected_observations, 1u);
  EXPECT_FALSE(reconstruction.GetImage(2).points2D[0].HasPoint3D());
  EXPECT_TRUE(reconstruction.GetImage(3).points2D[0].HasPoint3D());

  for (image_t id = 7; id <= 10; ++id) reconstruction.GetImage(id).registered = true;
  const TriangulationStatistics second =
      TriangulateReconstruction(&reconstruction, tracks, reconstruction.RegImageIds());
  EXPECT_EQ(second.num_extension_observations, 40u * 4 - 1);
  // The outlier of image 2 fails again, as does the new one of image 8.
  EXPECT_EQ(second.num_rejected_observations, 2u);
  EXPECT_FALSE(reconstruction.GetImage(8).points2D[1].HasPoint3D());
  EXPECT_TRUE(reconstruction.GetImage(9).points2D[1].HasPoint3D());
}

// Points made from the two halves of their tracks (images 1-5 and 6-10,
// before the matches between images 5, 6 and 7 were known) are joined
// once the whole tracks are known; a half that does not fit the other's
// point stays on its own.
TEST(TriangulatorTest, MergeTrackPointsJoinsTheHalvesOfATrack) {
  const SyntheticScene scene = MakeSyntheticScene(10, 40, 10);
  Reconstruction reconstruction = MakeSyntheticReconstruction(scene, 10);
  std::vector<ImagePairMatches> halves;
  for (image_t a = 1; a <= 10; ++a) {
    for (image_t b = a + 1; b <= std::min<image_t>(10, a + 2); ++b) {
      if ((a <= 5) != (b <= 5)) continue;
      ImagePairMatches pair{a, b, {}};
      for (size_t j = 0; j < scene.points.size(); ++j) {
        pair.matches.push_back({static_cast<point2D_t>(j), static_cast<point2D_t>(j)});
      }
      halves.push_back(std::move(pair));
    }
  }
  TriangulateReconstruction(&reconstruction, BuildTracks(halves).tracks,
                            reconstruction.RegImageIds());
  ASSERT_EQ(reconstruction.NumPoints3D(), 80u);
  // Point 0's first half made wrong: its other half cannot join it.
  const point3D_t wrong = reconstruction.GetImage(1).points2D[0].point3D_id;
  reconstruction.GetPoint3D(wrong).xyz += Eigen::Vector3d(0.3, 0.0, 0.0);

  const std::vector<point3D_t> merged_into = MergeTrackPoints(&reconstruction, SceneTracks(scene));
  EXPECT_EQ(merged_into.size(), 39u);
  EXPECT_EQ(reconstruction.NumPoints3D(), 41u);
  for (size_t j = 1; j < scene.points.size(); ++j) {
    const point3D_t id = reconstruction.GetImage(1).points2D[j].point3D_id;
    const Point3D& point3D = reconstruction.GetPoint3D(id);
    EXPECT_EQ(point3D.track.size(), 10u);
    EXPECT_EQ(reconstruction.GetImage(10).points2D[j].point3D_id, id);
    EXPECT_LT((point3D.xyz - scene.points[j]).norm(), 1e-8);
  }
  EXPECT_NE(reconstruction.GetImage(10).points2D[0].point3D_id, wrong);
  EXPECT_EQ(reconstruction.GetPoint3D(wrong).track.size(), 5u);
  EXPECT_EQ(reconstruction.ComputeNumObservations(), 400u);
  // Nothing left to join.
  EXPECT_EQ(MergeTrackPoints(&reconstruction, SceneTracks(scene)).size(), 0u);
}

// Points made from whole tracks, which later matches split into images 1-6
// and 7-10: each keeps its observations in the larger part; an observation
// no track holds goes too.
TEST(TriangulatorTest, SplitPointsByTracksKeepsEachPointWithinOneTrack) {
  const SyntheticScene scene = MakeSyntheticScene(10, 40, 11);
  Reconstruction reconstruction = MakeSyntheticReconstruction(scene, 10);
  TriangulateReconstruction(&reconstruction, SceneTracks(scene), reconstruction.RegImageIds());
  ASSERT_EQ(reconstruction.NumPoints3D(), 40u);
  std::vector<Track> split;
  for (size_t j = 0; j < scene.points.size(); ++j) {
    Track first;
    Track second;
    for (image_t id = 1; id <= 10; ++id) {
      // Point 0's keypoint of image 3 is in no track.
      if (j == 0 && id == 3) continue;
      (id <= 6 ? first : second).elements.push_back({id, static_cast<point2D_t>(j)});
    }
    split.push_back(first);
    split.push_back(second);
  }
  EXPECT_EQ(SplitPointsByTracks(&reconstruction, split), 40u * 4 + 1);
  EXPECT_EQ(reconstruction.NumPoints3D(), 40u);
  for (size_t j = 0; j < scene.points.size(); ++j) {
    const point3D_t id = reconstruction.GetImage(1).points2D[j].point3D_id;
    EXPECT_EQ(reconstruction.GetPoint3D(id).track.size(), j == 0 ? 5u : 6u);
    EXPECT_FALSE(reconstruction.GetImage(7).points2D[j].HasPoint3D());
  }
  EXPECT_FALSE(reconstruction.GetImage(3).points2D[0].HasPoint3D());
  // Consistent now: nothing more to split.
  EXPECT_EQ(SplitPointsByTracks(&reconstruction, split), 0u);
}

}  // namespace
}  // namespace viosfm

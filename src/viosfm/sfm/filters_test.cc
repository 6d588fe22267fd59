#include "viosfm/sfm/filters.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <set>

#include "viosfm/scene/reprojection.h"
#include "viosfm/sfm/synthetic_test_scene.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/random.h"

namespace viosfm {
namespace {

using testing::MakeSyntheticReconstruction;
using testing::MakeSyntheticScene;
using testing::ProjectToPixel;
using testing::SyntheticScene;

// Adds a point at `xyz` observed by keypoint `idx` of the given images (the
// keypoints are moved to its exact projections).
point3D_t AddExactPoint(Reconstruction* reconstruction, const Eigen::Vector3d& xyz,
                        const std::vector<image_t>& image_ids, point2D_t idx) {
  Point3D point3D;
  point3D.xyz = xyz;
  for (image_t image_id : image_ids) {
    Image& image = reconstruction->GetImage(image_id);
    image.points2D[idx].xy =
        ProjectToPixel(reconstruction->GetCamera(image.camera_id), image.cam_from_world, xyz);
    point3D.track.push_back({image_id, idx});
  }
  return reconstruction->AddPoint3D(point3D);
}

// 200 points seen by 10 images, 15 observations 5 to 20 px off on distinct
// points, one 3 px off (kept), a far point (removed by its angle) and a
// three-view point with two bad observations (removed).
struct InjectedScene {
  Reconstruction reconstruction;
  std::set<std::pair<image_t, point2D_t>> injected;
  point3D_t far_id = 0;
  point3D_t weak_id = 0;
};

InjectedScene MakeInjectedScene() {
  constexpr int kNumPoints = 200;
  constexpr int kNumImages = 10;
  SyntheticScene scene = MakeSyntheticScene(kNumImages, kNumPoints + 2, 11);
  InjectedScene out;
  out.reconstruction = MakeSyntheticReconstruction(scene, kNumImages);
  Reconstruction& reconstruction = out.reconstruction;
  for (int j = 0; j < kNumPoints; ++j) {
    Point3D point3D;
    point3D.xyz = scene.points[j];
    for (image_t id = 1; id <= kNumImages; ++id) {
      point3D.track.push_back({id, static_cast<point2D_t>(j)});
    }
    reconstruction.AddPoint3D(point3D);
  }
  // Far point (2 km, baseline 0.22 m: ~0.006 degrees): removed by the angle.
  out.far_id =
      AddExactPoint(&reconstruction, Eigen::Vector3d(10.0, 5.0, 2000.0), {1, 2}, kNumPoints);
  // A three-view point with two bad observations: removing them leaves one.
  out.weak_id =
      AddExactPoint(&reconstruction, Eigen::Vector3d(0.2, 0.1, 6.0), {3, 6, 9}, kNumPoints + 1);
  reconstruction.GetImage(6).points2D[kNumPoints + 1].xy += Eigen::Vector2d(8.0, 0.0);
  reconstruction.GetImage(9).points2D[kNumPoints + 1].xy += Eigen::Vector2d(0.0, -6.0);

  // 15 bad observations (5 to 20 px off) on distinct points.
  Random random(12);
  std::set<std::pair<image_t, point2D_t>>& injected = out.injected;
  // Keypoint kNumPoints - 1 gets a small offset below, not a bad one.
  std::set<point2D_t> used_points = {kNumPoints - 1};
  while (injected.size() < 15) {
    const point2D_t j = static_cast<point2D_t>(random.UniformInt(0, kNumPoints - 1));
    if (!used_points.insert(j).second) continue;
    const image_t id = static_cast<image_t>(random.UniformInt(1, kNumImages));
    const double angle = random.Uniform(0.0, 2.0 * M_PI);
    const double offset = random.Uniform(5.0, 20.0);
    reconstruction.GetImage(id).points2D[j].xy +=
        offset * Eigen::Vector2d(std::cos(angle), std::sin(angle));
    injected.insert({id, j});
  }
  // A good observation with 3 px of error stays (threshold 4 px).
  reconstruction.GetImage(5).points2D[kNumPoints - 1].xy += Eigen::Vector2d(3.0, 0.0);

  return out;
}

TEST(FiltersTest, RemovesInjectedBadObservationsAndOnlyThose) {
  constexpr int kNumPoints = 200;
  constexpr int kNumImages = 10;
  InjectedScene scene = MakeInjectedScene();
  Reconstruction& reconstruction = scene.reconstruction;
  const std::set<std::pair<image_t, point2D_t>>& injected = scene.injected;
  const point3D_t far_id = scene.far_id;
  const point3D_t weak_id = scene.weak_id;

  const PointFilterStatistics stats = FilterPoints(&reconstruction);
  EXPECT_EQ(stats.num_points_before, 202u);
  EXPECT_EQ(stats.num_observations_removed, 15u + 2u);
  EXPECT_EQ(stats.num_points_removed_few_observations, 1u);
  EXPECT_EQ(stats.num_points_removed_small_angle, 1u);
  EXPECT_EQ(stats.num_points_after, 200u);
  EXPECT_FALSE(reconstruction.ExistsPoint3D(far_id));
  EXPECT_FALSE(reconstruction.ExistsPoint3D(weak_id));
  EXPECT_FALSE(reconstruction.GetImage(3).points2D[kNumPoints + 1].HasPoint3D());

  // Exactly the injected observations are gone.
  for (image_t id = 1; id <= kNumImages; ++id) {
    const Image& image = reconstruction.GetImage(id);
    for (int j = 0; j < kNumPoints; ++j) {
      EXPECT_EQ(image.points2D[j].HasPoint3D(), injected.count({id, j}) == 0)
          << "image " << id << " keypoint " << j;
    }
  }
  EXPECT_EQ(reconstruction.ComputeNumObservations(), kNumPoints * kNumImages - 15u);
  // Errors are updated: 0 for exact points, 0.3 px mean for the 3 px one.
  for (const point3D_t point3D_id : reconstruction.Point3DIds()) {
    const Point3D& point3D = reconstruction.GetPoint3D(point3D_id);
    const bool has_offset = point3D.track.front().point2D_idx == kNumPoints - 1;
    EXPECT_NEAR(point3D.error, has_offset ? 0.3 : 0.0, 1e-6);
  }
}

// Every point's track (image, keypoint) and error, in id order.
std::vector<std::pair<std::vector<std::pair<image_t, point2D_t>>, double>> PointsOf(
    const Reconstruction& reconstruction) {
  std::vector<std::pair<std::vector<std::pair<image_t, point2D_t>>, double>> points;
  for (const point3D_t point3D_id : reconstruction.Point3DIds()) {
    const Point3D& point3D = reconstruction.GetPoint3D(point3D_id);
    std::vector<std::pair<image_t, point2D_t>> track;
    for (const TrackElement& element : point3D.track) {
      track.emplace_back(element.image_id, element.point2D_idx);
    }
    points.emplace_back(track, point3D.error);
  }
  return points;
}

TEST(FiltersTest, ThreadsGiveTheSameResult) {
  InjectedScene one = MakeInjectedScene();
  InjectedScene three = MakeInjectedScene();
  const PointFilterStatistics stats_one = FilterPoints(&one.reconstruction, {}, 1);
  const PointFilterStatistics stats_three = FilterPoints(&three.reconstruction, {}, 3);
  EXPECT_EQ(stats_one.Summary(), stats_three.Summary());
  EXPECT_EQ(stats_one.num_observations_removed, 17u);
  EXPECT_EQ(one.reconstruction.Point3DIds(), three.reconstruction.Point3DIds());
  EXPECT_EQ(PointsOf(one.reconstruction), PointsOf(three.reconstruction));
  EXPECT_EQ(MeanReprojectionError(one.reconstruction, 1),
            MeanReprojectionError(three.reconstruction, 3));
}

TEST(FiltersTest, StoresEachPointsErrorAsUpdateReprojectionErrorsDoes) {
  // Every keypoint 0.5 px off at random besides the injected errors: the
  // error each remaining point is left with is, bit for bit, what
  // UpdateReprojectionErrors computes on the filtered model.
  InjectedScene scene = MakeInjectedScene();
  Reconstruction& reconstruction = scene.reconstruction;
  Random random(5);
  for (const image_t image_id : reconstruction.RegImageIds()) {
    for (Point2D& point2D : reconstruction.GetImage(image_id).points2D) {
      point2D.xy += Eigen::Vector2d(random.Uniform(-0.5, 0.5), random.Uniform(-0.5, 0.5));
    }
  }
  FilterPoints(&reconstruction, {}, 2);
  Reconstruction recomputed = reconstruction;
  UpdateReprojectionErrors(&recomputed);
  ASSERT_GT(reconstruction.NumPoints3D(), 150u);
  for (const point3D_t point3D_id : reconstruction.Point3DIds()) {
    EXPECT_GT(reconstruction.GetPoint3D(point3D_id).error, 0.0);
    EXPECT_EQ(reconstruction.GetPoint3D(point3D_id).error, recomputed.GetPoint3D(point3D_id).error)
        << "point " << point3D_id;
  }
}

TEST(FiltersTest, MeanReprojectionErrorInImagesIsTheirObservationsMean) {
  // On the unfiltered injected scene: over every image it is the model's
  // mean; over images 2 and 7 the mean of their observations' errors,
  // computed here one by one; unknown ids are skipped; any thread count.
  const InjectedScene scene = MakeInjectedScene();
  const Reconstruction& reconstruction = scene.reconstruction;
  EXPECT_NEAR(MeanReprojectionErrorInImages(reconstruction, reconstruction.ImageIds(), 1),
              MeanReprojectionError(reconstruction, 1), 1e-12);
  double sum = 0.0;
  size_t count = 0;
  for (const image_t id : {image_t{2}, image_t{7}}) {
    const Image& image = reconstruction.GetImage(id);
    for (const Point2D& point2D : image.points2D) {
      if (!point2D.HasPoint3D()) continue;
      sum += ReprojectionErrorPx(reconstruction.GetCamera(image.camera_id), image.cam_from_world,
                                 reconstruction.GetPoint3D(point2D.point3D_id).xyz, point2D.xy);
      ++count;
    }
  }
  ASSERT_GT(count, 0u);
  ASSERT_GT(sum, 0.0);
  const double mean = MeanReprojectionErrorInImages(reconstruction, {2, 7, 999}, 1);
  EXPECT_NEAR(mean, sum / static_cast<double>(count), 1e-12);
  EXPECT_EQ(MeanReprojectionErrorInImages(reconstruction, {2, 7, 999}, 3), mean);
  EXPECT_EQ(MeanReprojectionErrorInImages(reconstruction, {}, 1), 0.0);
}

TEST(FiltersTest, FiltersOnlyTheGivenPointsAndTheRestLater) {
  InjectedScene whole = MakeInjectedScene();
  FilterPoints(&whole.reconstruction);
  InjectedScene parts = MakeInjectedScene();
  const std::vector<point3D_t> ids = parts.reconstruction.Point3DIds();
  const std::vector<point3D_t> first(ids.begin(), ids.begin() + ids.size() / 2);
  const std::vector<point3D_t> second(ids.begin() + ids.size() / 2, ids.end());
  const size_t observations_before = parts.reconstruction.ComputeNumObservations();

  // The first half: only its injected observations go.
  size_t injected_in_first = 0;
  for (const point3D_t point3D_id : first) {
    for (const TrackElement& element : parts.reconstruction.GetPoint3D(point3D_id).track) {
      injected_in_first += parts.injected.count({element.image_id, element.point2D_idx});
    }
  }
  ASSERT_GT(injected_in_first, 0u);
  const PointFilterStatistics stats = FilterPoints(&parts.reconstruction, {}, first, 2);
  EXPECT_EQ(stats.num_observations_removed, injected_in_first);
  EXPECT_EQ(parts.reconstruction.ComputeNumObservations(), observations_before - injected_in_first);
  EXPECT_TRUE(parts.reconstruction.ExistsPoint3D(parts.far_id));  // in the second half

  // Then the second half, and an id that no longer exists: as if filtered whole.
  std::vector<point3D_t> rest = second;
  rest.push_back(parts.weak_id);
  FilterPoints(&parts.reconstruction, {}, rest, 2);
  EXPECT_FALSE(parts.reconstruction.ExistsPoint3D(parts.far_id));
  EXPECT_EQ(PointsOf(parts.reconstruction), PointsOf(whole.reconstruction));
}

TEST(FiltersTest, IgnoresObservationsInUnregisteredImages) {
  const SyntheticScene scene = MakeSyntheticScene(4, 5, 13);
  Reconstruction reconstruction = MakeSyntheticReconstruction(scene, 3);  // image 4 not registered
  for (int j = 0; j < 5; ++j) {
    Point3D point3D;
    point3D.xyz = scene.points[j];
    for (image_t id = 1; id <= 4; ++id) point3D.track.push_back({id, static_cast<point2D_t>(j)});
    reconstruction.AddPoint3D(point3D);
  }
  reconstruction.GetImage(4).points2D[0].xy += Eigen::Vector2d(50.0, 0.0);
  reconstruction.GetImage(1).points2D[1].xy += Eigen::Vector2d(50.0, 0.0);
  EXPECT_EQ(FilterObservationsWithLargeReprojectionError(&reconstruction, 4.0,
                                                         reconstruction.Point3DIds()),
            1u);
  EXPECT_TRUE(reconstruction.GetImage(4).points2D[0].HasPoint3D());
  EXPECT_FALSE(reconstruction.GetImage(1).points2D[1].HasPoint3D());
}

TEST(FiltersTest, ObservedKeypointsCountWhatChangedNotWhatCameBack) {
  InjectedScene injected = MakeInjectedScene();
  Reconstruction& reconstruction = injected.reconstruction;
  std::vector<image_t> image_ids;
  for (image_t id = 1; id <= 10; ++id) image_ids.push_back(id);
  const size_t observations_before = reconstruction.ComputeNumObservations();
  const ObservedKeypoints before(reconstruction, image_ids);
  EXPECT_EQ(before.CountChanged(reconstruction), 0u);

  FilterPoints(&reconstruction, PointFilterOptions());
  const size_t removed = observations_before - reconstruction.ComputeNumObservations();
  // 15 injected, the far point's 2 and the weak point's 3.
  EXPECT_EQ(removed, 20u);
  EXPECT_EQ(before.CountChanged(reconstruction), removed);

  // One of the injected observations put back on its point: no longer a
  // change.
  const auto [image_id, idx] = *injected.injected.begin();
  point3D_t point_id = kInvalidPoint3DId;
  for (image_t other = 1; other <= 10; ++other) {
    const Point2D& point2D = reconstruction.GetImage(other).points2D[idx];
    if (other != image_id && point2D.HasPoint3D()) point_id = point2D.point3D_id;
  }
  ASSERT_NE(point_id, kInvalidPoint3DId);
  reconstruction.AddObservation(point_id, {image_id, idx});
  EXPECT_EQ(before.CountChanged(reconstruction), removed - 1);

  // Two keypoints that observed nothing now observing a new point: two
  // changes.
  Point3D point3D;
  point3D.xyz = Eigen::Vector3d(0.0, 0.0, 5.0);
  point3D.track = {{1, 201}, {2, 201}};
  ASSERT_FALSE(reconstruction.GetImage(1).points2D[201].HasPoint3D());
  reconstruction.AddPoint3D(point3D);
  EXPECT_EQ(before.CountChanged(reconstruction), removed + 1);
}

TEST(FiltersTest, OptionsValidate) {
  PointFilterOptions options;
  EXPECT_TRUE(options.Check());
  options.max_reprojection_error_px = -1.0;
  EXPECT_THAT(options.Validate(), ::testing::HasSubstr("max_reprojection_error_px"));
  Reconstruction reconstruction;
  EXPECT_THROW(FilterPoints(&reconstruction, options), InternalError);
}

}  // namespace
}  // namespace viosfm

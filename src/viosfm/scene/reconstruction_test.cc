#include "viosfm/scene/reconstruction.h"

#include <gtest/gtest.h>

#include "viosfm/util/errors.h"

namespace viosfm {
namespace {

Camera MakeCamera(camera_t id) {
  Camera camera;
  camera.camera_id = id;
  camera.model_id = CameraModelId::kPinhole;
  camera.width = 640;
  camera.height = 480;
  camera.params = {500, 500, 320, 240};
  return camera;
}

Image MakeImage(image_t id, const std::string& name, int num_points2D) {
  Image image;
  image.image_id = id;
  image.camera_id = 1;
  image.name = name;
  image.registered = true;
  for (int i = 0; i < num_points2D; ++i) {
    Point2D point2D;
    point2D.xy = Eigen::Vector2d(10.0 * i, 5.0 * i);
    image.points2D.push_back(point2D);
  }
  return image;
}

// Two images of 4 keypoints each, one camera.
Reconstruction MakeScene() {
  Reconstruction reconstruction;
  reconstruction.AddCamera(MakeCamera(1));
  reconstruction.AddImage(MakeImage(7, "b.png", 4));
  reconstruction.AddImage(MakeImage(3, "a.png", 4));
  return reconstruction;
}

TEST(ReconstructionTest, KeepsInsertionOrder) {
  Reconstruction reconstruction = MakeScene();
  reconstruction.AddCamera(MakeCamera(9));
  reconstruction.AddCamera(MakeCamera(2));
  EXPECT_EQ(reconstruction.CameraIds(), (std::vector<camera_t>{1, 9, 2}));
  EXPECT_EQ(reconstruction.ImageIds(), (std::vector<image_t>{7, 3}));
  reconstruction.ReorderImages({3, 7});
  EXPECT_EQ(reconstruction.ImageIds(), (std::vector<image_t>{3, 7}));
  EXPECT_THROW(reconstruction.ReorderImages({3}), InternalError);
  EXPECT_THROW(reconstruction.ReorderImages({3, 3}), InternalError);
}

TEST(ReconstructionTest, PointsKeepKeypointsAndTracksConsistent) {
  Reconstruction reconstruction = MakeScene();
  Point3D point;
  point.xyz = Eigen::Vector3d(1, 2, 3);
  point.track = {{7, 0}, {3, 2}};
  const point3D_t id1 = reconstruction.AddPoint3D(point);
  EXPECT_EQ(id1, 1u);
  EXPECT_EQ(reconstruction.GetImage(7).points2D[0].point3D_id, id1);
  EXPECT_EQ(reconstruction.GetImage(3).points2D[2].point3D_id, id1);
  EXPECT_EQ(reconstruction.GetImage(7).NumPoints3D(), 1u);

  // A keypoint can observe only one point.
  point.track = {{7, 0}, {3, 1}};
  EXPECT_THROW(reconstruction.AddPoint3D(point), InternalError);
  EXPECT_FALSE(reconstruction.GetImage(3).points2D[1].HasPoint3D());

  reconstruction.AddPoint3DWithId(
      10, Point3D{Eigen::Vector3d(0, 0, 1), Vector3ub(1, 2, 3), 0.5, {{7, 1}, {3, 1}}});
  EXPECT_EQ(reconstruction.AddPoint3D(Point3D{}), 11u);  // one more than the largest id
  reconstruction.AddObservation(id1, {7, 3});
  EXPECT_EQ(reconstruction.GetPoint3D(id1).track.size(), 3u);
  EXPECT_EQ(reconstruction.GetImage(7).points2D[3].point3D_id, id1);
  EXPECT_EQ(reconstruction.ComputeNumObservations(), 5u);
  EXPECT_DOUBLE_EQ(reconstruction.ComputeMeanTrackLength(), 5.0 / 3.0);
  EXPECT_DOUBLE_EQ(reconstruction.ComputeMeanObservationsPerRegImage(), 2.5);

  reconstruction.DeleteObservation(7, 0);
  EXPECT_FALSE(reconstruction.GetImage(7).points2D[0].HasPoint3D());
  EXPECT_EQ(reconstruction.GetPoint3D(id1).track, (std::vector<TrackElement>{{3, 2}, {7, 3}}));
  // A point left with one observation is deleted and its keypoints freed.
  reconstruction.DeleteObservation(3, 2);
  EXPECT_FALSE(reconstruction.ExistsPoint3D(id1));
  EXPECT_FALSE(reconstruction.GetImage(7).points2D[3].HasPoint3D());

  reconstruction.DeletePoint3D(10);
  EXPECT_FALSE(reconstruction.GetImage(7).points2D[1].HasPoint3D());
  EXPECT_FALSE(reconstruction.GetImage(3).points2D[1].HasPoint3D());
  EXPECT_EQ(reconstruction.Point3DIds(), (std::vector<point3D_t>{11}));
  EXPECT_EQ(reconstruction.ComputeNumObservations(), 0u);
}

TEST(ReconstructionTest, ImageByNameAndProjectionCenter) {
  Reconstruction reconstruction = MakeScene();
  Image& image = reconstruction.GetImage(3);
  image.cam_from_world =
      Rigid3d(Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ())),
              Eigen::Vector3d(1, 2, 3));
  ASSERT_NE(reconstruction.ImageByName("a.png"), nullptr);
  EXPECT_EQ(reconstruction.ImageByName("a.png")->image_id, 3u);
  EXPECT_EQ(reconstruction.ImageByName("c.png"), nullptr);
  // The centre maps to the camera origin.
  EXPECT_LT((image.cam_from_world * image.ProjectionCenter()).norm(), 1e-12);
  EXPECT_THROW(reconstruction.AddImage(MakeImage(8, "a.png", 0)), InternalError);
  EXPECT_THROW(reconstruction.AddImage(MakeImage(3, "z.png", 0)), InternalError);
}

TEST(ReconstructionTest, TimestampFromImageName) {
  EXPECT_EQ(TimestampFromImageName("1403715273262142976.png"), 1403715273262142976);
  EXPECT_EQ(TimestampFromImageName("cam0/data/1403715273262142976.png"), 1403715273262142976);
  EXPECT_EQ(TimestampFromImageName("0"), 0);
  EXPECT_EQ(TimestampFromImageName("0004.jpg"), std::nullopt);
  EXPECT_EQ(TimestampFromImageName("img12.jpg"), std::nullopt);
  EXPECT_EQ(TimestampFromImageName(".png"), std::nullopt);
  EXPECT_EQ(TimestampFromImageName("9999999999999999999.png"), std::nullopt);  // > int64
}

}  // namespace
}  // namespace viosfm

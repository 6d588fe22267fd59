// A synthetic multi-view scene with a known answer for the sfm tests
// (header-only; not part of the library's API): cameras on a line looking
// along +z with small random rotations, points in a box in front of them,
// and a Reconstruction whose image i has keypoint j at the exact projection
// of point j.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "viosfm/geometry/rigid3.h"
#include "viosfm/scene/reconstruction.h"
#include "viosfm/sensor/camera_models.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/random.h"

namespace viosfm::testing {

// OPENCV model with mild radial-tangential distortion, so that the
// triangulation must undistort.
inline Camera MakeDistortedTestCamera(camera_t camera_id = 1) {
  Camera camera = MakeCamera(CameraModelId::kOpenCV, 640, 480,
                             {500.0, 505.0, 320.0, 240.0, -0.1, 0.01, 0.001, -0.0005});
  camera.camera_id = camera_id;
  return camera;
}

// The pose of a camera at `center` rotated by the angle-axis vector
// `rotation_vector` (world_from_cam rotation).
inline Rigid3d CamFromWorldAt(const Eigen::Vector3d& center,
                              const Eigen::Vector3d& rotation_vector) {
  const double angle = rotation_vector.norm();
  const Eigen::Matrix3d world_from_cam =
      angle > 0.0 ? Eigen::AngleAxisd(angle, rotation_vector / angle).toRotationMatrix()
                  : Eigen::Matrix3d::Identity();
  const Eigen::Matrix3d cam_from_world = world_from_cam.transpose();
  return Rigid3d(cam_from_world, -cam_from_world * center);
}

inline Eigen::Vector2d ProjectToPixel(const Camera& camera, const Rigid3d& cam_from_world,
                                      const Eigen::Vector3d& point_in_world) {
  const std::optional<Eigen::Vector2d> pixel = Project(camera, cam_from_world * point_in_world);
  VIOSFM_CHECK(pixel.has_value()) << "test point behind a camera";
  return *pixel;
}

struct SyntheticScene {
  Camera camera;
  std::vector<Rigid3d> cams_from_world;
  std::vector<Eigen::Vector3d> points;
};

// Cameras with centres spread evenly over x in [-1, 1] m (jitter +-0.1 m in
// y and z, rotations up to ~3 degrees); points uniform in
// [-1.5, 1.5] x [-1, 1] x [5, 9] m, all in front of every camera.
inline SyntheticScene MakeSyntheticScene(int num_cameras, int num_points, uint64_t seed) {
  Random random(seed);
  SyntheticScene scene;
  scene.camera = MakeDistortedTestCamera();
  for (int i = 0; i < num_cameras; ++i) {
    const double x = num_cameras > 1 ? -1.0 + 2.0 * i / (num_cameras - 1) : 0.0;
    const Eigen::Vector3d center(x, random.Uniform(-0.1, 0.1), random.Uniform(-0.1, 0.1));
    const Eigen::Vector3d rotation(random.Uniform(-0.05, 0.05), random.Uniform(-0.05, 0.05),
                                   random.Uniform(-0.05, 0.05));
    scene.cams_from_world.push_back(CamFromWorldAt(center, rotation));
  }
  for (int j = 0; j < num_points; ++j) {
    scene.points.emplace_back(random.Uniform(-1.5, 1.5), random.Uniform(-1.0, 1.0),
                              random.Uniform(5.0, 9.0));
  }
  return scene;
}

// Image ids 1..N ("image<i>.png"), camera id 1, keypoint j of every image at
// the exact projection of scene.points[j]; no 3D points. Images whose index
// is below num_registered are registered.
inline Reconstruction MakeSyntheticReconstruction(const SyntheticScene& scene,
                                                  size_t num_registered) {
  Reconstruction reconstruction;
  reconstruction.AddCamera(scene.camera);
  for (size_t i = 0; i < scene.cams_from_world.size(); ++i) {
    Image image;
    image.image_id = static_cast<image_t>(i + 1);
    image.camera_id = scene.camera.camera_id;
    image.name = "image" + std::to_string(i + 1) + ".png";
    image.cam_from_world = scene.cams_from_world[i];
    image.registered = i < num_registered;
    for (const Eigen::Vector3d& point : scene.points) {
      Point2D point2D;
      point2D.xy = ProjectToPixel(scene.camera, scene.cams_from_world[i], point);
      image.points2D.push_back(point2D);
    }
    reconstruction.AddImage(std::move(image));
  }
  return reconstruction;
}

}  // namespace viosfm::testing

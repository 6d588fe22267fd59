// A synthetic multi-view scene with a known answer for the sfm tests
// (header-only; not part of the library's API): cameras on a line looking
// along +z with small random rotations, points in a box in front of them,
// and a Reconstruction whose image i has keypoint j at the exact projection
// of point j.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <string>
#include <vector>

#include "viosfm/geometry/rigid3.h"
#include "viosfm/scene/reconstruction.h"
#include "viosfm/sensor/camera_models.h"
#include "viosfm/sfm/batched_mapper.h"
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

// Sets the VIO odometers of `input` (one segment; distance and rotation
// travelled along its VIO camera poses), as the pipeline does from the
// VIO's trajectory.
inline void SetVioOdometers(BatchedMapperInput* input) {
  Trajectory world_from_cam;
  for (const MapperImage& image : input->images) {
    world_from_cam.poses.push_back({image.timestamp_ns, image.vio_cam_from_world->Inverse()});
  }
  const std::vector<VioOdometer> odometers = ComputeVioOdometers(world_from_cam, {});
  for (size_t i = 0; i < input->images.size(); ++i) input->images[i].vio_odometer = odometers[i];
}

// ---- A video-like sequence for the batched mapper ----
//
// World: z up (gravity along -z). The camera moves along +x (step_m per
// frame, with a slow lateral/vertical wobble and up to ~3 degrees of yaw and
// pitch wobble) looking horizontally along +y at points spread uniformly in
// x in [-3, L + 3] m, depth y in [3, 6] m, height z in [-1.5, 1.5] m. Every
// frame has one keypoint per point it sees (in image, in front), at the
// projection plus Gaussian noise. A feature is tracked for at most
// track_segment_frames frames (then lost and detected again as a new track,
// at a random phase per point), as a tracker loses features. Pairs (i, j)
// with 1 <= j - i <= max_frame_gap that share at least min_pair_matches
// tracked points are verified pairs holding all those matches (correct
// ones). The VIO poses are the true ones (see ApplyVioDrift).
struct SyntheticSequenceOptions {
  int num_frames = 150;
  double step_m = 0.05;            // camera motion per frame along x, m
  double points_per_m = 40.0;      // points per metre of corridor along x
  double keypoint_noise_px = 0.5;  // Gaussian sigma, px
  int max_frame_gap = 5;           // pairs up to this many frames apart
  int track_segment_frames = 20;   // longest track, frames
  int min_pair_matches = 15;
  timestamp_ns_t frame_interval_ns = 50'000'000;  // 20 Hz
  uint64_t seed = 1;
};

struct SyntheticSequence {
  Camera camera;
  std::vector<Rigid3d> cams_from_world;  // the truth, one per frame
  std::vector<Eigen::Vector3d> points;
  // point_of_keypoint[i][k] = index in `points` of keypoint k of frame i.
  std::vector<std::vector<int>> point_of_keypoint;
  BatchedMapperInput input;  // image ids 1..N, VIO poses exact
};

inline SyntheticSequence MakeSyntheticSequence(const SyntheticSequenceOptions& options) {
  Random random(options.seed);
  SyntheticSequence sequence;
  sequence.camera = MakeDistortedTestCamera();
  const int n = options.num_frames;
  const double length = options.step_m * std::max(0, n - 1);
  // world_from_cam of the unperturbed camera: x right = +x, y down = -z,
  // z forward = +y.
  Eigen::Matrix3d world_from_cam_base;
  world_from_cam_base << 1, 0, 0, 0, 0, 1, 0, -1, 0;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d center(options.step_m * i, 0.15 * std::sin(0.05 * i),
                                 0.1 * std::sin(0.031 * i));
    const Eigen::Matrix3d wobble =
        (Eigen::AngleAxisd(0.05 * std::sin(0.023 * i), Eigen::Vector3d::UnitZ()) *
         Eigen::AngleAxisd(0.03 * std::sin(0.041 * i), Eigen::Vector3d::UnitX()))
            .toRotationMatrix();
    const Eigen::Matrix3d cam_from_world = (wobble * world_from_cam_base).transpose();
    sequence.cams_from_world.emplace_back(cam_from_world, -cam_from_world * center);
  }
  const int num_points = static_cast<int>(options.points_per_m * (length + 6.0));
  std::vector<int> phases;
  for (int j = 0; j < num_points; ++j) {
    sequence.points.emplace_back(random.Uniform(-3.0, length + 3.0), random.Uniform(3.0, 6.0),
                                 random.Uniform(-1.5, 1.5));
    phases.push_back(static_cast<int>(random.UniformInt(0, options.track_segment_frames - 1)));
  }
  const auto segment = [&](int frame, int point) {
    return (frame + phases[point]) / options.track_segment_frames;
  };
  sequence.input.cameras = {sequence.camera};
  // keypoint_of_point[i][j] = keypoint of point j in frame i, -1 if unseen.
  std::vector<std::vector<int>> keypoint_of_point(n, std::vector<int>(num_points, -1));
  sequence.point_of_keypoint.resize(n);
  for (int i = 0; i < n; ++i) {
    MapperImage image;
    image.image_id = static_cast<image_t>(i + 1);
    image.camera_id = sequence.camera.camera_id;
    image.name = "frame" + std::to_string(i + 1) + ".png";
    image.timestamp_ns = 1'000'000'000 + options.frame_interval_ns * i;
    image.vio_cam_from_world = sequence.cams_from_world[i];
    for (int j = 0; j < num_points; ++j) {
      const Eigen::Vector3d point_in_cam = sequence.cams_from_world[i] * sequence.points[j];
      if (point_in_cam.z() < 0.5) continue;
      const std::optional<Eigen::Vector2d> pixel = Project(sequence.camera, point_in_cam);
      if (!pixel || pixel->x() < 0.0 || pixel->y() < 0.0 ||
          pixel->x() > static_cast<double>(sequence.camera.width - 1) ||
          pixel->y() > static_cast<double>(sequence.camera.height - 1)) {
        continue;
      }
      FeatureKeypoint keypoint;
      keypoint.x = static_cast<float>(pixel->x() + random.Normal(0.0, options.keypoint_noise_px));
      keypoint.y = static_cast<float>(pixel->y() + random.Normal(0.0, options.keypoint_noise_px));
      keypoint_of_point[i][j] = static_cast<int>(image.keypoints.size());
      sequence.point_of_keypoint[i].push_back(j);
      image.keypoints.push_back(keypoint);
    }
    sequence.input.images.push_back(std::move(image));
  }
  for (int i = 0; i < n; ++i) {
    for (int gap = 1; gap <= options.max_frame_gap && i + gap < n; ++gap) {
      ImagePairMatches pair;
      pair.image_id1 = static_cast<image_t>(i + 1);
      pair.image_id2 = static_cast<image_t>(i + gap + 1);
      for (int j = 0; j < num_points; ++j) {
        const int k1 = keypoint_of_point[i][j];
        const int k2 = keypoint_of_point[i + gap][j];
        if (k1 >= 0 && k2 >= 0 && segment(i, j) == segment(i + gap, j)) {
          pair.matches.push_back({static_cast<point2D_t>(k1), static_cast<point2D_t>(k2)});
        }
      }
      if (static_cast<int>(pair.matches.size()) >= options.min_pair_matches) {
        sequence.input.verified_pairs.push_back(std::move(pair));
      }
    }
  }
  SetVioOdometers(&sequence.input);
  return sequence;
}

// The errors of an emulated VIO: independent Gaussian errors added to every
// frame's motion, so that its position and its yaw (about the world's z,
// gravity: the directions a VIO cannot observe) drift as random walks while
// roll and pitch stay exact.
struct VioDriftOptions {
  double position_sigma_m = 0.001;  // per frame and horizontal axis (half vertically), m
  double yaw_sigma_rad = 0.002;     // per frame, rad (the later motion turns with it)
  uint64_t seed = 7;
};

// Replaces the VIO poses of `input` (one per true pose) by the drifting
// odometry of `options`; the first frame keeps its true pose.
inline void ApplyVioDrift(const std::vector<Rigid3d>& true_cams_from_world,
                          const VioDriftOptions& options, BatchedMapperInput* input) {
  Random random(options.seed);
  double yaw = 0.0;
  Eigen::Vector3d vio_center = ProjectionCenter(true_cams_from_world[0]);
  for (size_t i = 0; i < true_cams_from_world.size(); ++i) {
    if (i > 0) {
      const Eigen::Vector3d true_step =
          ProjectionCenter(true_cams_from_world[i]) - ProjectionCenter(true_cams_from_world[i - 1]);
      yaw += random.Normal(0.0, options.yaw_sigma_rad);
      vio_center += Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * true_step +
                    Eigen::Vector3d(random.Normal(0.0, options.position_sigma_m),
                                    random.Normal(0.0, options.position_sigma_m),
                                    random.Normal(0.0, 0.5 * options.position_sigma_m));
    }
    const Eigen::Matrix3d world_from_cam =
        Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
        true_cams_from_world[i].rotation.toRotationMatrix().transpose();
    const Eigen::Matrix3d cam_from_world = world_from_cam.transpose();
    input->images[i].vio_cam_from_world = Rigid3d(cam_from_world, -cam_from_world * vio_center);
  }
  SetVioOdometers(input);
}

// Root mean square distance (m) between the camera centres of `poses` and
// the true ones, without any alignment (both share the first frame's pose).
inline double CenterRmse(const std::vector<Rigid3d>& true_cams_from_world,
                         const std::vector<Rigid3d>& cams_from_world) {
  double sum = 0.0;
  for (size_t i = 0; i < true_cams_from_world.size(); ++i) {
    sum += (ProjectionCenter(true_cams_from_world[i]) - ProjectionCenter(cams_from_world[i]))
               .squaredNorm();
  }
  return std::sqrt(sum / static_cast<double>(true_cams_from_world.size()));
}

}  // namespace viosfm::testing

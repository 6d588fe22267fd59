// CPU ray casting of textured planar scenes into grey images.
//
// For each pixel the viewing ray comes from the camera model's undistortion
// (ImageToCam of the pixel centre; pixel (0, 0) is the centre of the top-left
// pixel, the OpenCV convention of the calibration), so points project with
// sensor/camera_models.h's Project() exactly where they are drawn. The rays
// are computed once per camera (RayTable) and reused for every frame.
//
// Radiance = texture * exposure_gain * distance falloff * vignetting; then
// Gaussian sensor noise and rounding to 8 bits. Texture lookups are trilinear
// in the mip pyramid at the level matching the pixel's footprint on the
// surface: footprint = t * pixel_angle / sqrt(cos(incidence)) (the geometric
// mean of the footprints along and across the slant), scaled by
// 2^mip_bias.
//
// Pixels are independent and the noise of pixel (x, y) is a hash of
// (seed, frame noise stream, x, y), so the image is identical for any number
// of threads.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "viosfm/geometry/rigid3.h"
#include "viosfm/sensor/camera.h"
#include "viosfm/sensor/grey_image.h"
#include "viosfm/sim/scene_model.h"

namespace viosfm {

// Viewing rays of every pixel of a camera.
class RayTable {
 public:
  RayTable() = default;
  // Throws InputError if the camera model cannot project.
  explicit RayTable(const Camera& camera);

  int width() const { return width_; }
  int height() const { return height_; }
  // Unit-norm viewing ray in the camera frame of pixel (x, y).
  const Eigen::Vector3f& Direction(int x, int y) const { return directions_[Index(x, y)]; }
  // Angle (radians) between the ray of (x, y) and its neighbours, the
  // geometric mean of the horizontal and vertical spacings.
  float PixelAngle(int x, int y) const { return pixel_angles_[Index(x, y)]; }
  // Squared distance of the pixel from the principal point, divided by the
  // squared half-diagonal of the image (0 at the centre, ~1 in the corners).
  float RadiusSquared(int x, int y) const { return radius_squared_[Index(x, y)]; }
  // Quads of `scene` that may be seen from cam_from_world: all but those
  // lying entirely outside one side of the view frustum (the cone of the
  // table's rays). Every quad if the rays span a hemisphere or more.
  std::vector<int> VisibleQuads(const Scene& scene, const Rigid3d& cam_from_world) const;

 private:
  size_t Index(int x, int y) const { return static_cast<size_t>(y) * width_ + x; }
  int width_ = 0;
  int height_ = 0;
  std::vector<Eigen::Vector3f> directions_;
  std::vector<float> pixel_angles_;
  std::vector<float> radius_squared_;
  // Frustum: x/z and y/z of every ray lie in [min_x, max_x] x [min_y, max_y].
  bool has_frustum_ = false;
  double min_x_ = 0.0, max_x_ = 0.0, min_y_ = 0.0, max_y_ = 0.0;
};

struct RenderOptions {
  double exposure_gain = 1.0;      // radiance multiplier (texture 1.0 -> 255 grey at gain 1)
  double vignetting = 0.3;         // brightness loss in the image corners (0: none, < 1)
  double distance_falloff = 0.05;  // 1/m: shading = 1 / (1 + distance_falloff * distance)
  double noise_sigma = 2.0;        // grey levels, Gaussian sensor noise (0: none)
  double background = 0.0;         // grey level where a ray hits nothing
  bool mipmapping = true;          // false: always sample the finest level (aliases)
  // Mip levels added to log2(footprint); < 0 is sharper. The default -0.5
  // best matches a box-filtered (supersampled) pixel, since bilinear and
  // trilinear interpolation blur a little more than the box.
  double mip_bias = -0.5;
  int motion_blur_samples = 4;  // sub-frames averaged by RenderWithMotionBlur (>= 1)
  int num_threads = 2;          // worker threads (>= 1)
  uint64_t seed = 0;            // noise seed; vary it per frame (e.g. seed + frame index)

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }
};

// Renders the scene seen from cam_from_world.
GreyImage Render(const Scene& scene, const RayTable& rays, const Rigid3d& cam_from_world,
                 const RenderOptions& options);
// Convenience: builds the RayTable (slow: prefer one table for many frames).
GreyImage Render(const Scene& scene, const Camera& camera, const Rigid3d& cam_from_world,
                 const RenderOptions& options);

// Motion blur: the average of options.motion_blur_samples sub-frames at poses
// interpolated (slerp of the rotation, linear in the camera centre) between
// the poses at shutter open and close, at the centres of equal sub-intervals;
// noise is added once to the average.
GreyImage RenderWithMotionBlur(const Scene& scene, const RayTable& rays,
                               const Rigid3d& cam_from_world_open,
                               const Rigid3d& cam_from_world_close, const RenderOptions& options);

// Rolling shutter: row y is seen from cam_from_world_open_of_row[y] (one pose
// a row, rays.height() of them), the view frustum culled per row. With
// cam_from_world_close_of_row non-empty (as many poses), row y is motion
// blurred as RenderWithMotionBlur blurs the whole image, between its own
// open and close poses; empty: sharp. The same pose for every row gives the
// image Render (or RenderWithMotionBlur) gives, byte for byte.
GreyImage RenderRowByRow(const Scene& scene, const RayTable& rays,
                         const std::vector<Rigid3d>& cam_from_world_open_of_row,
                         const std::vector<Rigid3d>& cam_from_world_close_of_row,
                         const RenderOptions& options);

}  // namespace viosfm

#include "viosfm/sim/renderer.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <exception>
#include <functional>
#include <iterator>
#include <limits>
#include <thread>

#include "viosfm/sensor/camera_models.h"
#include "viosfm/util/errors.h"

namespace viosfm {
namespace {

// Smallest |cos(incidence)| used for the footprint (grazing rays).
constexpr double kMinCosIncidence = 0.05;

uint64_t Hash64(uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// Standard normal value for pixel `index` of the noise stream `seed`
// (Box-Muller on two hashed uniforms).
double PixelNormal(uint64_t seed, uint64_t index) {
  const uint64_t a = Hash64(seed * 0x9e3779b97f4a7c15ULL + 2 * index + 1);
  const uint64_t b = Hash64(a ^ 0xd1b54a32d192ed03ULL);
  const double u1 = (static_cast<double>(a >> 11) + 0.5) * (1.0 / 9007199254740992.0);
  const double u2 = static_cast<double>(b >> 11) * (1.0 / 9007199254740992.0);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}

// Runs body(row) for every row, rows dealt round-robin to the threads.
void ForEachRow(int height, int num_threads, const std::function<void(int)>& body) {
  num_threads = std::clamp(num_threads, 1, std::max(1, height));
  if (num_threads == 1) {
    for (int y = 0; y < height; ++y) body(y);
    return;
  }
  std::vector<std::exception_ptr> errors(num_threads);
  std::vector<std::thread> workers;
  workers.reserve(num_threads);
  for (int k = 0; k < num_threads; ++k) {
    workers.emplace_back([&, k]() {
      try {
        for (int y = k; y < height; y += num_threads) body(y);
      } catch (...) {
        errors[k] = std::current_exception();
      }
    });
  }
  for (std::thread& worker : workers) worker.join();
  for (const std::exception_ptr& error : errors) {
    if (error) std::rethrow_exception(error);
  }
}

GreyImage Quantize(const std::vector<float>& radiance, int width, int height,
                   const RenderOptions& options) {
  GreyImage image(width, height);
  ForEachRow(height, options.num_threads, [&](int y) {
    for (int x = 0; x < width; ++x) {
      const size_t index = static_cast<size_t>(y) * width + x;
      double value = radiance[index];
      if (options.noise_sigma > 0.0)
        value += options.noise_sigma * PixelNormal(options.seed, index);
      image.pixels[index] = static_cast<uint8_t>(std::clamp(std::lround(value), 0L, 255L));
    }
  });
  return image;
}

// What a ray cast needs of one camera pose.
struct View {
  Eigen::Matrix3d world_from_cam_rotation;
  Eigen::Vector3d center;
  std::vector<int> candidates;  // quads that may be visible
};

View MakeView(const Scene& scene, const RayTable& rays, const Rigid3d& cam_from_world) {
  return {cam_from_world.rotation.inverse().toRotationMatrix(), ProjectionCenter(cam_from_world),
          rays.VisibleQuads(scene, cam_from_world)};
}

// Adds the radiance (grey levels, before noise) times `weight` to
// `radiance`: every row seen from cam_from_world_of_row[0] if it holds one
// pose, else row y from cam_from_world_of_row[y] (one pose a row).
void AccumulateRadiance(const Scene& scene, const RayTable& rays,
                        const std::vector<Rigid3d>& cam_from_world_of_row,
                        const RenderOptions& options, float weight, std::vector<float>* radiance) {
  const bool per_row = cam_from_world_of_row.size() > 1;
  VIOSFM_CHECK(cam_from_world_of_row.size() == 1 ||
               cam_from_world_of_row.size() == static_cast<size_t>(rays.height()))
      << cam_from_world_of_row.size() << " poses for " << rays.height() << " rows";
  const int width = rays.width();
  const double footprint_scale = std::exp2(options.mip_bias);
  View shared;
  if (!per_row) shared = MakeView(scene, rays, cam_from_world_of_row.front());
  ForEachRow(rays.height(), options.num_threads, [&](int y) {
    View own;
    if (per_row) own = MakeView(scene, rays, cam_from_world_of_row[y]);
    const View& view = per_row ? own : shared;
    float* row = radiance->data() + static_cast<size_t>(y) * width;
    for (int x = 0; x < width; ++x) {
      const Eigen::Vector3d direction =
          view.world_from_cam_rotation * rays.Direction(x, y).cast<double>();
      const std::optional<RayHit> hit =
          scene.Intersect(view.center, direction, 1e-6, view.candidates);
      double value = options.background;
      if (hit) {
        const TexturedQuad& quad = scene.quads()[hit->quad_id];
        const double tpm = quad.texels_per_metre;
        const double footprint =
            options.mipmapping ? hit->t * rays.PixelAngle(x, y) /
                                     std::sqrt(std::max(hit->cos_incidence, kMinCosIncidence)) *
                                     tpm * footprint_scale
                               : 0.0;
        const double texel = scene.texture(quad.texture_id)
                                 .Sample((hit->u + quad.texture_offset.x()) * tpm,
                                         (hit->v + quad.texture_offset.y()) * tpm, footprint);
        value = 255.0 * options.exposure_gain * texel *
                (1.0 - options.vignetting * rays.RadiusSquared(x, y)) /
                (1.0 + options.distance_falloff * hit->t);
      }
      row[x] += weight * static_cast<float>(value);
    }
  });
}

// The pose a fraction s in [0, 1] of the way from `open` to `close`: slerp
// of the rotation, linear in the camera centre.
Rigid3d InterpolateCamFromWorld(const Rigid3d& open, const Rigid3d& close, double s) {
  const Eigen::Quaterniond rotation = open.rotation.slerp(s, close.rotation).normalized();
  const Eigen::Vector3d center = (1.0 - s) * ProjectionCenter(open) + s * ProjectionCenter(close);
  return Rigid3d(rotation, -(rotation * center));
}

// The average of options.motion_blur_samples sub-frames between the poses
// of `open` and `close` (one pose, or one a row), or the single view `open`
// if `close` is empty; noise and quantisation once.
GreyImage RenderBlurred(const Scene& scene, const RayTable& rays, const std::vector<Rigid3d>& open,
                        const std::vector<Rigid3d>& close, const RenderOptions& options) {
  VIOSFM_CHECK(options.Check()) << options.Validate();
  std::vector<float> radiance(static_cast<size_t>(rays.width()) * rays.height(), 0.0f);
  if (close.empty()) {
    AccumulateRadiance(scene, rays, open, options, 1.0f, &radiance);
  } else {
    VIOSFM_CHECK_EQ(open.size(), close.size());
    const int n = options.motion_blur_samples;
    std::vector<Rigid3d> poses(open.size());
    for (int k = 0; k < n; ++k) {
      const double s = (k + 0.5) / n;
      for (size_t r = 0; r < open.size(); ++r)
        poses[r] = InterpolateCamFromWorld(open[r], close[r], s);
      AccumulateRadiance(scene, rays, poses, options, 1.0f / static_cast<float>(n), &radiance);
    }
  }
  return Quantize(radiance, rays.width(), rays.height(), options);
}

}  // namespace

RayTable::RayTable(const Camera& camera)
    : width_(static_cast<int>(camera.width)), height_(static_cast<int>(camera.height)) {
  if (!camera.HasValidParams() || !IsCameraModelSupported(camera.model_id)) {
    throw InputError("camera model " + camera.ModelName() +
                     " with these parameters cannot be rendered");
  }
  VIOSFM_CHECK(width_ > 1 && height_ > 1)
      << "camera of " << width_ << " x " << height_ << " pixels";
  const size_t count = static_cast<size_t>(width_) * height_;
  directions_.resize(count);
  pixel_angles_.resize(count);
  radius_squared_.resize(count);
  std::vector<Eigen::Vector3d> rays(count);
  for (int y = 0; y < height_; ++y) {
    for (int x = 0; x < width_; ++x) rays[Index(x, y)] = Unproject(camera, Eigen::Vector2d(x, y));
  }
  const Eigen::Matrix3d calibration = CalibrationMatrix(camera);
  const double cx = calibration(0, 2);
  const double cy = calibration(1, 2);
  const double half_diagonal_sq =
      0.25 * (static_cast<double>(width_) * width_ + static_cast<double>(height_) * height_);
  const auto angle = [](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return std::atan2(a.cross(b).norm(), a.dot(b));
  };
  for (int y = 0; y < height_; ++y) {
    for (int x = 0; x < width_; ++x) {
      const int x0 = std::max(x - 1, 0);
      const int x1 = std::min(x + 1, width_ - 1);
      const int y0 = std::max(y - 1, 0);
      const int y1 = std::min(y + 1, height_ - 1);
      const double angle_x = angle(rays[Index(x0, y)], rays[Index(x1, y)]) / (x1 - x0);
      const double angle_y = angle(rays[Index(x, y0)], rays[Index(x, y1)]) / (y1 - y0);
      const size_t index = Index(x, y);
      directions_[index] = rays[index].cast<float>();
      pixel_angles_[index] = static_cast<float>(std::sqrt(angle_x * angle_y));
      radius_squared_[index] =
          static_cast<float>(((x - cx) * (x - cx) + (y - cy) * (y - cy)) / half_diagonal_sq);
    }
  }
  has_frustum_ = true;
  min_x_ = min_y_ = std::numeric_limits<double>::infinity();
  max_x_ = max_y_ = -std::numeric_limits<double>::infinity();
  for (const Eigen::Vector3d& ray : rays) {
    if (!(ray.z() > 1e-3 * ray.norm())) {
      has_frustum_ = false;
      break;
    }
    min_x_ = std::min(min_x_, ray.x() / ray.z());
    max_x_ = std::max(max_x_, ray.x() / ray.z());
    min_y_ = std::min(min_y_, ray.y() / ray.z());
    max_y_ = std::max(max_y_, ray.y() / ray.z());
  }
  // A small margin for the float directions.
  const double margin = 1e-3;
  min_x_ -= margin;
  max_x_ += margin;
  min_y_ -= margin;
  max_y_ += margin;
}

std::vector<int> RayTable::VisibleQuads(const Scene& scene, const Rigid3d& cam_from_world) const {
  const std::vector<TexturedQuad>& quads = scene.quads();
  std::vector<int> visible;
  visible.reserve(quads.size());
  for (size_t k = 0; k < quads.size(); ++k) {
    if (!has_frustum_) {
      visible.push_back(static_cast<int>(k));
      continue;
    }
    const TexturedQuad& quad = quads[k];
    const Eigen::Vector3d corners[4] = {quad.origin, quad.origin + quad.axis_u,
                                        quad.origin + quad.axis_v,
                                        quad.origin + quad.axis_u + quad.axis_v};
    // Outside if all corners violate the same half-space: z > 0,
    // x <= max_x z, x >= min_x z, y <= max_y z, y >= min_y z.
    int inside_count[5] = {0, 0, 0, 0, 0};
    for (const Eigen::Vector3d& corner : corners) {
      const Eigen::Vector3d p = cam_from_world * corner;
      inside_count[0] += p.z() > 0.0;
      inside_count[1] += p.x() <= max_x_ * p.z();
      inside_count[2] += p.x() >= min_x_ * p.z();
      inside_count[3] += p.y() <= max_y_ * p.z();
      inside_count[4] += p.y() >= min_y_ * p.z();
    }
    if (std::all_of(std::begin(inside_count), std::end(inside_count),
                    [](int count) { return count > 0; })) {
      visible.push_back(static_cast<int>(k));
    }
  }
  return visible;
}

std::string RenderOptions::Validate() const {
  if (!(exposure_gain > 0.0)) return "exposure_gain must be > 0";
  if (!(vignetting >= 0.0 && vignetting < 1.0)) return "vignetting must be in [0, 1)";
  if (!(distance_falloff >= 0.0)) return "distance_falloff must be >= 0";
  if (!(noise_sigma >= 0.0)) return "noise_sigma must be >= 0";
  if (!(background >= 0.0 && background <= 255.0)) return "background must be in [0, 255]";
  if (!(std::abs(mip_bias) <= 8.0)) return "mip_bias must be in [-8, 8]";
  if (motion_blur_samples < 1) return "motion_blur_samples must be >= 1";
  if (num_threads < 1) return "num_threads must be >= 1";
  return "";
}

GreyImage Render(const Scene& scene, const RayTable& rays, const Rigid3d& cam_from_world,
                 const RenderOptions& options) {
  return RenderBlurred(scene, rays, {cam_from_world}, {}, options);
}

GreyImage Render(const Scene& scene, const Camera& camera, const Rigid3d& cam_from_world,
                 const RenderOptions& options) {
  return Render(scene, RayTable(camera), cam_from_world, options);
}

GreyImage RenderWithMotionBlur(const Scene& scene, const RayTable& rays,
                               const Rigid3d& cam_from_world_open,
                               const Rigid3d& cam_from_world_close, const RenderOptions& options) {
  return RenderBlurred(scene, rays, {cam_from_world_open}, {cam_from_world_close}, options);
}

GreyImage RenderRowByRow(const Scene& scene, const RayTable& rays,
                         const std::vector<Rigid3d>& cam_from_world_open_of_row,
                         const std::vector<Rigid3d>& cam_from_world_close_of_row,
                         const RenderOptions& options) {
  VIOSFM_CHECK_EQ(cam_from_world_open_of_row.size(), static_cast<size_t>(rays.height()));
  VIOSFM_CHECK(cam_from_world_close_of_row.empty() ||
               cam_from_world_close_of_row.size() == cam_from_world_open_of_row.size());
  return RenderBlurred(scene, rays, cam_from_world_open_of_row, cam_from_world_close_of_row,
                       options);
}

}  // namespace viosfm

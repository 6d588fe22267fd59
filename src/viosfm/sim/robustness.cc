#include "viosfm/sim/robustness.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <map>

#include "viosfm/util/errors.h"
#include "viosfm/util/random.h"

namespace viosfm {

std::string AutoExposureOptions::Validate() const {
  if (!(strength_stops >= 0.0 && strength_stops <= 8.0)) return "strength_stops must be in [0, 8]";
  if (!(drift_stddev >= 0.0)) return "drift_stddev must be >= 0";
  if (!(drift_time_constant_s > 0.0)) return "drift_time_constant_s must be > 0";
  if (!(step_rate_hz >= 0.0)) return "step_rate_hz must be >= 0";
  if (!(step_size >= 0.0)) return "step_size must be >= 0";
  if (!(recovery_time_constant_s > 0.0)) return "recovery_time_constant_s must be > 0";
  return "";
}

std::vector<double> AutoExposureGains(const std::vector<timestamp_ns_t>& frame_times_ns,
                                      const AutoExposureOptions& options, uint64_t seed) {
  VIOSFM_CHECK(options.Check()) << options.Validate();
  std::vector<double> gains(frame_times_ns.size(), 1.0);
  if (!options.enabled()) return gains;
  Random random(seed);
  double drift = 0.0;
  double step = 0.0;
  for (size_t k = 0; k < frame_times_ns.size(); ++k) {
    if (k > 0) {
      const double dt = NsToSeconds(frame_times_ns[k] - frame_times_ns[k - 1]);
      VIOSFM_CHECK_GT(dt, 0.0) << "frame times must increase";
      const double a = std::exp(-dt / options.drift_time_constant_s);
      drift = a * drift + std::sqrt(1.0 - a * a) * options.drift_stddev * random.Normal();
      step *= std::exp(-dt / options.recovery_time_constant_s);
      // Draw the step's three numbers every frame so the streams do not
      // depend on whether a step happens.
      const double u_event = random.Uniform();
      const double u_size = random.Uniform(0.5, 1.0);
      const double u_sign = random.Uniform();
      if (u_event < 1.0 - std::exp(-options.step_rate_hz * dt)) {
        step += (u_sign < 0.5 ? -1.0 : 1.0) * u_size * options.step_size;
      }
    }
    gains[k] = std::exp2(options.strength_stops * (drift + step));
  }
  return gains;
}

timestamp_ns_t RollingShutterRowTime(timestamp_ns_t stamp_ns, int row, int height,
                                     double readout_s) {
  VIOSFM_CHECK(height > 0 && row >= 0 && row < height) << "row " << row << " of " << height;
  const double fraction = (row + 0.5) / height - 0.5;
  return stamp_ns + static_cast<timestamp_ns_t>(std::llround(fraction * readout_s * 1e9));
}

std::string WhiteWallOptions::Validate() const {
  if (!(mean > 0.0 && mean <= 1.0)) return "mean must be in (0, 1]";
  if (!(contrast >= 0.0 && contrast <= 1.0)) return "contrast must be in [0, 1]";
  if (!(texels_per_metre > 0.0)) return "texels_per_metre must be > 0";
  return "";
}

int PaintWallsWhite(Scenario* scenario, const WhiteWallOptions& options, uint64_t seed) {
  VIOSFM_CHECK(scenario != nullptr);
  VIOSFM_CHECK(options.Check()) << options.Validate();
  const Scene& old = scenario->scene;
  const std::vector<TexturedQuad>& quads = old.quads();
  if (quads.empty()) return 0;
  const auto corners = [](const TexturedQuad& quad) {
    return std::array<Eigen::Vector3d, 4>{quad.origin, quad.origin + quad.axis_u,
                                          quad.origin + quad.axis_v,
                                          quad.origin + quad.axis_u + quad.axis_v};
  };
  Eigen::AlignedBox3d bounds;
  for (const TexturedQuad& quad : quads) {
    for (const Eigen::Vector3d& corner : corners(quad)) bounds.extend(corner);
  }
  // A quad is a wall if all its corners lie in one side face (x or y at the
  // bounds) or in the top face.
  constexpr double kTolerance = 1e-6;  // m
  const auto in_face = [&](const TexturedQuad& quad, int axis, bool at_max) {
    const double plane = at_max ? bounds.max()[axis] : bounds.min()[axis];
    for (const Eigen::Vector3d& corner : corners(quad)) {
      if (std::abs(corner[axis] - plane) > kTolerance) return false;
    }
    return true;
  };
  const auto is_wall = [&](const TexturedQuad& quad) {
    return in_face(quad, 0, false) || in_face(quad, 0, true) || in_face(quad, 1, false) ||
           in_face(quad, 1, true) || in_face(quad, 2, true);
  };
  // One white texture per texture used by walls (pieces of a wall cut
  // around openings share one), large enough for every such quad.
  std::map<int, Eigen::Vector2d> extent_of_texture;  // metres (u, v)
  for (const TexturedQuad& quad : quads) {
    if (!is_wall(quad)) continue;
    // (operator[] would leave a new Eigen vector uninitialised.)
    Eigen::Vector2d& extent =
        extent_of_texture.try_emplace(quad.texture_id, Eigen::Vector2d::Zero()).first->second;
    extent = extent.cwiseMax(Eigen::Vector2d(quad.texture_offset.x() + quad.axis_u.norm(),
                                             quad.texture_offset.y() + quad.axis_v.norm()));
  }
  Scene scene;
  for (const Texture& texture : old.textures()) scene.AddTexture(texture);
  std::map<int, int> white_of_texture;
  ProceduralTextureOptions smooth;  // value noise only
  smooth.blobs_per_megatexel = 0;
  smooth.posters_per_megatexel = 0;
  smooth.text_blocks_per_megatexel = 0;
  for (const auto& [texture_id, extent] : extent_of_texture) {
    const Texture noise =
        MakeSurfaceTexture(extent.x(), extent.y(), options.texels_per_metre,
                           MixSeed(seed, static_cast<uint64_t>(texture_id)), smooth);
    // MakeProceduralTexture stretches to about [0.05, 0.95]: contrast / 0.9
    // maps that span to `contrast`.
    white_of_texture[texture_id] = scene.AddTexture(WithContrast(
        noise, static_cast<float>(options.mean), static_cast<float>(options.contrast / 0.9)));
  }
  int repainted = 0;
  for (TexturedQuad quad : quads) {
    if (is_wall(quad)) {
      quad.texture_id = white_of_texture.at(quad.texture_id);
      quad.texels_per_metre = options.texels_per_metre;
      ++repainted;
    }
    scene.AddQuad(quad);
  }
  scenario->scene = std::move(scene);
  return repainted;
}

ImuNoise ScaledImuNoise(const ImuNoise& noise, double gyro_factor, double accel_factor) {
  ImuNoise scaled = noise;
  scaled.gyro_noise_density *= gyro_factor;
  scaled.gyro_random_walk *= gyro_factor;
  scaled.accel_noise_density *= accel_factor;
  scaled.accel_random_walk *= accel_factor;
  return scaled;
}

}  // namespace viosfm

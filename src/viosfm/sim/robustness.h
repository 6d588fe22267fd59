// Imperfections of real cameras and calibrations that the simulator can add
// to a sequence, to test how an estimator copes with them (the VIO
// robustness set, docs/simulator.md): auto-exposure changes, rolling-shutter
// row timing, white (nearly textureless) walls, and IMU noise figures in the
// written calibration that differ from the simulated noise. Motion blur
// (SimulationOptions::exposure_time_s) and a camera-IMU time offset
// (SimulationOptions::camera_time_offset_s) are options of the simulation
// itself. Every model here is off by default and deterministic for a seed.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "viosfm/sensor/imu.h"
#include "viosfm/sim/scenarios.h"
#include "viosfm/util/timestamp.h"

namespace viosfm {

// Auto exposure: every frame's radiance is multiplied by a gain before
// sensor noise and quantisation (RenderOptions::exposure_gain times the
// gain), like a camera whose auto-exposure drifts with the scene and is
// caught out by sudden changes (a bright window or screen entering the
// view). The gain of frame k is 2^(strength_stops * (d_k + s_k)):
//  - d, the slow drift: an Ornstein-Uhlenbeck process sampled at the frame
//    times, d_0 = 0, stationary standard deviation drift_stddev and time
//    constant drift_time_constant_s;
//  - s, the steps: at each frame a step happens with probability
//    1 - exp(-step_rate_hz * dt), adding +-U(0.5, 1) * step_size (sign
//    random) to s, which the auto-exposure then brings back to 0
//    exponentially with time constant recovery_time_constant_s (s decays by
//    exp(-dt / recovery_time_constant_s) from one frame to the next).
// So at strength_stops = 1 the image brightness drifts by about +-0.5 stop
// and jumps by 0.5 to 1 stop every 5 s on average, recovering in about 1 s.
struct AutoExposureOptions {
  double strength_stops = 0.0;            // stops (log2 of the gain); 0 (default): off, gain 1
  double drift_stddev = 0.5;              // stationary standard deviation of d (x strength)
  double drift_time_constant_s = 3.0;     // s, correlation time of the drift
  double step_rate_hz = 0.2;              // 1/s, mean rate of sudden steps
  double step_size = 1.0;                 // largest step (x strength); steps are U(0.5, 1) of it
  double recovery_time_constant_s = 0.5;  // s, how fast the auto exposure undoes a step

  bool enabled() const { return strength_stops > 0.0; }
  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }
};

// The gain of each frame at the stamps `frame_times_ns` (increasing), all 1
// when the model is off. Deterministic for `seed`.
std::vector<double> AutoExposureGains(const std::vector<timestamp_ns_t>& frame_times_ns,
                                      const AutoExposureOptions& options, uint64_t seed);

// Rolling shutter: row y (0 at the top) of an image of `height` rows
// stamped t is exposed at t + ((y + 0.5) / height - 0.5) * readout_s: the
// rows are read out top to bottom over readout_s, and the stamp is the
// exposure time of the middle of the image (so the mean pose of a frame is
// the pose at its stamp). Rounded to the nanosecond.
timestamp_ns_t RollingShutterRowTime(timestamp_ns_t stamp_ns, int row, int height,
                                     double readout_s);

// White walls: the scene's outer walls and ceiling — every quad lying in a
// side face or the top face of the bounding box of all quads (the room's
// four walls and ceiling; the outer walls of the other scenarios) — are
// repainted with a nearly uniform texture: smooth value noise remapped to
// mean +- contrast / 2 at texels_per_metre (each quad its own seed). The
// floor and everything inside (furniture, doors, inner walls) keep their
// textures, so the camera sees a few objects against white walls, like a
// real bedroom. With the default contrast 0.02 a wall spans about 4 grey
// levels before the sensor noise (sigma 2 in `room`).
struct WhiteWallOptions {
  bool enabled = false;            // default off
  double mean = 0.85;              // texture value (1 = 255 grey at exposure gain 1)
  double contrast = 0.02;          // peak-to-peak of the texture's noise, about
  double texels_per_metre = 24.0;  // texture resolution of the walls (smooth)

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }
};

// Repaints `scenario`'s walls as above; returns the number of quads
// repainted. Geometry, regions and everything else stay.
int PaintWallsWhite(Scenario* scenario, const WhiteWallOptions& options, uint64_t seed);

// The noise figures a calibration file states when it is wrong by these
// factors: both densities and random walks of the gyro multiplied by
// gyro_factor, those of the accelerometer by accel_factor (rate unchanged).
ImuNoise ScaledImuNoise(const ImuNoise& noise, double gyro_factor, double accel_factor);

}  // namespace viosfm

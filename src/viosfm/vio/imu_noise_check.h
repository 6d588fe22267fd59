// What the VIO does with the IMU noise figures of a calibration file.
//
// The white-noise densities weigh the IMU against the images in every
// optimisation, and calibration files get them wrong, by an order of
// magnitude either way; an IMU trusted too little leaves the scale and the
// velocity to the images (see docs/history/code-comments-2026.md for the
// real recording's figures).
//
// Policy (CheckImuNoise):
//  - with a static interval (static_init.h) of at least min_static_s, the
//    white noise of each sensor is measured there (the standard deviation of
//    the raw readings about their mean, times sqrt(dt), averaged over the
//    axes). The file's density is kept when it lies within [min_ratio,
//    max_ratio] times the measured one (a file may inflate the noise for
//    vibration and unmodelled errors, as VINS-Mono's configurations do, but
//    not far below what the sensor shows at rest or far above it);
//    otherwise the nearest bound is used;
//  - without one, a density outside the range of MEMS IMUs (data sheets:
//    gyros 5e-5 to 1e-2 rad/s/sqrt(Hz), accelerometers 5e-4 to 5e-2
//    m/s^2/sqrt(Hz), inflated by up to ten as configurations do) is clamped
//    into it; then the quietest min_static_s of the whole IMU stream (the
//    window whose accelerometer readings spread least about their mean)
//    bounds each density from above, measured there as at rest: motion
//    only adds to the spread, so the white noise cannot exceed it, and a
//    density above it is lowered to it: a start in motion with the file's
//    figure left the scale to the images (see docs/benchmarks.md,
//    "Starting in motion");
//  - in motion, what the preintegration must absorb is more than the
//    sensor's white noise: a flying platform vibrates (propellers, motors)
//    at frequencies the IMU's sampling aliases, and the readings scatter
//    far beyond the data sheet's figure. The high-frequency content of the
//    readings over the first motion_span_s of motion after the static
//    interval (or after the first image) is measured by second differences
//    (a reading against the line through its two neighbours: white noise of
//    density d gives d for any smooth motion), the median over windows of
//    motion_window_s; a density below min_ratio times it is raised to that,
//    the same lower bound a measurement at rest sets. The real EuRoC V1_01
//    flight measures 0.085 m/s^2/sqrt(Hz) and 3.1e-3 rad/s/sqrt(Hz), 43 and
//    18 times its data-sheet figures (VINS-Mono's EuRoC configuration states
//    0.08 and 4e-3); a handheld walk or a simulated sequence measures its
//    white noise, and nothing changes;
//  - random walks cannot be measured in a few seconds. A sensor's random
//    walk is scaled by the factor its white-noise density was changed by
//    (scale_random_walks): a calibration's two figures of one sensor come
//    from one source, so one found wrong by a factor makes the same error
//    likely in the other: an inflated random walk leaves the bias free to
//    wander and the scale with it (see docs/benchmarks.md, "VIO robustness
//    set"). Then values outside
//    [1e-7, 1e-2] rad/s^2/sqrt(Hz) (gyro) and [1e-6, 1e-1] m/s^3/sqrt(Hz)
//    (accelerometer) are clamped.
// Every change is logged with the file's and the used value.
#pragma once

#include <string>
#include <vector>

#include "viosfm/sensor/imu.h"
#include "viosfm/vio/static_init.h"

namespace viosfm {

struct ImuNoiseCheckOptions {
  // Apply the policy (default true); false uses the file's figures as they are.
  bool enabled = true;
  // A file's white-noise density is kept within [min_ratio, max_ratio]
  // times the density measured at rest. Defaults 0.5 (the measurement over
  // half a second scatters by about 5 %, and quantisation adds to it) and 4.
  double min_ratio = 0.5;
  double max_ratio = 4.0;
  // Scale each random walk by the factor its sensor's white-noise density
  // was changed by (default true); false leaves the walks as the file
  // states them (within the MEMS range).
  bool scale_random_walks = true;
  // s, shortest static interval to measure on. Default 0.5.
  double min_static_s = 0.5;
  // Measure the high-frequency content of the readings in motion (default
  // true), over motion_span_s of motion (default 10) in windows of
  // motion_window_s (default 1).
  bool check_in_motion = true;
  double motion_span_s = 10.0;
  double motion_window_s = 1.0;

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }
};

struct ImuNoiseCheck {
  ImuNoise given;         // as the calibration states
  ImuNoise used;          // what the VIO uses
  bool measured = false;  // whether a static interval was measured
  // Without one: the quietest window's densities, upper bounds (0 when the
  // stream is shorter than the window), and the window's first stamp.
  double bound_gyro_density = 0.0;
  double bound_accel_density = 0.0;
  timestamp_ns_t bound_start_ns = 0;
  double measured_gyro_density = 0.0;   // rad/s/sqrt(Hz), when measured
  double measured_accel_density = 0.0;  // m/s^2/sqrt(Hz), when measured
  // The high-frequency content in motion (check_in_motion), densities as
  // above; 0 when the motion was shorter than one window.
  double motion_gyro_density = 0.0;
  double motion_accel_density = 0.0;
  std::vector<std::string> changes;  // one line per changed figure
  std::string message;               // one paragraph for the log and summary
};

// White-noise densities of the readings in [start_ns, end_ns] (stamps of
// `imu`, increasing): {gyro, accel}, the per-axis standard deviations about
// the mean times sqrt(mean sample interval), averaged over the three axes;
// {0, 0} with fewer than 10 samples.
std::pair<double, double> MeasureWhiteNoiseDensities(const std::vector<ImuSample>& imu,
                                                     timestamp_ns_t start_ns,
                                                     timestamp_ns_t end_ns);

// The window of `window_s` (stepped by a quarter of it) whose accelerometer
// readings spread least about their mean, and its densities measured as by
// MeasureWhiteNoiseDensities: {start stamp, {gyro, accel}}; {0, {0, 0}}
// when the stream is shorter than the window.
std::pair<timestamp_ns_t, std::pair<double, double>> QuietestWindowDensities(
    const std::vector<ImuSample>& imu, double window_s);
// The high-frequency content of the readings in [start_ns, end_ns] as
// white-noise densities {gyro, accel}: in each window of window_s, the
// per-axis standard deviation of a reading's difference from the line
// through its neighbours (scaled to a reading's noise), times sqrt(mean
// sample interval), averaged over the axes; the median over the windows.
// {0, 0} when the span holds no whole window.
std::pair<double, double> MeasureHighFrequencyDensities(const std::vector<ImuSample>& imu,
                                                        timestamp_ns_t start_ns,
                                                        timestamp_ns_t end_ns, double window_s);

// `static_interval` may be null or not static (no measurement then).
// `motion_start_ns`: where the motion the VIO estimates begins (the first
// image, or the end of the static interval after it); its first
// options.motion_span_s, as far as `imu` reaches and before `motion_end_ns`,
// are measured in motion.
ImuNoiseCheck CheckImuNoise(const ImuNoise& given, const std::vector<ImuSample>& imu,
                            const StaticInitResult* static_interval,
                            const ImuNoiseCheckOptions& options = {},
                            timestamp_ns_t motion_start_ns = 0, timestamp_ns_t motion_end_ns = 0);

}  // namespace viosfm

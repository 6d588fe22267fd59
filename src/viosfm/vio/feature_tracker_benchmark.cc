// Front-end speed: milliseconds per frame of FeatureTracker::Track (default
// options: 150 corners, KLT forward and backward, essential-matrix RANSAC,
// detection of new corners) on rendered 752x480 frames of the `room`
// scenario walking at 20 Hz. 40 consecutive frames are rendered once, outside
// the timed loop; each iteration tracks the next one, and the tracker starts
// over (untimed) after the last, so every iteration is a frame-to-frame step
// at the sequence's real motion. Variants: with the gyro rotation prior
// (ground truth), and with CLAHE on every frame.
//
// OpenCV's own worker threads: run with OPENCV_FOR_THREADS_NUM=1 (read by
// OpenCV at start-up) for a strictly single-threaded measurement; the
// per-point KLT and the detector are what OpenCV may parallelise.
#include <benchmark/benchmark.h>

#include <optional>
#include <vector>

#include "viosfm/sim/renderer.h"
#include "viosfm/sim/sequence_simulator.h"
#include "viosfm/vio/feature_tracker.h"

namespace viosfm {
namespace {

constexpr size_t kNumFrames = 40;

struct Frames {
  SimulationOptions options;
  std::vector<GreyImage> images;
  std::vector<timestamp_ns_t> stamps;
  std::vector<Eigen::Quaterniond> cam_now_from_cam_prev;  // [k]: frame k-1 -> k
};

Frames MakeFrames() {
  Frames frames;
  frames.options.scenario = "room";
  frames.options.duration_s = 4.0;
  frames.options.static_start_s = 0.0;
  frames.options.seed = 0;
  const SimulatedSequence simulated = SimulateSequence(frames.options);
  const RayTable rays(frames.options.camera);
  const size_t first = simulated.sequence.images.size() - kNumFrames;
  for (size_t k = first; k < simulated.sequence.images.size(); ++k) {
    const timestamp_ns_t t = simulated.sequence.images[k].timestamp_ns;
    frames.images.push_back(RenderSimulatedFrame(simulated, rays, k, frames.options, 2));
    frames.stamps.push_back(t);
    const timestamp_ns_t previous = simulated.sequence.images[k - 1].timestamp_ns;
    frames.cam_now_from_cam_prev.push_back(
        (SimulatedCamFromWorld(simulated, t) * SimulatedCamFromWorld(simulated, previous).Inverse())
            .rotation);
  }
  return frames;
}

const Frames& RoomFrames() {
  static const Frames frames = MakeFrames();
  return frames;
}

void RunTracker(benchmark::State& state, const FeatureTrackerOptions& options, bool with_prior) {
  const Frames& frames = RoomFrames();
  std::optional<FeatureTracker> tracker;
  size_t k = 0;
  size_t num_features = 0;
  size_t num_frames = 0;
  for (auto _ : state) {
    if (k == 0) {
      state.PauseTiming();
      tracker.emplace(frames.options.camera, options);
      tracker->Track(frames.stamps[0], frames.images[0]);
      k = 1;
      state.ResumeTiming();
    }
    std::optional<Eigen::Quaterniond> prior;
    if (with_prior) prior = frames.cam_now_from_cam_prev[k];
    const FrameFeatures features = tracker->Track(frames.stamps[k], frames.images[k], prior);
    benchmark::DoNotOptimize(features.observations.data());
    num_features += features.observations.size();
    ++num_frames;
    k = (k + 1) % frames.images.size();
  }
  state.counters["features"] =
      num_frames > 0 ? static_cast<double>(num_features) / static_cast<double>(num_frames) : 0.0;
  state.SetItemsProcessed(state.iterations());
}

void BM_TrackRoom752x480(benchmark::State& state) {
  RunTracker(state, FeatureTrackerOptions{}, /*with_prior=*/false);
}
BENCHMARK(BM_TrackRoom752x480)->Unit(benchmark::kMillisecond)->MinTime(2.0);

void BM_TrackRoom752x480WithRotationPrior(benchmark::State& state) {
  RunTracker(state, FeatureTrackerOptions{}, /*with_prior=*/true);
}
BENCHMARK(BM_TrackRoom752x480WithRotationPrior)->Unit(benchmark::kMillisecond)->MinTime(2.0);

void BM_TrackRoom752x480Clahe(benchmark::State& state) {
  FeatureTrackerOptions options;
  options.equalization = ContrastEqualization::kAlways;
  RunTracker(state, options, /*with_prior=*/false);
}
BENCHMARK(BM_TrackRoom752x480Clahe)->Unit(benchmark::kMillisecond)->MinTime(2.0);

void BM_TrackRoom752x480Fundamental(benchmark::State& state) {
  FeatureTrackerOptions options;
  options.ransac_essential = false;
  RunTracker(state, options, /*with_prior=*/false);
}
BENCHMARK(BM_TrackRoom752x480Fundamental)->Unit(benchmark::kMillisecond)->MinTime(2.0);

}  // namespace
}  // namespace viosfm

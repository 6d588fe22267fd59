// The shared fixture of the pipeline's tests: a small simulated sequence,
// its run with small options, and helpers to copy runs and datasets.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "viosfm/geometry/alignment.h"
#include "viosfm/io/colmap_model.h"
#include "viosfm/io/ply.h"
#include "viosfm/io/trajectory_io.h"
#include "viosfm/pipeline/pipeline.h"
#include "viosfm/pipeline/run_fingerprint.h"
#include "viosfm/pipeline/stage_dataset.h"
#include "viosfm/scene/reprojection.h"
#include "viosfm/sensor/camera_models.h"
#include "viosfm/sim/sequence_simulator.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace pipeline_testing {

namespace fs = std::filesystem;

// A 4.5 s walk in the simulated room (1 s static start) at 10 Hz, rendered at
// half the EuRoC resolution, with an emulated VIO that drifts 5 times more
// than the simulator's default but jitters less; the pipeline run once on it with small settings.
struct Fixture {
  fs::path folder;
  fs::path dataset;
  fs::path vio_file;
  fs::path out;
  PipelineSummary summary;
  // The simulator's exact world_from_body at every image stamp.
  std::map<timestamp_ns_t, Rigid3d> truth;
  timestamp_ns_t first_stamp_ns = 0;
};

// The small settings of the pipeline's tests: `max_features` SIFT
// features, N1 4, N2 2, a small vocabulary for ~50 images (see
// verification_driver_test.cc), batches of 10, no progress bars.
inline PipelineOptions SmallRunOptions(const fs::path& dataset, const fs::path& vio_file,
                                       const fs::path& out, int max_features) {
  PipelineOptions options;
  options.dataset = dataset;
  options.output_folder = out;
  options.vio_trajectory = vio_file;
  options.sift.max_num_features = max_features;
  options.verification.pairs.num_temporal_neighbors = 4;
  options.verification.pairs.num_retrieval_neighbors = 2;
  options.verification.retrieval.vocabulary.branching = 8;
  options.verification.retrieval.vocabulary.depth = 3;
  options.mapper.batch_size = 10;
  options.show_progress = false;
  return options;
}

inline PipelineOptions SmallOptions(const Fixture& f, const fs::path& out) {
  PipelineOptions options = SmallRunOptions(f.dataset, f.vio_file, out, 600);
  options.num_threads = 2;
  options.seed = 7;
  return options;
}

// A 3 s walk in the simulated room (0.5 s static start) at 10 Hz and half
// the default camera's resolution: a few seconds of a whole run.
inline SimulationOptions HalfResolutionRoom(uint64_t seed) {
  SimulationOptions sim;
  sim.scenario = "room";
  sim.duration_s = 3.0;
  sim.static_start_s = 0.5;
  sim.camera_rate_hz = 10.0;
  sim.texels_per_metre = 64.0;
  sim.seed = seed;
  Camera camera = SimulationOptions::DefaultCamera();
  camera.width /= 2;
  camera.height /= 2;
  for (int i = 0; i < 4; ++i)
    camera.params[i] = i < 2 ? camera.params[i] / 2 : (camera.params[i] + 0.5) / 2 - 0.5;
  sim.camera = camera;
  return sim;
}

// The fixture's simulation; another seed gives another dataset with the
// same image names and stamps (other images, IMU readings and VIO drift).
inline SimulationOptions FixtureSimulation(uint64_t seed) {
  SimulationOptions sim = HalfResolutionRoom(seed);
  sim.duration_s = 4.5;
  sim.static_start_s = 1.0;
  // A VIO that is locally accurate but drifts (the case the paper's
  // relative-pose constraints are made for).
  sim.vio_drift.position_walk_m_per_sqrt_m = 0.05;
  sim.vio_drift.yaw_walk_rad_per_sqrt_m = 0.01;
  sim.vio_drift.position_jitter_m = 0.001;
  sim.vio_drift.rotation_jitter_rad = 0.0005;
  return sim;
}

inline const Fixture& SharedFixture() {
  static const Fixture fixture = [] {
    Fixture f;
    f.folder = testing::MakeScratchFolder("pipeline");
    const SimulationOptions sim = FixtureSimulation(5);
    const SimulatedSequence simulated = SimulateSequence(sim);
    f.dataset = f.folder / "dataset";
    WriteSimulatedSequence(f.dataset, simulated, sim);
    for (size_t k = 0; k < simulated.sequence.images.size(); ++k) {
      f.truth[simulated.sequence.images[k].timestamp_ns] =
          simulated.motion.WorldFromBody(simulated.FrameTime(k));
    }
    f.first_stamp_ns = simulated.sequence.images.front().timestamp_ns;
    f.vio_file = f.dataset / "vio_emulated.tum";
    f.out = f.folder / "out";
    f.summary = RunPipeline(SmallOptions(f, f.out));
    std::cerr << f.summary.ToString() << "\n";
    return f;
  }();
  return fixture;
}

// The fixture's simulation with seed 6: the same image names and stamps.
inline const fs::path& SecondDataset() {
  static const fs::path dataset = [] {
    const fs::path path = SharedFixture().folder / "dataset_seed6";
    const SimulationOptions sim = FixtureSimulation(6);
    WriteSimulatedSequence(path, SimulateSequence(sim), sim);
    return path;
  }();
  return dataset;
}

// A copy of the fixture's output folder (database, fingerprint, outputs):
// what a re-run into the fixture's folder would find there.
inline fs::path CopyOfTheRun(const Fixture& f, const std::string& name) {
  const fs::path out = f.folder / name;
  fs::remove_all(out);
  fs::copy(f.out, out, fs::copy_options::recursive);
  return out;
}

// A copy of a dataset: text files copied, images linked.
inline fs::path CopyDataset(const fs::path& source, const fs::path& target) {
  return testing::CopyFolderLinkingImages(source, target);
}

// world_from_body of every registered image of a COLMAP model, by stamp
// (image names are "<stamp>.png").
inline std::map<timestamp_ns_t, Rigid3d> BodyPosesOfModel(const Reconstruction& model) {
  const Rigid3d cam_from_body = SimulationOptions::DefaultBodyFromCam().Inverse();
  std::map<timestamp_ns_t, Rigid3d> poses;
  for (const image_t image_id : model.RegImageIds()) {
    const Image& image = model.GetImage(image_id);
    const timestamp_ns_t stamp = std::stoll(fs::path(image.name).stem().string());
    poses[stamp] = image.cam_from_world.Inverse() * cam_from_body;
  }
  return poses;
}

// The Sim(3) that best aligns the positions of `poses` to the truth
// (Umeyama), and each pose's position error after it (m).
inline std::vector<double> AlignedPositionErrors(const std::map<timestamp_ns_t, Rigid3d>& poses,
                                                 const std::map<timestamp_ns_t, Rigid3d>& truth,
                                                 Sim3d* truth_from_estimate) {
  std::vector<Eigen::Vector3d> estimated, expected;
  for (const auto& [stamp, pose] : poses) {
    estimated.push_back(pose.translation);
    expected.push_back(truth.at(stamp).translation);
  }
  const std::optional<Sim3d> alignment = AlignPointsUmeyama(estimated, expected, true);
  EXPECT_TRUE(alignment.has_value());
  if (!alignment) return {};
  *truth_from_estimate = *alignment;
  std::vector<double> errors;
  for (size_t i = 0; i < estimated.size(); ++i) {
    errors.push_back((*alignment * estimated[i] - expected[i]).norm());
  }
  return errors;
}

inline size_t CountLines(const fs::path& path) {
  std::ifstream stream(path);
  size_t count = 0;
  for (std::string line; std::getline(stream, line);) ++count;
  return count;
}

}  // namespace pipeline_testing
}  // namespace viosfm

// Run time and accuracy of the batched mapper on the synthetic corridor
// sequence of synthetic_test_scene.h (10 cm per frame, ~240 keypoints a
// frame, 0.5 px noise, tracks of at most 20 frames, pairs up to 5 frames
// apart) with a VIO whose position and yaw drift as random walks (1 mm and
// 2 mrad a frame), batch size 50. Arguments: frames; ba_window_batches (0 =
// the paper's BA over all images after every batch); prior sigmas (0 = the
// BA defaults, 1 = sigma_t 0.025 m and sigma_rot 0.05 rad: the VIO's
// frame-to-frame noise at the weight w ~ 1e3 exp(-0.003 * 240) ~ 490 of
// ~240 matches, sigma / sqrt(w)). One iteration a configuration; counters:
// the VIO's and the mapper's camera-centre RMSE (m, no alignment: both
// share the first pose), the RMSE after a Sim(3) alignment and the Sim(3)
// scale; wall seconds (total, per batch, BA, final BA) and the process CPU
// seconds (all threads: the machine may be shared).
#include <benchmark/benchmark.h>

#include <ctime>
#include <vector>

#include "viosfm/geometry/alignment.h"
#include "viosfm/sfm/batched_mapper.h"
#include "viosfm/sfm/synthetic_test_scene.h"

namespace viosfm {
namespace {

struct Alignment {
  double rmse_m = 0.0;
  double sim3_rmse_m = 0.0;
  double scale = 1.0;
};

Alignment Compare(const std::vector<Rigid3d>& truth, const std::vector<Rigid3d>& poses) {
  Alignment result;
  result.rmse_m = testing::CenterRmse(truth, poses);
  std::vector<Eigen::Vector3d> estimated;
  std::vector<Eigen::Vector3d> reference;
  for (size_t i = 0; i < truth.size(); ++i) {
    estimated.push_back(ProjectionCenter(poses[i]));
    reference.push_back(ProjectionCenter(truth[i]));
  }
  const std::optional<Sim3d> reference_from_estimated =
      AlignPointsUmeyama(estimated, reference, true);
  if (!reference_from_estimated) return result;
  double sum = 0.0;
  for (size_t i = 0; i < truth.size(); ++i) {
    const Eigen::Vector3d aligned =
        reference_from_estimated->scale * (reference_from_estimated->rotation * estimated[i]) +
        reference_from_estimated->translation;
    sum += (aligned - reference[i]).squaredNorm();
  }
  result.sim3_rmse_m = std::sqrt(sum / static_cast<double>(truth.size()));
  result.scale = 1.0 / reference_from_estimated->scale;
  return result;
}

void BM_BatchedMapperCorridor(benchmark::State& state) {
  testing::SyntheticSequenceOptions sequence_options;
  sequence_options.num_frames = static_cast<int>(state.range(0));
  sequence_options.step_m = 0.1;
  testing::SyntheticSequence sequence = testing::MakeSyntheticSequence(sequence_options);
  testing::ApplyVioDrift(sequence.cams_from_world, testing::VioDriftOptions{0.001, 0.002, 7},
                         &sequence.input);
  BatchedMapperOptions options;
  options.show_progress = false;
  options.ba_window_batches = static_cast<int>(state.range(1));
  if (state.range(2) == 1) {
    options.ba.prior_translation_sigma_m = 0.025;
    options.ba.prior_rotation_sigma_rad = 0.05;
  }
  std::vector<Rigid3d> vio;
  for (const MapperImage& image : sequence.input.images) vio.push_back(*image.vio_cam_from_world);
  const Alignment vio_alignment = Compare(sequence.cams_from_world, vio);

  BatchedMapperSummary summary;
  for (auto _ : state) {
    const std::clock_t cpu_start = std::clock();
    const Reconstruction reconstruction = RunBatchedMapper(sequence.input, options, &summary);
    state.counters["cpu_s"] = static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC;
    double ba_s = 0.0;
    for (const MapperBatchStatistics& batch : summary.batches) ba_s += batch.seconds_ba;
    state.counters["ba_s"] = ba_s;
    state.counters["final_ba_iterations"] = summary.final_ba.num_iterations;
    std::vector<Rigid3d> poses;
    for (const MapperImage& image : sequence.input.images) {
      poses.push_back(reconstruction.GetImage(image.image_id).cam_from_world);
    }
    const Alignment alignment = Compare(sequence.cams_from_world, poses);
    state.counters["vio_rmse_m"] = vio_alignment.rmse_m;
    state.counters["vio_sim3_rmse_m"] = vio_alignment.sim3_rmse_m;
    state.counters["rmse_m"] = alignment.rmse_m;
    state.counters["sim3_rmse_m"] = alignment.sim3_rmse_m;
    state.counters["scale"] = alignment.scale;
    state.counters["registered"] = summary.num_registered;
    state.counters["points"] = summary.num_points;
    state.counters["reproj_px"] = summary.mean_reprojection_error_px;
    state.counters["total_s"] = summary.seconds_total;
    state.counters["s_per_batch"] =
        summary.seconds_total / static_cast<double>(summary.batches.size());
    state.counters["final_ba_s"] = summary.final_ba.time_s;
    state.counters["last_batch_s"] = summary.batches.size() > 1
                                         ? summary.batches[summary.batches.size() - 2].seconds_total
                                         : 0.0;
  }
}
BENCHMARK(BM_BatchedMapperCorridor)
    ->Args({600, 0, 1})
    ->Args({600, 2, 1})
    ->Args({300, 0, 1})
    ->Args({300, 2, 1})
    ->Args({600, 0, 0})
    ->Args({1000, 2, 1})
    ->Args({1000, 0, 1})
    ->ArgNames({"frames", "window", "sigmas"})
    ->Iterations(1)
    ->Unit(benchmark::kSecond)
    ->UseRealTime();

}  // namespace
}  // namespace viosfm

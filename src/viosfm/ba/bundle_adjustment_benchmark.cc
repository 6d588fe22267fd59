// Time of bundle adjustment on a reconstruction from a `viosfm run` (its
// `model` folder, given by the environment variable VIOSFM_BA_MODEL; the
// benchmark is skipped without it), e.g. the 610-image room of the
// benchmark suite:
//
//   export VIOSFM_BA_MODEL=/tmp/bench_full/room/runs/viosfm/run/model
//   build/src/viosfm/ba/bench_ba_bundle_adjustment_benchmark
//
// The model's points are perturbed by 1 cm and its poses by 1 mm / 1 mrad
// (seed 0); the first pose is held. Arguments: the linear solver (0 auto,
// 1 SPARSE_SCHUR, 2 DENSE_SCHUR, 3 ITERATIVE_SCHUR), the number of images
// (the first N registered ones; 0 = all) and threads. Five
// Levenberg-Marquardt iterations, no relative-pose priors. Counters: seconds
// per iteration (wall and process CPU), final cost and mean reprojection
// error.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdlib>
#include <ctime>
#include <string>
#include <vector>

#include "viosfm/ba/bundle_adjustment.h"
#include "viosfm/io/colmap_model.h"
#include "viosfm/util/random.h"

namespace viosfm {
namespace {

const Reconstruction* LoadedModel() {
  static const Reconstruction* model = []() -> const Reconstruction* {
    const char* folder = std::getenv("VIOSFM_BA_MODEL");
    if (folder == nullptr) return nullptr;
    return new Reconstruction(ReadColmapModel(folder));
  }();
  return model;
}

// The first `num_images` registered images of `model` (all for 0) with the
// points they observe, perturbed.
Reconstruction PerturbedSubset(const Reconstruction& model, int num_images) {
  Reconstruction reconstruction = model;
  std::vector<image_t> registered = reconstruction.RegImageIds();
  std::sort(registered.begin(), registered.end());
  if (num_images > 0 && num_images < static_cast<int>(registered.size())) {
    for (size_t i = static_cast<size_t>(num_images); i < registered.size(); ++i) {
      reconstruction.GetImage(registered[i]).registered = false;
    }
    // Points seen by fewer than two of the kept images go.
    for (const point3D_t point3D_id : reconstruction.Point3DIds()) {
      int seen = 0;
      for (const TrackElement& element : reconstruction.GetPoint3D(point3D_id).track) {
        seen += reconstruction.GetImage(element.image_id).registered ? 1 : 0;
      }
      if (seen < 2) reconstruction.DeletePoint3D(point3D_id);
    }
  }
  Random random(0);
  for (const image_t image_id : reconstruction.RegImageIds()) {
    if (image_id == registered.front()) continue;
    Rigid3d& pose = reconstruction.GetImage(image_id).cam_from_world;
    const Eigen::Vector3d angle(random.Normal(0, 1e-3), random.Normal(0, 1e-3),
                                random.Normal(0, 1e-3));
    pose.rotation =
        Eigen::Quaterniond(Eigen::AngleAxisd(angle.norm(), angle.normalized())) * pose.rotation;
    pose.translation +=
        Eigen::Vector3d(random.Normal(0, 1e-3), random.Normal(0, 1e-3), random.Normal(0, 1e-3));
  }
  for (const point3D_t point3D_id : reconstruction.Point3DIds()) {
    reconstruction.GetPoint3D(point3D_id).xyz +=
        Eigen::Vector3d(random.Normal(0, 1e-2), random.Normal(0, 1e-2), random.Normal(0, 1e-2));
  }
  return reconstruction;
}

void BM_BundleAdjustModel(benchmark::State& state) {
  const Reconstruction* model = LoadedModel();
  if (model == nullptr) {
    state.SkipWithError("set VIOSFM_BA_MODEL to a COLMAP model folder");
    return;
  }
  BundleAdjustmentOptions options;
  options.linear_solver = static_cast<BaLinearSolver>(state.range(0));
  options.max_num_iterations = 5;
  options.function_tolerance = 0.0;
  options.gradient_tolerance = 0.0;
  options.parameter_tolerance = 0.0;
  options.num_threads = static_cast<int>(state.range(2));
  for (auto _ : state) {
    state.PauseTiming();
    Reconstruction reconstruction = PerturbedSubset(*model, static_cast<int>(state.range(1)));
    std::vector<image_t> registered = reconstruction.RegImageIds();
    const image_t first = *std::min_element(registered.begin(), registered.end());
    state.ResumeTiming();
    const std::clock_t cpu_start = std::clock();
    const BundleAdjustmentSummary summary = BundleAdjust(&reconstruction, {}, {first}, options);
    const double cpu_s = static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC;
    const double iterations = std::max(1, summary.num_iterations);
    state.counters["images"] = summary.num_images;
    state.counters["observations"] = summary.num_observations;
    state.counters["s_per_iteration"] = summary.time_s / iterations;
    state.counters["cpu_s_per_iteration"] = cpu_s / iterations;
    state.counters["final_cost"] = summary.final_cost;
    state.counters["reproj_px"] = summary.mean_reprojection_error_after_px;
  }
}
BENCHMARK(BM_BundleAdjustModel)
    ->ArgsProduct({{1, 2, 3}, {150, 300, 0}, {1}})
    ->ArgNames({"solver", "images", "threads"})
    ->Iterations(1)
    ->Unit(benchmark::kSecond)
    ->UseRealTime();

}  // namespace
}  // namespace viosfm

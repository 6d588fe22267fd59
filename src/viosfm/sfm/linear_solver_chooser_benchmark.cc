// What each linear solver costs per Levenberg-Marquardt iteration on a
// stored reconstruction, beside the problem structure the chooser decides
// from (sfm/linear_solver_chooser.h), both solvers in the same run:
//
//   export VIOSFM_BA_MODEL=/tmp/bench/room/run/model
//   build/src/viosfm/sfm/bench_sfm_linear_solver_chooser_benchmark
//
// As bench_ba_bundle_adjustment_benchmark: the first N registered images
// (by id; 0 = all) with the points at least two of them see, points
// perturbed by 1 cm and poses by 1 mm / 1 mrad (seed 0), the first pose
// held, five iterations, one thread. Arguments: solver (1 SPARSE_SCHUR,
// 3 ITERATIVE_SCHUR), images, priors (1: the mapper's relative-pose terms
// between consecutive images, from the model's poses, weighted by the
// points the two share; 0: none, as bench_ba). Counters: the
// structure (n, observations, points, covisible pairs E, X = E^2 / (n obs),
// the solver the chooser takes), the wall and process CPU seconds per
// iteration and per iteration and observation (us), and the final cost.
#include <benchmark/benchmark.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cstdlib>
#include <ctime>
#include <memory>
#include <vector>

#include "viosfm/ba/bundle_adjustment.h"
#include "viosfm/io/colmap_model.h"
#include "viosfm/sfm/ba_problem_structure.h"
#include "viosfm/sfm/linear_solver_chooser.h"
#include "viosfm/util/random.h"

namespace viosfm {
namespace {

const Reconstruction* LoadedModel() {
  static const std::unique_ptr<Reconstruction> model = []() -> std::unique_ptr<Reconstruction> {
    const char* folder = std::getenv("VIOSFM_BA_MODEL");
    if (folder == nullptr) return nullptr;
    return std::make_unique<Reconstruction>(ReadColmapModel(folder));
  }();
  return model.get();
}

Reconstruction PerturbedSubset(const Reconstruction& model, int num_images) {
  Reconstruction reconstruction = model;
  std::vector<image_t> registered = reconstruction.RegImageIds();
  std::sort(registered.begin(), registered.end());
  if (num_images > 0 && num_images < static_cast<int>(registered.size())) {
    for (size_t i = static_cast<size_t>(num_images); i < registered.size(); ++i) {
      reconstruction.GetImage(registered[i]).registered = false;
    }
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

// The mapper's relative-pose terms between consecutive registered images
// (by id), from the model's own (unperturbed) poses, weighted by the number
// of points the two images share (the mapper uses its verified matches).
std::vector<RelativePosePrior> ConsecutivePriors(const Reconstruction& model, int num_images) {
  std::vector<image_t> registered = model.RegImageIds();
  std::sort(registered.begin(), registered.end());
  if (num_images > 0 && num_images < static_cast<int>(registered.size())) {
    registered.resize(static_cast<size_t>(num_images));
  }
  std::vector<RelativePosePrior> priors;
  for (size_t i = 1; i < registered.size(); ++i) {
    const Image& image1 = model.GetImage(registered[i - 1]);
    const Image& image2 = model.GetImage(registered[i]);
    std::vector<point3D_t> points1;
    for (const Point2D& point2D : image1.points2D) {
      if (point2D.HasPoint3D()) points1.push_back(point2D.point3D_id);
    }
    std::sort(points1.begin(), points1.end());
    int shared = 0;
    for (const Point2D& point2D : image2.points2D) {
      shared += point2D.HasPoint3D() &&
                std::binary_search(points1.begin(), points1.end(), point2D.point3D_id);
    }
    RelativePosePrior prior;
    prior.image_id1 = image1.image_id;
    prior.image_id2 = image2.image_id;
    prior.cam2_from_cam1 = image2.cam_from_world * image1.cam_from_world.Inverse();
    prior.num_verified_matches = shared;
    priors.push_back(prior);
  }
  return priors;
}

void BM_SolverCostAndStructure(benchmark::State& state) {
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
  options.num_threads = 1;
  const std::vector<RelativePosePrior> priors =
      state.range(2) != 0 ? ConsecutivePriors(*model, static_cast<int>(state.range(1)))
                          : std::vector<RelativePosePrior>();
  for (auto _ : state) {
    state.PauseTiming();
    Reconstruction reconstruction = PerturbedSubset(*model, static_cast<int>(state.range(1)));
    std::vector<image_t> registered = reconstruction.RegImageIds();
    std::sort(registered.begin(), registered.end());
    const image_t first = registered.front();
    const std::vector<image_t> free_images(registered.begin() + 1, registered.end());
    const std::clock_t structure_start = std::clock();
    const BaProblemStructure structure = ComputeBaProblemStructure(reconstruction, free_images);
    const double structure_s = static_cast<double>(std::clock() - structure_start) / CLOCKS_PER_SEC;
    BundleAdjustmentOptions auto_options;  // the chooser's defaults
    LinearSolverChooser chooser(auto_options);
    const BaLinearSolver chosen = chooser.Next(structure, /*final=*/false);
    state.ResumeTiming();
    const std::clock_t cpu_start = std::clock();
    const BundleAdjustmentSummary summary = BundleAdjust(&reconstruction, priors, {first}, options);
    const double cpu_s = static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC;
    const double iterations = std::max(1, summary.num_iterations);
    const double observations = std::max(1, summary.num_observations);
    state.counters["n"] = static_cast<double>(structure.num_free_images);
    state.counters["obs"] = static_cast<double>(structure.num_observations);
    state.counters["points"] = static_cast<double>(structure.num_points);
    state.counters["E"] = static_cast<double>(structure.num_covisible_pairs);
    state.counters["X"] = structure.FillPerObservation();
    state.counters["structure_s"] = structure_s;
    state.counters["chosen"] = static_cast<double>(chosen);
    state.counters["s_per_it"] = summary.time_s / iterations;
    state.counters["cpu_s_per_it"] = cpu_s / iterations;
    state.counters["cpu_us_per_it_obs"] = 1e6 * cpu_s / iterations / observations;
    state.counters["final_cost"] = summary.final_cost;
  }
}
BENCHMARK(BM_SolverCostAndStructure)
    ->ArgsProduct({{1, 3}, {150, 300, 0}, {1, 0}})
    ->ArgNames({"solver", "images", "priors"})
    ->Iterations(1)
    ->Unit(benchmark::kSecond)
    ->UseRealTime();

// The structure alone (no adjustment) of the first N images, every 50, then all (0).
void BM_Structure(benchmark::State& state) {
  const Reconstruction* model = LoadedModel();
  if (model == nullptr) {
    state.SkipWithError("set VIOSFM_BA_MODEL to a COLMAP model folder");
    return;
  }
  for (auto _ : state) {
    state.PauseTiming();
    Reconstruction reconstruction = PerturbedSubset(*model, static_cast<int>(state.range(0)));
    std::vector<image_t> registered = reconstruction.RegImageIds();
    std::sort(registered.begin(), registered.end());
    const std::vector<image_t> free_images(registered.begin() + 1, registered.end());
    state.ResumeTiming();
    const BaProblemStructure structure =
        ComputeBaProblemStructure(reconstruction, free_images, /*with_factorization=*/true);
    state.counters["n"] = static_cast<double>(structure.num_free_images);
    state.counters["F"] = structure.FactorizationPerObservation();
    state.counters["F_image"] = structure.FactorizationPerImage();
    state.counters["L"] = static_cast<double>(structure.num_observations) /
                          static_cast<double>(std::max<size_t>(1, structure.num_points));
    state.counters["X"] = structure.FillPerObservation();
    state.counters["E_fraction"] = 2.0 * static_cast<double>(structure.num_covisible_pairs) /
                                   (static_cast<double>(structure.num_free_images) *
                                    static_cast<double>(structure.num_free_images - 1));
  }
}
BENCHMARK(BM_Structure)
    ->DenseRange(100, 600, 50)
    ->Arg(0)
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace viosfm

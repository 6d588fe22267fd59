// Tables and figures of a benchmark-suite folder (bench/run.sh): for every
// sequence the methods side by side (frames registered, Sim(3) ATE RMSE and
// median, time, peak memory), as the paper's Table I; the ablations; ATE and
// time against batch size (the paper's Fig. 6); time and memory against
// sequence length; trajectory views of viosfm and COLMAP.
//
// Folder layout (what bench/run.sh writes):
//   ROOT/meta.txt                      "key: value" lines (date, machine, settings)
//   ROOT/<sequence>/sequence/          the dataset (EuRoC layout; ground truth)
//   ROOT/<sequence>/runs/<method>/     one run: time.txt ("seconds peak_kib
//       [user_s system_s]"), eval.json (`viosfm eval --json`, Sim(3)),
//       eval_se3.json (the same with SE(3); optional), failed (present
//       if the run failed), reused.txt (present if the run started from
//       another run's features and matches: what it reused), version.txt
//       (the viosfm version that made the run, if recorded), run/ (a
//       `viosfm run` output folder) or sparse/N/ (COLMAP models)
//   ROOT/batch_size/<k>/               a `viosfm run` with batch size k
//   ROOT/batch_size_sequence.txt       the sequence the batch sizes ran on (its
//       COLMAP and VIO runs are the reference lines; default: the first)
//   ROOT/length/<frames>/              a `viosfm run` on a sequence of that length
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "viosfm/scene/trajectory.h"

namespace viosfm {

// One run of one method.
struct BenchRun {
  std::string sequence;  // e.g. "two_floors"
  std::string method;    // e.g. "viosfm", "colmap_same_pairs", "batch 25"
  std::filesystem::path folder;
  bool failed = false;
  int frames_in = 0;                   // images of the sequence
  int frames_registered = 0;           // poses evaluated (0 without eval.json)
  int num_models = 0;                  // COLMAP: models written (0 for others)
  std::optional<double> ate_rmse_m;    // Sim(3)
  std::optional<double> ate_median_m;  // Sim(3)
  // Metric accuracy: the SE(3) ATE RMSE (eval_se3.json) and the run's scale
  // (1 / the Sim(3) alignment's scale; 1.02: 2 % too long).
  std::optional<double> ate_se3_rmse_m;
  std::optional<double> scale;
  std::optional<double> seconds;          // wall clock of the whole run
  std::optional<double> cpu_seconds;      // user + system CPU time
  std::string reused;                     // what the run reused (reused.txt), or empty
  std::string version;                    // version.txt (viosfm runs), or empty
  std::optional<double> peak_memory_mb;   // MiB
  std::optional<double> mapping_seconds;  // viosfm: the mapper stage
};

// Where a run put the floors of a multi-floor sequence (sequence/frames.csv
// with a "floor" column; -1 = between floors): the mean height of each
// floor's frames after the Sim(3) alignment to the ground truth, beside the
// true mean height of the same frames.
struct FloorPlacement {
  std::string method;
  std::vector<int> floors;            // floor numbers, ascending
  std::vector<int> num_frames;        // registered frames per floor
  std::vector<double> mean_height_m;  // estimated, ground-truth world z
  std::vector<double> true_mean_height_m;
  // Sim(3) ATE RMSE of each floor's frames aligned on their own (the
  // accuracy within a floor, without the placement of the floors).
  std::vector<double> floor_ate_rmse_m;
};

struct BenchResults {
  std::filesystem::path root;
  std::vector<std::pair<std::string, std::string>> meta;  // meta.txt
  std::vector<BenchRun> runs;                             // <sequence>/runs/<method>
  std::vector<BenchRun> batch_size;                       // method = the batch size
  std::vector<BenchRun> length;                           // method = the number of frames
  std::string batch_size_sequence;                        // the sequence of the batch-size sweep
  // Per sequence with two or more floors: the floor placement of each run
  // with a trajectory.
  std::vector<std::pair<std::string, std::vector<FloorPlacement>>> floors;
};

// Reads a benchmark folder. Throws InputError for a missing folder or a
// malformed eval.json / summary.json / time.txt (naming the file).
BenchResults ReadBenchResults(const std::filesystem::path& root);

// The floor placement of `estimate` (body poses) against `ground_truth` for
// the frames of frames_csv (columns timestamp, region, floor, ...). Empty
// `floors` if the file has fewer than two floors or the estimate cannot be
// aligned to the ground truth. Throws InputError for a
// malformed frames.csv.
FloorPlacement ComputeFloorPlacement(const Trajectory& estimate, const Trajectory& ground_truth,
                                     const std::filesystem::path& frames_csv);

// The Markdown page: settings, the Table-I-style table per sequence, the
// floor placement, the ablation rows, the sweeps, links to the figures
// (relative to the page).
std::string FormatBenchMarkdown(const BenchResults& results,
                                const std::string& figures_relative_path);

// Writes the Markdown page (atomically) and the figures (SVG) into
// figures_folder: bench_batch_size_ate.svg, bench_batch_size_time.svg,
// bench_<sequence>_<method>_{top,side}.svg for viosfm and COLMAP.
void WriteBenchReport(const BenchResults& results, const std::filesystem::path& markdown_path,
                      const std::filesystem::path& figures_folder);

}  // namespace viosfm

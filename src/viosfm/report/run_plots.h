// Figures of a run: trajectory views coloured by position error (the paper's
// Fig. 5) and accuracy / time against the batch size (the paper's Fig. 6).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "viosfm/eval/traj_eval.h"
#include "viosfm/report/svg_plot.h"
#include "viosfm/scene/trajectory.h"

namespace viosfm {

struct TrajectoryPlotOptions {
  // How the estimate (and the input VIO) are aligned to the ground truth
  // before drawing. Default Sim(3) (a monocular SfM result has a free scale).
  AlignmentMode alignment = AlignmentMode::kSim3;
  // Largest stamp difference of an associated pose pair (ns). Default 10 ms.
  int64_t max_dt_ns = 10'000'000;
  // Legend of the estimate (e.g. "COLMAP 3.8" in the benchmark report).
  std::string estimate_label = "viosfm";
  // Size of each view (px). Defaults 560 x 440.
  double width = 560.0;
  double height = 440.0;

  // Empty if valid; otherwise names the bad field.
  std::string Validate() const;
  bool Check() const { return Validate().empty(); }
};

struct TrajectoryFigures {
  Figure top_view;   // x-y (m)
  Figure side_view;  // x-z (m)
  // The evaluations that placed the estimate / the VIO in the ground truth's
  // frame (set when a ground truth was given and the alignment succeeded).
  std::optional<EvaluationResult> estimate_evaluation;
  std::optional<EvaluationResult> vio_evaluation;
  // Why an alignment was not possible (empty when it was or was not tried).
  std::string estimate_alignment_error;
  std::string vio_alignment_error;
};

// The top and side views of `estimate`. With a non-empty `ground_truth`: the
// ground truth as a grey line and the estimate, aligned to it
// (EvaluateTrajectories with `options.alignment`), as a line coloured by each
// associated pose's position error (m, with a colour bar). A non-empty `vio`
// is drawn dashed, aligned to the ground truth on its own when there is one.
// Without a ground truth (or when the alignment fails) the trajectories are
// drawn as they are, in one colour each. Throws InputError for invalid options.
TrajectoryFigures MakeTrajectoryFigures(const Trajectory& estimate, const Trajectory& ground_truth,
                                        const Trajectory& vio,
                                        const TrajectoryPlotOptions& options = {});

// One curve of a batch-size sweep: values at the same batch sizes.
struct BatchSizeCurve {
  std::string label;  // legend, e.g. the sequence name
  std::vector<double> batch_sizes;
  std::vector<double> ate_rmse_m;
  std::vector<double> seconds;
};

// A value drawn as a dotted horizontal line (e.g. COLMAP's ATE or time).
struct ReferenceValue {
  std::string label;
  double value = 0.0;
};

struct BatchSizeSweep {
  std::vector<BatchSizeCurve> curves;
  std::vector<ReferenceValue> ate_references;   // m
  std::vector<ReferenceValue> time_references;  // s
  bool log_x = false;                           // logarithmic batch-size axis
  double width = 560.0;                         // px a figure
  double height = 380.0;
};

struct BatchSizeFigures {
  Figure ate;   // ATE RMSE (m) against batch size
  Figure time;  // total time (s) against batch size
};

// The two figures of a sweep. Throws InputError if a curve's vectors differ
// in length.
BatchSizeFigures MakeBatchSizeFigures(const BatchSizeSweep& sweep);

}  // namespace viosfm

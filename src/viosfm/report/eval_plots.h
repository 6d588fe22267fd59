// The figures of `viosfm eval --plot`, in the manner of evo's `evo_ape
// --plot`: the trajectories from above and from the side (the reference
// dashed grey, the aligned estimate coloured by its position error), the
// position error over time with its RMSE, median and mean, and the error's
// histogram; with a gyro check, its per-interval rotation error over time.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "viosfm/eval/gyro_check.h"
#include "viosfm/eval/traj_eval.h"
#include "viosfm/report/svg_plot.h"
#include "viosfm/scene/trajectory.h"

namespace viosfm {

struct EvaluationPlotOptions {
  std::string estimate_label = "estimate";
  std::string reference_label = "reference";
  // Size of each figure (px). Defaults 640 x 480.
  double width = 640.0;
  double height = 480.0;
  // Bins of the histogram; 0: about sqrt(n), 10 to 60. Default 0.
  int histogram_bins = 0;

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }
};

struct NamedFigure {
  std::string name;  // file stem, e.g. "trajectory_top"
  Figure figure;
};

// The figures of one evaluation. `est` and `ref` are the trajectories
// `result` was computed from, in the frames it compared (body poses when the
// evaluation converted camera poses); with `ref` empty only the gyro figure
// is made. Throws InputError for invalid options or when `result` does not
// index into `est` and `ref`.
std::vector<NamedFigure> MakeEvaluationFigures(const Trajectory& est, const Trajectory& ref,
                                               const EvaluationResult* result,
                                               const GyroCheckResult* gyro,
                                               const EvaluationPlotOptions& options = {});

// Writes FOLDER/NAME.svg and FOLDER/NAME.png of each figure (the folder is
// created); returns the paths written.
std::vector<std::filesystem::path> WriteFigures(const std::filesystem::path& folder,
                                                const std::vector<NamedFigure>& figures);

}  // namespace viosfm

// The HTML report of a `viosfm run` folder: one self-contained page (inline
// CSS and SVG, the 3D view's three.js and data embedded, no external files).
//
// Reads from RUN (only summary.json is required):
//   summary.json                 counts, timings, per-batch numbers, ATE summary
//   options.json                 the options used (shown as a table)
//   trajectory_body.tum          the estimate (body poses)
//   vio_body.tum                 the input VIO (body poses)
//   groundtruth_body.tum         the ground truth (body poses)
//   eval.json, eval_vio.json     eval/report.h EvaluationToJson of the
//                                estimate / the VIO against the ground truth
//   verification/verification.json, verification/pairs.csv
//                                io/verification_report.h
//   points.ply                   the points of the 3D view (report/viewer_3d.h)
// Sections: summary numbers, accuracy, trajectory views coloured by position
// error (Sim(3)-aligned to the ground truth), a 3D view of the points and the
// camera path (report/viewer_3d.h), pair verification (decisions,
// histogram of the VIO outlier ratio with its threshold), per-stage timings,
// per-batch bundle adjustment, options. A section whose files are missing
// says so ("no ground truth", ...).
#pragma once

#include <filesystem>
#include <string>

namespace viosfm {

// RUN/report.html.
std::filesystem::path DefaultReportPath(const std::filesystem::path& run_dir);

// The page's HTML text. Throws InputError naming RUN/summary.json if it is
// missing, and naming any file that is malformed.
std::string RenderRunReport(const std::filesystem::path& run_dir);

// Writes RenderRunReport(run_dir) atomically to `html_path`.
void WriteRunReport(const std::filesystem::path& run_dir, const std::filesystem::path& html_path);

}  // namespace viosfm

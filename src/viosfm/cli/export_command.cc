// `viosfm export RUN`: a finished run folder as the inputs of the next tools
// (COLMAP database with pose priors and model, transforms.json for
// nerfstudio / instant-ngp / Gaussian splatting, the images), in one
// self-contained folder; see pipeline/run_export.h.
#include <iostream>
#include <memory>
#include <string>

#include "viosfm/cli/commands.h"
#include "viosfm/pipeline/run_export.h"

namespace viosfm::cli {
namespace {

struct ExportArguments {
  std::string run;
  std::string out;
  std::string images;
  RunExportOptions options;
};

void RunExport(ExportArguments args) {
  RunExportOptions& options = args.options;
  options.run_folder = args.run;
  options.output_folder = args.out;
  options.image_folder = args.images;
  const RunExportSummary summary = ExportRun(options);
  std::cout << "Exported to " << summary.output_folder.string()
            << (summary.num_image_files > 0
                    ? " (self-contained: copy the folder alone; its README.txt repeats this).\n"
                    : " WITHOUT the images (the run's image folder was not found: export again "
                      "with --images DIR to make it self-contained).\n")
            << ExportGuide(summary, summary.output_folder);
}

}  // namespace

void RegisterExport(CLI::App& app) {
  auto args = std::make_shared<ExportArguments>();
  CLI::App* command = app.add_subcommand(
      "export",
      "Export a run for COLMAP, nerfstudio and gsplat, self-contained. One folder holds "
      "the images, a COLMAP database with the poses as pose priors, the model "
      "(sparse/0), transforms.json with sparse_pc.ply; prints the next steps");
  command->footer(
      "Example: viosfm export out/v101 (writes out/v101/export/; copy it to a GPU machine as "
      "it is). The images are hard links to the run's image files where the filesystem allows, "
      "else copies; every path in the folder is relative to it.");
  command->add_option("run", args->run, "Output folder of `viosfm run`")->required();
  command->add_option("--out", args->out,
                      "Export folder (default RUN/export): new, empty or an earlier export, whose "
                      "own files are replaced and what you added kept");
  command->add_option("--images", args->images,
                      "The run's image folder (default: from RUN/options.json)");
  command
      ->add_option("--prior-position-stddev", args->options.prior_position_stddev_m,
                   "Standard deviation of every camera position prior (m, isotropic); 0 "
                   "(default): each image's covariance from the model (its observations and "
                   "the metric scale's uncertainty)")
      ->capture_default_str();
  command->callback([args] { RunExport(*args); });
}

}  // namespace viosfm::cli

// `viosfm export RUN`: a finished run folder as the inputs of the next tools
// (COLMAP database with pose priors and model, transforms.json for
// nerfstudio / instant-ngp / Gaussian splatting), see pipeline/run_export.h.
#include <memory>
#include <string>

#include "viosfm/cli/commands.h"
#include "viosfm/pipeline/run_export.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/logging.h"

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
  VIOSFM_LOG(INFO) << "export: next, e.g.\n"
                   << "  colmap pose_prior_mapper --database_path "
                   << (summary.output_folder / "database.db").string() << " --image_path "
                   << (summary.output_folder / "images").string() << " --output_path OUT  "
                   << "(COLMAP 3.10+)\n"
                   << "  ns-train splatfacto --data " << summary.output_folder.string()
                   << "  (nerfstudio)";
}

}  // namespace

void RegisterExport(CLI::App& app) {
  auto args = std::make_shared<ExportArguments>();
  CLI::App* command = app.add_subcommand(
      "export",
      "Export a run folder for the next tool: a COLMAP database with the poses as pose priors "
      "(COLMAP 3.10+ pose_priors table and 3.8 prior columns) and the model in sparse/0, a "
      "nerfstudio/instant-ngp transforms.json with sparse_pc.ply, and an images link");
  command->add_option("run", args->run, "Output folder of `viosfm run`")->required();
  command->add_option("--out", args->out, "Export folder (default RUN/export, replaced)");
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

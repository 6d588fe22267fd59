// `viosfm report RUN_DIR [--out FILE]`: writes the self-contained HTML report
// of a `viosfm run` output folder (see report/html_report.h).
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>

#include "viosfm/cli/commands.h"
#include "viosfm/pipeline/run_folder.h"
#include "viosfm/report/html_report.h"
#include "viosfm/util/folder_manifest.h"

namespace viosfm::cli {
namespace {

struct ReportArguments {
  std::string run_dir;
  std::string out_path;  // empty: RUN_DIR/report.html
};

namespace fs = std::filesystem;

void RunReport(const ReportArguments& args) {
  const fs::path html_path =
      args.out_path.empty() ? DefaultReportPath(args.run_dir) : fs::path(args.out_path);
  // A report written into a run folder viosfm made is recorded in its
  // manifest (removed with the run's outputs by --overwrite), and never
  // written over a file of the user's.
  std::optional<ManagedFolder> folder;
  const fs::path parent = html_path.has_parent_path() ? html_path.parent_path() : fs::path(".");
  if (fs::is_directory(args.run_dir) && fs::is_directory(parent) &&
      fs::equivalent(parent, args.run_dir) && ReadFolderManifest(args.run_dir)) {
    folder.emplace(args.run_dir, RunFolderManifestOptions());
    folder->Claim({html_path.filename().string()});
    folder->Save();
  }
  WriteRunReport(args.run_dir, html_path);
  if (folder) folder->Finish();
  std::cout << "wrote " << html_path.string() << "\n";
}

}  // namespace

void RegisterReport(CLI::App& app) {
  CLI::App* command =
      app.add_subcommand("report", "Write the HTML report (one self-contained page) of a run");
  auto args = std::make_shared<ReportArguments>();
  command->add_option("run_dir", args->run_dir, "Output folder of `viosfm run`")->required();
  command->add_option("--out", args->out_path, "HTML file to write (default: RUN_DIR/report.html)");
  command->callback([args] { RunReport(*args); });
}

}  // namespace viosfm::cli

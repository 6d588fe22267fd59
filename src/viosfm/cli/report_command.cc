// `viosfm report RUN_DIR [--out FILE]`: writes the self-contained HTML report
// of a `viosfm run` output folder (see report/html_report.h).
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>

#include "viosfm/cli/commands.h"
#include "viosfm/report/html_report.h"

namespace viosfm::cli {
namespace {

struct ReportArguments {
  std::string run_dir;
  std::string out_path;  // empty: RUN_DIR/report.html
};

void RunReport(const ReportArguments& args) {
  const std::filesystem::path html_path = args.out_path.empty()
                                              ? DefaultReportPath(args.run_dir)
                                              : std::filesystem::path(args.out_path);
  WriteRunReport(args.run_dir, html_path);
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

// `viosfm bench-report BENCH_DIR --markdown FILE --figures DIR`: tables and
// figures of a benchmark-suite folder written by bench/run.sh (see
// report/bench_report.h).
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>

#include "viosfm/cli/commands.h"
#include "viosfm/report/bench_report.h"

namespace viosfm::cli {
namespace {

struct BenchReportArguments {
  std::string bench_dir;
  std::string markdown = "docs/benchmarks-suite.md";
  std::string figures = "docs/images";
};

void RunBenchReport(const BenchReportArguments& args) {
  const BenchResults results = ReadBenchResults(args.bench_dir);
  WriteBenchReport(results, args.markdown, args.figures);
  std::cout << "read " << results.runs.size() << " runs, " << results.batch_size.size()
            << " batch sizes, " << results.length.size() << " lengths; wrote " << args.markdown
            << " and figures in " << args.figures << "\n";
}

}  // namespace

void RegisterBenchReport(CLI::App& app) {
  CLI::App* command = app.add_subcommand(
      "bench-report", "Tables (Markdown) and figures (SVG) of a bench/run.sh results folder");
  auto args = std::make_shared<BenchReportArguments>();
  command->add_option("bench_dir", args->bench_dir, "Results folder of bench/run.sh")->required();
  command->add_option("--markdown", args->markdown, "Markdown page to write")
      ->capture_default_str();
  command->add_option("--figures", args->figures, "Folder for the SVG figures")
      ->capture_default_str();
  command->callback([args] { RunBenchReport(*args); });
}

}  // namespace viosfm::cli

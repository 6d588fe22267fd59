// viosfm: VIO-aided structure from motion. See `viosfm --help`.
#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>
#include <memory>

#include "viosfm/cli/command_help.h"
#include "viosfm/cli/commands.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/logging.h"

int main(int argc, char** argv) {
  CLI::App app{"viosfm: VIO-aided structure from motion for sequences with an IMU"};
  // Set first: the subcommands take the formatter their parent has.
  app.formatter(std::make_shared<viosfm::cli::HelpFormatter>());
  app.set_version_flag("--version", "viosfm 0.1.0");
  app.require_subcommand(1);
  std::string log_level = "info";
  app.add_option("--log-level", log_level, "debug, info, warning or error")->capture_default_str();
  app.parse_complete_callback(
      [&log_level] { viosfm::SetLogLevel(viosfm::ParseLogLevel(log_level)); });
  app.footer(
      "Start with `viosfm run DATASET --out OUT` (`viosfm run --help` shows three examples), then "
      "`viosfm report OUT` and `viosfm export OUT`. `viosfm --help-all` also lists the developer "
      "tools (simulated sequences, single stages, benchmark tables).");

  // The user's commands, in the order of a first session.
  viosfm::cli::RegisterRun(app);
  viosfm::cli::RegisterReport(app);
  viosfm::cli::RegisterExport(app);
  viosfm::cli::RegisterConvert(app);
  viosfm::cli::RegisterEval(app);
  viosfm::cli::RegisterReplay(app);
  viosfm::cli::RegisterVio(app);
  // Developer tools: not in `viosfm --help`, called by their names as before.
  viosfm::cli::RegisterSimulate(app);
  viosfm::cli::RegisterEmulateVio(app);
  viosfm::cli::RegisterFeatures(app);
  viosfm::cli::RegisterMatch(app);
  viosfm::cli::RegisterCheckPairs(app);
  viosfm::cli::RegisterBenchReport(app);
  viosfm::cli::SetSubcommandSections(
      &app, {{"Commands", true, {"run", "report", "export", "convert", "eval", "replay", "vio"}},
             {"Developer tools",
              false,
              {"simulate", "emulate-vio", "features", "match", "check-pairs", "bench-report"}}});

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version exit with 0; a command line that cannot be
    // parsed is a usage error, exit 2 like any bad input.
    if (e.get_exit_code() == 0) return app.exit(e);
    std::cerr << "error: " << e.what() << "\nRun with --help for more information.\n";
    return viosfm::kExitInputError;
  } catch (const std::exception& e) {
    // Bad input and filesystem errors (naming the path) exit with 2, bugs with 3.
    const viosfm::TopLevelError error = viosfm::DescribeTopLevelError(e);
    std::cerr << error.message << "\n";
    return error.exit_code;
  }
  return 0;
}

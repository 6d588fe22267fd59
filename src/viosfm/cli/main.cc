// viosfm: VIO-aided structure from motion. See `viosfm --help`.
#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>

#include "viosfm/cli/commands.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/logging.h"

int main(int argc, char** argv) {
  CLI::App app{"viosfm: VIO-aided structure from motion for sequences with an IMU"};
  app.set_version_flag("--version", "viosfm 0.1.0");
  app.require_subcommand(1);
  std::string log_level = "info";
  app.add_option("--log-level", log_level, "debug, info, warning or error")->capture_default_str();
  app.parse_complete_callback(
      [&log_level] { viosfm::SetLogLevel(viosfm::ParseLogLevel(log_level)); });

  viosfm::cli::RegisterSimulate(app);
  viosfm::cli::RegisterFeatures(app);
  viosfm::cli::RegisterMatch(app);
  viosfm::cli::RegisterCheckPairs(app);
  viosfm::cli::RegisterVio(app);
  viosfm::cli::RegisterRun(app);
  viosfm::cli::RegisterReport(app);
  viosfm::cli::RegisterBenchReport(app);
  viosfm::cli::RegisterEval(app);
  viosfm::cli::RegisterConvert(app);
  viosfm::cli::RegisterReplay(app);
  viosfm::cli::RegisterExport(app);
  viosfm::cli::RegisterEmulateVio(app);

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

#include "viosfm/cli/commands.h"

namespace viosfm::cli {

void RegisterEval(CLI::App& app) {
  app.add_subcommand("eval", "Evaluate a trajectory against a reference (ATE, RPE)");
}

}  // namespace viosfm::cli

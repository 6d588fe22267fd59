#include "viosfm/cli/commands.h"
namespace viosfm::cli {
void RegisterRun(CLI::App& app) {
  (void)app;
}
}  // namespace viosfm::cli

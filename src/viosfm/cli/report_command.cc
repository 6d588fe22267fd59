#include "viosfm/cli/commands.h"
namespace viosfm::cli {
void RegisterReport(CLI::App& app) {
  (void)app;
}
}  // namespace viosfm::cli

#include "viosfm/cli/commands.h"
namespace viosfm::cli {
void RegisterVio(CLI::App& app) {
  (void)app;
}
}  // namespace viosfm::cli

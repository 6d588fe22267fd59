#include "viosfm/cli/commands.h"
namespace viosfm::cli {
void RegisterCheckPairs(CLI::App& app) {
  (void)app;
}
}  // namespace viosfm::cli

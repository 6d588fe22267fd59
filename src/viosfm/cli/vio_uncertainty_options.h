// The command-line options of the VIO uncertainty model
// (scene/vio_uncertainty.h), shared by `viosfm run` and `viosfm match`.
#pragma once

#include <CLI/CLI.hpp>
#include <memory>

#include "viosfm/scene/vio_uncertainty.h"

namespace viosfm::cli {

struct VioUncertaintyArguments {
  VioUncertaintyModel model;
  double factor = 1.0;  // --vio-uncertainty: every rate times this
  // The model the flags describe. Throws InputError for a factor <= 0.
  VioUncertaintyModel Model() const;
};

// Adds --vio-uncertainty F and one flag per rate (--vio-yaw-per-sqrt-m ...).
void AddVioUncertaintyOptions(CLI::App* command, VioUncertaintyArguments* arguments);

}  // namespace viosfm::cli

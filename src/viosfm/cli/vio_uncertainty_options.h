// The command-line options of the VIO uncertainty model
// (scene/vio_uncertainty.h), and of how the pair verification trusts the
// VIO's relative pose (matching/verification_driver.h), shared by `viosfm
// run` and `viosfm match`.
#pragma once

#include <CLI/CLI.hpp>
#include <memory>
#include <string>
#include <vector>

#include "viosfm/matching/verification_driver.h"
#include "viosfm/scene/vio_uncertainty.h"

namespace viosfm::cli {

struct VioUncertaintyArguments {
  VioUncertaintyModel model;
  double factor = 1.0;  // --vio-uncertainty: every rate times this
  // The model the flags describe. Throws InputError for a factor <= 0.
  VioUncertaintyModel Model() const;
};

// Adds --vio-uncertainty F and one flag per rate (--vio-yaw-per-sqrt-m ...),
// in the group kVioUncertaintyGroup.
void AddVioUncertaintyOptions(CLI::App* command, VioUncertaintyArguments* arguments);
inline constexpr const char* kVioUncertaintyGroup =
    "VIO uncertainty (how far its relative poses are trusted)";
// The names of the flags AddVioUncertaintyOptions adds.
std::vector<std::string> VioUncertaintyFlagNames();

struct VerificationBandArguments {
  bool fixed_band = false;  // --fixed-band: band_follows_drift false
  bool wide_band = false;   // --wide-band: correct_within_drift false
  // Sets what the given flags say, nothing else. Throws InputError when both
  // are given.
  void ApplyTo(VerificationOptions* options) const;
};

// Adds --fixed-band and --wide-band.
void AddVerificationBandOptions(CLI::App* command, VerificationBandArguments* arguments);

}  // namespace viosfm::cli

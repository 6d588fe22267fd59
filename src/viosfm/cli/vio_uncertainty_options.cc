#include "viosfm/cli/vio_uncertainty_options.h"

#include <cmath>
#include <string>

#include "viosfm/util/errors.h"

namespace viosfm::cli {

VioUncertaintyModel VioUncertaintyArguments::Model() const {
  if (!(factor > 0.0) || !std::isfinite(factor)) {
    throw InputError("--vio-uncertainty must be > 0 (got " + std::to_string(factor) + ")");
  }
  return model.Scaled(factor);
}

void VerificationBandArguments::ApplyTo(VerificationOptions* options) const {
  if (fixed_band && wide_band) {
    throw InputError("--fixed-band and --wide-band exclude each other");
  }
  if (fixed_band) options->band_follows_drift = false;
  if (wide_band) options->correct_within_drift = false;
}

void AddVerificationBandOptions(CLI::App* command, VerificationBandArguments* arguments) {
  command->add_flag("--fixed-band", arguments->fixed_band,
                    "The paper's test: the VIO's relative pose as it is, with the fixed "
                    "epipolar band T_EE (without it, a pair that pose does not explain is "
                    "judged again under it corrected by the pair's matches within the VIO's "
                    "expected drift between the two frames)");
  command->add_flag("--wide-band", arguments->wide_band,
                    "Each match judged alone against the band the VIO's drift allows, instead "
                    "of the VIO's pose corrected by the matches within that drift");
}

void AddVioUncertaintyOptions(CLI::App* command, VioUncertaintyArguments* arguments) {
  VioUncertaintyModel& m = arguments->model;
  const auto add = [&](const char* name, double* value, const char* help) {
    command->add_option(name, *value, help)->capture_default_str()->group(kVioUncertaintyGroup);
  };
  add("--vio-uncertainty", &arguments->factor,
      "Multiplier of every rate below (2: a VIO twice as bad as the defaults assume)");
  add("--vio-position-per-sqrt-m", &m.position_per_sqrt_m,
      "Position random walk, m per sqrt(m travelled), each axis");
  add("--vio-position-per-sqrt-s", &m.position_per_sqrt_s, "Position random walk, m per sqrt(s)");
  add("--vio-yaw-per-sqrt-m", &m.yaw_per_sqrt_m, "Yaw random walk, rad per sqrt(m travelled)");
  add("--vio-yaw-per-sqrt-s", &m.yaw_per_sqrt_s, "Yaw random walk, rad per sqrt(s)");
  add("--vio-yaw-per-sqrt-rad", &m.yaw_per_sqrt_rad, "Yaw random walk, rad per sqrt(rad turned)");
  add("--vio-tilt-per-sqrt-s", &m.tilt_per_sqrt_s, "Roll and pitch random walk, rad per sqrt(s)");
  add("--vio-scale-sigma", &m.scale_sigma, "Relative scale error of displacements");
  add("--vio-relative-scale-sigma", &m.relative_scale_sigma,
      "Relative scale error varying between pairs of frames of a segment (the priors')");
  add("--vio-position-noise", &m.position_noise_m, "White position noise per frame, m (> 0)");
  add("--vio-rotation-noise", &m.rotation_noise_rad, "White rotation noise per frame, rad (> 0)");
  add("--vio-correlated-position-noise", &m.correlated_position_noise_m,
      "Slowly varying position noise, m");
  add("--vio-correlated-rotation-noise", &m.correlated_rotation_noise_rad,
      "Slowly varying rotation noise, rad");
  add("--vio-noise-correlation", &m.noise_correlation_s,
      "Correlation time of the slowly varying noise, s");
}

std::vector<std::string> VioUncertaintyFlagNames() {
  CLI::App app;
  VioUncertaintyArguments arguments;
  AddVioUncertaintyOptions(&app, &arguments);
  std::vector<std::string> names;
  for (const CLI::Option* option : app.get_options()) {
    if (option->get_group() == kVioUncertaintyGroup) names.push_back(option->get_name());
  }
  return names;
}

}  // namespace viosfm::cli

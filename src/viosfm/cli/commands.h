// The table of `viosfm` subcommands. Each Register* adds one subcommand to the
// CLI11 app and sets its callback, which parses arguments and calls a library
// function; no algorithm lives in cli/.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "viosfm/io/dataset_checks.h"
#include "viosfm/io/kalibr.h"

namespace viosfm::cli {

void RegisterEval(CLI::App& app);
void RegisterSimulate(CLI::App& app);
void RegisterFeatures(CLI::App& app);
void RegisterMatch(CLI::App& app);
void RegisterCheckPairs(CLI::App& app);
void RegisterVio(CLI::App& app);
void RegisterRun(CLI::App& app);
void RegisterReport(CLI::App& app);
void RegisterBenchReport(CLI::App& app);
void RegisterConvert(CLI::App& app);
void RegisterReplay(CLI::App& app);
void RegisterExport(CLI::App& app);
void RegisterEmulateVio(CLI::App& app);

// --calibration FILE and --imu-calibration FILE (Kalibr camchain.yaml and
// imu.yaml, io/kalibr.h) of the subcommands that read a dataset's rig.
void AddCalibrationOptions(CLI::App* command, CalibrationFiles* files);
// --allow-external-links, --imu-max-accel and --imu-max-gyro
// (io/dataset_checks.h) of the subcommands that read a dataset.
void AddDatasetCheckOptions(CLI::App* command, DatasetChecks* checks);

// A --threads value beyond kMaxThreadsPerHardwareThread a hardware thread
// (at least kMinThreadCap) is capped there, with a warning naming `flag`:
// more threads than that only take memory.
inline constexpr int kMaxThreadsPerHardwareThread = 4;
inline constexpr int kMinThreadCap = 8;
int CapNumThreads(int requested, const std::string& flag);

}  // namespace viosfm::cli

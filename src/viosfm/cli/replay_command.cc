// `viosfm replay IN --out OUT`: a recorded EuRoC folder written again into
// OUT as a recorder writes it while it records, at the pace of its stamps
// (io/euroc_replay.h): the input of `viosfm run --follow`.
#include <memory>
#include <string>

#include "viosfm/cli/commands.h"
#include "viosfm/io/euroc_replay.h"

namespace viosfm::cli {
namespace {

struct ReplayArguments {
  std::string in;
  std::string out;
  EurocReplayOptions options;
};

}  // namespace

void RegisterReplay(CLI::App& app) {
  auto args = std::make_shared<ReplayArguments>();
  CLI::App* command = app.add_subcommand(
      "replay",
      "Record a EuRoC folder again at its pace, for `viosfm run --follow`. It writes at the pace "
      "of the stamps as a recorder would: `viosfm run OUT --follow` follows OUT as it grows.");
  command->footer(
      "The sensor.yaml files first, then the IMU rows and the images (each image before its row) "
      "at the pace of their stamps times --speed.");
  command->add_option("dataset", args->in, "EuRoC dataset (folder containing mav0/)")->required();
  command->add_option("--out", args->out, "The folder to record into (created)")->required();
  command->add_option("--speed", args->options.speed, "Times real time (0: as fast as possible)")
      ->capture_default_str();
  command->add_option("--skip", args->options.skip_s, "Seconds skipped at the recording's start")
      ->capture_default_str();
  command->callback([args] { ReplayEurocRecording(args->in, args->out, args->options); });
}

}  // namespace viosfm::cli

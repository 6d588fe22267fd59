// `viosfm eval`: absolute trajectory error and relative pose error of an
// estimated trajectory against a reference (see eval/traj_eval.h), its
// rotations against a dataset's gyro (eval/gyro_check.h), and their figures
// (report/eval_plots.h).
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "viosfm/cli/commands.h"
#include "viosfm/eval/gyro_check.h"
#include "viosfm/eval/report.h"
#include "viosfm/eval/traj_eval.h"
#include "viosfm/io/dataset.h"
#include "viosfm/io/euroc.h"
#include "viosfm/io/trajectory_io.h"
#include "viosfm/report/eval_plots.h"
#include "viosfm/report/json_file.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/string_util.h"
#include "viosfm/util/timestamp.h"

namespace viosfm::cli {
namespace {

struct EvalArguments {
  std::string est_path;
  std::string ref_path;
  std::string est_format;  // empty: guess
  std::string ref_format;
  std::string colmap_prefix;
  std::string association = "auto";
  std::string max_dt = "0.01";
  std::string offset = "0";
  std::string alignment = "se3";
  int64_t align_first = 0;
  int64_t rpe_delta = 1;
  double rpe_delta_m = 0.0;
  bool rpe_consecutive = false;
  std::string body_from_cam;
  std::string extrinsics_yaml;
  std::string cam_frame = "est";
  std::string json_path;
  // The gyro check: the dataset whose IMU judges the estimate's rotations.
  std::string gyro_dataset;
  CalibrationFiles calibration;
  double gyro_interval_s = 1.0;
  bool gyro_raw = false;
  std::string gyro_time_offset;  // empty: the calibration's
  std::string gyro_est = "cam";
  // Folder of the figures (--plot); empty: none.
  std::string plot_dir;
};

namespace fs = std::filesystem;

// The `viosfm run` output folder that `est_path` is or lies in (the folder
// holding summary.json: the path itself, its folder, or that folder's
// parent, e.g. RUN/model/), if any.
std::optional<fs::path> RunFolderOf(const std::string& est_path) {
  std::error_code error;
  const fs::path path = fs::absolute(est_path, error).lexically_normal();
  if (error) return std::nullopt;
  std::vector<fs::path> candidates;
  if (fs::is_directory(path, error)) candidates.push_back(path);
  candidates.push_back(path.parent_path());
  candidates.push_back(path.parent_path().parent_path());
  for (const fs::path& folder : candidates) {
    if (!folder.empty() && fs::is_regular_file(folder / "summary.json", error)) return folder;
  }
  return std::nullopt;
}

// The camera-IMU time offset a run used, and where it was read: its
// summary.json's gyro check (the offset the run's own check and model
// used: the one its VIO estimated, or the calibration's), else the
// time_offset_ns line of its vio/vio_summary.txt.
std::optional<std::pair<timestamp_ns_t, std::string>> RunTimeOffset(const fs::path& run_dir) {
  const fs::path summary_path = run_dir / "summary.json";
  const nlohmann::json summary = ReadJsonFile(summary_path);
  if (summary.contains("gyro_check") && summary["gyro_check"].is_object() &&
      summary["gyro_check"].contains("time_offset_ns") &&
      summary["gyro_check"]["time_offset_ns"].is_number_integer()) {
    return std::pair{summary["gyro_check"]["time_offset_ns"].get<timestamp_ns_t>(),
                     summary_path.string()};
  }
  const fs::path vio_summary = run_dir / "vio" / "vio_summary.txt";
  std::ifstream in(vio_summary);
  std::string line;
  int64_t line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    const std::string_view text = Trim(line);
    if (!StartsWith(text, "time_offset_ns:")) continue;
    const std::string_view value = Trim(Split(text.substr(15), "#").front());
    const std::optional<int64_t> ns = ParseInt(value);
    if (!ns) {
      throw InputError(vio_summary.string(), line_number,
                       "expected an integer time_offset_ns, got '" + std::string(value) + "'");
    }
    return std::pair{*ns, vio_summary.string()};
  }
  return std::nullopt;
}

timestamp_ns_t ParseSecondsOption(const std::string& text, const std::string& option) {
  const std::optional<timestamp_ns_t> ns = ParseSecondsToNs(Trim(text));
  if (!ns) throw InputError(option + ": expected decimal seconds, got '" + text + "'");
  return *ns;
}

Trajectory ReadInput(const std::string& path, const std::string& format_name,
                     const std::string& colmap_prefix, std::string* format_used) {
  const TrajectoryFormat format =
      format_name.empty() ? GuessTrajectoryFormat(path) : ParseTrajectoryFormat(format_name);
  *format_used = TrajectoryFormatName(format);
  if (format == TrajectoryFormat::kColmap) return ReadColmapTrajectory(path, colmap_prefix);
  return ReadTrajectory(path, format);
}

// The dataset whose gyro judges the estimate. Its time offset is replaced by
// --gyro-time-offset when given, else by the run's when the estimate is a
// run's; `offset_source` says which.
Sequence ReadGyroDataset(const EvalArguments& args, const std::optional<fs::path>& run_dir,
                         std::string* offset_source) {
  DatasetReadOptions read_options;
  read_options.calibration = args.calibration;
  read_options.require_imu = true;
  Sequence sequence = ReadDataset(args.gyro_dataset, read_options);
  if (!args.gyro_time_offset.empty()) {
    sequence.rig.cam_time_offset_ns =
        ParseSecondsOption(args.gyro_time_offset, "--gyro-time-offset");
    *offset_source = "--gyro-time-offset";
  } else if (const auto run_offset = run_dir ? RunTimeOffset(*run_dir) : std::nullopt) {
    sequence.rig.cam_time_offset_ns = run_offset->first;
    *offset_source = "the run's, " + run_offset->second;
  } else {
    *offset_source = "the calibration's";
  }
  return sequence;
}

void RunEval(const EvalArguments& args) {
  if (args.ref_path.empty() && args.gyro_dataset.empty()) {
    throw InputError(
        "give --ref (a reference trajectory), --gyro (a dataset with an IMU), or both");
  }
  if (!args.calibration.empty() && args.gyro_dataset.empty()) {
    throw InputError("--calibration and --imu-calibration apply to --gyro's dataset: give --gyro");
  }
  EvaluationOptions options;
  options.association = ParseAssociationMethod(args.association);
  options.max_dt_ns = ParseSecondsOption(args.max_dt, "--max-dt");
  options.offset_ns = ParseSecondsOption(args.offset, "--offset");
  options.alignment = ParseAlignmentMode(args.alignment);
  options.align_first = args.align_first;
  options.rpe_delta_frames = args.rpe_delta;
  options.rpe_delta_m = args.rpe_delta_m;
  options.rpe_all_pairs = !args.rpe_consecutive;

  if (!args.body_from_cam.empty() && !args.extrinsics_yaml.empty()) {
    throw InputError("give either --body-from-cam or --extrinsics-yaml, not both");
  }
  std::optional<Rigid3d> body_from_cam;
  if (!args.body_from_cam.empty()) {
    body_from_cam = ParsePoseTxyzQxyzw(args.body_from_cam, "--body-from-cam");
  } else if (!args.extrinsics_yaml.empty()) {
    body_from_cam = ReadEurocSensorTransform(args.extrinsics_yaml);
  }
  if (body_from_cam) {
    const std::string cam_frame = ToLower(args.cam_frame);
    if (cam_frame == "est" || cam_frame == "both") options.est_body_from_cam = body_from_cam;
    if (cam_frame == "ref" || cam_frame == "both") options.ref_body_from_cam = body_from_cam;
  }
  if (const std::string error = options.Validate(); !error.empty()) {
    throw InputError("invalid options: " + error);
  }
  GyroCheckOptions gyro_options;
  gyro_options.interval_s = args.gyro_interval_s;
  gyro_options.fit_bias = !args.gyro_raw;
  if (const std::string error = gyro_options.Validate(); !error.empty()) {
    throw InputError("invalid --gyro options: " + error);
  }

  // Everything read and checked before anything is printed or written.
  // A run folder as --est stands for its body trajectory.
  const std::optional<fs::path> run_dir = RunFolderOf(args.est_path);
  std::string est_path = args.est_path;
  std::string gyro_est = ToLower(args.gyro_est);
  if (run_dir && fs::equivalent(*run_dir, args.est_path)) {
    est_path = (*run_dir / "trajectory_body.tum").string();
    gyro_est = "body";
    std::cout << "--est " << args.est_path << ": the run's trajectory_body.tum (body poses)\n";
  }
  std::optional<Sequence> gyro_dataset;
  std::string offset_source;
  if (!args.gyro_dataset.empty()) gyro_dataset = ReadGyroDataset(args, run_dir, &offset_source);
  EvaluationInputs inputs;
  inputs.est_path = est_path;
  inputs.ref_path = args.ref_path;
  const Trajectory est =
      ReadInput(est_path, args.est_format, args.colmap_prefix, &inputs.est_format);
  std::optional<Trajectory> ref;
  if (!args.ref_path.empty()) {
    ref = ReadInput(args.ref_path, args.ref_format, args.colmap_prefix, &inputs.ref_format);
  }
  std::optional<GyroCheckResult> gyro;
  if (gyro_dataset) {
    const Trajectory world_from_cam =
        gyro_est == "body" ? BodyToCameraTrajectory(est, gyro_dataset->rig.body_from_cam) : est;
    gyro = CheckRotationsAgainstGyro(world_from_cam, gyro_dataset->imu, gyro_dataset->rig,
                                     gyro_options);
  }
  nlohmann::json json;
  std::optional<EvaluationResult> evaluation;
  if (ref) {
    evaluation = EvaluateTrajectories(est, *ref, options);
    const EvaluationResult& result = *evaluation;
    std::cout << FormatEvaluationReport(result, options, inputs);
    json = nlohmann::json::parse(EvaluationToJson(result, options, inputs));
  } else {
    json["inputs"] = {{"est_path", inputs.est_path}, {"est_format", inputs.est_format}};
  }
  if (gyro) {
    std::cout << (ref ? "\n" : "") << FormatGyroCheck(*gyro) << "time offset: " << offset_source
              << "\n";
    json["gyro"] = nlohmann::json::parse(GyroCheckToJson(*gyro, gyro_options));
    json["gyro"]["dataset"] = args.gyro_dataset;
    json["gyro"]["est_poses"] = gyro_est;
    json["gyro"]["time_offset_source"] = offset_source;
  }
  if (!args.plot_dir.empty()) {
    // The trajectories in the frames the evaluation compared.
    const Trajectory est_compared =
        options.est_body_from_cam ? CameraToBodyTrajectory(est, *options.est_body_from_cam) : est;
    const Trajectory ref_compared =
        !ref ? Trajectory()
             : (options.ref_body_from_cam ? CameraToBodyTrajectory(*ref, *options.ref_body_from_cam)
                                          : *ref);
    EvaluationPlotOptions plot_options;
    plot_options.estimate_label = fs::path(est_path).filename().string();
    if (!args.ref_path.empty()) {
      plot_options.reference_label = fs::path(args.ref_path).filename().string();
    }
    const std::vector<NamedFigure> figures =
        MakeEvaluationFigures(est_compared, ref_compared, evaluation ? &*evaluation : nullptr,
                              gyro ? &*gyro : nullptr, plot_options);
    WriteFigures(args.plot_dir, figures);
    std::cout << "wrote " << figures.size() << " figures (SVG and PNG) to " << args.plot_dir << ":";
    for (const NamedFigure& figure : figures) std::cout << ' ' << figure.name;
    std::cout << "\n";
  }
  if (!args.json_path.empty()) {
    const std::string text = json.dump(2) + "\n";
    WriteFileAtomically(args.json_path, [&text](std::ostream& out) { out << text; });
    std::cout << "wrote " << args.json_path << "\n";
  }
}

}  // namespace

void RegisterEval(CLI::App& app) {
  CLI::App* command =
      app.add_subcommand("eval", "Evaluate a trajectory against a reference (ATE, RPE)");
  auto args = std::make_shared<EvalArguments>();
  command
      ->add_option("--est", args->est_path,
                   "Estimated trajectory (file, COLMAP model folder, or a `viosfm run` folder: "
                   "its trajectory_body.tum)")
      ->required();
  command->add_option("--ref", args->ref_path,
                      "Reference trajectory (file, or COLMAP model folder); needed unless --gyro");
  const auto formats = CLI::IsMember({"tum", "euroc", "kitti", "colmap"}, CLI::ignore_case);
  command
      ->add_option("--est-format", args->est_format, "tum, euroc, kitti or colmap (default: guess)")
      ->check(formats);
  command
      ->add_option("--ref-format", args->ref_format, "tum, euroc, kitti or colmap (default: guess)")
      ->check(formats);
  command->add_option("--colmap-prefix", args->colmap_prefix,
                      "Only COLMAP images whose name starts with this (e.g. cam0/)");
  command
      ->add_option("--associate", args->association,
                   "auto (index without stamps, else nearest), index, nearest (evo) or greedy "
                   "(TUM evaluate_ate.py)")
      ->check(CLI::IsMember({"auto", "index", "nearest", "greedy"}, CLI::ignore_case))
      ->capture_default_str();
  command->add_option("--max-dt", args->max_dt, "Largest stamp difference of a pair (s)")
      ->capture_default_str();
  command->add_option("--offset", args->offset, "Added to the estimate's stamps (s)")
      ->capture_default_str();
  command->add_option("--align", args->alignment, "none, se3, sim3 or posyaw")
      ->check(CLI::IsMember({"none", "se3", "sim3", "posyaw"}, CLI::ignore_case))
      ->capture_default_str();
  command
      ->add_option("--align-first", args->align_first, "Align on the first N pairs only (0: all)")
      ->capture_default_str();
  command->add_option("--rpe-delta", args->rpe_delta, "RPE frame delta (0: off)")
      ->capture_default_str();
  command
      ->add_option("--rpe-delta-m", args->rpe_delta_m,
                   "RPE travelled-distance delta along the reference, m (0: off)")
      ->capture_default_str();
  command->add_flag(
      "--rpe-consecutive", args->rpe_consecutive,
      "RPE on consecutive non-overlapping pairs (evo's default) instead of all pairs");
  command->add_option("--body-from-cam", args->body_from_cam,
                      "Camera-to-body extrinsics \"tx ty tz qx qy qz qw\"");
  command->add_option("--extrinsics-yaml", args->extrinsics_yaml,
                      "Camera sensor.yaml whose T_BS is body_from_cam (EuRoC)");
  command
      ->add_option("--cam-frame", args->cam_frame,
                   "Which trajectory holds camera poses to convert to body poses: est, ref or both")
      ->check(CLI::IsMember({"est", "ref", "both"}, CLI::ignore_case))
      ->capture_default_str();
  command->add_option("--json", args->json_path, "Write all numbers to this JSON file");
  command->add_option("--plot", args->plot_dir,
                      "Folder for the figures, each as .svg and .png: trajectories from above "
                      "and the side, position error over time and its histogram (with --ref), "
                      "rotation error against the gyro over time (with --gyro)");
  command->add_option("--gyro", args->gyro_dataset,
                      "Dataset with an IMU (EuRoC folder): the estimate's relative rotations "
                      "against its gyro's");
  AddCalibrationOptions(command, &args->calibration);
  command
      ->add_option("--gyro-interval", args->gyro_interval_s,
                   "s, compare the rotations of frames this far apart (intervals end to end)")
      ->capture_default_str();
  command->add_option("--gyro-time-offset", args->gyro_time_offset,
                      "s, t_imu = t_cam + offset for --gyro (default: when --est is a run's "
                      "folder or lies in one, the offset the run used, from its summary.json; "
                      "else the calibration's)");
  command->add_flag("--gyro-raw", args->gyro_raw,
                    "The raw gyro (bias zero) instead of one bias fitted to the estimate");
  command
      ->add_option("--gyro-est", args->gyro_est,
                   "--est holds camera poses (cam) or body (IMU) poses (body), for --gyro")
      ->check(CLI::IsMember({"cam", "body"}, CLI::ignore_case))
      ->capture_default_str();
  command->callback([args] { RunEval(*args); });
}

}  // namespace viosfm::cli

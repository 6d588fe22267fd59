#include "viosfm/report/bench_report.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>

#include "viosfm/eval/traj_eval.h"
#include "viosfm/io/euroc.h"
#include "viosfm/io/trajectory_io.h"
#include "viosfm/report/json_file.h"
#include "viosfm/report/run_plots.h"
#include "viosfm/report/svg_plot.h"
#include "viosfm/scene/trajectory.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/string_util.h"
#include "viosfm/util/timestamp.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

// The order methods are listed in, and their table names.
const std::vector<std::pair<std::string, std::string>>& MethodNames() {
  static const std::vector<std::pair<std::string, std::string>> names = {
      {"vio", "input VIO (emulated)"},
      {"viosfm", "viosfm"},
      {"viosfm_paper_weighting", "viosfm with the paper's prior weighting"},
      {"viosfm_no_bridging", "viosfm w/o bridging priors (the paper's terms only)"},
      {"viosfm_no_vio_check", "viosfm w/o VIO-aided verification"},
      {"viosfm_no_rpc", "viosfm w/o relative-pose term"},
      {"viosfm_batch_ba50", "viosfm, 50 iterations in every batch's BA"},
      {"own_vio", "viosfm's own VIO"},
      {"viosfm_own_vio", "viosfm with its own VIO"},
      {"colmap_same_pairs", "COLMAP 3.8, viosfm's pairs"},
      {"colmap_sequential", "COLMAP 3.8, sequential matcher"},
  };
  return names;
}

std::string MethodName(const std::string& method) {
  for (const auto& [key, name] : MethodNames()) {
    if (key == method) return name;
  }
  return method;
}

int MethodRank(const std::string& method) {
  const auto& names = MethodNames();
  for (size_t i = 0; i < names.size(); ++i) {
    if (names[i].first == method) return static_cast<int>(i);
  }
  return static_cast<int>(names.size());
}

std::optional<double> NumberAt(const Json& json, std::initializer_list<const char*> keys) {
  const Json* node = &json;
  for (const char* key : keys) {
    if (!node->is_object() || !node->contains(key)) return std::nullopt;
    node = &(*node)[key];
  }
  if (!node->is_number()) return std::nullopt;
  return node->get<double>();
}

int CountImages(const fs::path& sequence) {
  const fs::path csv = sequence / "mav0" / "cam0" / "data.csv";
  if (!fs::is_regular_file(csv)) return 0;
  std::ifstream in(csv);
  std::string line;
  int count = 0;
  while (std::getline(in, line)) {
    if (!Trim(line).empty() && line[0] != '#') ++count;
  }
  return count;
}

// Reads one run folder (see the header for its files).
BenchRun ReadRun(const fs::path& folder, const std::string& sequence, const std::string& method,
                 int frames_in) {
  BenchRun run;
  run.sequence = sequence;
  run.method = method;
  run.folder = folder;
  run.frames_in = frames_in;
  run.failed = fs::exists(folder / "failed");
  const fs::path time_path = folder / "time.txt";
  // GNU time creates its file at the start and fills it at the end: an empty
  // one is a run still going, or one that was killed.
  // A command that failed or was killed gets GNU time's status line
  // ("Command exited with non-zero status 1", "Command terminated by signal
  // 15") before the figures.
  std::string figures;
  int figures_line = 0;
  if (fs::is_regular_file(time_path)) {
    std::istringstream lines(ReadTextFile(time_path));
    std::string line;
    while (std::getline(lines, line)) {
      ++figures_line;
      if (Trim(line).empty() || line.rfind("Command ", 0) == 0) continue;
      figures = line;
      break;
    }
  }
  if (!figures.empty()) {
    std::istringstream in(figures);
    double seconds = 0.0;
    double kib = 0.0;
    if (!(in >> seconds >> kib)) {
      throw InputError(time_path.string(), figures_line,
                       "expected 'seconds peak_kib [user_s system_s]' (/usr/bin/time -f "
                       "'%e %M %U %S')");
    }
    run.seconds = seconds;
    run.peak_memory_mb = kib / 1024.0;
    double user = 0.0;
    double system = 0.0;
    if (in >> user >> system) run.cpu_seconds = user + system;
  }
  const fs::path reused_path = folder / "reused.txt";
  if (fs::is_regular_file(reused_path)) run.reused = Trim(ReadTextFile(reused_path));
  const fs::path version_path = folder / "version.txt";
  if (fs::is_regular_file(version_path)) run.version = Trim(ReadTextFile(version_path));
  const fs::path eval_path = folder / "eval.json";
  if (fs::is_regular_file(eval_path)) {
    const Json eval = ReadJsonFile(eval_path);
    run.ate_rmse_m = NumberAt(eval, {"ate", "translation_m", "rmse"});
    run.ate_median_m = NumberAt(eval, {"ate", "translation_m", "median"});
    if (const auto n = NumberAt(eval, {"num_pairs"})) run.frames_registered = static_cast<int>(*n);
    if (const auto s = NumberAt(eval, {"alignment", "scale"}); s && *s > 0.0) run.scale = 1.0 / *s;
  }
  const fs::path eval_se3_path = folder / "eval_se3.json";
  if (fs::is_regular_file(eval_se3_path)) {
    run.ate_se3_rmse_m = NumberAt(ReadJsonFile(eval_se3_path), {"ate", "translation_m", "rmse"});
  }
  const fs::path summary_path = folder / "run" / "summary.json";
  if (fs::is_regular_file(summary_path)) {
    const Json summary = ReadJsonFile(summary_path);
    if (const auto n = NumberAt(summary, {"frames", "in"})) run.frames_in = static_cast<int>(*n);
    if (const auto n = NumberAt(summary, {"frames", "registered"})) {
      run.frames_registered = static_cast<int>(*n);
    }
    if (summary.contains("stages") && summary["stages"].is_array()) {
      for (const Json& stage : summary["stages"]) {
        if (stage.value("name", "") == "mapper" && stage.contains("seconds")) {
          run.mapping_seconds = stage["seconds"].get<double>();
        }
      }
    }
  }
  const fs::path models = folder / "num_models.txt";
  if (fs::is_regular_file(models)) {
    std::istringstream in(ReadTextFile(models));
    in >> run.num_models;
  }
  return run;
}

std::vector<fs::path> SortedSubfolders(const fs::path& folder) {
  std::vector<fs::path> result;
  if (!fs::is_directory(folder)) return result;
  for (const auto& entry : fs::directory_iterator(folder)) {
    if (entry.is_directory()) result.push_back(entry.path());
  }
  std::sort(result.begin(), result.end());
  return result;
}

// Numeric subfolders (batch sizes, lengths) as runs, sorted by number.
std::vector<BenchRun> ReadSweep(const fs::path& folder, const std::string& sequence) {
  std::vector<std::pair<int, BenchRun>> runs;
  for (const fs::path& sub : SortedSubfolders(folder)) {
    const std::string name = sub.filename().string();
    if (name.empty() || !std::all_of(name.begin(), name.end(), ::isdigit)) continue;
    runs.emplace_back(std::stoi(name), ReadRun(sub, sequence, name, CountImages(sub / "sequence")));
  }
  std::sort(runs.begin(), runs.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<BenchRun> result;
  for (auto& [n, run] : runs) result.push_back(std::move(run));
  return result;
}

// An ATE in metres as millimetres with two decimals ("n/a" without one).
std::string Millimetres(const std::optional<double>& metres) {
  if (!metres) return "n/a";
  return FormatFixedOrNa(*metres * 1e3, 2);
}

std::string Registered(const BenchRun& run) {
  if (run.failed && run.frames_registered == 0) return "failed";
  if (!run.seconds && run.frames_registered == 0) return "not finished";
  std::string text = std::to_string(run.frames_registered);
  if (run.frames_in > 0) text += " / " + std::to_string(run.frames_in);
  if (run.num_models > 1) text += " (" + std::to_string(run.num_models) + " models)";
  return text;
}

const BenchRun* FindRun(const BenchResults& results, const std::string& sequence,
                        const std::string& method) {
  for (const BenchRun& run : results.runs) {
    if (run.sequence == sequence && run.method == method) return &run;
  }
  return nullptr;
}

// The ground truth of a sequence folder (EuRoC layout).
fs::path GroundTruthCsv(const fs::path& sequence) {
  return sequence / "mav0" / "state_groundtruth_estimate0" / "data.csv";
}

// Whether the page draws `run`'s trajectory: the sequence has a ground truth
// and the run left a trajectory (viosfm's TUM file or a COLMAP model).
bool DrawsTrajectory(const BenchResults& results, const BenchRun& run) {
  const fs::path sequence = results.root / run.sequence / "sequence";
  if (!fs::is_regular_file(GroundTruthCsv(sequence))) return false;
  if (fs::is_regular_file(run.folder / "run" / "trajectory_body.tum")) return true;
  for (const fs::path& model : SortedSubfolders(run.folder / "sparse")) {
    if (fs::is_regular_file(model / "images.bin")) return true;
  }
  return false;
}

// The estimated body trajectory of a run folder: viosfm's
// run/trajectory_body.tum, or COLMAP's largest model converted to body poses.
std::optional<Trajectory> RunTrajectory(const BenchRun& run, const fs::path& sequence) {
  const fs::path tum = run.folder / "run" / "trajectory_body.tum";
  if (fs::is_regular_file(tum)) return ReadTumTrajectory(tum);
  Trajectory best;
  for (const fs::path& model : SortedSubfolders(run.folder / "sparse")) {
    if (!fs::is_regular_file(model / "images.bin")) continue;
    Trajectory cams = ReadColmapTrajectory(model);
    if (cams.size() > best.size()) best = std::move(cams);
  }
  if (best.empty()) return std::nullopt;
  const Rigid3d body_from_cam =
      ReadEurocSensorTransform(sequence / "mav0" / "cam0" / "sensor.yaml");
  return CameraToBodyTrajectory(best, body_from_cam);
}

// timestamp -> floor of frames.csv.
std::map<int64_t, int> ReadFloors(const fs::path& frames_csv) {
  std::map<int64_t, int> floors;
  std::ifstream in(frames_csv);
  if (!in) throw InputError(frames_csv.string(), 0, "cannot open");
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    if (Trim(line).empty() || line[0] == '#') continue;
    const std::vector<std::string_view> fields = Split(line, ",");
    const std::optional<timestamp_ns_t> stamp =
        fields.size() >= 3 ? ParseNs(Trim(fields[0])) : std::nullopt;
    const std::optional<int64_t> floor =
        fields.size() >= 3 ? ParseInt(Trim(fields[2])) : std::nullopt;
    if (!stamp || !floor) {
      throw InputError(frames_csv.string(), line_number,
                       "expected 'timestamp [ns],region,floor,...', got '" + line + "'");
    }
    floors[*stamp] = static_cast<int>(*floor);
  }
  return floors;
}

}  // namespace

FloorPlacement ComputeFloorPlacement(const Trajectory& estimate, const Trajectory& ground_truth,
                                     const fs::path& frames_csv) {
  const std::map<int64_t, int> floor_of = ReadFloors(frames_csv);
  std::map<int, int> counts;
  for (const auto& [stamp, floor] : floor_of) {
    if (floor >= 0) ++counts[floor];
  }
  FloorPlacement placement;
  if (counts.size() < 2 || estimate.size() < 3) return placement;
  EvaluationOptions options;
  options.alignment = AlignmentMode::kSim3;
  options.rpe_delta_frames = 0;
  EvaluationResult result;
  try {
    result = EvaluateTrajectories(estimate, ground_truth, options);
  } catch (const InputError&) {
    return placement;  // no stamp in common, or positions too degenerate to align
  }
  std::map<int, std::array<double, 3>> sums;               // floor -> {count, est z, true z}
  std::map<int, std::pair<Trajectory, Trajectory>> parts;  // floor -> {est, true}
  for (const PosePair& pair : result.pairs) {
    const StampedPose& est = estimate.poses[pair.est_index];
    const auto it = floor_of.find(est.timestamp_ns);
    if (it == floor_of.end() || it->second < 0) continue;
    const Eigen::Vector3d position = result.ref_from_est * est.world_from_frame.translation;
    auto& sum = sums[it->second];
    sum[0] += 1.0;
    sum[1] += position.z();
    sum[2] += ground_truth.poses[pair.ref_index].world_from_frame.translation.z();
    parts[it->second].first.poses.push_back(est);
    parts[it->second].second.poses.push_back(ground_truth.poses[pair.ref_index]);
  }
  options.association = AssociationMethod::kIndex;
  for (const auto& [floor, sum] : sums) {
    placement.floors.push_back(floor);
    placement.num_frames.push_back(static_cast<int>(sum[0]));
    placement.mean_height_m.push_back(sum[1] / sum[0]);
    placement.true_mean_height_m.push_back(sum[2] / sum[0]);
    const auto& [est, truth] = parts.at(floor);
    double rmse = std::numeric_limits<double>::quiet_NaN();
    try {
      if (est.size() >= 3) rmse = EvaluateTrajectories(est, truth, options).ate_translation_m.rmse;
    } catch (const InputError&) {
      // Too few or collinear positions on this floor: no alignment of its own.
    }
    placement.floor_ate_rmse_m.push_back(rmse);
  }
  return placement;
}

BenchResults ReadBenchResults(const fs::path& root) {
  if (!fs::is_directory(root)) {
    throw InputError(root.string(), 0, "expected a benchmark folder (written by bench/run.sh)");
  }
  BenchResults results;
  results.root = root;
  const fs::path meta = root / "meta.txt";
  if (fs::is_regular_file(meta)) {
    std::istringstream in(ReadTextFile(meta));
    std::string line;
    while (std::getline(in, line)) {
      const size_t colon = line.find(':');
      if (colon == std::string::npos) continue;
      results.meta.emplace_back(Trim(line.substr(0, colon)), Trim(line.substr(colon + 1)));
    }
  }
  for (const fs::path& folder : SortedSubfolders(root)) {
    const std::string name = folder.filename().string();
    if (name == "batch_size" || name == "length") continue;
    if (!fs::is_directory(folder / "runs")) continue;
    const int frames_in = CountImages(folder / "sequence");
    std::vector<BenchRun> runs;
    for (const fs::path& method : SortedSubfolders(folder / "runs")) {
      runs.push_back(ReadRun(method, name, method.filename().string(), frames_in));
    }
    std::stable_sort(runs.begin(), runs.end(), [](const BenchRun& a, const BenchRun& b) {
      return MethodRank(a.method) < MethodRank(b.method);
    });
    const fs::path frames_csv = folder / "sequence" / "frames.csv";
    const fs::path gt_csv = GroundTruthCsv(folder / "sequence");
    if (fs::is_regular_file(frames_csv) && fs::is_regular_file(gt_csv)) {
      const Trajectory ground_truth = ReadEurocTrajectory(gt_csv);
      std::vector<FloorPlacement> placements;
      for (const BenchRun& run : runs) {
        std::optional<Trajectory> estimate;
        if (run.method == "vio" || run.method == "own_vio") continue;
        try {
          estimate = RunTrajectory(run, folder / "sequence");
        } catch (const InputError&) {
          continue;  // a failed run's partial output
        }
        if (!estimate) continue;
        FloorPlacement placement = ComputeFloorPlacement(*estimate, ground_truth, frames_csv);
        if (placement.floors.empty()) continue;
        placement.method = run.method;
        placements.push_back(std::move(placement));
      }
      if (!placements.empty()) results.floors.emplace_back(name, std::move(placements));
    }
    results.runs.insert(results.runs.end(), runs.begin(), runs.end());
  }
  results.batch_size = ReadSweep(root / "batch_size", "batch_size");
  results.length = ReadSweep(root / "length", "length");
  const fs::path sweep_sequence = root / "batch_size_sequence.txt";
  if (fs::is_regular_file(sweep_sequence)) {
    results.batch_size_sequence = Trim(ReadTextFile(sweep_sequence));
  } else if (!results.runs.empty()) {
    results.batch_size_sequence = results.runs.front().sequence;
  }
  return results;
}

namespace {

// The results page in named steps: the settings, a section a sequence (its
// methods' table with notes, the floors, the trajectories' figures), the
// batch-size and the sequence-length sweeps.
class BenchMarkdown {
 public:
  BenchMarkdown(const BenchResults& results, const std::string& figures_relative_path)
      : results_(results), figures_(figures_relative_path) {
    for (const auto& [key, value] : results.meta) {
      if (key == "viosfm") meta_version_ = value;
    }
  }

  std::string Format() {
    WriteIntro();
    for (const std::string& sequence : Sequences()) {
      WriteMethods(sequence);
      WriteFloors(sequence);
      WriteFigures(sequence);
    }
    if (!results_.batch_size.empty()) WriteBatchSize();
    if (!results_.length.empty()) WriteLength();
    return md_.str();
  }

 private:
  void WriteIntro() {
    md_ << "# Benchmark suite results\n\n"
        << "Written by `bench/run.sh` and `viosfm bench-report` (docs/benchmarks.md explains the "
           "methods and how to reproduce them). Every number below was measured on this machine "
           "by bench/run.sh with these settings (meta.txt of the results folder; date and "
           "version of the last invocation):\n\n";
    for (const auto& [key, value] : results_.meta) md_ << "- " << key << ": " << value << "\n";
    md_ << "\nATE: Sim(3)-aligned absolute trajectory error of the body trajectory against the "
           "ground truth, over the frames each method registered; SE(3) ATE: the same aligned "
           "without scale (shape and metric scale), and scale: the trajectory's scale (1 / the "
           "Sim(3) alignment's; 1.02: 2 % too long). Time, CPU and memory: wall "
           "clock, user + system CPU time and peak resident memory of the whole run (COLMAP: "
           "feature extraction, matching and mapping; viosfm: every stage of `viosfm run`, "
           "except where a note says the run reused another run's features and matches).\n";
  }

  // The sequences in the order of their first run.
  std::vector<std::string> Sequences() const {
    std::vector<std::string> sequences;
    for (const BenchRun& run : results_.runs) {
      if (std::find(sequences.begin(), sequences.end(), run.sequence) == sequences.end()) {
        sequences.push_back(run.sequence);
      }
    }
    return sequences;
  }

  // The methods' table of `sequence`; runs that reused another run's data
  // or were made by another viosfm version than meta.txt's get a note.
  void WriteMethods(const std::string& sequence) {
    md_ << "\n## " << sequence << "\n\n"
        << "| method | registered / frames | ATE RMSE (mm) | ATE median (mm) | SE(3) ATE (mm) | "
           "scale | time (s) | CPU (s) | peak memory (MiB) "
           "|\n|---|---|---|---|---|---|---|---|---|\n";
    std::vector<std::string> notes;
    for (const BenchRun& run : results_.runs) {
      if (run.sequence != sequence) continue;
      const bool is_vio = run.method == "vio" || run.method == "own_vio";
      std::string name = MethodName(run.method);
      // The emulated VIO is the simulator's; a dataset's is the user's --vio-trajectory.
      if (run.method == "vio" &&
          !fs::is_regular_file(results_.root / sequence / "sequence" / "simulation.yaml")) {
        name = "input VIO (--vio-trajectory)";
      }
      std::string marks;
      if (!run.reused.empty()) {
        notes.push_back(name + ": started from the " + run.reused +
                        "; its time is that of the "
                        "remaining stages.");
        marks += " [" + std::to_string(notes.size()) + "]";
      }
      if (!run.version.empty() && run.version != meta_version_) {
        notes.push_back(name + ": run with viosfm " + run.version + ".");
        marks += " [" + std::to_string(notes.size()) + "]";
      }
      name += marks;
      md_ << "| " << name << " | " << (is_vio ? "-" : Registered(run)) << " | "
          << Millimetres(run.ate_rmse_m) << " | " << Millimetres(run.ate_median_m) << " | "
          << Millimetres(run.ate_se3_rmse_m) << " | " << FormatFixedOrNa(run.scale, 4) << " | "
          << (is_vio ? "-" : FormatFixedOrNa(run.seconds, 1)) << " | "
          << (is_vio ? "-" : FormatFixedOrNa(run.cpu_seconds, 1)) << " | "
          << (is_vio ? "-" : FormatFixedOrNa(run.peak_memory_mb, 0)) << " |\n";
    }
    if (!notes.empty()) md_ << "\n";
    for (size_t i = 0; i < notes.size(); ++i) md_ << "[" << i + 1 << "] " << notes[i] << "\n";
  }

  void WriteFloors(const std::string& sequence) {
    for (const auto& [floor_sequence, placements] : results_.floors) {
      if (floor_sequence != sequence) continue;
      md_ << "\nFloors: mean height of each floor's registered frames after the Sim(3) "
             "alignment, against the true height of the same frames (frames.csv), and the ATE of "
             "each floor's frames aligned on their own.\n\n"
          << "| method | floor | frames | height (m) | true height (m) | ATE RMSE within the "
             "floor (mm) |\n|---|---|---|---|---|---|\n";
      for (const FloorPlacement& p : placements) {
        for (size_t i = 0; i < p.floors.size(); ++i) {
          const double ate = p.floor_ate_rmse_m[i];
          md_ << "| " << MethodName(p.method) << " | " << p.floors[i] << " | " << p.num_frames[i]
              << " | " << FormatFixedOrNa(p.mean_height_m[i], 2) << " | "
              << FormatFixedOrNa(p.true_mean_height_m[i], 2) << " | "
              << (std::isnan(ate) ? std::string("n/a") : Millimetres(ate)) << " |\n";
        }
      }
    }
  }

  void WriteFigures(const std::string& sequence) {
    for (const char* method : {"viosfm", "colmap_same_pairs", "colmap_sequential"}) {
      const BenchRun* run = FindRun(results_, sequence, method);
      if (run == nullptr || !DrawsTrajectory(results_, *run)) continue;
      const std::string stem = "bench_" + sequence + "_" + method;
      md_ << "\n"
          << MethodName(method) << ": ![top](" << figures_ << "/" << stem << "_top.svg) ![side]("
          << figures_ << "/" << stem << "_side.svg)\n";
    }
  }

  void WriteBatchSize() {
    md_ << "\n## Batch size (the paper's Fig. 6)\n\n"
        << "On " << results_.batch_size_sequence
        << "; every batch size started from the features and verified matches of that "
           "sequence's viosfm run, so the time is that of the VIO read, the mapping and the "
           "outputs. The figures' reference lines are the methods of the "
        << results_.batch_size_sequence << " table.\n\n"
        << "| batch size | registered / frames | ATE RMSE (mm) | time (s) | CPU (s) | mapping (s) "
           "| viosfm |\n"
        << "|---|---|---|---|---|---|---|\n";
    for (const BenchRun& run : results_.batch_size) {
      md_ << "| " << run.method << " | " << Registered(run) << " | " << Millimetres(run.ate_rmse_m)
          << " | " << FormatFixedOrNa(run.seconds, 1) << " | "
          << FormatFixedOrNa(run.cpu_seconds, 1) << " | " << FormatFixedOrNa(run.mapping_seconds, 1)
          << " | " << (run.version.empty() ? meta_version_ : run.version) << " |\n";
    }
    md_ << "\n![ATE against batch size](" << figures_
        << "/bench_batch_size_ate.svg) ![time against batch size](" << figures_
        << "/bench_batch_size_time.svg)\n";
  }

  void WriteLength() {
    md_ << "\n## Sequence length\n\n"
        << "| frames | registered / frames | ATE RMSE (mm) | time (s) | CPU (s) | mapping (s) | "
           "peak memory (MiB) | viosfm |\n|---|---|---|---|---|---|---|---|\n";
    for (const BenchRun& run : results_.length) {
      md_ << "| " << run.method << " | " << Registered(run) << " | " << Millimetres(run.ate_rmse_m)
          << " | " << FormatFixedOrNa(run.seconds, 1) << " | "
          << FormatFixedOrNa(run.cpu_seconds, 1) << " | " << FormatFixedOrNa(run.mapping_seconds, 1)
          << " | " << FormatFixedOrNa(run.peak_memory_mb, 0) << " | "
          << (run.version.empty() ? meta_version_ : run.version) << " |\n";
    }
    for (const BenchRun& run : results_.length) {
      if (!run.reused.empty()) {
        md_ << "\n"
            << run.method << " frames: started from the " << run.reused
            << "; its time is that of the remaining stages.\n";
      }
    }
  }

  const BenchResults& results_;
  const std::string figures_;
  std::string meta_version_;
  std::ostringstream md_;
};

}  // namespace

std::string FormatBenchMarkdown(const BenchResults& results,
                                const std::string& figures_relative_path) {
  return BenchMarkdown(results, figures_relative_path).Format();
}

void WriteBenchReport(const BenchResults& results, const fs::path& markdown_path,
                      const fs::path& figures_folder) {
  fs::create_directories(figures_folder);
  // Trajectory views.
  for (const BenchRun& run : results.runs) {
    if (run.method != "viosfm" && run.method != "colmap_same_pairs" &&
        run.method != "colmap_sequential") {
      continue;
    }
    const fs::path sequence = results.root / run.sequence / "sequence";
    const fs::path gt_csv = GroundTruthCsv(sequence);
    // Without the sequence's ground truth (e.g. a dataset folder that has moved)
    // or the run's trajectory (a run still going), no figure and no link to one.
    if (!DrawsTrajectory(results, run)) continue;
    const std::optional<Trajectory> estimate = RunTrajectory(run, sequence);
    if (!estimate) continue;
    const Trajectory ground_truth = ReadEurocTrajectory(gt_csv);
    TrajectoryPlotOptions plot_options;
    plot_options.estimate_label = MethodName(run.method);
    TrajectoryFigures figures =
        MakeTrajectoryFigures(*estimate, ground_truth, Trajectory{}, plot_options);
    const std::string stem = "bench_" + run.sequence + "_" + run.method;
    figures.top_view.title = run.sequence + ": " + MethodName(run.method) + " (top view)";
    figures.side_view.title = run.sequence + ": " + MethodName(run.method) + " (side view)";
    WriteSvg(figures_folder / (stem + "_top.svg"), figures.top_view);
    WriteSvg(figures_folder / (stem + "_side.svg"), figures.side_view);
  }
  // Batch-size sweep with its sequence's COLMAP and VIO runs as references.
  if (!results.batch_size.empty()) {
    BatchSizeSweep sweep;
    BatchSizeCurve curve;
    curve.label = "viosfm";
    for (const BenchRun& run : results.batch_size) {
      if (!run.ate_rmse_m || !run.seconds) continue;
      curve.batch_sizes.push_back(std::stod(run.method));
      curve.ate_rmse_m.push_back(*run.ate_rmse_m);
      curve.seconds.push_back(*run.seconds);
    }
    sweep.curves.push_back(curve);
    sweep.log_x = true;
    {
      for (const char* method : {"colmap_same_pairs", "colmap_sequential", "vio"}) {
        const BenchRun* run = FindRun(results, results.batch_size_sequence, method);
        if (run == nullptr) continue;
        if (run->ate_rmse_m) sweep.ate_references.push_back({MethodName(method), *run->ate_rmse_m});
        if (run->seconds && std::string(method) != "vio") {
          sweep.time_references.push_back({MethodName(method), *run->seconds});
        }
      }
    }
    if (!curve.batch_sizes.empty()) {
      const BatchSizeFigures figures = MakeBatchSizeFigures(sweep);
      WriteSvg(figures_folder / "bench_batch_size_ate.svg", figures.ate);
      WriteSvg(figures_folder / "bench_batch_size_time.svg", figures.time);
    }
  }
  const fs::path relative = fs::relative(figures_folder, fs::absolute(markdown_path).parent_path());
  const std::string markdown = FormatBenchMarkdown(results, relative.generic_string());
  WriteFileAtomically(markdown_path, [&](std::ostream& out) { out << markdown; });
}

}  // namespace viosfm

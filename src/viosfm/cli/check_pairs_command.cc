// `viosfm check-pairs`: judges the pair decisions of verification runs
// (`viosfm match --report DIR`) on a simulated sequence against its ground
// truth (sim/pair_truth.h): correct candidates, accepted correct and wrong
// pairs, and the share of the first run's correct pairs each run keeps.
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "viosfm/cli/commands.h"
#include "viosfm/io/verification_report.h"
#include "viosfm/sim/pair_truth.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/logging.h"

namespace viosfm::cli {
namespace {

namespace fs = std::filesystem;

struct CheckPairsArguments {
  std::string sequence;
  std::vector<std::string> reports;
  std::vector<std::string> databases;
  std::string json;
  PairTruthOptions options;
};

void RunCheckPairs(const CheckPairsArguments& args) {
  if (!args.databases.empty() && args.databases.size() != args.reports.size()) {
    throw InputError("--database: give one per --report (" + std::to_string(args.reports.size()) +
                     "), or none to take each from the report's verification.json");
  }
  std::vector<VerificationRunInput> runs;
  for (size_t k = 0; k < args.reports.size(); ++k) {
    const fs::path report = args.reports[k];
    VerificationRunInput run;
    run.name = report.filename().empty() ? report.parent_path().filename().string()
                                         : report.filename().string();
    run.decisions = ReadPairDecisionsCsv(report / "pairs.csv");
    run.database = args.databases.empty()
                       ? fs::path(ReadVerificationDatabasePath(report / "verification.json"))
                       : fs::path(args.databases[k]);
    if (run.database.empty()) {
      throw InputError((report / "verification.json").string(), 0,
                       "no summary.database: pass --database");
    }
    runs.push_back(std::move(run));
  }
  const PairTruthLabeller labeller = PairTruthLabeller::FromSimulation(args.sequence, args.options);
  VIOSFM_LOG(INFO) << "check-pairs: " << labeller.frames().size() << " frames of " << args.sequence
                   << ", " << runs.size() << " run(s)";
  const std::vector<VerificationTruthSummary> summaries = EvaluateVerificationRuns(labeller, runs);
  std::cout << FormatVerificationTruthTable(summaries);
  for (const VerificationTruthSummary& summary : summaries) {
    for (const auto& [name1, name2] : summary.wrong_pairs) {
      std::cout << "wrong (" << summary.name << "): " << name1 << " " << name2 << "\n";
    }
  }
  if (!args.json.empty()) {
    const PairTruthOptions& o = args.options;
    WriteVerificationTruthJson(
        args.json, summaries,
        {{"sequence", args.sequence},
         {"grid_step_px", std::to_string(o.grid_step_px)},
         {"occlusion_tolerance_m", std::to_string(o.occlusion_tolerance_m)},
         {"occlusion_tolerance_relative", std::to_string(o.occlusion_tolerance_relative)},
         {"max_match_error_px", std::to_string(o.max_match_error_px)},
         {"min_covisibility", std::to_string(o.min_covisibility)},
         {"min_inlier_agreement", std::to_string(o.min_inlier_agreement)},
         {"covisibility", "max of both directions"}});
  }
}

}  // namespace

void RegisterCheckPairs(CLI::App& app) {
  auto args = std::make_shared<CheckPairsArguments>();
  CLI::App* command = app.add_subcommand(
      "check-pairs",
      "Judge verification runs on a simulated sequence against its ground truth. Of each run "
      "(viosfm match --report): correct candidate pairs (views sharing a surface), accepted wrong "
      "pairs "
      "(inliers disagreeing with the true geometry), and each run's share of the first run's "
      "correct pairs");
  command->add_option("sequence", args->sequence, "`viosfm simulate` output folder")->required();
  command
      ->add_option("--report", args->reports,
                   "Report folder of a match run (pairs.csv, verification.json); repeat; the "
                   "first is the baseline of the recall")
      ->required();
  command->add_option("--database", args->databases,
                      "Database of each run, in --report order (default: from verification.json)");
  command->add_option("--json", args->json, "Write the results as JSON");
  command
      ->add_option("--grid-step", args->options.grid_step_px, "Covisibility pixel grid step (px)")
      ->capture_default_str();
  command
      ->add_option("--min-covisibility", args->options.min_covisibility,
                   "A pair is correct at this covisibility or more")
      ->capture_default_str();
  command
      ->add_option("--max-match-error", args->options.max_match_error_px,
                   "A match agrees with the truth within this distance (px)")
      ->capture_default_str();
  command
      ->add_option("--min-inlier-agreement", args->options.min_inlier_agreement,
                   "An accepted pair is wrong below this fraction of agreeing inliers")
      ->capture_default_str();
  command->add_option("--threads", args->options.num_threads, "Threads")->capture_default_str();
  command->callback([args] { RunCheckPairs(*args); });
}

}  // namespace viosfm::cli

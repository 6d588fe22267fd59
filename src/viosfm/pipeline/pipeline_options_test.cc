#include "viosfm/pipeline/pipeline_options.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/option_fields.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

// "key\tvalue\t1|0" rows of options.json for each configuration below,
// frozen from the hand-written lists the descriptions replaced.
std::map<std::string, std::vector<std::string>> FrozenRows() {
  std::map<std::string, std::vector<std::string>> rows;
  std::string section;
  std::istringstream text(ReadTextFile(testing::SourcePath("pipeline/testdata/options_keys.txt")));
  std::string line;
  while (std::getline(text, line)) {
    if (line.empty() || line.rfind("# ", 0) == 0) continue;
    if (line.rfind("## ", 0) == 0) {
      section = line.substr(3);
    } else {
      rows[section].push_back(line);
    }
  }
  return rows;
}

std::vector<std::string> Rows(const PipelineOptions& options) {
  std::set<std::string> stored;
  for (const auto& [key, value] : options.StoredDataKeyValues()) stored.insert(key);
  std::vector<std::string> rows;
  for (const auto& [key, value] : options.ToKeyValues()) {
    rows.push_back(key + "\t" + value + "\t" + (stored.count(key) ? "1" : "0"));
  }
  return rows;
}

TEST(PipelineOptions, KeysValuesAndStoredDataAsFrozen) {
  const auto frozen = FrozenRows();
  PipelineOptions base;
  base.dataset = "/data/MH_01";
  base.output_folder = "/out";
  std::map<std::string, PipelineOptions> configurations;
  configurations["default"] = base;
  PipelineOptions bag = base;
  bag.dataset = "/data/x.bag";
  bag.vio_trajectory = "/data/vio.tum";
  configurations["bag_file"] = bag;
  PipelineOptions source = base;
  source.vio_source = [](const Sequence&) { return Trajectory{}; };
  configurations["source"] = source;
  PipelineOptions no_drift = base;
  no_drift.verification.band_follows_drift = false;
  configurations["nodrift"] = no_drift;
  PipelineOptions no_prior = base;
  no_prior.verification.use_vio_prior = false;
  configurations["noprior"] = no_prior;
  ASSERT_EQ(frozen.size(), configurations.size());
  if (const char* dump = std::getenv("VIOSFM_DUMP_OPTION_ROWS")) {
    std::ofstream out(dump);
    for (const auto& [name, options] : configurations) {
      out << "## " << name << "\n";
      for (const std::string& row : Rows(options)) out << row << "\n";
    }
  }
  for (const auto& [name, options] : configurations) {
    ASSERT_EQ(frozen.count(name), 1u) << name;
    EXPECT_EQ(Rows(options), frozen.at(name)) << name;
  }
}

TEST(PipelineOptions, EveryKeyCanBeSetFromItsText) {
  PipelineOptions options;
  options.dataset = "/data/MH_01";
  options.output_folder = "/out";
  SetOptionFromText(options, "mapper.ba.prior_weighting", "paper");
  SetOptionFromText(options, "verification.pairs.num_temporal_neighbors", "12");
  SetOptionFromText(options, "own_vio.tracker.equalization", "always");
  SetOptionFromText(options, "vio.max_gap_ns", "0");
  SetOptionFromText(options, "mapper.bridge_spans", "5");
  EXPECT_EQ(options.mapper.ba.prior_weighting, PriorWeighting::kPaper);
  EXPECT_EQ(options.verification.pairs.num_temporal_neighbors, 12);
  EXPECT_EQ(options.own_vio.tracker.equalization, ContrastEqualization::kAlways);
  EXPECT_EQ(options.vio_max_gap_ns, 0);
  EXPECT_EQ(options.mapper.bridge_spans, std::vector<int>{5});
  // Every written text parses back to the same value (except what only code
  // can give).
  PipelineOptions copy = options;
  copy.mapper = BatchedMapperOptions();
  for (const auto& [key, value] : OptionsToKeyValues(options)) {
    if (key == "vio.source" || key == "rosbag.rig") continue;
    SetOptionFromText(copy, key, value);
  }
  EXPECT_EQ(OptionsToKeyValues(copy), OptionsToKeyValues(options));
  EXPECT_THROW(SetOptionFromText(options, "vio.source", "function"), InputError);
  EXPECT_THROW(SetOptionFromText(options, "vio.frame", "world"), InputError);
  EXPECT_THROW(SetOptionFromText(options, "no.such_option", "1"), InputError);
}

TEST(PipelineOptions, DescriptionsCoverEveryKeyWithAHelp) {
  const std::vector<OptionDescription> descriptions = OptionDescriptions<PipelineOptions>();
  std::set<std::string> keys;
  for (const OptionDescription& description : descriptions) {
    EXPECT_TRUE(keys.insert(description.key).second) << "twice: " << description.key;
    EXPECT_FALSE(description.help.empty()) << description.key;
  }
  PipelineOptions bag;
  bag.dataset = "x.bag";
  for (const auto& [key, value] : bag.ToKeyValues()) EXPECT_EQ(keys.count(key), 1u) << key;
}

// The real-time preset changes exactly its options, every other one keeps
// the paper's default, the result is valid, and the paper preset undoes it.
TEST(PipelineOptions, RealtimePresetChangesOnlyItsOptions) {
  PipelineOptions options;
  options.dataset = "d";
  options.output_folder = "o";
  PipelineOptions realtime = options;
  ApplyPreset(RunPreset::kRealtime, &realtime);
  EXPECT_EQ(realtime.Validate(), "");
  const auto before = options.ToKeyValues();
  const auto after = realtime.ToKeyValues();
  ASSERT_EQ(before.size(), after.size());
  std::map<std::string, std::string> changed;
  for (size_t i = 0; i < before.size(); ++i) {
    ASSERT_EQ(before[i].first, after[i].first);
    if (before[i].second != after[i].second) changed[after[i].first] = after[i].second;
  }
  const std::map<std::string, std::string> expected = {
      {"verification.pairs.num_temporal_neighbors", "10"},
      {"verification.pairs.num_retrieval_neighbors", "5"},
      {"feature_budget.features_per_second", "10000"},
      {"verification.guided_matching", "true"},
      {"mapper.ba_window_batches", "4"},
      {"mapper.ba_window_max_held_views", "5"},
      {"texture_probe.enable", "true"},
      {"mapper.ba.function_tolerance", "3e-05"},
      {"mapper.ba.max_linear_solver_iterations", "100"},
      {"mapper.final_ba_max_refinements", "1"},
      {"mapper.final_ba_refine_min_change", "0.02"}};
  EXPECT_EQ(changed, expected);
  ApplyPreset(RunPreset::kPaper, &realtime);
  EXPECT_EQ(realtime.ToKeyValues(), before);
}

// A sparse recording (its frames slower than the budget limits: 10000 / 8192
// = 1.22 a second) gets back the paper's N2 and adjustment settings, and
// only those; a frame-rate recording, a photo collection (rate 0), a run
// without the budget and a user's own choice keep the preset's.
TEST(PipelineOptions, SparseRecordingTakesThePapersRetrievalAndAdjustments) {
  PipelineOptions paper;
  PipelineOptions realtime;
  ApplyPreset(RunPreset::kRealtime, &realtime);
  PipelineOptions sparse = realtime;
  EXPECT_NE(ApplySparseRecordingSettings(0.9, &sparse), "");
  PipelineOptions expected = realtime;
  expected.verification.pairs.num_retrieval_neighbors =
      paper.verification.pairs.num_retrieval_neighbors;
  expected.mapper.ba.function_tolerance = paper.mapper.ba.function_tolerance;
  expected.mapper.ba.max_linear_solver_iterations = paper.mapper.ba.max_linear_solver_iterations;
  expected.mapper.final_ba_max_refinements = paper.mapper.final_ba_max_refinements;
  expected.mapper.final_ba_refine_min_change = paper.mapper.final_ba_refine_min_change;
  EXPECT_EQ(sparse.ToKeyValues(), expected.ToKeyValues());
  EXPECT_EQ(sparse.verification.pairs.num_retrieval_neighbors, 30);
  EXPECT_EQ(sparse.mapper.final_ba_max_refinements, 3);

  PipelineOptions at_budget = realtime;  // 10000 / 1.3 < 8192: limited
  EXPECT_EQ(ApplySparseRecordingSettings(1.3, &at_budget), "");
  EXPECT_EQ(at_budget.ToKeyValues(), realtime.ToKeyValues());
  for (const double rate_hz : {10.0, 0.0}) {
    PipelineOptions options = realtime;
    EXPECT_EQ(ApplySparseRecordingSettings(rate_hz, &options), "") << rate_hz;
    EXPECT_EQ(options.ToKeyValues(), realtime.ToKeyValues()) << rate_hz;
  }
  PipelineOptions no_budget = realtime;
  no_budget.feature_budget.features_per_second = 0;
  EXPECT_EQ(ApplySparseRecordingSettings(0.9, &no_budget), "");
  PipelineOptions users_n2 = realtime;
  users_n2.verification.pairs.num_retrieval_neighbors = 7;
  users_n2.feature_budget.paper_settings_when_sparse = false;  // as `--n2 7` leaves it
  EXPECT_EQ(ApplySparseRecordingSettings(0.9, &users_n2), "");
  EXPECT_EQ(users_n2.verification.pairs.num_retrieval_neighbors, 7);
  EXPECT_TRUE(SettledBySparseRecording("verification.pairs.num_retrieval_neighbors"));
  EXPECT_TRUE(SettledBySparseRecording("mapper.final_ba_max_refinements"));
  EXPECT_FALSE(SettledBySparseRecording("verification.pairs.num_temporal_neighbors"));
}

}  // namespace
}  // namespace viosfm

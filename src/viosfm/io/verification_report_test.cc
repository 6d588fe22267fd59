#include "viosfm/io/verification_report.h"

#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/string_util.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

std::vector<PairDecision> TwoDecisions() {
  PairDecision accepted;
  accepted.image_id1 = 1;
  accepted.image_id2 = 2;
  accepted.name1 = "100.png";
  accepted.name2 = "200.png";
  accepted.source = "temporal";
  accepted.num_matches = 321;
  accepted.has_vio_prior = true;
  accepted.vio_outlier_ratio = 0.125;
  accepted.num_inliers = 300;
  accepted.accepted = true;
  accepted.reason = kPairAccepted;
  PairDecision rejected;
  rejected.image_id1 = 1;
  rejected.image_id2 = 7;
  rejected.name1 = "100.png";
  rejected.name2 = "700.png";
  rejected.source = "retrieval";
  rejected.num_matches = 40;
  rejected.reason = kPairTooFewInliers;  // no prior: ratio stays NaN
  return {accepted, rejected};
}

TEST(VerificationReport, CsvHasHeaderAndOneLinePerPair) {
  const auto folder = testing::MakeScratchFolder("verification_report_csv");
  const auto path = folder / "pairs.csv";
  WritePairDecisionsCsv(path, TwoDecisions());
  const std::string text = ReadTextFile(path);
  const std::vector<std::string_view> lines = Split(text, "\n", /*skip_empty=*/true);
  ASSERT_EQ(lines.size(), 3u);
  EXPECT_EQ(Split(lines[0], ",", false).size(), 14u);
  EXPECT_EQ(lines[1], "1,2,100.png,200.png,temporal,321,1,0.125000,0,0,300,1,0,accepted");
  EXPECT_EQ(lines[2], "1,7,100.png,700.png,retrieval,40,0,nan,0,0,0,0,0,too_few_inliers");
}

TEST(VerificationReport, CsvRejectsNamesWithCommas) {
  const auto folder = testing::MakeScratchFolder("verification_report_bad");
  std::vector<PairDecision> decisions = TwoDecisions();
  decisions[0].name1 = "a,b.png";
  EXPECT_THROW(WritePairDecisionsCsv(folder / "pairs.csv", decisions), InputError);
  EXPECT_FALSE(std::filesystem::exists(folder / "pairs.csv"));
}

TEST(VerificationReport, JsonParsesBack) {
  const auto folder = testing::MakeScratchFolder("verification_report_json");
  const auto path = folder / "verification.json";
  VerificationSummary summary;
  summary.num_images = 12;
  summary.num_pairs = 2;
  summary.num_accepted = 1;
  summary.num_ransac_rejected = 1;
  summary.seconds_total = 1.5;
  summary.options = {{"prior.max_epipolar_error_px", "20"}, {"use_vio_prior", "true"}};
  WriteVerificationJson(path, summary, TwoDecisions());
  const nlohmann::json json = nlohmann::json::parse(ReadTextFile(path));
  EXPECT_EQ(json.at("summary").at("num_images").get<int>(), 12);
  EXPECT_EQ(json.at("summary").at("num_accepted").get<int>(), 1);
  EXPECT_EQ(json.at("summary").at("num_ransac_rejected").get<int>(), 1);
  EXPECT_DOUBLE_EQ(json.at("summary").at("seconds_total").get<double>(), 1.5);
  EXPECT_EQ(json.at("options").at("prior.max_epipolar_error_px").get<std::string>(), "20");
  const nlohmann::json& pairs = json.at("pairs");
  ASSERT_EQ(pairs.size(), 2u);
  EXPECT_EQ(pairs[0].at("image_id2").get<int>(), 2);
  EXPECT_EQ(pairs[0].at("name2").get<std::string>(), "200.png");
  EXPECT_DOUBLE_EQ(pairs[0].at("vio_outlier_ratio").get<double>(), 0.125);
  EXPECT_TRUE(pairs[0].at("accepted").get<bool>());
  EXPECT_TRUE(pairs[1].at("vio_outlier_ratio").is_null());
  EXPECT_EQ(pairs[1].at("reason").get<std::string>(), "too_few_inliers");
  EXPECT_EQ(pairs[1].at("num_matches").get<int>(), 40);
}

}  // namespace
}  // namespace viosfm

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
  accepted.vio_depth_applied = true;
  accepted.vio_depth_inconsistent_ratio = 0.25;
  accepted.vio_correction_sigmas = 1.5;
  accepted.vio_corrected = true;
  accepted.guided_band_px = 42.5;
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
  EXPECT_EQ(Split(lines[0], ",", false).size(), 20u);
  EXPECT_EQ(lines[1],
            "1,2,100.png,200.png,temporal,321,1,0.125000,0,0,300,1,0,accepted,1,0.250000,0,"
            "1.500000,1,42.500000");
  EXPECT_EQ(lines[2],
            "1,7,100.png,700.png,retrieval,40,0,nan,0,0,0,0,0,too_few_inliers,0,nan,0,nan,0,nan");
}

TEST(VerificationReport, CsvReadsBack) {
  const auto folder = testing::MakeScratchFolder("verification_report_read");
  const auto path = folder / "pairs.csv";
  std::vector<PairDecision> written = TwoDecisions();
  written[1].vio_depth_rejected = true;
  written[1].vio_rejected = true;
  written[1].reason = kPairVioDepth;
  WritePairDecisionsCsv(path, written);
  const std::vector<PairDecision> read = ReadPairDecisionsCsv(path);
  ASSERT_EQ(read.size(), 2u);
  for (size_t k = 0; k < 2; ++k) {
    EXPECT_EQ(read[k].image_id1, written[k].image_id1);
    EXPECT_EQ(read[k].image_id2, written[k].image_id2);
    EXPECT_EQ(read[k].name1, written[k].name1);
    EXPECT_EQ(read[k].name2, written[k].name2);
    EXPECT_EQ(read[k].source, written[k].source);
    EXPECT_EQ(read[k].num_matches, written[k].num_matches);
    EXPECT_EQ(read[k].has_vio_prior, written[k].has_vio_prior);
    EXPECT_EQ(read[k].vio_rejected, written[k].vio_rejected);
    EXPECT_EQ(read[k].num_inliers, written[k].num_inliers);
    EXPECT_EQ(read[k].accepted, written[k].accepted);
    EXPECT_EQ(read[k].reason, written[k].reason);
    EXPECT_EQ(read[k].vio_depth_applied, written[k].vio_depth_applied);
    EXPECT_EQ(read[k].vio_depth_rejected, written[k].vio_depth_rejected);
    EXPECT_EQ(read[k].vio_corrected, written[k].vio_corrected);
  }
  EXPECT_DOUBLE_EQ(read[0].vio_correction_sigmas, 1.5);
  EXPECT_TRUE(std::isnan(read[1].vio_correction_sigmas));
  EXPECT_DOUBLE_EQ(read[0].guided_band_px, 42.5);
  EXPECT_TRUE(std::isnan(read[1].guided_band_px));
  EXPECT_DOUBLE_EQ(read[0].vio_outlier_ratio, 0.125);
  EXPECT_DOUBLE_EQ(read[0].vio_depth_inconsistent_ratio, 0.25);
  EXPECT_TRUE(std::isnan(read[1].vio_outlier_ratio));
  EXPECT_TRUE(std::isnan(read[1].vio_depth_inconsistent_ratio));

  // The 14-column form written before the depth check existed.
  WriteFileAtomically(folder / "old.csv", [](std::ostream& out) {
    out << "image_id1,image_id2,name1,name2,source,num_matches,has_vio_prior,vio_outlier_ratio,"
           "vio_rotation_only,vio_rejected,num_inliers,accepted,resumed,reason\n"
           "3,4,a.png,b.png,temporal,50,1,0.500000,0,0,20,1,0,accepted\n";
  });
  const std::vector<PairDecision> old = ReadPairDecisionsCsv(folder / "old.csv");
  ASSERT_EQ(old.size(), 1u);
  EXPECT_EQ(old[0].num_inliers, 20);
  EXPECT_FALSE(old[0].vio_depth_applied);

  // The 19-column form written before the guided band was recorded.
  WriteFileAtomically(folder / "old19.csv", [](std::ostream& out) {
    out << "image_id1,image_id2,name1,name2,source,num_matches,has_vio_prior,vio_outlier_ratio,"
           "vio_rotation_only,vio_rejected,num_inliers,accepted,resumed,reason,"
           "vio_depth_applied,vio_depth_inconsistent_ratio,vio_depth_rejected,"
           "vio_correction_sigmas,vio_corrected\n"
           "3,4,a.png,b.png,temporal,50,1,0.500000,0,0,20,1,0,accepted,1,0.100000,0,2.000000,1\n";
  });
  const std::vector<PairDecision> old19 = ReadPairDecisionsCsv(folder / "old19.csv");
  ASSERT_EQ(old19.size(), 1u);
  EXPECT_TRUE(old19[0].vio_corrected);
  EXPECT_TRUE(std::isnan(old19[0].guided_band_px));
}

TEST(VerificationReport, CsvReadErrorsNameLine) {
  const auto folder = testing::MakeScratchFolder("verification_report_read_bad");
  const auto path = folder / "pairs.csv";
  WritePairDecisionsCsv(path, TwoDecisions());
  std::string text = ReadTextFile(path);
  text.replace(text.find("321"), 3, "x21");
  WriteFileAtomically(path, [&text](std::ostream& out) { out << text; });
  try {
    ReadPairDecisionsCsv(path);
    FAIL() << "expected an InputError";
  } catch (const InputError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find(":2"), std::string::npos) << message;
    EXPECT_NE(message.find("num_matches"), std::string::npos) << message;
  }
  EXPECT_THROW(ReadPairDecisionsCsv(folder / "missing.csv"), InputError);
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
  summary.database_path = "/data/run.db";
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
  EXPECT_DOUBLE_EQ(pairs[0].at("vio_depth_inconsistent_ratio").get<double>(), 0.25);
  EXPECT_TRUE(pairs[1].at("vio_depth_inconsistent_ratio").is_null());
  EXPECT_EQ(ReadVerificationDatabasePath(path), "/data/run.db");
}

}  // namespace
}  // namespace viosfm

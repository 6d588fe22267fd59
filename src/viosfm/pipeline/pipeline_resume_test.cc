#include <gtest/gtest.h>

#include <sstream>
#include <string>

#include "viosfm/pipeline/pipeline_test_fixture.h"
#include "viosfm/util/folder_manifest.h"
#include "viosfm/util/logging.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;
using namespace pipeline_testing;

TEST(PipelineTest, ResumesFromTheStoredFeaturesAndMatches) {
  const Fixture& f = SharedFixture();
  const fs::path out = CopyOfTheRun(f, "resume");
  PipelineOptions options = SmallOptions(f, out);
  options.mapper.ba.use_relative_pose_priors = false;
  options.mapper.ba.prior_weighting = PriorWeighting::kPaper;
  options.mapper.bridge_spans.clear();
  options.mapper.batch_size = 12;
  options.use_imu_scale = false;
  options.num_threads = 1;
  const PipelineSummary s = RunPipeline(options);
  EXPECT_EQ(s.features.num_extracted, 0u);
  EXPECT_EQ(s.features.num_skipped, f.summary.num_frames_selected);
  EXPECT_EQ(s.verification.num_resumed, f.summary.verification.num_pairs);
  EXPECT_EQ(s.verification.num_accepted, f.summary.verification.num_accepted);
  EXPECT_EQ(s.num_frames_registered, f.summary.num_frames_registered);
  EXPECT_TRUE(fs::is_regular_file(out / "summary.json"));
  // The same stored data: the same fingerprint.
  EXPECT_EQ(s.fingerprint, f.summary.fingerprint);
  EXPECT_EQ(ReadTextFile(out / "fingerprint.json"), ReadTextFile(f.out / "fingerprint.json"));
  // Without the VIO terms: 2 mm ATE and 0.2 px reprojection error on the
  // synthetic images (measured 0.002 m, 0.18 px).
  ASSERT_TRUE(s.evaluation.has_value());
  EXPECT_LT(s.evaluation->ate_rmse_m, 0.005);
  EXPECT_LT(s.mean_reprojection_error_px, 0.4);
}

// The console's lines of a resumed run, its summary included, are at most
// 120 characters; run.log holds the first run's section, then this one's
// with its debug lines and its summary.
TEST(PipelineTest, AResumedRunAddsItsSectionToTheLogAndKeepsTheConsoleNarrow) {
  const Fixture& f = SharedFixture();
  const fs::path out = CopyOfTheRun(f, "resume_log");
  const std::string first_log = ReadTextFile(out / kRunLogFileName);
  ::testing::internal::CaptureStderr();
  const PipelineSummary s = RunPipeline(SmallOptions(f, out));
  std::string console = ::testing::internal::GetCapturedStderr();
  console += s.ToString() + "\n";
  std::istringstream lines(console);
  size_t num_lines = 0;
  for (std::string line; std::getline(lines, line); ++num_lines) {
    EXPECT_LE(line.size(), kMaxConsoleLineLength) << line;
  }
  EXPECT_GT(num_lines, 20u);

  const std::string log = ReadTextFile(out / kRunLogFileName);
  ASSERT_EQ(log.substr(0, first_log.size()), first_log);  // the first run's log stays
  const std::string second = log.substr(first_log.size());
  EXPECT_EQ(second.find("\n== viosfm "), 0u) << second.substr(0, 200);
  EXPECT_NE(second.find("an earlier run's log above"), std::string::npos);
  EXPECT_NE(second.find("\nD "), std::string::npos);  // debug lines, not on the console
  EXPECT_NE(second.find("decisions (summary.json: warnings)"), std::string::npos);
  EXPECT_NE(second.find("run: complete (summary.json written)"), std::string::npos);
}

TEST(PipelineTest, ResumeWithOtherFeatureOptionsIsAnError) {
  const Fixture& f = SharedFixture();
  const fs::path out = CopyOfTheRun(f, "resume_changed");
  PipelineOptions options = SmallOptions(f, out);
  options.sift.max_num_features = 300;
  const std::string message = testing::InputErrorMessage([&] { RunPipeline(options); });
  EXPECT_NE(message.find((out / "fingerprint.json").string()), std::string::npos) << message;
  EXPECT_NE(message.find("sift.max_num_features was '600', is now '300'"), std::string::npos)
      << message;
  EXPECT_NE(message.find("--overwrite"), std::string::npos) << message;
  // Refused before the folder changed: the earlier run's summary stays.
  EXPECT_TRUE(fs::is_regular_file(out / "summary.json"));
}

// A database without the fingerprint that says what made it is not reused.
TEST(PipelineTest, DatabaseWithoutFingerprintIsAnError) {
  const Fixture& f = SharedFixture();
  const fs::path out = f.folder / "database_alone";
  fs::create_directories(out);
  fs::copy_file(f.out / "database.db", out / "database.db", fs::copy_options::overwrite_existing);
  // A folder viosfm did not make (no manifest) is refused as a whole.
  const std::string foreign =
      testing::InputErrorMessage([&] { RunPipeline(SmallOptions(f, out)); });
  EXPECT_NE(foreign.find("viosfm did not make it"), std::string::npos) << foreign;
  // One viosfm made, whose database lost its fingerprint.json.
  fs::copy_file(f.out / kManifestFileName, out / kManifestFileName,
                fs::copy_options::overwrite_existing);
  const std::string message =
      testing::InputErrorMessage([&] { RunPipeline(SmallOptions(f, out)); });
  EXPECT_NE(message.find("without the fingerprint.json"), std::string::npos) << message;
  EXPECT_NE(message.find("--overwrite"), std::string::npos) << message;
}

// Another simulated dataset with the same image names and stamps, run into
// the folder of the first: refused, naming what differs, and the folder is
// left as it was (nothing of the two datasets mixed).
TEST(PipelineTest, SecondDatasetIntoTheSameFolderIsRefused) {
  const Fixture& f = SharedFixture();
  const fs::path second = SecondDataset();
  // Same names and stamps: only the content differs.
  ASSERT_EQ(ReadTextFile(second / "mav0" / "cam0" / "data.csv"),
            ReadTextFile(f.dataset / "mav0" / "cam0" / "data.csv"));
  const fs::path out = CopyOfTheRun(f, "second_dataset");
  const std::string database_before = ReadTextFile(out / "database.db");
  PipelineOptions options = SmallOptions(f, out);
  options.dataset = second;
  options.vio_trajectory = second / "vio_emulated.tum";
  const std::string message = testing::InputErrorMessage([&] { RunPipeline(options); });
  for (const char* key :
       {"dataset.file.mav0/imu0/data.csv was '", "vio.input was 'file, ", "--overwrite"}) {
    EXPECT_NE(message.find(key), std::string::npos) << key << "\n" << message;
  }
  // The camera's list is the same file.
  EXPECT_EQ(message.find("dataset.file.mav0/cam0/data.csv"), std::string::npos) << message;
  EXPECT_EQ(ReadTextFile(out / "database.db"), database_before);
  EXPECT_TRUE(fs::is_regular_file(out / "summary.json"));

  // The images alone tell the datasets apart: with the first dataset's text
  // files and VIO, and the second's images, the image sizes differ.
  const fs::path mixed = CopyDataset(f.dataset, f.folder / "dataset_mixed");
  for (const fs::directory_entry& entry :
       fs::directory_iterator(second / "mav0" / "cam0" / "data")) {
    const fs::path link = mixed / "mav0" / "cam0" / "data" / entry.path().filename();
    fs::remove(link);
    fs::copy_file(entry.path(), link);
  }
  options.dataset = mixed;
  options.vio_trajectory = f.vio_file;
  const std::string images_message = testing::InputErrorMessage([&] { RunPipeline(options); });
  EXPECT_NE(images_message.find("dataset.images was '46 images"), std::string::npos)
      << images_message;
  EXPECT_EQ(ReadTextFile(out / "database.db"), database_before);
}

// --overwrite: the second dataset into the first one's folder starts afresh
// (every feature extracted and every pair verified again) and leaves what
// the folder held besides the run's outputs.
TEST(PipelineTest, OverwriteRecomputesEverything) {
  const Fixture& f = SharedFixture();
  const fs::path second = SecondDataset();
  const fs::path out = CopyOfTheRun(f, "overwrite");
  testing::WriteTextFile(out / "notes.txt", "mine\n");
  // Leftovers of an interrupted run (a killed atomic write) go too.
  testing::WriteTextFile(out / "summary.json.tmp-999999", "{");
  fs::create_directories(out / "model.old-999999");
  PipelineOptions options = SmallOptions(f, out);
  options.dataset = second;
  options.vio_trajectory = second / "vio_emulated.tum";
  options.overwrite = true;
  const PipelineSummary s = RunPipeline(options);
  EXPECT_EQ(s.features.num_skipped, 0u);
  EXPECT_EQ(s.features.num_extracted, s.num_frames_selected);
  EXPECT_EQ(s.verification.num_resumed, 0u);
  EXPECT_NE(s.fingerprint, f.summary.fingerprint);
  EXPECT_EQ(ReadRunFingerprint(out / "fingerprint.json").Hash(), s.fingerprint);
  EXPECT_EQ(ReadTextFile(out / "notes.txt"), "mine\n");
  EXPECT_FALSE(fs::exists(out / "summary.json.tmp-999999"));
  EXPECT_FALSE(fs::exists(out / "model.old-999999"));
  // A complete run of the second dataset: its summary and model.
  const nlohmann::json summary = nlohmann::json::parse(ReadTextFile(out / "summary.json"));
  EXPECT_EQ(summary["fingerprint"], s.fingerprint);
  EXPECT_EQ(summary["dataset"], second.string());
  EXPECT_EQ(ReadColmapModelBinary(out / "model").NumPoints3D(), s.num_points);
  // The same command again now reuses what the overwrite stored.
  options.overwrite = false;
  const PipelineSummary again = RunPipeline(options);
  EXPECT_EQ(again.features.num_extracted, 0u);
  EXPECT_EQ(again.verification.num_resumed, s.verification.num_pairs);
}

// One changed byte in a dataset file is another dataset.
TEST(PipelineTest, ChangedCsvByteIsDetected) {
  const Fixture& f = SharedFixture();
  const fs::path dataset = CopyDataset(f.dataset, f.folder / "dataset_one_byte");
  PipelineOptions options = SmallOptions(f, CopyOfTheRun(f, "one_byte"));
  options.dataset = dataset;
  const RunFingerprint before = FingerprintOfInputs(options);
  // The same content elsewhere: the same fingerprint (paths are not part of it).
  EXPECT_TRUE(
      CompareFingerprints(FingerprintOfInputs(SmallOptions(f, f.out)), before, true).empty());
  const fs::path csv = dataset / "mav0" / "imu0" / "data.csv";
  std::string text = ReadTextFile(csv);
  const size_t last_digit = text.find_last_of("0123456789");
  ASSERT_NE(last_digit, std::string::npos);
  text[last_digit] = text[last_digit] == '1' ? '2' : '1';
  fs::remove(csv);
  testing::WriteTextFile(csv, text);
  const std::vector<FingerprintDifference> differences =
      CompareFingerprints(before, FingerprintOfInputs(options), true);
  ASSERT_EQ(differences.size(), 1u);
  EXPECT_EQ(differences[0].key, "dataset.file.mav0/imu0/data.csv");
  const std::string message = testing::InputErrorMessage([&] { RunPipeline(options); });
  EXPECT_NE(message.find("dataset.file.mav0/imu0/data.csv"), std::string::npos) << message;
}

// Without a VIO trajectory, viosfm's own VIO gives the poses (from the
// images and the IMU).

}  // namespace
}  // namespace viosfm

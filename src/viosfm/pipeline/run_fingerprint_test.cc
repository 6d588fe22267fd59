#include "viosfm/pipeline/run_fingerprint.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <set>
#include <string>

#include "viosfm/io/colmap_database.h"
#include "viosfm/pipeline/run_folder.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/hash.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;

PipelineOptions Options(const fs::path& dataset, const fs::path& out) {
  PipelineOptions options;
  options.dataset = dataset;
  options.output_folder = out;
  options.vio_trajectory = dataset / "vio.tum";
  return options;
}

// A EuRoC folder of text files only (FingerprintOfInputs reads no image).
fs::path MakeEurocTextFiles(const fs::path& root) {
  for (const char* file : {"mav0/cam0/sensor.yaml", "mav0/cam0/data.csv", "mav0/imu0/sensor.yaml",
                           "mav0/imu0/data.csv"}) {
    fs::create_directories((root / file).parent_path());
    testing::WriteTextFile(root / file, std::string(file) + "\n");
  }
  testing::WriteTextFile(root / "vio.tum", "1 0 0 0 0 0 0 1\n");
  return root;
}

std::set<std::string> Keys(const RunFingerprint& fingerprint) {
  std::set<std::string> keys;
  for (const auto& [key, value] : fingerprint.entries) keys.insert(key);
  return keys;
}

// Which options of options.json shape the stored data, as their
// descriptions mark them (util/option_fields.h).
TEST(RunFingerprint, WhichOptionsShapeTheStoredData) {
  PipelineOptions options = Options("d", "o");
  for (const char* key :
       {"sift.max_num_features", "sift.root_sift", "frame_selection.target_rate_hz",
        "frame_selection.trim_static", "verification.pairs.num_temporal_neighbors",
        "verification.pairs.num_retrieval_neighbors", "verification.retrieval.vocabulary.depth",
        "verification.prior.max_epipolar_error_px", "verification.geometry.min_num_inliers",
        "verification.seed", "vio.max_time_difference_ns", "vio.max_gap_ns", "vio.frame",
        "vio_uncertainty.position_per_sqrt_m"}) {
    EXPECT_TRUE(ShapesStoredData(key, options)) << key;
  }
  for (const char* key : {"mapper.batch_size",
                          "mapper.ba.use_relative_pose_priors",
                          "mapper.ba.prior_weighting",
                          "mapper.bridge_spans",
                          "use_imu_scale",
                          "imu_scale.max_scale_sigma",
                          "num_threads",
                          "sift.num_threads",
                          "verification.num_threads",
                          "own_vio.window.num_threads",
                          "show_progress",
                          "own_vio.show_progress",
                          "seed",
                          "dataset",
                          "output_folder",
                          "vio.trajectory",
                          "calibration.camchain",
                          "verification.retrieval.vocabulary_path",
                          "own_vio.window.window_size",
                          "some.new_option"}) {
    EXPECT_FALSE(ShapesStoredData(key, options)) << key;
  }
  // The own VIO's options count only when it runs (no VIO file).
  PipelineOptions own_vio = options;
  own_vio.vio_trajectory.clear();
  EXPECT_TRUE(ShapesStoredData("own_vio.window.window_size", own_vio));
  EXPECT_FALSE(ShapesStoredData("own_vio.window.num_threads", own_vio));
  // The uncertainty model shapes the verification only through the band
  // that follows the drift.
  options.verification.band_follows_drift = false;
  EXPECT_FALSE(ShapesStoredData("vio_uncertainty.position_per_sqrt_m", options));
  options.verification.band_follows_drift = true;
  options.verification.use_vio_prior = false;
  EXPECT_FALSE(ShapesStoredData("vio_uncertainty.position_per_sqrt_m", options));
}

TEST(RunFingerprint, InputsFilesAndOptions) {
  const fs::path root = MakeEurocTextFiles(testing::MakeScratchFolder("fingerprint_inputs"));
  const RunFingerprint fingerprint = FingerprintOfInputs(Options(root, root / "out"));
  EXPECT_EQ(*fingerprint.Find("fingerprint.version"), kRunFingerprintVersion);
  EXPECT_EQ(*fingerprint.Find("dataset.kind"), "euroc");
  // "mav0/imu0/data.csv\n" is 19 bytes.
  EXPECT_EQ(*fingerprint.Find("dataset.file.mav0/imu0/data.csv"),
            HashFile(root / "mav0/imu0/data.csv").ToString());
  EXPECT_EQ(HashFile(root / "mav0/imu0/data.csv").size, 19u);
  EXPECT_EQ(fingerprint.Find("dataset.file.mav0/state_groundtruth_estimate0/data.csv"), nullptr);
  EXPECT_EQ(*fingerprint.Find("vio.input"), "file, " + HashFile(root / "vio.tum").ToString());
  EXPECT_EQ(*fingerprint.Find("sift.max_num_features"), "8192");
  const std::set<std::string> keys = Keys(fingerprint);
  EXPECT_EQ(keys.count("mapper.batch_size"), 0u);
  EXPECT_EQ(keys.count("output_folder"), 0u);
  EXPECT_EQ(keys.count("own_vio.window.window_size"), 0u);  // a VIO file: no own VIO

  // The own VIO and its options; a missing VIO file is "missing" (its reader
  // says what is wrong later).
  PipelineOptions own = Options(root, root / "out");
  own.vio_trajectory.clear();
  const RunFingerprint own_fingerprint = FingerprintOfInputs(own);
  EXPECT_EQ(*own_fingerprint.Find("vio.input"), "viosfm's own VIO");
  EXPECT_NE(own_fingerprint.Find("own_vio.window.window_size"), nullptr);
  own.vio_trajectory = root / "absent.tum";
  EXPECT_EQ(*FingerprintOfInputs(own).Find("vio.input"), "file, missing");
  own.dataset = root / "absent";
  EXPECT_EQ(*FingerprintOfInputs(own).Find("dataset.kind"), "missing");
}

// Under the real-time preset N2 is left out until the recording's pace has
// settled it: a sparse recording's 30 is then what the fingerprint holds;
// a user's own N2 is there from the start.
TEST(RunFingerprint, NTwoAsTheRecordingsPaceSettlesIt) {
  const fs::path root = MakeEurocTextFiles(testing::MakeScratchFolder("fingerprint_pace"));
  PipelineOptions options = Options(root, root / "out");
  ApplyPreset(RunPreset::kRealtime, &options);
  const std::string key = "verification.pairs.num_retrieval_neighbors";
  RunFingerprint fingerprint = FingerprintOfInputs(options);
  EXPECT_EQ(fingerprint.Find(key), nullptr);
  PipelineOptions sparse = options;
  ASSERT_NE(ApplySparseRecordingSettings(0.9, &sparse), "");
  AddSettledRateAndFeatures(sparse, &fingerprint);
  ASSERT_NE(fingerprint.Find(key), nullptr);
  EXPECT_EQ(*fingerprint.Find(key), "30");

  RunFingerprint at_frame_rate = FingerprintOfInputs(options);
  PipelineOptions frame_rate = options;
  EXPECT_EQ(ApplySparseRecordingSettings(10.0, &frame_rate), "");
  AddSettledRateAndFeatures(frame_rate, &at_frame_rate);
  EXPECT_EQ(*at_frame_rate.Find(key), "5");

  PipelineOptions users = options;
  users.verification.pairs.num_retrieval_neighbors = 30;
  users.feature_budget.paper_settings_when_sparse = false;  // as `--n2 30` leaves it
  ASSERT_NE(FingerprintOfInputs(users).Find(key), nullptr);
  EXPECT_EQ(*FingerprintOfInputs(users).Find(key), "30");
}

TEST(RunFingerprint, SequenceAndVioPoses) {
  const fs::path root = testing::MakeScratchFolder("fingerprint_sequence");
  Sequence sequence;
  for (int k = 0; k < 3; ++k) {
    const fs::path image = root / (std::to_string(k) + ".png");
    testing::WriteTextFile(image, std::string(static_cast<size_t>(10 + k), 'x'));
    sequence.images.push_back({int64_t{1'000'000'000} * (k + 1), image});
  }
  RunFingerprint a;
  AddSequenceToFingerprint(sequence, &a);
  EXPECT_EQ(a.Find("dataset.images")->substr(0, 39), "3 images [1.000, 3.000] s, 33 bytes, fn");
  ASSERT_EQ(a.image_files.size(), 3u);
  // One image one byte longer: other images.
  testing::WriteTextFile(sequence.images[1].path, std::string(12, 'x'));
  RunFingerprint b;
  AddSequenceToFingerprint(sequence, &b);
  EXPECT_NE(*a.Find("dataset.images"), *b.Find("dataset.images"));
  EXPECT_EQ(*a.Find("dataset.rig"), *b.Find("dataset.rig"));
  // An image replaced by another of the same size: its content's hash
  // tells them apart.
  testing::WriteTextFile(sequence.images[1].path, std::string(11, 'y') + "x");
  RunFingerprint same_size;
  AddSequenceToFingerprint(sequence, &same_size);
  EXPECT_EQ(same_size.image_files[1].size, b.image_files[1].size);
  EXPECT_NE(same_size.image_files[1].xxh3, b.image_files[1].xxh3);
  EXPECT_NE(*same_size.Find("dataset.images"), *b.Find("dataset.images"));
  EXPECT_EQ(same_size.image_files[1].name, "1.png");
  EXPECT_EQ(same_size.image_files[1].xxh3, HashFile(sequence.images[1].path).hash);
  // Another calibration: another rig.
  sequence.rig.body_from_cam.translation.x() += 1e-12;
  RunFingerprint c;
  AddSequenceToFingerprint(sequence, &c);
  EXPECT_NE(*b.Find("dataset.rig"), *c.Find("dataset.rig"));

  Trajectory poses;
  poses.poses.push_back({1, Rigid3d()});
  poses.poses.push_back({2, Rigid3d()});
  RunFingerprint one_segment, two_segments, moved;
  AddVioPosesToFingerprint(poses, {0, 0}, &one_segment);
  AddVioPosesToFingerprint(poses, {0, 1}, &two_segments);
  EXPECT_NE(*one_segment.Find("vio.poses"), *two_segments.Find("vio.poses"));
  EXPECT_EQ(one_segment.Find("vio.poses")->substr(0, 27), "2 poses in 1 segment(s), fn");
  poses.poses[1].world_from_frame.translation.z() = 1e-300;  // bit for bit
  AddVioPosesToFingerprint(poses, {0, 0}, &moved);
  EXPECT_NE(*one_segment.Find("vio.poses"), *moved.Find("vio.poses"));
}

TEST(RunFingerprint, JsonRoundTripAndComparison) {
  const fs::path folder = testing::MakeScratchFolder("fingerprint_json");
  RunFingerprint stored;
  stored.Set("a", "1");
  stored.Set("b", "two words");
  stored.Set("a", "3");  // replaced, keeps its place
  ASSERT_EQ(stored.entries.size(), 2u);
  EXPECT_EQ(stored.entries[0].second, "3");
  WriteFileAtomically(folder / "fingerprint.json",
                      [&](std::ostream& out) { out << RunFingerprintToJson(stored); });
  const RunFingerprint read = ReadRunFingerprint(folder / "fingerprint.json");
  EXPECT_EQ(read.entries, stored.entries);
  EXPECT_EQ(read.Hash(), stored.Hash());

  RunFingerprint current;
  current.Set("a", "3");
  current.Set("c", "new");
  // Partial: only the keys computed so far count.
  std::vector<FingerprintDifference> differences = CompareFingerprints(stored, current, false);
  ASSERT_EQ(differences.size(), 1u);
  EXPECT_EQ(differences[0].key, "c");
  EXPECT_EQ(differences[0].stored, "(absent)");
  differences = CompareFingerprints(stored, current, true);
  ASSERT_EQ(differences.size(), 2u);
  EXPECT_EQ(differences[1].key, "b");
  EXPECT_EQ(differences[1].current, "(absent)");
  EXPECT_NE(stored.Hash(), current.Hash());

  testing::WriteTextFile(folder / "bad.json", "{\"entries\": {\"a\": 1}}");
  EXPECT_NE(testing::InputErrorMessage([&] {
              ReadRunFingerprint(folder / "bad.json");
            }).find("\"a\" is not a string"),
            std::string::npos);
  testing::WriteTextFile(folder / "bad.json", "not json");
  EXPECT_NE(testing::InputErrorMessage([&] {
              ReadRunFingerprint(folder / "bad.json");
            }).find("--overwrite"),
            std::string::npos);
}

// Writes `fingerprint` as a run does before its database's rows:
// fingerprint.json and the database's record.
void WriteStoredFingerprint(const fs::path& out, const RunFingerprint& fingerprint) {
  WriteFileAtomically(out / "fingerprint.json",
                      [&](std::ostream& stream) { stream << RunFingerprintToJson(fingerprint); });
  ColmapDatabase::Open(out / "database.db").WriteViosfmRecord(DatabaseRecordOf(fingerprint));
}

TEST(RunFingerprint, CheckStoredRunDataNamesWhatChanged) {
  const fs::path out = testing::MakeScratchFolder("fingerprint_check");
  RunFingerprint stored;
  stored.Set("dataset.file.mav0/imu0/data.csv", "10 bytes, xxh3 0000000000000001");
  stored.Set("sift.max_num_features", "600");
  RunFingerprint current = stored;
  // Nothing stored: nothing to check.
  current.Set("sift.max_num_features", "300");
  EXPECT_NO_THROW(CheckStoredRunData(out, current, true));
  // A database without its fingerprint.
  testing::WriteTextFile(out / "database.db", "");
  EXPECT_NE(testing::InputErrorMessage([&] {
              CheckStoredRunData(out, current, true);
            }).find("without the fingerprint.json"),
            std::string::npos);
  // A fingerprint.json beside a database without a record of its rows (a
  // database another tool made, or copied here).
  WriteFileAtomically(out / "fingerprint.json",
                      [&](std::ostream& stream) { stream << RunFingerprintToJson(stored); });
  EXPECT_NE(testing::InputErrorMessage([&] {
              CheckStoredRunData(out, stored, true);
            }).find("holds no record of what made its features and matches"),
            std::string::npos);
  WriteStoredFingerprint(out, stored);
  EXPECT_NO_THROW(CheckStoredRunData(out, stored, true));
  const InputError error =
      testing::ExpectInputError([&] { CheckStoredRunData(out, current, true); });
  EXPECT_EQ(error.path(), (out / "fingerprint.json").string());
  const std::string message = error.what();
  EXPECT_NE(message.find("sift.max_num_features was '600', is now '300'"), std::string::npos)
      << message;
  EXPECT_EQ(message.find("imu0"), std::string::npos) << message;  // unchanged
  EXPECT_NE(message.find("--overwrite"), std::string::npos) << message;

  // A fingerprint of another version of viosfm: a key one side lacks.
  RunFingerprint newer = stored;
  newer.Set("mapper.new_option", "1");
  const std::string newer_message =
      testing::InputErrorMessage([&] { CheckStoredRunData(out, newer, true); });
  EXPECT_NE(newer_message.find("mapper.new_option is '1' and was not recorded then"),
            std::string::npos)
      << newer_message;
  EXPECT_NE(newer_message.find("another version"), std::string::npos) << newer_message;

  // Rows written under another fingerprint (e.g. `viosfm features` with
  // other options, or a database copied from another run): the database's
  // record is not fingerprint.json.
  ColmapDatabase::Open(out / "database.db").WriteViosfmRecord(DatabaseRecordOf(current));
  const InputError rows = testing::ExpectInputError([&] { CheckStoredRunData(out, stored, true); });
  EXPECT_EQ(rows.path(), (out / "database.db").string());
  EXPECT_NE(std::string(rows.what()).find("written by another run or command"), std::string::npos)
      << rows.what();
  EXPECT_NE(std::string(rows.what()).find("sift.max_num_features was '300', is now '600'"),
            std::string::npos)
      << rows.what();
}

TEST(RunFingerprint, AChangedImageIsNamed) {
  const fs::path out = testing::MakeScratchFolder("fingerprint_image");
  Sequence sequence;
  for (int k = 0; k < 4; ++k) {
    const fs::path image = out / "images" / (std::to_string(k) + ".png");
    fs::create_directories(image.parent_path());
    testing::WriteTextFile(image, "pixels " + std::to_string(k));
    sequence.images.push_back({int64_t{1'000'000'000} * (k + 1), image});
  }
  RunFingerprint stored;
  AddSequenceToFingerprint(sequence, &stored);
  WriteStoredFingerprint(out, stored);
  testing::WriteTextFile(sequence.images[2].path, "pixels X");  // the same size
  RunFingerprint current;
  AddSequenceToFingerprint(sequence, &current);
  const std::string message =
      testing::InputErrorMessage([&] { CheckStoredRunData(out, current, false); });
  EXPECT_NE(message.find("dataset.images was '4 images"), std::string::npos) << message;
  EXPECT_NE(message.find("the content of 1 image(s) changed: 2.png"), std::string::npos) << message;
}

}  // namespace
}  // namespace viosfm

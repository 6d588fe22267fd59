#include "viosfm/io/euroc.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "viosfm/util/errors.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;
using testing::ExpectInputError;
using ::testing::HasSubstr;
using testing::InputErrorMessage;
using testing::WriteTextFile;

// ---------------------------------------------------------------- ground truth

TEST(ReadEurocGroundTruth, ReadsFullAndPoseOnlyRows) {
  const fs::path folder = testing::MakeScratchFolder("gt_ok");
  const fs::path csv = folder / "data.csv";
  WriteTextFile(csv,
                "#timestamp [ns], p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], "
                "q_RS_y [], q_RS_z []\n"
                "\n"
                "100,1,2,3,1,0,0,0,0.1,0.2,0.3,0.01,0.02,0.03,-0.1,-0.2,-0.3\r\n"
                "200, 4, 5, 6, 0, 0, 0, 1.0005\n");
  const std::vector<GroundTruthState> states = ReadEurocGroundTruth(csv);
  ASSERT_EQ(states.size(), 2u);
  EXPECT_EQ(states[0].timestamp_ns, 100);
  EXPECT_TRUE(states[0].has_velocity_and_biases);
  EXPECT_EQ(states[0].world_from_body.translation, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(states[0].velocity_in_world, Eigen::Vector3d(0.1, 0.2, 0.3));
  EXPECT_EQ(states[0].gyro_bias, Eigen::Vector3d(0.01, 0.02, 0.03));
  EXPECT_EQ(states[0].accel_bias, Eigen::Vector3d(-0.1, -0.2, -0.3));
  EXPECT_EQ(states[1].timestamp_ns, 200);
  EXPECT_FALSE(states[1].has_velocity_and_biases);
  EXPECT_EQ(states[1].velocity_in_world, Eigen::Vector3d::Zero());
  // qw first: (0, 0, 0, 1.0005) is a rotation of pi about z, normalised.
  EXPECT_NEAR(states[1].world_from_body.rotation.norm(), 1.0, 1e-15);
  EXPECT_NEAR(states[1].world_from_body.rotation.z(), 1.0, 1e-15);
  EXPECT_NEAR(states[1].world_from_body.rotation.w(), 0.0, 1e-15);
}

TEST(ReadEurocGroundTruth, ErrorsNameFileLineAndExpectation) {
  const fs::path folder = testing::MakeScratchFolder("gt_errors");
  const fs::path csv = folder / "data.csv";
  const std::string good = "#header\n100,1,2,3,1,0,0,0\n";
  struct Case {
    std::string row;
    std::string expected;
  };
  const Case cases[] = {
      {"200,1,2,3,1,0,0\n", "expected 8 comma-separated fields"},
      {"200,1,2,3,1,0,0,0,1\n", "got 9"},
      {"200,1,x2,3,1,0,0,0\n", "column 3, got 'x2'"},
      {"200.5,1,2,3,1,0,0,0\n", "integer timestamp in nanoseconds"},
      {"100,1,2,3,1,0,0,0\n", "timestamps must strictly increase"},
      {"50,1,2,3,1,0,0,0\n", "timestamps must strictly increase"},
      {"200,1,2,3,1.01,0,0,0\n", "unit quaternion"},
      {"200,1,2,3,nan,0,0,0\n", "finite number in column 5"},
  };
  for (const Case& c : cases) {
    WriteTextFile(csv, good + c.row);
    const InputError error = ExpectInputError([&] { ReadEurocGroundTruth(csv); });
    EXPECT_EQ(error.path(), csv.string()) << c.row;
    EXPECT_EQ(error.line(), 3) << c.row;
    EXPECT_THAT(error.what(), HasSubstr(csv.string() + ":3:")) << c.row;
    EXPECT_THAT(error.what(), HasSubstr(c.expected)) << c.row;
  }
  WriteTextFile(csv, "# only a header\n");
  EXPECT_THAT(ExpectInputError([&] { ReadEurocGroundTruth(csv); }).what(), HasSubstr("found none"));
  EXPECT_THAT(ExpectInputError([&] { ReadEurocGroundTruth(folder / "absent.csv"); }).what(),
              HasSubstr("does not exist"));
}

TEST(ReadEurocGroundTruth, RealEurocFile) {
  VIOSFM_REQUIRE_DATASET(root, "euroc_v101_static_micro");
  const std::vector<GroundTruthState> states =
      ReadEurocGroundTruth(root / "mav0/state_groundtruth_estimate0/data.csv");
  ASSERT_EQ(states.size(), 2895u);
  // First row: 1403715273262142976,0.878895,2.1834,0.948427,0.069433,-0.824237,-0.106942,
  // -0.551702,0.00157587,0.00179383,-0.00231615,-0.00224703,0.0215352,0.0770299,
  // -0.0180115,0.0659796,0.0309774
  const GroundTruthState& first = states.front();
  EXPECT_EQ(first.timestamp_ns, 1403715273262142976);
  EXPECT_TRUE(first.has_velocity_and_biases);
  EXPECT_DOUBLE_EQ(first.world_from_body.translation.x(), 0.878895);
  EXPECT_DOUBLE_EQ(first.world_from_body.translation.y(), 2.1834);
  EXPECT_DOUBLE_EQ(first.world_from_body.translation.z(), 0.948427);
  // The file's quaternion has 6 digits, so normalising moves it by < 1e-5.
  EXPECT_NEAR(first.world_from_body.rotation.w(), 0.069433, 1e-5);
  EXPECT_NEAR(first.world_from_body.rotation.x(), -0.824237, 1e-5);
  EXPECT_NEAR(first.world_from_body.rotation.y(), -0.106942, 1e-5);
  EXPECT_NEAR(first.world_from_body.rotation.z(), -0.551702, 1e-5);
  EXPECT_DOUBLE_EQ(first.velocity_in_world.z(), -0.00231615);
  EXPECT_DOUBLE_EQ(first.gyro_bias.y(), 0.0215352);
  EXPECT_DOUBLE_EQ(first.accel_bias.z(), 0.0309774);
  EXPECT_EQ(states.back().timestamp_ns, 1403715417962142976);
}

// ---------------------------------------------------------------- dataset

constexpr char kMicro[] = "euroc_v101_static_micro";

std::vector<std::string> ReadLines(const fs::path& path) {
  std::ifstream stream(path);
  std::vector<std::string> lines;
  for (std::string line; std::getline(stream, line);) lines.push_back(line);
  return lines;
}

void WriteLines(const fs::path& path, const std::vector<std::string>& lines) {
  std::ostringstream text;
  for (const std::string& line : lines) text << line << "\n";
  WriteTextFile(path, text.str());
}

// A copy of a EuRoC folder in a scratch folder (images linked).
fs::path CopyDataset(const fs::path& source, const std::string& name) {
  return testing::CopyFolderLinkingImages(source, testing::MakeScratchFolder(name));
}

// Line numbers below are 1-based, as in error messages.
void ReplaceLine(const fs::path& path, size_t line, const std::string& text) {
  std::vector<std::string> lines = ReadLines(path);
  ASSERT_LE(line, lines.size());
  lines[line - 1] = text;
  WriteLines(path, lines);
}

TEST(ReadEurocDataset, MicroSequence) {
  VIOSFM_REQUIRE_DATASET(root, kMicro);
  const Sequence sequence = ReadEurocDataset(root);
  EXPECT_EQ(sequence.root, root);

  ASSERT_EQ(sequence.images.size(), 95u);
  EXPECT_EQ(sequence.images.front().timestamp_ns, 1403715273262142976);
  EXPECT_EQ(sequence.images.back().timestamp_ns, 1403715277962142976);
  EXPECT_EQ(sequence.images.front().path, root / "mav0/cam0/data/1403715273262142976.png");
  for (const SequenceImage& image : sequence.images) EXPECT_TRUE(fs::exists(image.path));
  EXPECT_DOUBLE_EQ(sequence.rig.camera_rate_hz, 20.0);

  // cam0/sensor.yaml.
  const Camera& camera = sequence.rig.camera;
  EXPECT_EQ(camera.camera_id, 1u);
  EXPECT_EQ(camera.model_id, CameraModelId::kOpenCV);
  EXPECT_EQ(camera.ModelName(), "OPENCV");
  EXPECT_EQ(camera.width, 752u);
  EXPECT_EQ(camera.height, 480u);
  EXPECT_THAT(camera.params, ::testing::ElementsAre(458.654, 457.296, 367.215, 248.375, -0.28340811,
                                                    0.07395907, 0.00019359, 1.76187114e-05));
  Eigen::Matrix<double, 3, 4> body_from_cam;
  body_from_cam << 0.0148655429818, -0.999880929698, 0.00414029679422, -0.0216401454975,
      0.999557249008, 0.0149672133247, 0.025715529948, -0.064676986768, -0.0257744366974,
      0.00375618835797, 0.999660727178, 0.00981073058949;
  // The file's rotation has 12 digits; re-orthonormalising moves it by ~1e-12.
  EXPECT_LT((sequence.rig.body_from_cam.ToMatrix() - body_from_cam).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_EQ(sequence.rig.body_from_cam.translation, body_from_cam.col(3));

  // imu0.
  ASSERT_TRUE(sequence.has_imu());
  ASSERT_EQ(sequence.imu.size(), 29120u);
  EXPECT_EQ(sequence.imu.front().timestamp_ns, 1403715273262142976);
  EXPECT_EQ(sequence.imu.back().timestamp_ns, 1403715418857143040);
  EXPECT_DOUBLE_EQ(sequence.imu.front().gyro.x(), -0.0020943951023931952);
  EXPECT_DOUBLE_EQ(sequence.imu.front().accel.z(), -3.6938381666666662);
  EXPECT_DOUBLE_EQ(sequence.rig.imu_noise.gyro_noise_density, 1.6968e-04);
  EXPECT_DOUBLE_EQ(sequence.rig.imu_noise.gyro_random_walk, 1.9393e-05);
  EXPECT_DOUBLE_EQ(sequence.rig.imu_noise.accel_noise_density, 2.0e-3);
  EXPECT_DOUBLE_EQ(sequence.rig.imu_noise.accel_random_walk, 3.0e-3);
  EXPECT_DOUBLE_EQ(sequence.rig.imu_noise.rate_hz, 200.0);

  // Ground truth.
  ASSERT_TRUE(sequence.has_ground_truth());
  ASSERT_EQ(sequence.ground_truth.size(), 2895u);
  EXPECT_EQ(sequence.ground_truth.front().timestamp_ns, 1403715273262142976);
  EXPECT_DOUBLE_EQ(sequence.ground_truth.front().world_from_body.translation.x(), 0.878895);

  const Trajectory body = GroundTruthBodyTrajectory(sequence);
  const Trajectory cam = GroundTruthCameraTrajectory(sequence);
  ASSERT_EQ(body.size(), 2895u);
  ASSERT_EQ(cam.size(), 2895u);
  EXPECT_EQ(cam.poses[7].timestamp_ns, sequence.ground_truth[7].timestamp_ns);
  // world_from_cam maps the camera origin to world_from_body * (body_from_cam origin).
  const Eigen::Vector3d cam_center =
      sequence.ground_truth[7].world_from_body * sequence.rig.body_from_cam.translation;
  EXPECT_LT((cam.poses[7].world_from_frame.translation - cam_center).norm(), 1e-12);
  EXPECT_LT((body.poses[7].world_from_frame.translation -
             sequence.ground_truth[7].world_from_body.translation)
                .norm(),
            1e-15);
}

TEST(EurocDatasetFiles, ListsTheFilesTheReaderReads) {
  const fs::path root = testing::MakeScratchFolder("euroc_files");
  EXPECT_TRUE(EurocDatasetFiles(root).empty());  // not a EuRoC folder
  for (const char* file : {"mav0/cam0/sensor.yaml", "mav0/cam0/data.csv", "mav0/imu0/data.csv",
                           "mav0/state_groundtruth_estimate0/data.csv", "mav0/leica0/data.csv"}) {
    fs::create_directories((root / file).parent_path());
    WriteTextFile(root / file, "x\n");
  }
  // imu0/sensor.yaml is absent, leica0 is not read.
  EXPECT_THAT(EurocDatasetFiles(root),
              ::testing::ElementsAre(fs::path("mav0/cam0/sensor.yaml"),
                                     fs::path("mav0/cam0/data.csv"), fs::path("mav0/imu0/data.csv"),
                                     fs::path("mav0/state_groundtruth_estimate0/data.csv")));
  EurocReadOptions options;
  options.read_ground_truth = false;
  EXPECT_EQ(EurocDatasetFiles(root, options).size(), 3u);
  // Given mav0/ itself, the paths are relative to it.
  EXPECT_EQ(EurocDatasetFiles(root / "mav0").front(), fs::path("cam0/sensor.yaml"));
}

TEST(ReadEurocDataset, AcceptsTheMav0FolderItself) {
  VIOSFM_REQUIRE_DATASET(root, kMicro);
  EurocReadOptions options;
  options.read_ground_truth = false;
  const Sequence sequence = ReadEurocDataset(root / "mav0", options);
  EXPECT_EQ(sequence.images.size(), 95u);
  EXPECT_EQ(sequence.imu.size(), 29120u);
  EXPECT_FALSE(sequence.has_ground_truth());
}

TEST(ReadEurocDataset, DeletedImage) {
  VIOSFM_REQUIRE_DATASET(source, kMicro);
  const fs::path root = CopyDataset(source, "euroc_deleted_image");
  // Line 11 of data.csv lists the 10th image.
  ASSERT_TRUE(fs::remove(root / "mav0/cam0/data/1403715273712143104.png"));
  const fs::path csv = root / "mav0/cam0/data.csv";
  const InputError error = ExpectInputError([&] { ReadEurocDataset(root); });
  EXPECT_EQ(error.path(), csv.string());
  EXPECT_EQ(error.line(), 11);
  EXPECT_THAT(error.what(), HasSubstr("'1403715273712143104.png' does not exist"));
  // Without the existence check the listing is accepted.
  EurocReadOptions options;
  options.check_images_exist = false;
  EXPECT_EQ(ReadEurocDataset(root, options).images.size(), 95u);
}

TEST(ReadEurocDataset, GarbledImageListRow) {
  VIOSFM_REQUIRE_DATASET(source, kMicro);
  const fs::path root = CopyDataset(source, "euroc_garbled_cam");
  const fs::path csv = root / "mav0/cam0/data.csv";
  ReplaceLine(csv, 5, "1403715273462142976;1403715273462142976.png");
  InputError error = ExpectInputError([&] { ReadEurocDataset(root); });
  EXPECT_EQ(error.path(), csv.string());
  EXPECT_EQ(error.line(), 5);
  EXPECT_THAT(error.what(), HasSubstr(csv.string() + ":5: expected 2 comma-separated fields"));

  ReplaceLine(csv, 5, "14037152734621429x6,1403715273462142976.png");
  error = ExpectInputError([&] { ReadEurocDataset(root); });
  EXPECT_EQ(error.line(), 5);
  EXPECT_THAT(error.what(), HasSubstr("integer timestamp in nanoseconds"));
}

TEST(ReadEurocDataset, NonIncreasingImuStamps) {
  VIOSFM_REQUIRE_DATASET(source, kMicro);
  const fs::path root = CopyDataset(source, "euroc_shuffled_imu");
  const fs::path csv = root / "mav0/imu0/data.csv";
  std::vector<std::string> lines = ReadLines(csv);
  std::swap(lines[99], lines[100]);  // lines 100 and 101
  WriteLines(csv, lines);
  const InputError error = ExpectInputError([&] { ReadEurocDataset(root); });
  EXPECT_EQ(error.path(), csv.string());
  EXPECT_EQ(error.line(), 101);
  EXPECT_THAT(error.what(), HasSubstr("timestamps must strictly increase"));
  EXPECT_THAT(error.what(), HasSubstr("(line 100)"));
}

TEST(ReadEurocDataset, GarbledGroundTruthRow) {
  VIOSFM_REQUIRE_DATASET(source, kMicro);
  const fs::path root = CopyDataset(source, "euroc_garbled_gt");
  const fs::path csv = root / "mav0/state_groundtruth_estimate0/data.csv";
  ReplaceLine(csv, 10, "1403715273712143104,0.878895,2.18?34,0.948427,0.069433,-0.824237");
  EurocReadOptions strict;
  strict.strict_ground_truth = true;
  const InputError error = ExpectInputError([&] { ReadEurocDataset(root, strict); });
  EXPECT_EQ(error.path(), csv.string());
  EXPECT_EQ(error.line(), 10);
  EXPECT_THAT(error.what(), HasSubstr("got 6"));
  ReplaceLine(csv, 10, "1403715273712143104,0.878895,2.18?34,0.948427,0.069433,-0.824237,0,0");
  EXPECT_THAT(ExpectInputError([&] { ReadEurocDataset(root, strict); }).what(),
              HasSubstr(csv.string() + ":10: expected a finite number in column 3, got '2.18?34'"));
  // By default the dataset is read without its (optional) ground truth.
  const Sequence sequence = ReadEurocDataset(root);
  EXPECT_EQ(sequence.images.size(), 95u);
  EXPECT_FALSE(sequence.has_ground_truth());
  // Not read at all when not asked for.
  EurocReadOptions options;
  options.read_ground_truth = false;
  EXPECT_FALSE(ReadEurocDataset(root, options).has_ground_truth());
}

TEST(ReadEurocDataset, UnknownDistortionModel) {
  VIOSFM_REQUIRE_DATASET(source, kMicro);
  const fs::path root = CopyDataset(source, "euroc_unknown_distortion");
  const fs::path yaml = root / "mav0/cam0/sensor.yaml";
  std::vector<std::string> lines = ReadLines(yaml);
  size_t line = 0;
  for (size_t i = 0; i < lines.size(); ++i) {
    if (lines[i].rfind("distortion_model:", 0) == 0) {
      lines[i] = "distortion_model: kannala-brandt";
      line = i + 1;
    }
  }
  ASSERT_GT(line, 0u);
  WriteLines(yaml, lines);
  const InputError error = ExpectInputError([&] { ReadEurocDataset(root); });
  EXPECT_EQ(error.path(), yaml.string());
  EXPECT_EQ(error.line(), static_cast<int64_t>(line));
  EXPECT_THAT(error.what(), HasSubstr("unknown distortion model 'kannala-brandt'"));
  EXPECT_THAT(error.what(), HasSubstr("supported: radial-tangential"));
}

// A minimal synthetic EuRoC folder, for the calibration variants.
fs::path MakeSyntheticEuroc(const std::string& name, const std::string& cam_yaml_tail,
                            timestamp_ns_t imu_first, timestamp_ns_t imu_last) {
  const fs::path root = testing::MakeScratchFolder(name);
  fs::create_directories(root / "mav0/cam0/data");
  fs::create_directories(root / "mav0/imu0");
  WriteTextFile(root / "mav0/cam0/data.csv", "#timestamp [ns],filename\n1000,a.png\n2000,b.png\n");
  WriteTextFile(root / "mav0/cam0/data/a.png", "x");
  WriteTextFile(root / "mav0/cam0/data/b.png", "x");
  WriteTextFile(root / "mav0/cam0/sensor.yaml",
                "%YAML:1.0\n"
                "T_BS:\n  cols: 4\n  rows: 4\n"
                "  data: [1, 0, 0, 0.1, 0, 1, 0, 0.2, 0, 0, 1, 0.3, 0, 0, 0, 1]\n"
                "rate_hz: 10\nresolution: [640, 480]\ncamera_model: pinhole\n"
                "intrinsics: [500, 501, 320, 240]\n" +
                    cam_yaml_tail);
  WriteTextFile(root / "mav0/imu0/sensor.yaml",
                "%YAML:1.0\nrate_hz: 1000\ngyroscope_noise_density: 1e-4\n"
                "gyroscope_random_walk: 2e-5\naccelerometer_noise_density: 3e-3\n"
                "accelerometer_random_walk: 4e-3\n");
  std::ostringstream imu;
  imu << "#timestamp [ns],w_x,w_y,w_z,a_x,a_y,a_z\n";
  for (timestamp_ns_t t = imu_first; t <= imu_last; t += 100) imu << t << ",0,0,0,0,0,9.81\n";
  WriteTextFile(root / "mav0/imu0/data.csv", imu.str());
  return root;
}

TEST(ReadEurocDataset, DistortionModels) {
  {
    const fs::path root = MakeSyntheticEuroc(
        "euroc_equidistant",
        "distortion_model: equidistant\ndistortion_coefficients: [0.1, 0.2, 0.3, 0.4]\n", 1000,
        2000);
    const Sequence sequence = ReadEurocDataset(root);
    EXPECT_EQ(sequence.rig.camera.model_id, CameraModelId::kOpenCVFisheye);
    EXPECT_THAT(sequence.rig.camera.params,
                ::testing::ElementsAre(500, 501, 320, 240, 0.1, 0.2, 0.3, 0.4));
    EXPECT_EQ(sequence.rig.body_from_cam.translation, Eigen::Vector3d(0.1, 0.2, 0.3));
    EXPECT_DOUBLE_EQ(sequence.rig.camera_rate_hz, 10.0);
    EXPECT_EQ(sequence.imu.size(), 11u);
    EXPECT_DOUBLE_EQ(sequence.rig.imu_noise.rate_hz, 1000.0);
    EXPECT_DOUBLE_EQ(sequence.rig.imu_noise.accel_random_walk, 4e-3);
    EXPECT_FALSE(sequence.has_ground_truth());
  }
  {
    const fs::path root = MakeSyntheticEuroc("euroc_none", "", 1000, 2000);
    const Sequence sequence = ReadEurocDataset(root);
    EXPECT_EQ(sequence.rig.camera.model_id, CameraModelId::kPinhole);
    EXPECT_THAT(sequence.rig.camera.params, ::testing::ElementsAre(500, 501, 320, 240));
  }
  {
    const fs::path root = MakeSyntheticEuroc(
        "euroc_three_coefficients",
        "distortion_model: radial-tangential\ndistortion_coefficients: [0.1, 0.2, 0.3]\n", 1000,
        2000);
    const fs::path yaml = root / "mav0/cam0/sensor.yaml";
    const InputError error = ExpectInputError([&] { ReadEurocDataset(root); });
    EXPECT_EQ(error.path(), yaml.string());
    EXPECT_EQ(error.line(), 11);
    EXPECT_THAT(error.what(), HasSubstr("expects 4 coefficients (k1, k2, p1, p2), got 3"));
  }
  {
    const fs::path root = MakeSyntheticEuroc("euroc_omni", "", 1000, 2000);
    const fs::path yaml = root / "mav0/cam0/sensor.yaml";
    std::vector<std::string> lines = ReadLines(yaml);
    ASSERT_EQ(lines[7], "camera_model: pinhole");
    lines[7] = "camera_model: omni";
    WriteLines(yaml, lines);
    const InputError error = ExpectInputError([&] { ReadEurocDataset(root); });
    EXPECT_EQ(error.line(), 8);
    EXPECT_THAT(error.what(), HasSubstr("unknown camera model 'omni'; supported: pinhole"));
  }
}

TEST(ReadEurocDataset, ImuCoverage) {
  // IMU from 1500 ns: the first image (1000 ns) is not covered.
  const fs::path root = MakeSyntheticEuroc("euroc_partial_imu", "", 1500, 2500);
  EXPECT_EQ(ReadEurocDataset(root).imu.size(), 11u);  // a warning only
  EurocReadOptions options;
  options.require_imu_coverage = true;
  InputError error = ExpectInputError([&] { ReadEurocDataset(root, options); });
  EXPECT_EQ(error.path(), (root / "mav0/imu0/data.csv").string());
  EXPECT_THAT(error.what(), HasSubstr("does not cover the whole image time span"));

  // No overlap at all is always an error.
  const fs::path disjoint = MakeSyntheticEuroc("euroc_disjoint_imu", "", 3000, 4000);
  error = ExpectInputError([&] { ReadEurocDataset(disjoint); });
  EXPECT_THAT(error.what(), HasSubstr("found none: images span [1000, 2000] ns"));
}

TEST(ReadEurocDataset, MissingPiecesAndEmptyList) {
  const fs::path root = MakeSyntheticEuroc("euroc_missing", "", 1000, 2000);
  EXPECT_THAT(ExpectInputError([&] { ReadEurocDataset(root / "nowhere"); }).what(),
              HasSubstr("does not exist"));
  EXPECT_THAT(ExpectInputError([&] { ReadEurocDataset(root / "mav0/cam0"); }).what(),
              HasSubstr("expected a EuRoC ASL folder"));

  fs::remove_all(root / "mav0/imu0");
  EXPECT_THAT(ExpectInputError([&] { ReadEurocDataset(root); }).what(),
              HasSubstr("IMU folder does not exist"));
  EurocReadOptions options;
  options.require_imu = false;
  EXPECT_FALSE(ReadEurocDataset(root, options).has_imu());

  WriteTextFile(root / "mav0/cam0/data.csv", "#timestamp [ns],filename\n\n");
  const InputError error = ExpectInputError([&] { ReadEurocDataset(root, options); });
  EXPECT_EQ(error.path(), (root / "mav0/cam0/data.csv").string());
  EXPECT_THAT(error.what(), HasSubstr("expected image rows, found none"));

  fs::remove(root / "mav0/cam0/sensor.yaml");
  EXPECT_THAT(ExpectInputError([&] { ReadEurocDataset(root, options); }).what(),
              HasSubstr("sensor.yaml: file does not exist"));
}

// A data.csv of a dataset cannot make the reader open files outside its
// image folder.
TEST(ReadEurocImageList, RejectsNamesOutsideTheImageFolder) {
  const fs::path folder = testing::MakeScratchFolder("euroc_escape");
  fs::create_directories(folder / "cam0/data/sub");
  WriteTextFile(folder / "cam0/data/sub/c.png", "x");
  WriteTextFile(folder / "cam0/secret.png", "x");
  const fs::path csv = folder / "cam0/data.csv";
  for (const std::string& name :
       {std::string("../secret.png"), std::string("sub/../../secret.png"),
        (folder / "cam0/secret.png").string(), std::string("/etc/passwd"), std::string("sub/..")}) {
    WriteTextFile(csv, "#timestamp [ns],filename\n1000,sub/c.png\n2000," + name + "\n");
    for (const bool check_exist : {true, false}) {
      const InputError error =
          ExpectInputError([&] { ReadEurocImageList(csv, folder / "cam0/data", check_exist); });
      EXPECT_EQ(error.path(), csv.string()) << name;
      EXPECT_EQ(error.line(), 3) << name;
      EXPECT_THAT(error.what(), HasSubstr("'" + name + "' must be a relative path inside")) << name;
    }
  }
  // A name with a NUL would be cut short when the file is opened.
  WriteTextFile(csv, std::string("1000,sub/c.png\0../../x\n", 23));
  EXPECT_EQ(ExpectInputError([&] { ReadEurocImageList(csv, folder / "cam0/data", false); }).line(),
            1);
  // Sub-folders (and names merely containing dots) are fine.
  WriteTextFile(csv, "1000,sub/c.png\n2000,sub/..c.png\n");
  const std::vector<SequenceImage> images = ReadEurocImageList(csv, folder / "cam0/data", false);
  ASSERT_EQ(images.size(), 2u);
  EXPECT_EQ(images[0].path, folder / "cam0/data/sub/c.png");
}

// Stamps must lie within +-2^62 ns, so that no difference of two overflows
// (the frame-rate estimate of two stamps 2^63 ns apart was undefined
// behaviour).
TEST(ReadEurocImageList, StampsOutOfRangeAndFarApart) {
  const fs::path folder = testing::MakeScratchFolder("euroc_stamp_range");
  const fs::path csv = folder / "data.csv";
  WriteTextFile(csv, "1000,a.png\n9223372036854775807,b.png\n");
  const InputError error = ExpectInputError([&] { ReadEurocImageList(csv, folder, false); });
  EXPECT_EQ(error.line(), 2);
  EXPECT_THAT(error.what(), HasSubstr("timestamp '9223372036854775807' is out of range"));
  WriteTextFile(csv, "-4611686018427387904,a.png\n4611686018427387904,b.png\n");
  const std::vector<SequenceImage> images = ReadEurocImageList(csv, folder, false);
  ASSERT_EQ(images.size(), 2u);
  // 2^63 ns apart: one frame in 292 years (computed without overflow).
  EXPECT_NEAR(EstimateFrameRateHz(images), 1e9 / 9223372036854775807.0, 1e-22);
  EXPECT_EQ(EstimateFrameRateHz({{INT64_MIN, ""}, {INT64_MAX, ""}}), 1e9 / 9223372036854775807.0);
}

// The ground truth of a dataset only serves evaluation: a malformed one is a
// warning (the run goes on without evaluation), unless asked to be strict.
TEST(ReadEurocDataset, MalformedOptionalGroundTruthIsSkipped) {
  const fs::path root = MakeSyntheticEuroc("euroc_bad_gt", "", 1000, 2000);
  const fs::path csv = root / "mav0/state_groundtruth_estimate0/data.csv";
  fs::create_directories(csv.parent_path());
  WriteTextFile(csv, "#t,x,y,z,qw,qx,qy,qz\n1000,0,0,0,1,0,0,0\n1500,0,0,0,2,0,0,0\n");
  const Sequence sequence = ReadEurocDataset(root);
  EXPECT_EQ(sequence.images.size(), 2u);
  EXPECT_EQ(sequence.imu.size(), 11u);
  EXPECT_FALSE(sequence.has_ground_truth());

  const GroundTruthReadResult result = TryReadEurocGroundTruth(csv);
  EXPECT_FALSE(result.ok());
  EXPECT_TRUE(result.states.empty());
  EXPECT_THAT(result.error, HasSubstr(csv.string() + ":3: expected a unit quaternion"));

  EurocReadOptions strict;
  strict.strict_ground_truth = true;
  const InputError error = ExpectInputError([&] { ReadEurocDataset(root, strict); });
  EXPECT_EQ(error.path(), csv.string());
  EXPECT_EQ(error.line(), 3);

  // A good file is read either way.
  WriteTextFile(csv, "#t,x,y,z,qw,qx,qy,qz\n1000,0,0,0,1,0,0,0\n1500,0,0,1,1,0,0,0\n");
  EXPECT_EQ(ReadEurocDataset(root).ground_truth.size(), 2u);
  EXPECT_EQ(ReadEurocDataset(root, strict).ground_truth.size(), 2u);
  EXPECT_TRUE(TryReadEurocGroundTruth(csv).ok());
}

// T_BS must be a proper rotation: a mirrored frame is rejected.
TEST(ReadEurocDataset, MirroredExtrinsicsAreRejected) {
  const fs::path root = MakeSyntheticEuroc("euroc_mirror", "", 1000, 2000);
  const fs::path yaml = root / "mav0/cam0/sensor.yaml";
  WriteTextFile(yaml,
                "%YAML:1.0\n"
                "T_BS:\n  cols: 4\n  rows: 4\n"
                "  data: [1, 0, 0, 0.1, 0, 1, 0, 0.2, 0, 0, -1, 0.3, 0, 0, 0, 1]\n"
                "resolution: [640, 480]\nintrinsics: [500, 501, 320, 240]\n");
  const InputError error = ExpectInputError([&] { ReadEurocDataset(root); });
  EXPECT_EQ(error.path(), yaml.string());
  EXPECT_EQ(error.line(), 3);
  EXPECT_THAT(error.what(), HasSubstr("determinant is -1 (a reflection"));
}

}  // namespace
}  // namespace viosfm

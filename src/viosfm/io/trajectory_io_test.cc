#include "viosfm/io/trajectory_io.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

#include "viosfm/io/euroc.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;
using testing::ExpectInputError;
using ::testing::HasSubstr;
using testing::InputErrorMessage;
using testing::WriteTextFile;

// Random poses with awkward doubles and stamps with all 9 decimals.
Trajectory RandomTrajectory(size_t count, uint32_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uniform(-1000.0, 1000.0);
  Trajectory trajectory;
  timestamp_ns_t stamp = 1403715273262142976;
  for (size_t i = 0; i < count; ++i) {
    stamp += 1 + static_cast<timestamp_ns_t>(rng() % 100'000'000);
    const Eigen::Quaterniond q =
        Eigen::Quaterniond(uniform(rng), uniform(rng), uniform(rng), uniform(rng)).normalized();
    trajectory.poses.push_back(
        {stamp, Rigid3d(q, Eigen::Vector3d(uniform(rng), uniform(rng), uniform(rng)) / 7.0)});
  }
  return trajectory;
}

void ExpectSamePoses(const Trajectory& a, const Trajectory& b, double rotation_tolerance,
                     double translation_tolerance, bool same_stamps) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    if (same_stamps) {
      EXPECT_EQ(a.poses[i].timestamp_ns, b.poses[i].timestamp_ns) << i;
    }
    const Rigid3d& pa = a.poses[i].world_from_frame;
    const Rigid3d& pb = b.poses[i].world_from_frame;
    if (translation_tolerance == 0.0) {
      EXPECT_EQ(pa.translation, pb.translation) << i;
    } else {
      EXPECT_LE((pa.translation - pb.translation).norm(), translation_tolerance) << i;
    }
    if (rotation_tolerance == 0.0) {
      EXPECT_EQ(pa.rotation.coeffs(), pb.rotation.coeffs()) << i;
    } else {
      EXPECT_LE(pa.rotation.angularDistance(pb.rotation), rotation_tolerance) << i;
    }
  }
}

TEST(TumTrajectory, WriteReadIsLosslessAndStable) {
  const fs::path folder = testing::MakeScratchFolder("tum_roundtrip");
  const Trajectory original = RandomTrajectory(200, 1);
  WriteTumTrajectory(folder / "a.txt", original);
  const Trajectory read = ReadTumTrajectory(folder / "a.txt");
  EXPECT_TRUE(read.has_timestamps);
  ExpectSamePoses(original, read, 0.0, 0.0, /*same_stamps=*/true);
  // A second write of what was read gives the same bytes.
  WriteTumTrajectory(folder / "b.txt", read);
  EXPECT_EQ(ReadTextFile(folder / "a.txt"), ReadTextFile(folder / "b.txt"));
}

TEST(TumTrajectory, ParsesCommentsBlankLinesAndStampsDigitExactly) {
  const fs::path folder = testing::MakeScratchFolder("tum_parse");
  WriteTextFile(folder / "t.txt",
                "# ground truth trajectory\n"
                "\n"
                "1311868164.363181 1 2 3 0 0 0 1\n"
                "  1311868164.3632\t-1e-3 2.5 3 0 0 0.7071067811865476 0.7071067811865476  \n"
                "1311868164.4 0 0 0 0 0 0 1.0008\n");
  const Trajectory trajectory = ReadTumTrajectory(folder / "t.txt");
  ASSERT_EQ(trajectory.size(), 3u);
  EXPECT_EQ(trajectory.poses[0].timestamp_ns, 1311868164363181000);
  EXPECT_EQ(trajectory.poses[1].timestamp_ns, 1311868164363200000);
  EXPECT_EQ(trajectory.poses[1].world_from_frame.translation, Eigen::Vector3d(-1e-3, 2.5, 3));
  EXPECT_NEAR(trajectory.poses[1].world_from_frame.rotation.z(), std::sqrt(0.5), 1e-16);
  // qx qy qz qw order: (0, 0, 0, 1.0008) is the identity after normalisation.
  EXPECT_EQ(trajectory.poses[2].world_from_frame.rotation.w(), 1.0);
  EXPECT_EQ(GuessTrajectoryFormat(folder / "t.txt"), TrajectoryFormat::kTum);
}

TEST(TumTrajectory, RepeatedStampIsKeptDecreasingIsAnError) {
  const fs::path folder = testing::MakeScratchFolder("tum_stamps");
  WriteTextFile(folder / "repeat.txt", "1.5 0 0 0 0 0 0 1\n1.5 1 0 0 0 0 0 1\n2 0 0 0 0 0 0 1\n");
  EXPECT_EQ(ReadTumTrajectory(folder / "repeat.txt").size(), 3u);
  WriteTextFile(folder / "decrease.txt", "1.5 0 0 0 0 0 0 1\n1.4 0 0 0 0 0 0 1\n");
  const std::string message =
      InputErrorMessage([&] { ReadTumTrajectory(folder / "decrease.txt"); });
  EXPECT_THAT(message, HasSubstr("decrease.txt:2"));
  EXPECT_THAT(message, HasSubstr("not smaller than the previous one (1.500000000 s)"));
}

TEST(TumTrajectory, ErrorsNameFileLineAndExpectation) {
  const fs::path folder = testing::MakeScratchFolder("tum_errors");
  WriteTextFile(folder / "columns.txt", "# c\n1 0 0 0 0 0 0 1\n2 0 0 0 0 0 1\n");
  std::string message = InputErrorMessage([&] { ReadTumTrajectory(folder / "columns.txt"); });
  EXPECT_THAT(message, HasSubstr("columns.txt:3"));
  EXPECT_THAT(message, HasSubstr("expected 8 columns"));
  EXPECT_THAT(message, HasSubstr("got 7"));

  WriteTextFile(folder / "number.txt", "1 0 0 zero 0 0 0 1\n");
  message = InputErrorMessage([&] { ReadTumTrajectory(folder / "number.txt"); });
  EXPECT_THAT(message, HasSubstr("number.txt:1"));
  EXPECT_THAT(message, HasSubstr("column 4 (tz): expected a finite number, got 'zero'"));

  WriteTextFile(folder / "stamp.txt", "1.2.3 0 0 0 0 0 0 1\n");
  message = InputErrorMessage([&] { ReadTumTrajectory(folder / "stamp.txt"); });
  EXPECT_THAT(message, HasSubstr("stamp.txt:1"));
  EXPECT_THAT(message, HasSubstr("column 1 (timestamp): expected decimal seconds"));

  WriteTextFile(folder / "quat.txt", "1 0 0 0 0 0 0 0\n");
  message = InputErrorMessage([&] { ReadTumTrajectory(folder / "quat.txt"); });
  EXPECT_THAT(message, HasSubstr("quat.txt:1"));
  EXPECT_THAT(message, HasSubstr("expected a unit quaternion (qx qy qz qw in columns 5-8): its "
                                 "norm is 0"));

  // The same tolerance as every reader (EuRoC, COLMAP, KITTI): 1e-3 on the
  // norm. A TUM file printed with 4 decimals passes; a scaled quaternion
  // does not (it used to be normalised silently).
  WriteTextFile(folder / "scaled.txt", "1 0 0 0 0 0 0 1\n2 0 0 0 0.6 0 0 0.8\n3 0 0 0 0 0 0 2\n");
  const InputError error =
      testing::ExpectInputError([&] { ReadTumTrajectory(folder / "scaled.txt"); });
  EXPECT_EQ(error.line(), 3);
  EXPECT_THAT(error.what(), HasSubstr("its norm is 2"));
  WriteTextFile(folder / "rounded.txt",
                "1 0 0 0 0.6132 0.5962 -0.3311 -0.3986\n2 0 0 0 0 0 0 1.0009\n");
  const Trajectory rounded = ReadTumTrajectory(folder / "rounded.txt");
  ASSERT_EQ(rounded.size(), 2u);
  EXPECT_NEAR(rounded.poses[0].world_from_frame.rotation.norm(), 1.0, 1e-15);
  EXPECT_EQ(rounded.poses[1].world_from_frame.rotation.w(), 1.0);
  WriteTextFile(folder / "off.txt", "1 0 0 0 0 0 0 1.0011\n");
  EXPECT_THAT(InputErrorMessage([&] { ReadTumTrajectory(folder / "off.txt"); }),
              HasSubstr("off.txt:1: expected a unit quaternion"));

  WriteTextFile(folder / "empty.txt", "# nothing\n");
  message = InputErrorMessage([&] { ReadTumTrajectory(folder / "empty.txt"); });
  EXPECT_THAT(message, HasSubstr("empty.txt"));
  EXPECT_THAT(message, HasSubstr("at least one pose"));

  message = InputErrorMessage([&] { ReadTumTrajectory(folder / "missing.txt"); });
  EXPECT_THAT(message, HasSubstr("missing.txt"));
}

TEST(KittiTrajectory, RoundTripAndIndexStamps) {
  const fs::path folder = testing::MakeScratchFolder("kitti_roundtrip");
  const Trajectory original = RandomTrajectory(100, 2);
  WriteKittiTrajectory(folder / "k.txt", original);
  const Trajectory read = ReadKittiTrajectory(folder / "k.txt");
  EXPECT_FALSE(read.has_timestamps);
  for (size_t i = 0; i < read.size(); ++i) {
    EXPECT_EQ(read.poses[i].timestamp_ns, static_cast<timestamp_ns_t>(i));
  }
  // The matrix form re-orthonormalises the rotation: equal to rounding.
  ExpectSamePoses(original, read, 1e-14, 0.0, /*same_stamps=*/false);
  EXPECT_EQ(GuessTrajectoryFormat(folder / "k.txt"), TrajectoryFormat::kKitti);
}

TEST(KittiTrajectory, ErrorsNameFileLineAndExpectation) {
  const fs::path folder = testing::MakeScratchFolder("kitti_errors");
  WriteTextFile(folder / "short.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1\n");
  std::string message = InputErrorMessage([&] { ReadKittiTrajectory(folder / "short.txt"); });
  EXPECT_THAT(message, HasSubstr("short.txt:2"));
  EXPECT_THAT(message, HasSubstr("expected 12 numbers"));
  WriteTextFile(folder / "nan.txt", "1 0 0 0 0 1 0 0 0 0 1 x\n");
  message = InputErrorMessage([&] { ReadKittiTrajectory(folder / "nan.txt"); });
  EXPECT_THAT(message, HasSubstr("nan.txt:1"));
  EXPECT_THAT(message, HasSubstr("column 12"));
  WriteTextFile(folder / "zero.txt", "0 0 0 0 0 0 0 0 0 0 0 0\n");
  message = InputErrorMessage([&] { ReadKittiTrajectory(folder / "zero.txt"); });
  EXPECT_THAT(message, HasSubstr("zero.txt:1"));
  EXPECT_THAT(message, HasSubstr("expected a rotation"));

  // A mirrored frame (determinant -1) is not a pose; it used to be turned
  // into some rotation silently.
  WriteTextFile(folder / "mirror.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 -1 0\n");
  message = InputErrorMessage([&] { ReadKittiTrajectory(folder / "mirror.txt"); });
  EXPECT_THAT(message, HasSubstr("mirror.txt:2: expected a rotation matrix in the left 3x3 block: "
                                 "its determinant is -1 (a reflection"));
  // Scaled or sheared blocks are not rotations either.
  WriteTextFile(folder / "scaled.txt", "2 0 0 0 0 2 0 0 0 0 2 0\n");
  message = InputErrorMessage([&] { ReadKittiTrajectory(folder / "scaled.txt"); });
  EXPECT_THAT(message, HasSubstr("scaled.txt:1"));
  EXPECT_THAT(message, HasSubstr("not orthonormal: R^T R differs from the identity by up to 3"));
  WriteTextFile(folder / "shear.txt", "1 0.01 0 0 0 1 0 0 0 0 1 0\n");
  EXPECT_THAT(InputErrorMessage([&] { ReadKittiTrajectory(folder / "shear.txt"); }),
              HasSubstr("not orthonormal"));
  // Rounding to 6 digits (as KITTI files are written) is within tolerance.
  const double c = std::cos(0.3);
  const double s = std::sin(0.3);
  std::ostringstream text;
  text.precision(6);
  text << c << " " << -s << " 0 1 " << s << " " << c << " 0 2 0 0 1 3\n";
  WriteTextFile(folder / "rounded.txt", text.str());
  const Trajectory rounded = ReadKittiTrajectory(folder / "rounded.txt");
  ASSERT_EQ(rounded.size(), 1u);
  EXPECT_NEAR(rounded.poses[0].world_from_frame.rotation.angularDistance(
                  Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()))),
              0.0, 1e-5);
}

TEST(EurocTrajectory, RoundTripAndFullStateFile) {
  const fs::path folder = testing::MakeScratchFolder("euroc_roundtrip");
  const Trajectory original = RandomTrajectory(100, 3);
  WriteEurocTrajectory(folder / "e.csv", original);
  const Trajectory read = ReadEurocTrajectory(folder / "e.csv");
  EXPECT_TRUE(read.has_timestamps);
  ExpectSamePoses(original, read, 1e-15, 0.0, /*same_stamps=*/true);
  EXPECT_EQ(GuessTrajectoryFormat(folder / "e.csv"), TrajectoryFormat::kEuroc);

  WriteTextFile(folder / "full.csv",
                "#timestamp [ns],p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m],q_RS_w [],q_RS_x [],"
                "q_RS_y [],q_RS_z [],v_RS_R_x [m s^-1],v_RS_R_y,v_RS_R_z,b_w_RS_S_x,b_w_RS_S_y,"
                "b_w_RS_S_z,b_a_RS_S_x,b_a_RS_S_y,b_a_RS_S_z\n"
                "1403715273262142976,0.878612,2.142470,0.947262,0.060514,-0.828459,-0.058956,"
                "-0.553641,0.009474,-0.014009,-0.002145,-0.002229,0.020700,0.076350,-0.012492,"
                "0.547666,0.069073\n");
  const Trajectory full = ReadEurocTrajectory(folder / "full.csv");
  ASSERT_EQ(full.size(), 1u);
  EXPECT_EQ(full.poses[0].timestamp_ns, 1403715273262142976);
  EXPECT_EQ(full.poses[0].world_from_frame.translation,
            Eigen::Vector3d(0.878612, 2.14247, 0.947262));
  EXPECT_NEAR(full.poses[0].world_from_frame.rotation.w(), 0.060514, 1e-6);
  EXPECT_NEAR(full.poses[0].world_from_frame.rotation.x(), -0.828459, 1e-6);
}

TEST(EurocTrajectory, ErrorNamesFileAndLine) {
  const fs::path folder = testing::MakeScratchFolder("euroc_errors");
  WriteTextFile(folder / "bad.csv", "#t\n100,0,0,0,1,0,0,0\n200,0,0,0,1,0,0\n");
  const std::string message = InputErrorMessage([&] { ReadEurocTrajectory(folder / "bad.csv"); });
  EXPECT_THAT(message, HasSubstr("bad.csv:3"));
}

// Found by fuzz/fuzz_euroc_trajectory: the EuRoC reader normalised every
// quaternion, so read -> write -> read changed the last bits of one that
// was already unit; it now keeps those bit for bit, as the TUM reader does.
TEST(EurocTrajectory, WriteReadKeepsQuaternionsBitForBit) {
  const fs::path folder = testing::MakeScratchFolder("euroc_bits");
  WriteTextFile(folder / "in.csv", "200, 4, 5, 6, 0, 0, 1, 0.0047\n300,1,2,3,0.5,0.5,0.5,0.5\n");
  const Trajectory first = ReadEurocTrajectory(folder / "in.csv");
  WriteEurocTrajectory(folder / "out.csv", first);
  const Trajectory second = ReadEurocTrajectory(folder / "out.csv");
  ASSERT_EQ(second.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    for (int k = 0; k < 4; ++k) {
      EXPECT_EQ(first.poses[i].world_from_frame.rotation.coeffs()[k],
                second.poses[i].world_from_frame.rotation.coeffs()[k])
          << i << " " << k;
    }
  }
}

// Stamps beyond +-2^62 ns would overflow when two of them are subtracted.
TEST(TumTrajectory, StampsBeyondTheRangeAreRejected) {
  const fs::path folder = testing::MakeScratchFolder("tum_range");
  WriteTextFile(folder / "far.txt", "1 0 0 0 0 0 0 1\n9223372036 0 0 0 0 0 0 1\n");
  EXPECT_THAT(InputErrorMessage([&] { ReadTumTrajectory(folder / "far.txt"); }),
              HasSubstr("far.txt:2: column 1 (timestamp): expected decimal seconds within"));
  WriteTextFile(folder / "near.txt",
                "-4611686018.427387904 0 0 0 0 0 0 1\n4611686018 0 0 0 0 0 0 1\n");
  EXPECT_EQ(ReadTumTrajectory(folder / "near.txt").poses[0].timestamp_ns, -kMaxAbsTimestampNs);
}

TEST(TrajectoryFormat, NamesParseAndGuessFailures) {
  EXPECT_EQ(ParseTrajectoryFormat("TUM"), TrajectoryFormat::kTum);
  EXPECT_EQ(ParseTrajectoryFormat("euroc"), TrajectoryFormat::kEuroc);
  EXPECT_EQ(ParseTrajectoryFormat("kitti"), TrajectoryFormat::kKitti);
  EXPECT_EQ(TrajectoryFormatName(TrajectoryFormat::kEuroc), "euroc");
  EXPECT_THAT(InputErrorMessage([] { ParseTrajectoryFormat("bag"); }),
              HasSubstr("expected tum, euroc, kitti or colmap"));
  const fs::path folder = testing::MakeScratchFolder("guess");
  WriteTextFile(folder / "five.txt", "# x\n1 2 3 4 5\n");
  const std::string message =
      InputErrorMessage([&] { GuessTrajectoryFormat(folder / "five.txt"); });
  EXPECT_THAT(message, HasSubstr("five.txt:2"));
  EXPECT_THAT(message, HasSubstr("cannot guess"));
}

TEST(TrajectoryWriters, RoundTripAcrossFormats) {
  const fs::path folder = testing::MakeScratchFolder("across");
  const Trajectory original = RandomTrajectory(20, 4);
  for (TrajectoryFormat format :
       {TrajectoryFormat::kTum, TrajectoryFormat::kEuroc, TrajectoryFormat::kKitti}) {
    const fs::path path = folder / ("t." + TrajectoryFormatName(format));
    WriteTrajectory(path, original, format);
    EXPECT_EQ(GuessTrajectoryFormat(path), format);
    ExpectSamePoses(original, ReadTrajectory(path, format), 1e-14, 0.0,
                    format != TrajectoryFormat::kKitti);
  }
}

TEST(ParsePoseTxyzQxyzw, ParsesAndRejects) {
  const Rigid3d pose = ParsePoseTxyzQxyzw("1 2 3 0 0 0 1.0005", "--body-from-cam");
  EXPECT_EQ(pose.translation, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(pose.rotation.w(), 1.0);
  EXPECT_THAT(InputErrorMessage([] { ParsePoseTxyzQxyzw("1 2 3 0 0 0 2", "--body-from-cam"); }),
              HasSubstr("--body-from-cam: expected a unit quaternion qx qy qz qw: its norm is 2"));
  EXPECT_THAT(InputErrorMessage([] { ParsePoseTxyzQxyzw("1 2 3", "--body-from-cam"); }),
              HasSubstr("--body-from-cam: expected 7 numbers"));
  EXPECT_THAT(InputErrorMessage([] { ParsePoseTxyzQxyzw("1 2 3 0 0 a 1", "--x"); }),
              HasSubstr("got 'a'"));
}

TEST(SensorYaml, ReadsTbsOfEurocCamera) {
  const fs::path folder = testing::MakeScratchFolder("sensor_yaml");
  WriteTextFile(folder / "sensor.yaml",
                "%YAML:1.0\n"
                "sensor_type: camera\n"
                "T_BS:\n"
                "  cols: 4\n"
                "  rows: 4\n"
                "  data: [0.0148655429818, -0.999880929698, 0.00414029679422, -0.0216401454975,\n"
                "         0.999557249008, 0.0149672133247, 0.025715529948, -0.064676986768,\n"
                "        -0.0257744366974, 0.00375618835797, 0.999660727178, 0.00981073058949,\n"
                "         0.0, 0.0, 0.0, 1.0]\n");
  const Rigid3d body_from_cam = ReadEurocSensorTransform(folder / "sensor.yaml");
  EXPECT_NEAR((body_from_cam.translation -
               Eigen::Vector3d(-0.0216401454975, -0.064676986768, 0.00981073058949))
                  .norm(),
              0.0, 1e-15);
  EXPECT_NEAR(body_from_cam.rotation.toRotationMatrix()(0, 1), -0.999880929698, 1e-9);
  WriteTextFile(folder / "no_tbs.yaml", "%YAML:1.0\nrate_hz: 20\n");
  EXPECT_THAT(InputErrorMessage([&] { ReadEurocSensorTransform(folder / "no_tbs.yaml"); }),
              HasSubstr("T_BS"));
}

TEST(TrajectoryReaders, ReadTheRealTrajEvalFiles) {
  VIOSFM_REQUIRE_DATASET(data, "traj_eval");
  const Trajectory gt = ReadTumTrajectory(data / "fr2_desk_groundtruth.txt");
  EXPECT_EQ(gt.size(), 20957u);
  EXPECT_EQ(gt.poses.front().timestamp_ns, 1311868163869700000);  // "1311868163.8697"
  const Trajectory kitti = ReadKittiTrajectory(data / "KITTI_00_gt.txt");
  EXPECT_EQ(kitti.size(), 4541u);
  EXPECT_EQ(GuessTrajectoryFormat(data / "KITTI_00_ORB.txt"), TrajectoryFormat::kKitti);
  EXPECT_EQ(GuessTrajectoryFormat(data / "fr2_desk_ORB.txt"), TrajectoryFormat::kTum);
}

TEST(ColmapTrajectory, RegisteredImagesSortedByNameStamp) {
  const fs::path folder = testing::MakeScratchFolder("colmap_trajectory");
  WriteTextFile(folder / "cameras.txt", "1 PINHOLE 640 480 500 500 320 240\n");
  // cam_from_world of image 1: rotation 90 deg about z, t = (1, 2, 3).
  WriteTextFile(
      folder / "images.txt",
      "1 0.70710678118654757 0 0 0.70710678118654757 1 2 3 1 cam0/1403715273312142976.png\n"
      "\n"
      "2 1 0 0 0 0 0 0 1 cam0/1403715273262142976.png\n"
      "\n"
      "3 1 0 0 0 5 5 5 1 cam1/1403715273262142976.png\n"
      "\n");
  WriteTextFile(folder / "points3D.txt", "");
  EXPECT_EQ(GuessTrajectoryFormat(folder), TrajectoryFormat::kColmap);
  const Trajectory trajectory = ReadColmapTrajectory(folder, "cam0/");
  ASSERT_EQ(trajectory.size(), 2u);
  EXPECT_TRUE(trajectory.has_timestamps);
  EXPECT_EQ(trajectory.poses[0].timestamp_ns, 1403715273262142976);
  EXPECT_EQ(trajectory.poses[1].timestamp_ns, 1403715273312142976);
  // world_from_cam = cam_from_world^-1: the centre is -R^T t.
  const Eigen::Vector3d centre = trajectory.poses[1].world_from_frame.translation;
  EXPECT_NEAR((centre - Eigen::Vector3d(-2.0, 1.0, -3.0)).norm(), 0.0, 1e-12);
  // Both cameras together have two images with the same stamp.
  EXPECT_THAT(InputErrorMessage([&] { ReadColmapTrajectory(folder); }),
              HasSubstr("same timestamp"));
  EXPECT_THAT(InputErrorMessage([&] { ReadColmapTrajectory(folder, "cam9/"); }),
              HasSubstr("found none"));
}

}  // namespace
}  // namespace viosfm

#include "viosfm/eval/traj_eval.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>

#include "viosfm/eval/report.h"
#include "viosfm/io/trajectory_io.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;

// The evo / evaluate_ate.py numbers of ../shared/data/README.md (traj_eval).
struct ReferenceCase {
  const char* name;
  const char* est_file;
  const char* ref_file;
  TrajectoryFormat format;
  AlignmentMode alignment;
  size_t pairs;
  double rmse;
  double mean;
  double median;
  double scale;  // 0: not printed (SE(3))
};

const ReferenceCase kCases[] = {
    {"KittiOrbSE3", "KITTI_00_ORB.txt", "KITTI_00_gt.txt", TrajectoryFormat::kKitti,
     AlignmentMode::kSE3, 4541, 1.3034497145650266, 1.1569971285389768, 1.065624769555848, 0.0},
    {"KittiSptamSE3", "KITTI_00_SPTAM.txt", "KITTI_00_gt.txt", TrajectoryFormat::kKitti,
     AlignmentMode::kSE3, 4541, 3.738487907582613, 3.4909766330848684, 3.6425846417432637, 0.0},
    {"KittiOrbSim3", "KITTI_00_ORB.txt", "KITTI_00_gt.txt", TrajectoryFormat::kKitti,
     AlignmentMode::kSim3, 4541, 0.9377090736, 0.8726926320, 0.8446910135, 1.004698},
    {"DeskOrbSE3", "fr2_desk_ORB.txt", "fr2_desk_groundtruth.txt", TrajectoryFormat::kTum,
     AlignmentMode::kSE3, 2174, 0.0081189776, 0.0074917769, 0.0074146298, 0.0},
    {"DeskOrbSim3", "fr2_desk_ORB.txt", "fr2_desk_groundtruth.txt", TrajectoryFormat::kTum,
     AlignmentMode::kSim3, 2174, 0.0061231630, 0.0055861973, 0.0053052251, 0.996970},
    {"DeskOrbKfMonoSE3", "fr2_desk_ORB_kf_mono.txt", "fr2_desk_groundtruth.txt",
     TrajectoryFormat::kTum, AlignmentMode::kSE3, 118, 0.9390492628, 0.9169908762, 0.9212130012,
     0.0},
    {"DeskOrbKfMonoSim3", "fr2_desk_ORB_kf_mono.txt", "fr2_desk_groundtruth.txt",
     TrajectoryFormat::kTum, AlignmentMode::kSim3, 118, 0.0077292648, 0.0071036160, 0.0070998222,
     2.228022},
};

// |actual / expected - 1| < 5e-7, i.e. agreement to 6+ significant digits
// with the value as printed in the table.
void ExpectSignificant(double actual, double expected, const std::string& what) {
  EXPECT_LT(std::abs(actual / expected - 1.0), 5e-7)
      << what << ": got " << std::setprecision(17) << actual << ", expected " << expected;
}

// The scale is printed with 7 significant digits (e.g. 1.004698): compare
// to the printed precision.
void ExpectScale(double actual, double printed, const std::string& what) {
  EXPECT_NEAR(actual, printed, 5e-7 * 1.0001 * std::max(1.0, printed))
      << what << ": scale " << std::setprecision(17) << actual;
}

TEST(TrajEval, ReproducesPublishedAteOfEvo) {
  VIOSFM_REQUIRE_DATASET(data, "traj_eval");
  for (const ReferenceCase& c : kCases) {
    SCOPED_TRACE(c.name);
    const Trajectory est = ReadTrajectory(data / c.est_file, c.format);
    const Trajectory ref = ReadTrajectory(data / c.ref_file, c.format);
    EvaluationOptions options;
    options.alignment = c.alignment;
    // KITTI has no stamps: kAuto takes the index rule, TUM the nearest stamp within 0.01 s.
    const EvaluationResult result = EvaluateTrajectories(est, ref, options);
    EXPECT_EQ(result.association, c.format == TrajectoryFormat::kKitti
                                      ? AssociationMethod::kIndex
                                      : AssociationMethod::kNearest);
    EXPECT_EQ(result.pairs.size(), c.pairs);
    EXPECT_EQ(result.ate_translation_m.count, c.pairs);
    ExpectSignificant(result.ate_translation_m.rmse, c.rmse, "rmse");
    ExpectSignificant(result.ate_translation_m.mean, c.mean, "mean");
    ExpectSignificant(result.ate_translation_m.median, c.median, "median");
    if (c.scale > 0.0) {
      ExpectScale(result.ref_from_est.scale, c.scale, "sim3");
    } else {
      EXPECT_EQ(result.ref_from_est.scale, 1.0);
    }
  }
}

#ifdef VIOSFM_CLI_BINARY
// Runs the built `viosfm eval` end to end and reads the numbers back from --json.
nlohmann::json RunCli(const std::string& arguments, const fs::path& json_path, int* exit_code) {
  const std::string command = std::string(VIOSFM_CLI_BINARY) + " eval " + arguments + " --json " +
                              json_path.string() + " > " +
                              (json_path.parent_path() / "stdout.txt").string() + " 2>&1";
  const int status = std::system(command.c_str());
  *exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  if (*exit_code != 0 || !fs::exists(json_path)) return nullptr;
  return nlohmann::json::parse(ReadTextFile(json_path));
}

TEST(TrajEvalCli, JsonReproducesPublishedAte) {
  VIOSFM_REQUIRE_DATASET(data, "traj_eval");
  ASSERT_TRUE(fs::exists(VIOSFM_CLI_BINARY)) << VIOSFM_CLI_BINARY;
  const fs::path scratch = testing::MakeScratchFolder("eval_cli");
  for (const ReferenceCase& c : kCases) {
    SCOPED_TRACE(c.name);
    const fs::path json_path = scratch / (std::string(c.name) + ".json");
    int exit_code = -1;
    // Formats are guessed; KITTI is associated by index, TUM by nearest stamp.
    const nlohmann::json json =
        RunCli("--est " + (data / c.est_file).string() + " --ref " + (data / c.ref_file).string() +
                   " --align " + AlignmentModeName(c.alignment) + " --max-dt 0.01",
               json_path, &exit_code);
    ASSERT_EQ(exit_code, 0) << ReadTextFile(scratch / "stdout.txt");
    EXPECT_EQ(json["num_pairs"].get<size_t>(), c.pairs);
    EXPECT_EQ(json["ate"]["translation_m"]["count"].get<size_t>(), c.pairs);
    ExpectSignificant(json["ate"]["translation_m"]["rmse"].get<double>(), c.rmse, "rmse");
    ExpectSignificant(json["ate"]["translation_m"]["mean"].get<double>(), c.mean, "mean");
    ExpectSignificant(json["ate"]["translation_m"]["median"].get<double>(), c.median, "median");
    if (c.scale > 0.0) ExpectScale(json["alignment"]["scale"].get<double>(), c.scale, "sim3");
    EXPECT_EQ(json["inputs"]["est_format"].get<std::string>(),
              c.format == TrajectoryFormat::kKitti ? "kitti" : "tum");
  }
}

TEST(TrajEvalCli, BadInputExitsWithCodeTwoAndNamesTheProblem) {
  VIOSFM_REQUIRE_DATASET(data, "traj_eval");
  const fs::path scratch = testing::MakeScratchFolder("eval_cli_bad");
  int exit_code = -1;
  RunCli("--est " + (data / "KITTI_00_ORB.txt").string() + " --ref " +
             (data / "KITTI_00_gt.txt").string() + " --associate nearest",
         scratch / "out.json", &exit_code);
  EXPECT_EQ(exit_code, 2);
  EXPECT_THAT(ReadTextFile(scratch / "stdout.txt"), ::testing::HasSubstr("needs timestamps"));
  EXPECT_FALSE(fs::exists(scratch / "out.json"));
}
#endif

// ---------------------------------------------------------------- synthetic

// A smooth trajectory of `count` poses, one every 0.1 s: a helix with a
// turning yaw and some roll, in metres.
Trajectory MakeTrajectory(size_t count) {
  Trajectory trajectory;
  for (size_t i = 0; i < count; ++i) {
    const double t = 0.1 * static_cast<double>(i);
    StampedPose pose;
    pose.timestamp_ns = 1'000'000'000 + static_cast<timestamp_ns_t>(i) * 100'000'000;
    pose.world_from_frame.translation =
        Eigen::Vector3d(3.0 * std::cos(0.5 * t), 2.0 * std::sin(0.5 * t), 0.3 * t);
    pose.world_from_frame.rotation =
        Eigen::Quaterniond(Eigen::AngleAxisd(0.5 * t, Eigen::Vector3d::UnitZ()) *
                           Eigen::AngleAxisd(0.1 * std::sin(t), Eigen::Vector3d::UnitX()));
    trajectory.poses.push_back(pose);
  }
  return trajectory;
}

Trajectory TransformTrajectory(const Sim3d& b_from_a, const Trajectory& trajectory) {
  Trajectory out = trajectory;
  for (StampedPose& pose : out.poses)
    pose.world_from_frame = b_from_a.TransformPose(pose.world_from_frame);
  return out;
}

const Sim3d kEstFromRef(0.5, Eigen::Quaterniond(0.9, 0.1, -0.3, 0.2).normalized(),
                        Eigen::Vector3d(10.0, -3.0, 2.0));

TEST(ComputeErrorStatistics, MatchesNumpyDefinitions) {
  const ErrorStatistics even = ComputeErrorStatistics({4.0, 1.0, 3.0, 2.0});
  EXPECT_EQ(even.count, 4u);
  EXPECT_DOUBLE_EQ(even.rmse, std::sqrt(7.5));
  EXPECT_DOUBLE_EQ(even.mean, 2.5);
  EXPECT_DOUBLE_EQ(even.median, 2.5);
  EXPECT_DOUBLE_EQ(even.std, std::sqrt(1.25));  // population std (np.std)
  EXPECT_EQ(even.min, 1.0);
  EXPECT_EQ(even.max, 4.0);
  EXPECT_DOUBLE_EQ(even.sse, 30.0);
  const ErrorStatistics odd = ComputeErrorStatistics({3.0, 1.0, 2.0});
  EXPECT_EQ(odd.median, 2.0);
  EXPECT_EQ(ComputeErrorStatistics({}).count, 0u);
}

TEST(EvaluateTrajectories, Sim3AlignmentRemovesAKnownSimilarity) {
  const Trajectory ref = MakeTrajectory(100);
  const Trajectory est = TransformTrajectory(kEstFromRef, ref);
  EvaluationOptions options;
  options.alignment = AlignmentMode::kSim3;
  const EvaluationResult result = EvaluateTrajectories(est, ref, options);
  EXPECT_EQ(result.association, AssociationMethod::kNearest);
  EXPECT_EQ(result.pairs.size(), 100u);
  EXPECT_NEAR(result.ref_from_est.scale, 1.0 / kEstFromRef.scale, 1e-12);
  EXPECT_LT(result.ate_translation_m.max, 1e-9);
  EXPECT_LT(result.ate_rotation_deg.max, 1e-6);
  ASSERT_TRUE(result.rpe_frames.has_value());
  EXPECT_LT(result.rpe_frames->translation_m.max, 1e-9);

  // SE(3) cannot undo the scale: the error is that of the best rigid fit.
  options.alignment = AlignmentMode::kSE3;
  const EvaluationResult rigid = EvaluateTrajectories(est, ref, options);
  EXPECT_EQ(rigid.ref_from_est.scale, 1.0);
  EXPECT_GT(rigid.ate_translation_m.rmse, 0.1);
  EXPECT_LT(rigid.ate_rotation_deg.max, 1e-6);  // the rotation is still exact
}

TEST(EvaluateTrajectories, NoAlignmentMeasuresTheRawOffset) {
  const Trajectory ref = MakeTrajectory(20);
  const Trajectory est = TransformTrajectory(
      Sim3d(1.0, Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0, 0.25)), ref);
  EvaluationOptions options;
  options.alignment = AlignmentMode::kNone;
  const EvaluationResult result = EvaluateTrajectories(est, ref, options);
  EXPECT_NEAR(result.ate_translation_m.rmse, 0.25, 1e-12);
  EXPECT_NEAR(result.ate_translation_m.std, 0.0, 1e-12);
  EXPECT_NEAR(result.ate_rotation_deg.max, 0.0, 1e-9);
}

TEST(EvaluateTrajectories, PosYawAlignmentRemovesYawAndTranslation) {
  const Trajectory ref = MakeTrajectory(60);
  const Sim3d yaw_shift(1.0, Eigen::Quaterniond(Eigen::AngleAxisd(1.2, Eigen::Vector3d::UnitZ())),
                        Eigen::Vector3d(1.0, 2.0, 3.0));
  EvaluationOptions options;
  options.alignment = AlignmentMode::kPosYaw;
  EXPECT_LT(
      EvaluateTrajectories(TransformTrajectory(yaw_shift, ref), ref, options).ate_translation_m.max,
      1e-9);
  // A roll cannot be removed by a yaw.
  const Sim3d roll(1.0, Eigen::Quaterniond(Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitX())),
                   Eigen::Vector3d::Zero());
  EXPECT_GT(
      EvaluateTrajectories(TransformTrajectory(roll, ref), ref, options).ate_translation_m.rmse,
      0.01);
}

TEST(EvaluateTrajectories, AlignFirstUsesOnlyThoseStablePairs) {
  const Trajectory ref = MakeTrajectory(50);
  Trajectory est = TransformTrajectory(kEstFromRef, ref);
  // From pose 20 on the estimate drifts upwards (in its own frame).
  for (size_t i = 20; i < est.size(); ++i) {
    est.poses[i].world_from_frame.translation.z() += 0.05 * static_cast<double>(i - 19);
  }
  EvaluationOptions options;
  options.alignment = AlignmentMode::kSim3;
  options.align_first = 20;
  const EvaluationResult result = EvaluateTrajectories(est, ref, options);
  EXPECT_EQ(result.num_alignment_pairs, 20u);
  EXPECT_NEAR(result.ref_from_est.scale, 2.0, 1e-9);
  for (size_t k = 0; k < 20; ++k) EXPECT_LT(result.translation_errors_m[k], 1e-9) << k;
  // Pose 49 drifted 1.5 m in the estimate frame, i.e. 3 m in the reference.
  EXPECT_NEAR(result.translation_errors_m[49], 3.0, 1e-9);
}

TEST(EvaluateTrajectories, RpeOfAConstantDriftPerFrame) {
  // The reference moves 1 m along x per frame; every estimated step carries
  // an extra constant motion D (0.5 deg yaw and a small translation).
  const size_t count = 50;
  const Rigid3d drift(Eigen::Quaterniond(Eigen::AngleAxisd(0.5 * std::numbers::pi / 180.0,
                                                           Eigen::Vector3d::UnitZ())),
                      Eigen::Vector3d(0.02, -0.01, 0.005));
  const Rigid3d step(Eigen::Quaterniond::Identity(), Eigen::Vector3d(1.0, 0.0, 0.0));
  Trajectory ref, est;
  Rigid3d ref_pose, est_pose;
  for (size_t i = 0; i < count; ++i) {
    const timestamp_ns_t stamp = static_cast<timestamp_ns_t>(i) * 50'000'000;
    ref.poses.push_back({stamp, ref_pose});
    est.poses.push_back({stamp, est_pose});
    ref_pose = ref_pose * step;
    est_pose = est_pose * step * drift;
  }
  EvaluationOptions options;
  options.alignment = AlignmentMode::kNone;
  options.rpe_delta_frames = 1;
  options.rpe_delta_m = 3.0;
  EvaluationResult result = EvaluateTrajectories(est, ref, options);
  // delta 1: E = step^-1 (step D) = D for every pair.
  ASSERT_TRUE(result.rpe_frames.has_value());
  EXPECT_EQ(result.rpe_frames->translation_m.count, count - 1);
  EXPECT_NEAR(result.rpe_frames->translation_m.mean, drift.translation.norm(), 1e-12);
  EXPECT_NEAR(result.rpe_frames->translation_m.std, 0.0, 1e-12);
  EXPECT_NEAR(result.rpe_frames->rotation_deg.max, 0.5, 1e-9);
  EXPECT_NEAR(result.rpe_frames->rotation_deg.min, 0.5, 1e-9);
  // 3 m along the reference is 3 frames: E = (M^3)^-1 (M D)^3 has 1.5 deg.
  ASSERT_TRUE(result.rpe_distance.has_value());
  EXPECT_EQ(result.rpe_distance->translation_m.count, count - 3);
  EXPECT_NEAR(result.rpe_distance->rotation_deg.mean, 1.5, 1e-9);
  const Rigid3d three = step * drift * step * drift * step * drift;
  const Rigid3d expected = (step * step * step).Inverse() * three;
  EXPECT_NEAR(result.rpe_distance->translation_m.max, expected.translation.norm(), 1e-12);

  // delta 2 with consecutive pairs (0,2), (2,4), ...: E = M^-1 D M D.
  options.rpe_delta_frames = 2;
  options.rpe_all_pairs = false;
  result = EvaluateTrajectories(est, ref, options);
  EXPECT_EQ(result.rpe_frames->translation_m.count, (count - 1) / 2);
  const Rigid3d two = step.Inverse() * drift * step * drift;
  EXPECT_NEAR(result.rpe_frames->translation_m.mean, two.translation.norm(), 1e-12);
  EXPECT_NEAR(result.rpe_frames->rotation_deg.mean, 1.0, 1e-9);
  // evo's consecutive distance pairs: poses 3, 6, ..., 48 are kept.
  EXPECT_EQ(result.rpe_distance->translation_m.count, 15u);
  EXPECT_EQ(result.rpe_distance->pair_indices.front(), std::make_pair(size_t{3}, size_t{6}));
}

TEST(EvaluateTrajectories, RpeIgnoresARigidWorldChangeOfTheEstimate) {
  const Trajectory ref = MakeTrajectory(40);
  const Sim3d world_change(1.0, kEstFromRef.rotation, kEstFromRef.translation);
  EvaluationOptions options;
  options.alignment = AlignmentMode::kNone;
  const EvaluationResult result =
      EvaluateTrajectories(TransformTrajectory(world_change, ref), ref, options);
  EXPECT_GT(result.ate_translation_m.rmse, 1.0);
  EXPECT_LT(result.rpe_frames->translation_m.max, 1e-12);
  EXPECT_LT(result.rpe_frames->rotation_deg.max, 1e-6);
}

TEST(EvaluateTrajectories, CameraPosesAreConvertedToBodyPoses) {
  const Trajectory world_from_body = MakeTrajectory(30);
  const Rigid3d body_from_cam(Eigen::Quaterniond(0.5, -0.5, 0.5, -0.5),
                              Eigen::Vector3d(0.05, -0.02, 0.1));
  Trajectory world_from_cam = world_from_body;
  for (StampedPose& pose : world_from_cam.poses) {
    pose.world_from_frame = pose.world_from_frame * body_from_cam;
  }
  EvaluationOptions options;
  options.alignment = AlignmentMode::kNone;
  EXPECT_GT(EvaluateTrajectories(world_from_cam, world_from_body, options).ate_rotation_deg.min,
            10.0);
  options.est_body_from_cam = body_from_cam;
  EvaluationResult result = EvaluateTrajectories(world_from_cam, world_from_body, options);
  EXPECT_LT(result.ate_translation_m.max, 1e-12);
  EXPECT_LT(result.ate_rotation_deg.max, 1e-6);
  // Converting both sides keeps them equal too.
  options.ref_body_from_cam = body_from_cam;
  result = EvaluateTrajectories(world_from_cam, world_from_cam, options);
  EXPECT_LT(result.ate_translation_m.max, 1e-12);
}

TEST(EvaluateTrajectories, IndexAssociationForTrajectoriesWithoutStamps) {
  Trajectory ref = MakeTrajectory(30);
  Trajectory est = ref;
  est.poses.resize(25);
  est.has_timestamps = false;
  for (size_t i = 0; i < est.size(); ++i)
    est.poses[i].timestamp_ns = static_cast<timestamp_ns_t>(i);
  const EvaluationResult result = EvaluateTrajectories(est, ref, EvaluationOptions());
  EXPECT_EQ(result.association, AssociationMethod::kIndex);
  EXPECT_EQ(result.pairs.size(), 25u);
  EXPECT_LT(result.ate_translation_m.max, 1e-9);
}

TEST(EvaluateTrajectories, FailuresNameTheProblem) {
  const Trajectory ref = MakeTrajectory(30);
  Trajectory late = ref;
  for (StampedPose& pose : late.poses) pose.timestamp_ns += 1'000'000'000'000;
  try {
    EvaluateTrajectories(late, ref, EvaluationOptions());
    ADD_FAILURE() << "expected an InputError";
  } catch (const InputError& error) {
    EXPECT_THAT(error.what(), ::testing::HasSubstr("no estimated pose could be associated"));
  }
  Trajectory two = ref;
  two.poses.resize(2);
  EXPECT_THROW(EvaluateTrajectories(two, ref, EvaluationOptions()), InputError);
  EvaluationOptions bad;
  bad.max_dt_ns = -1;
  EXPECT_FALSE(bad.Check());
  EXPECT_THAT(bad.Validate(), ::testing::HasSubstr("max_dt_ns"));
  bad = EvaluationOptions();
  bad.rpe_delta_m = -2.0;
  EXPECT_THAT(bad.Validate(), ::testing::HasSubstr("rpe_delta_m"));
  bad = EvaluationOptions();
  bad.align_first = -3;
  EXPECT_THAT(bad.Validate(), ::testing::HasSubstr("align_first"));
  EXPECT_THROW(EvaluateTrajectories(ref, ref, bad), InputError);
  EXPECT_TRUE(EvaluationOptions().Check());
}

TEST(EvaluationReport, JsonHoldsFullPrecisionNumbers) {
  const Trajectory ref = MakeTrajectory(30);
  const Trajectory est = TransformTrajectory(
      Sim3d(1.0, Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.1, 0.2, 0.3)), ref);
  EvaluationOptions options;
  options.alignment = AlignmentMode::kNone;
  const EvaluationResult result = EvaluateTrajectories(est, ref, options);
  const EvaluationInputs inputs{"est.txt", "tum", "ref.txt", "tum"};
  const nlohmann::json json = nlohmann::json::parse(EvaluationToJson(result, options, inputs));
  EXPECT_EQ(json["ate"]["translation_m"]["rmse"].get<double>(), result.ate_translation_m.rmse);
  EXPECT_EQ(json["ate"]["translation_m"]["count"].get<size_t>(), 30u);
  EXPECT_EQ(json["options"]["alignment"].get<std::string>(), "none");
  EXPECT_EQ(json["rpe_frames"]["num_pairs"].get<size_t>(), 29u);
  const std::string text = FormatEvaluationReport(result, options, inputs);
  EXPECT_THAT(text, ::testing::HasSubstr("ATE translation (m)"));
  EXPECT_THAT(text, ::testing::HasSubstr("30 pairs"));

  const fs::path scratch = testing::MakeScratchFolder("eval_json");
  WriteEvaluationJson(scratch / "eval.json", result, options, inputs);
  EXPECT_EQ(ReadTextFile(scratch / "eval.json"), EvaluationToJson(result, options, inputs));
}

}  // namespace
}  // namespace viosfm

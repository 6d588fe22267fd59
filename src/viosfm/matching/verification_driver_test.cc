#include "viosfm/matching/verification_driver.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "viosfm/features/feature_extraction.h"
#include "viosfm/io/euroc.h"
#include "viosfm/io/verification_report.h"
#include "viosfm/sensor/camera_models.h"
#include "viosfm/sim/sequence_simulator.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/string_util.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {
namespace fs = std::filesystem;

// A 1.2 s walk in the simulated room at 10 Hz (13 frames), rendered at half
// the EuRoC resolution, with features extracted into `features.db`.
struct Fixture {
  fs::path folder;
  Sequence sequence;
  Trajectory vio_body;
  fs::path features_db;
};

const Fixture& SharedFixture() {
  static const Fixture fixture = [] {
    Fixture f;
    f.folder = testing::MakeScratchFolder("verification_driver");
    SimulationOptions options;
    options.scenario = "room";
    options.duration_s = 1.2;
    options.static_start_s = 0.0;
    options.camera_rate_hz = 10.0;
    options.texels_per_metre = 64.0;
    options.seed = 3;
    Camera camera = SimulationOptions::DefaultCamera();
    camera.width /= 2;
    camera.height /= 2;
    for (int i = 0; i < 4; ++i)
      camera.params[i] = i < 2 ? camera.params[i] / 2 : (camera.params[i] + 0.5) / 2 - 0.5;
    options.camera = camera;
    const SimulatedSequence simulated = SimulateSequence(options);
    WriteSimulatedSequence(f.folder / "dataset", simulated, options);
    f.sequence = ReadEurocDataset(f.folder / "dataset");
    f.vio_body = simulated.vio_body;
    f.features_db = f.folder / "features.db";
    {
      ColmapDatabase database = ColmapDatabase::Open(f.features_db);
      SiftOptions sift;
      sift.max_num_features = 1000;
      ExtractFeatures(f.sequence, sift, &database, /*show_progress=*/false);
    }
    return f;
  }();
  return fixture;
}

// A fresh database holding only the features.
fs::path CopyFeatures(const Fixture& f, const std::string& name) {
  const fs::path path = f.folder / name;
  fs::remove(path);
  fs::copy_file(f.features_db, path);
  return path;
}

// RANSAC's inlier threshold of the resume test: between the inlier counts
// of this walk's consecutive pairs (483 to 626).
constexpr int kStrictMinInliers = 550;

VerificationOptions SmallOptions() {
  VerificationOptions options;
  options.pairs.num_temporal_neighbors = 2;
  options.pairs.num_retrieval_neighbors = 2;
  // 512 words: a vocabulary so small that every image holds every word
  // would give every word zero IDF weight and retrieve nothing.
  options.retrieval.vocabulary.branching = 8;
  options.retrieval.vocabulary.depth = 3;
  options.show_progress = false;
  return options;
}

// The VIO trajectory with the pose of the image at `index` moved 3 m up and
// turned 30 degrees about the vertical: a pose from somewhere else.
Trajectory CorruptPose(const Trajectory& vio, size_t index) {
  Trajectory corrupted = vio;
  Rigid3d& pose = corrupted.poses.at(index).world_from_frame;
  pose.rotation =
      Eigen::Quaterniond(Eigen::AngleAxisd(30.0 * M_PI / 180.0, Eigen::Vector3d::UnitZ())) *
      pose.rotation;
  pose.translation += Eigen::Vector3d(0.0, 0.0, 3.0);
  return corrupted;
}

const PairDecision* FindPair(const VerificationResult& result, const std::string& name1,
                             const std::string& name2) {
  for (const PairDecision& d : result.decisions) {
    if ((d.name1 == name1 && d.name2 == name2) || (d.name1 == name2 && d.name2 == name1)) return &d;
  }
  return nullptr;
}

std::set<image_pair_t> AcceptedPairIds(const VerificationResult& result) {
  std::set<image_pair_t> ids;
  for (const PairDecision& d : result.decisions) {
    if (d.accepted) ids.insert(ImagePairToPairId(d.image_id1, d.image_id2));
  }
  return ids;
}

std::set<image_pair_t> StoredGeometryPairIds(const ColmapDatabase& database) {
  std::set<image_pair_t> ids;
  for (const auto& [pair_id, geometry] : database.ReadAllTwoViewGeometries()) {
    EXPECT_EQ(geometry.config, TwoViewGeometryConfig::kCalibrated);
    ids.insert(pair_id);
  }
  return ids;
}

TEST(VerificationDriver, OptionsValidate) {
  VerificationOptions options;
  EXPECT_TRUE(options.Check());
  EXPECT_EQ(options.pairs.num_temporal_neighbors, 40);
  EXPECT_EQ(options.pairs.num_retrieval_neighbors, 30);
  EXPECT_EQ(options.prior.max_epipolar_error_px, 20.0);
  EXPECT_EQ(options.prior.max_outlier_ratio, 0.5);
  options.prior.max_outlier_ratio = 1.5;
  EXPECT_NE(options.Validate().find("prior."), std::string::npos);
  options = VerificationOptions();
  options.pairs.mode = PairMode::kPairList;
  EXPECT_NE(options.Validate().find("pairs.mode"), std::string::npos);
  options = VerificationOptions();
  options.batch_size = 0;
  EXPECT_NE(options.Validate().find("batch_size"), std::string::npos);
}

TEST(VerificationDriver, CameraToBodyTrajectoryInvertsTheExtrinsics) {
  Trajectory body;
  body.poses.push_back(
      {5, Rigid3d(Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY())),
                  Eigen::Vector3d(1, 2, 3))});
  const Rigid3d body_from_cam = SimulationOptions::DefaultBodyFromCam();
  Trajectory cam = body;
  cam.poses[0].world_from_frame = body.poses[0].world_from_frame * body_from_cam;
  const Trajectory back = CameraToBodyTrajectory(cam, body_from_cam);
  ASSERT_EQ(back.size(), 1u);
  EXPECT_EQ(back.poses[0].timestamp_ns, 5);
  EXPECT_LT((back.poses[0].world_from_frame.translation - Eigen::Vector3d(1, 2, 3)).norm(), 1e-12);
  EXPECT_LT(back.poses[0].world_from_frame.rotation.angularDistance(
                body.poses[0].world_from_frame.rotation),
            1e-12);
}

TEST(VerificationDriver, VioPriorRejectsACorruptedPoseThatRansacAccepts) {
  const Fixture& f = SharedFixture();
  const size_t num_images = f.sequence.images.size();
  ASSERT_GE(num_images, 12u);
  ASSERT_EQ(f.vio_body.size(), num_images);
  const size_t bad = 6;
  const Trajectory corrupted = CorruptPose(f.vio_body, bad);
  const auto name = [&](size_t k) { return DatabaseImageName(f.sequence.images[k]); };

  // VIO prior + RANSAC.
  const fs::path vio_db_path = CopyFeatures(f, "vio.db");
  VerificationResult vio;
  {
    ColmapDatabase database = ColmapDatabase::Open(vio_db_path);
    vio = RunVerification(f.sequence, corrupted, &database, SmallOptions());
    EXPECT_EQ(vio.summary.num_images, num_images);
    EXPECT_EQ(vio.summary.num_images_with_prior, num_images);
    EXPECT_EQ(vio.summary.num_pairs, vio.decisions.size());
    EXPECT_EQ(vio.summary.num_pairs_without_prior, 0u);
    EXPECT_EQ(vio.summary.num_resumed, 0u);
    EXPECT_EQ(vio.summary.num_accepted + vio.summary.num_vio_rejected +
                  vio.summary.num_ransac_rejected + vio.summary.num_no_matches,
              vio.summary.num_pairs);
    // The database holds exactly the accepted pairs' geometries, and every
    // pair's matches.
    EXPECT_EQ(StoredGeometryPairIds(database), AcceptedPairIds(vio));
    EXPECT_EQ(database.NumMatchedImagePairs(), vio.decisions.size());
    for (const PairDecision& d : vio.decisions) {
      EXPECT_EQ(database.ReadMatches(d.image_id1, d.image_id2).size(),
                static_cast<size_t>(d.num_matches));
      if (d.accepted) {
        EXPECT_EQ(database.ReadTwoViewGeometry(d.image_id1, d.image_id2).inlier_matches.size(),
                  static_cast<size_t>(d.num_inliers));
      }
    }
  }
  // Neighbouring frames (not involving the corrupted one) are accepted by
  // both steps, with many inliers.
  for (size_t k = 0; k + 1 < num_images; ++k) {
    const PairDecision* d = FindPair(vio, name(k), name(k + 1));
    ASSERT_NE(d, nullptr) << k;
    EXPECT_EQ(d->source, "temporal");
    if (k == bad - 1 || k == bad) {
      // The corrupted pose's pairs: rejected by the VIO step.
      EXPECT_TRUE(d->vio_rejected) << k;
      EXPECT_GT(d->vio_outlier_ratio, 0.5) << k;
      EXPECT_FALSE(d->accepted) << k;
      EXPECT_EQ(d->reason, kPairVioOutlierRatio);
      continue;
    }
    EXPECT_TRUE(d->accepted) << k;
    EXPECT_TRUE(d->has_vio_prior) << k;
    EXPECT_LT(d->vio_outlier_ratio, 0.2) << k;
    EXPECT_GT(d->num_inliers, 100) << k;
  }
  EXPECT_GE(vio.summary.num_vio_rejected, 2u);
  // Exactly the pairs with the corrupted image are rejected by the VIO step.
  for (const PairDecision& d : vio.decisions) {
    const bool involves_bad = d.name1 == name(bad) || d.name2 == name(bad);
    EXPECT_EQ(d.vio_rejected, involves_bad) << d.name1 << " " << d.name2;
    EXPECT_EQ(d.accepted, !involves_bad) << d.name1 << " " << d.name2;
  }
  // Retrieval adds pairs beyond the N1 = 2 temporal neighbours.
  size_t num_retrieval = 0;
  for (const PairDecision& d : vio.decisions) num_retrieval += d.source == "retrieval";
  EXPECT_GT(num_retrieval, 0u);

  // RANSAC only: the same pairs are accepted.
  const fs::path ransac_db_path = CopyFeatures(f, "ransac.db");
  VerificationOptions ransac_options = SmallOptions();
  ransac_options.use_vio_prior = false;
  ColmapDatabase ransac_db = ColmapDatabase::Open(ransac_db_path);
  const VerificationResult ransac =
      RunVerification(f.sequence, corrupted, &ransac_db, ransac_options);
  EXPECT_EQ(ransac.summary.num_images_with_prior, 0u);
  EXPECT_EQ(ransac.summary.num_vio_rejected, 0u);
  for (const size_t k : {bad - 1, bad}) {
    const PairDecision* d = FindPair(ransac, name(k), name(k + 1));
    ASSERT_NE(d, nullptr);
    EXPECT_TRUE(std::isnan(d->vio_outlier_ratio));
    EXPECT_FALSE(d->has_vio_prior);
    EXPECT_TRUE(d->accepted) << k;
    EXPECT_GT(d->num_inliers, 100) << k;
  }
  EXPECT_EQ(StoredGeometryPairIds(ransac_db), AcceptedPairIds(ransac));
  // Same pairs, same matches: VIO-aided accepts a subset of RANSAC-only.
  ASSERT_EQ(ransac.decisions.size(), vio.decisions.size());
  for (size_t i = 0; i < vio.decisions.size(); ++i) {
    EXPECT_EQ(vio.decisions[i].num_matches, ransac.decisions[i].num_matches) << i;
    if (vio.decisions[i].accepted) {
      EXPECT_TRUE(ransac.decisions[i].accepted) << i;
    }
  }

  // Resume: a second run skips every stored pair and reports the same.
  {
    ColmapDatabase database = ColmapDatabase::Open(vio_db_path);
    const VerificationResult again =
        RunVerification(f.sequence, corrupted, &database, SmallOptions());
    EXPECT_EQ(again.summary.num_resumed, vio.decisions.size());
    ASSERT_EQ(again.decisions.size(), vio.decisions.size());
    for (size_t i = 0; i < vio.decisions.size(); ++i) {
      const PairDecision& a = again.decisions[i];
      const PairDecision& b = vio.decisions[i];
      EXPECT_TRUE(a.resumed);
      EXPECT_EQ(a.image_id1, b.image_id1);
      EXPECT_EQ(a.image_id2, b.image_id2);
      EXPECT_EQ(a.accepted, b.accepted) << i;
      EXPECT_EQ(a.num_matches, b.num_matches) << i;
      EXPECT_EQ(a.num_inliers, b.num_inliers) << i;
      EXPECT_EQ(a.vio_rejected, b.vio_rejected) << i;
      EXPECT_EQ(a.reason, b.reason) << i;
    }
    EXPECT_EQ(again.summary.num_accepted, vio.summary.num_accepted);
    EXPECT_EQ(again.summary.num_vio_rejected, vio.summary.num_vio_rejected);
    EXPECT_EQ(StoredGeometryPairIds(database), AcceptedPairIds(vio));
  }

  // Reports parse back.
  const fs::path csv = f.folder / "pairs.csv";
  const fs::path json_path = f.folder / "verification.json";
  WritePairDecisionsCsv(csv, vio.decisions);
  WriteVerificationJson(json_path, vio.summary, vio.decisions);
  EXPECT_EQ(Split(ReadTextFile(csv), "\n", true).size(), vio.decisions.size() + 1);
  const nlohmann::json json = nlohmann::json::parse(ReadTextFile(json_path));
  EXPECT_EQ(json.at("summary").at("num_pairs").get<size_t>(), vio.decisions.size());
  EXPECT_EQ(json.at("summary").at("num_vio_rejected").get<size_t>(), vio.summary.num_vio_rejected);
  EXPECT_EQ(json.at("options").at("prior.max_epipolar_error_px").get<std::string>(), "20");
  EXPECT_EQ(json.at("pairs").size(), vio.decisions.size());
}

// The VIO drifts by 8 degrees of pitch after the walk's seventh frame (its
// later poses turned together about the sixth frame's pose), and
// the uncertainty model allows that much (its tilt rate raised to 0.2
// rad / sqrt(s): 3.6 degrees over 0.1 s, 8 over 0.5 s). Pairs across the drift: under the
// VIO's pose most of their matches miss the fixed band, so the paper's test
// rejects them; corrected within the drift by their matches, they are
// accepted under the fixed band. Pairs on one side of the drift are
// accepted either way.
// The fixture's VIO turned by 8 degrees of pitch about frame first_drifted
// - 1 from frame first_drifted on.
Trajectory PitchedFrom(const Fixture& f, size_t first_drifted) {
  Trajectory drifted = f.vio_body;
  const Rigid3d& pivot = f.vio_body.poses.at(first_drifted - 1).world_from_frame;
  const Rigid3d drift_about_pivot =
      pivot *
      Rigid3d(Eigen::Quaterniond(Eigen::AngleAxisd(8.0 * M_PI / 180.0, Eigen::Vector3d::UnitY())),
              Eigen::Vector3d::Zero()) *
      pivot.Inverse();
  for (size_t k = first_drifted; k < drifted.size(); ++k) {
    drifted.poses[k].world_from_frame = drift_about_pivot * drifted.poses[k].world_from_frame;
  }
  return drifted;
}

// The options of the drift tests: the model's tilt rate 0.2 rad / sqrt(s).
VerificationOptions DriftOptions() {
  VerificationOptions options = SmallOptions();
  options.pairs.num_temporal_neighbors = 4;
  options.vio_uncertainty.tilt_per_sqrt_s = 0.2;
  return options;
}

// The sequence's image index of a database image name.
size_t ImageIndex(const Fixture& f, const std::string& name) {
  for (size_t k = 0; k < f.sequence.images.size(); ++k) {
    if (DatabaseImageName(f.sequence.images[k]) == name) return k;
  }
  ADD_FAILURE() << name;
  return 0;
}

TEST(VerificationDriver, PairsAcrossADriftAreJudgedUnderTheCorrectedPose) {
  const Fixture& f = SharedFixture();
  const size_t num_images = f.sequence.images.size();
  ASSERT_GE(num_images, 12u);
  const size_t first_drifted = 7;
  const Trajectory drifted = PitchedFrom(f, first_drifted);
  const VerificationOptions options = DriftOptions();
  VerificationOptions paper = options;
  paper.band_follows_drift = false;

  VerificationResult corrected;
  VerificationResult uncorrected;
  {
    ColmapDatabase database = ColmapDatabase::Open(CopyFeatures(f, "drift_corrected.db"));
    corrected = RunVerification(f.sequence, drifted, &database, options);
  }
  {
    ColmapDatabase database = ColmapDatabase::Open(CopyFeatures(f, "drift_paper.db"));
    uncorrected = RunVerification(f.sequence, drifted, &database, paper);
  }
  ASSERT_EQ(corrected.decisions.size(), uncorrected.decisions.size());
  const auto index = [&](const std::string& name) { return ImageIndex(f, name); };
  int num_across = 0;
  int num_across_rejected_by_paper = 0;
  for (size_t i = 0; i < corrected.decisions.size(); ++i) {
    const PairDecision& d = corrected.decisions[i];
    const PairDecision& p = uncorrected.decisions[i];
    ASSERT_EQ(d.image_id1, p.image_id1);
    ASSERT_EQ(d.image_id2, p.image_id2);
    if (d.num_matches < 100) continue;  // too little overlap to say anything
    const bool across = (index(d.name1) < first_drifted) != (index(d.name2) < first_drifted);
    EXPECT_TRUE(d.accepted) << d.name1 << " " << d.name2 << ": " << d.vio_correction_sigmas
                            << " sigmas";
    EXPECT_LT(d.vio_outlier_ratio, 0.2) << d.name1 << " " << d.name2;
    if (across) {
      ++num_across;
      EXPECT_TRUE(d.vio_corrected) << d.name1 << " " << d.name2;
      num_across_rejected_by_paper += p.vio_rejected;
    } else {
      EXPECT_TRUE(p.accepted) << d.name1 << " " << d.name2;
    }
  }
  std::cout << num_across << " pairs across the drift, " << num_across_rejected_by_paper
            << " of them rejected under the VIO's pose with the fixed band\n";
  EXPECT_GE(num_across, 4);
  // Pairs across the drift whose matches run along the pitch's motion can
  // pass the paper's test too; most do not.
  EXPECT_GE(num_across_rejected_by_paper, num_across / 2);
  EXPECT_GT(corrected.summary.num_accepted_corrected, 0u);
  EXPECT_EQ(uncorrected.summary.num_accepted_corrected, 0u);
}

// Guided matching inside the band the VIO's drift allows: the pairs across
// the drift keep their matches, which the fixed band around the VIO's lines
// loses, and are accepted under the corrected pose with about the inliers
// brute-force matching finds. Pairs on one side of the drift are matched in
// the fixed band, the drift between them being small.
TEST(VerificationDriver, GuidedMatchingFollowsTheDrift) {
  const Fixture& f = SharedFixture();
  const size_t first_drifted = 7;
  const Trajectory drifted = PitchedFrom(f, first_drifted);
  VerificationOptions options = DriftOptions();
  VerificationOptions guided = options;
  guided.guided_matching = true;
  VerificationOptions guided_fixed = guided;
  guided_fixed.band_follows_drift = false;
  const auto run = [&](const VerificationOptions& run_options, const std::string& name) {
    ColmapDatabase database = ColmapDatabase::Open(CopyFeatures(f, name));
    return RunVerification(f.sequence, drifted, &database, run_options);
  };
  const VerificationResult brute = run(options, "guided_brute.db");
  const VerificationResult drift_band = run(guided, "guided_drift.db");
  const VerificationResult fixed_band = run(guided_fixed, "guided_fixed.db");
  ASSERT_EQ(brute.decisions.size(), drift_band.decisions.size());
  ASSERT_EQ(brute.decisions.size(), fixed_band.decisions.size());
  int num_across = 0;
  int inliers_brute = 0;
  int inliers_drift_band = 0;
  int inliers_fixed_band = 0;
  for (size_t i = 0; i < brute.decisions.size(); ++i) {
    const PairDecision& b = brute.decisions[i];
    const PairDecision& d = drift_band.decisions[i];
    const PairDecision& x = fixed_band.decisions[i];
    ASSERT_EQ(b.image_id1, d.image_id1);
    ASSERT_EQ(b.image_id2, d.image_id2);
    if (!b.accepted || b.num_inliers < 100) continue;  // too little overlap to say anything
    const bool across =
        (ImageIndex(f, b.name1) < first_drifted) != (ImageIndex(f, b.name2) < first_drifted);
    EXPECT_DOUBLE_EQ(x.guided_band_px, guided.guided_band_px);
    if (!across) {
      EXPECT_TRUE(d.accepted) << d.name1 << " " << d.name2;
      continue;
    }
    ++num_across;
    EXPECT_GT(d.guided_band_px, 2.0 * guided.guided_band_px) << d.name1 << " " << d.name2;
    EXPECT_TRUE(d.accepted) << d.name1 << " " << d.name2;
    EXPECT_TRUE(d.vio_corrected) << d.name1 << " " << d.name2;
    inliers_brute += b.num_inliers;
    inliers_drift_band += d.num_inliers;
    inliers_fixed_band += x.num_inliers;
  }
  std::cout << num_across << " pairs across the drift: inliers " << inliers_brute
            << " (brute force), " << inliers_drift_band << " (the drift's band), "
            << inliers_fixed_band << " (the fixed band)\n";
  EXPECT_GE(num_across, 4);
  EXPECT_GE(inliers_drift_band, 0.9 * inliers_brute);
  EXPECT_LT(inliers_fixed_band, 0.5 * inliers_brute);
}

TEST(VerificationDriver, ImagesWithoutVioPoseFallBackToRansac) {
  const Fixture& f = SharedFixture();
  // A trajectory without the last pose: the last image has no prior.
  Trajectory partial = f.vio_body;
  partial.poses.pop_back();
  const fs::path path = CopyFeatures(f, "partial.db");
  ColmapDatabase database = ColmapDatabase::Open(path);
  VerificationOptions options = SmallOptions();
  options.pairs.mode = PairMode::kSequential;
  options.pairs.num_temporal_neighbors = 1;
  const VerificationResult result = RunVerification(f.sequence, partial, &database, options);
  const size_t n = f.sequence.images.size();
  EXPECT_EQ(result.summary.num_images_with_prior, n - 1);
  ASSERT_EQ(result.decisions.size(), n - 1);  // sequential with overlap 1
  EXPECT_EQ(result.summary.num_pairs_without_prior, 1u);
  const PairDecision& last = result.decisions.back();
  EXPECT_EQ(last.source, "sequential");
  EXPECT_FALSE(last.has_vio_prior);
  EXPECT_TRUE(std::isnan(last.vio_outlier_ratio));
  EXPECT_TRUE(last.accepted);
  for (size_t i = 0; i + 1 < result.decisions.size(); ++i) {
    EXPECT_TRUE(result.decisions[i].has_vio_prior);
    EXPECT_TRUE(result.decisions[i].accepted) << i;
  }
}

// Stored matches verified again (reverify_stored_matches): a RANSAC-only
// database re-verified with the VIO prior (on copies, with and without the
// depth check, which is on by default): the pairs of the corrupted pose are
// now rejected by the VIO step and keep no inliers; every stored geometry
// matches its decision. On this room walk (baselines of at most ~1 m, walls
// within 5 m) the depth check changes nothing.
TEST(VerificationDriver, ReverifyStoredMatchesWithAndWithoutDepthCheck) {
  const Fixture& f = SharedFixture();
  const size_t bad = 6;
  const Trajectory corrupted = CorruptPose(f.vio_body, bad);
  const std::string bad_name = DatabaseImageName(f.sequence.images[bad]);
  VerificationOptions ransac_only = SmallOptions();
  ransac_only.use_vio_prior = false;
  const fs::path matched_path = CopyFeatures(f, "matched.db");
  VerificationResult baseline;
  {
    ColmapDatabase database = ColmapDatabase::Open(matched_path);
    baseline = RunVerification(f.sequence, Trajectory{}, &database, ransac_only);
  }
  ASSERT_GT(baseline.summary.num_accepted, 0u);
  EXPECT_TRUE(SmallOptions().prior.check_depth);
  std::vector<VerificationResult> results;
  for (const bool check_depth : {true, false}) {
    const fs::path path = f.folder / (check_depth ? "reverify_depth.db" : "reverify_paper.db");
    fs::remove(path);
    fs::copy_file(matched_path, path);
    VerificationOptions options = SmallOptions();
    options.reverify_stored_matches = true;
    options.prior.check_depth = check_depth;
    ColmapDatabase database = ColmapDatabase::Open(path);
    VerificationResult result = RunVerification(f.sequence, corrupted, &database, options);
    EXPECT_EQ(result.summary.num_reverified, result.summary.num_pairs);
    EXPECT_EQ(result.summary.num_resumed, 0u);
    EXPECT_EQ(result.summary.num_vio_depth_rejected, 0u);
    ASSERT_EQ(result.decisions.size(), baseline.decisions.size());
    for (size_t k = 0; k < result.decisions.size(); ++k) {
      const PairDecision& d = result.decisions[k];
      EXPECT_FALSE(d.resumed);
      EXPECT_EQ(d.num_matches, baseline.decisions[k].num_matches);
      const size_t stored_inliers =
          database.ExistsTwoViewGeometry(d.image_id1, d.image_id2)
              ? database.ReadTwoViewGeometry(d.image_id1, d.image_id2).inlier_matches.size()
              : 0u;
      EXPECT_EQ(stored_inliers, d.accepted ? static_cast<size_t>(d.num_inliers) : 0u);
      if ((d.name1 == bad_name || d.name2 == bad_name) && d.num_matches > 0) {
        EXPECT_TRUE(d.vio_rejected) << d.name1 << " " << d.name2;
        EXPECT_FALSE(d.accepted);
      }
      if (!check_depth) {
        EXPECT_FALSE(d.vio_depth_applied);
        EXPECT_TRUE(std::isnan(d.vio_depth_inconsistent_ratio));
      }
    }
    results.push_back(std::move(result));
  }
  EXPECT_LT(results[0].summary.num_accepted, baseline.summary.num_accepted);
  EXPECT_EQ(AcceptedPairIds(results[0]), AcceptedPairIds(results[1]));
}

// A run interrupted after part of its pairs (here: the consecutive pairs,
// among them pairs the VIO step rejects, by the epipolar band and by the
// depth check, and pairs RANSAC rejects) and run
// again decides every pair as an uninterrupted run does: the stored pairs
// resumed, a rejected one decided again from its stored matches (the same
// VIO check, inlier count and reason), the others verified anew.
TEST(VerificationDriver, ResumingAHalfVerifiedPairSetDecidesAsAnUninterruptedRun) {
  const Fixture& f = SharedFixture();
  const Trajectory corrupted = CorruptPose(f.vio_body, 6);
  VerificationOptions options = SmallOptions();
  // Strict enough that RANSAC rejects some pairs.
  options.geometry.min_num_inliers = kStrictMinInliers;
  // A scene taken to end 1.5 m away: the depth check rejects the pairs
  // whose baseline shows the walls' parallax to be too small.
  options.prior.max_scene_depth_m = 1.5;
  options.prior.min_depth_parallax_px = 5.0;
  options.prior.depth_tolerance_px = 2.0;
  VerificationResult uninterrupted;
  {
    ColmapDatabase database = ColmapDatabase::Open(CopyFeatures(f, "uninterrupted.db"));
    uninterrupted = RunVerification(f.sequence, corrupted, &database, options);
  }
  // What an interrupted run stored: the consecutive pairs only.
  const fs::path path = CopyFeatures(f, "interrupted.db");
  VerificationOptions first_part = options;
  first_part.pairs.num_temporal_neighbors = 1;
  first_part.pairs.num_retrieval_neighbors = 0;
  size_t num_stored = 0;
  {
    ColmapDatabase database = ColmapDatabase::Open(path);
    const VerificationResult part = RunVerification(f.sequence, corrupted, &database, first_part);
    num_stored = part.decisions.size();
    // It holds each kind of decision.
    EXPECT_GT(part.summary.num_accepted, 0u);
    EXPECT_GT(part.summary.num_vio_rejected, 0u);
    EXPECT_GT(part.summary.num_ransac_rejected, 0u);
    EXPECT_GT(part.summary.num_vio_depth_rejected, 0u);
  }
  ColmapDatabase database = ColmapDatabase::Open(path);
  const VerificationResult resumed = RunVerification(f.sequence, corrupted, &database, options);
  EXPECT_EQ(resumed.summary.num_resumed, num_stored);
  ASSERT_EQ(resumed.decisions.size(), uninterrupted.decisions.size());
  for (size_t i = 0; i < resumed.decisions.size(); ++i) {
    const PairDecision& a = resumed.decisions[i];
    const PairDecision& b = uninterrupted.decisions[i];
    const std::string pair = a.name1 + " " + a.name2;
    EXPECT_EQ(a.image_id1, b.image_id1) << pair;
    EXPECT_EQ(a.image_id2, b.image_id2) << pair;
    EXPECT_EQ(a.source, b.source) << pair;
    EXPECT_EQ(a.accepted, b.accepted) << pair;
    EXPECT_EQ(a.num_matches, b.num_matches) << pair;
    EXPECT_EQ(a.num_inliers, b.num_inliers) << pair;
    EXPECT_EQ(a.vio_rejected, b.vio_rejected) << pair;
    EXPECT_EQ(a.vio_depth_rejected, b.vio_depth_rejected) << pair;
    EXPECT_EQ(a.reason, b.reason) << pair;
    EXPECT_EQ(std::isnan(a.vio_outlier_ratio), std::isnan(b.vio_outlier_ratio)) << pair;
    if (!std::isnan(b.vio_outlier_ratio)) {
      EXPECT_EQ(a.vio_outlier_ratio, b.vio_outlier_ratio) << pair;
    }
  }
  EXPECT_EQ(resumed.summary.num_accepted, uninterrupted.summary.num_accepted);
  EXPECT_EQ(resumed.summary.num_ransac_rejected, uninterrupted.summary.num_ransac_rejected);
  EXPECT_GT(resumed.summary.num_ransac_rejected, 0u);
  EXPECT_EQ(StoredGeometryPairIds(database), AcceptedPairIds(uninterrupted));
  EXPECT_EQ(database.NumMatchedImagePairs(), uninterrupted.decisions.size());
}

// The accepted pairs handed to a mapper beside the verification
// (`on_verified`): every accepted pair once, with the inlier matches the
// database holds, stored pairs of an earlier run included, and each after
// the frontier the call before it promised (every later pair's frames at or
// after that stamp); the last call closes the stream.
TEST(VerificationDriver, OnVerifiedHandsOverTheAcceptedPairsBehindAFrontier) {
  const Fixture& f = SharedFixture();
  const Trajectory corrupted = CorruptPose(f.vio_body, 6);
  VerificationOptions options = SmallOptions();
  options.batch_size = 3;
  const fs::path path = CopyFeatures(f, "streamed.db");
  {
    // An earlier run stored the consecutive pairs.
    VerificationOptions first_part = options;
    first_part.pairs.num_temporal_neighbors = 1;
    first_part.pairs.num_retrieval_neighbors = 0;
    ColmapDatabase database = ColmapDatabase::Open(path);
    RunVerification(f.sequence, corrupted, &database, first_part);
  }
  ColmapDatabase database = ColmapDatabase::Open(path);
  std::map<image_t, timestamp_ns_t> stamp_of;
  for (const DatabaseImage& row : database.ReadAllImages()) {
    for (const SequenceImage& image : f.sequence.images) {
      if (DatabaseImageName(image) == row.name) stamp_of[row.image_id] = image.timestamp_ns;
    }
  }
  std::vector<std::pair<ImagePairMatches, timestamp_ns_t>> handed;  // pair, frontier before it
  std::vector<timestamp_ns_t> frontiers;
  timestamp_ns_t frontier = std::numeric_limits<timestamp_ns_t>::min();
  // Each image's VIO pose, as the trajectory overload finds it.
  const std::vector<VioOdometer> odometers = ComputeVioOdometers(corrupted, {});
  std::vector<std::optional<FrameVioPose>> poses(f.sequence.images.size());
  for (size_t i = 0; i < poses.size(); ++i) {
    const std::optional<size_t> index = NearestPoseIndex(
        corrupted, f.sequence.images[i].timestamp_ns, options.max_pose_time_difference_ns);
    ASSERT_TRUE(index.has_value());
    poses[i] = FrameVioPose{corrupted.poses[*index].world_from_frame, odometers[*index]};
  }
  const VerificationResult result =
      RunVerification(f.sequence, poses, &database, options, {},
                      [&](std::vector<ImagePairMatches> accepted, timestamp_ns_t pending_from_ns) {
                        for (ImagePairMatches& pair : accepted)
                          handed.emplace_back(std::move(pair), frontier);
                        frontiers.push_back(pending_from_ns);
                        frontier = pending_from_ns;
                      });
  EXPECT_GT(result.summary.num_resumed, 0u);
  ASSERT_GE(frontiers.size(), 3u);
  EXPECT_TRUE(std::is_sorted(frontiers.begin(), frontiers.end()));
  EXPECT_EQ(frontiers.back(), std::numeric_limits<timestamp_ns_t>::max());
  std::set<image_pair_t> handed_ids;
  for (const auto& [pair, frontier_before] : handed) {
    EXPECT_TRUE(handed_ids.insert(ImagePairToPairId(pair.image_id1, pair.image_id2)).second);
    EXPECT_GE(std::min(stamp_of.at(pair.image_id1), stamp_of.at(pair.image_id2)), frontier_before);
    const FeatureMatches stored =
        database.ReadTwoViewGeometry(pair.image_id1, pair.image_id2).inlier_matches;
    ASSERT_EQ(pair.matches.size(), stored.size());
    for (size_t m = 0; m < stored.size(); ++m) {
      EXPECT_EQ(pair.matches[m].point2D_idx1, stored[m].point2D_idx1);
      EXPECT_EQ(pair.matches[m].point2D_idx2, stored[m].point2D_idx2);
    }
  }
  EXPECT_EQ(handed_ids, AcceptedPairIds(result));
}

}  // namespace
}  // namespace viosfm

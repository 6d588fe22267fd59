#include "viosfm/vio/feature_tracker.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <vector>

#include "viosfm/geometry/epipolar.h"
#include "viosfm/sensor/camera_models.h"
#include "viosfm/sim/renderer.h"
#include "viosfm/sim/sequence_simulator.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

constexpr double kStaticStartS = 1.0;

// The `room` scenario, 3 s at 20 Hz (1 s static, then walking), rendered
// once for every test of the file.
struct RoomSequence {
  SimulationOptions options;
  SimulatedSequence simulated;
  std::vector<GreyImage> frames;
  std::vector<timestamp_ns_t> stamps;

  Rigid3d CamFromWorld(size_t k) const { return SimulatedCamFromWorld(simulated, stamps[k]); }
  bool IsStatic(size_t k) const {
    return NsToSeconds(stamps[k] - stamps[0]) < kStaticStartS - 1e-6;
  }
};

// Simulates and renders the sequence `options` describe.
RoomSequence* RenderRoom(const SimulationOptions& options) {
  auto* r = new RoomSequence;
  r->options = options;
  r->simulated = SimulateSequence(r->options);
  const RayTable rays(r->options.camera);
  for (size_t k = 0; k < r->simulated.sequence.images.size(); ++k) {
    r->frames.push_back(RenderSimulatedFrame(r->simulated, rays, k, r->options, 2));
    r->stamps.push_back(r->simulated.sequence.images[k].timestamp_ns);
  }
  return r;
}

const RoomSequence& Room() {
  static const RoomSequence* room = [] {
    SimulationOptions options;
    options.scenario = "room";
    options.duration_s = 3.0;
    options.static_start_s = kStaticStartS;
    options.camera_rate_hz = 20.0;
    options.seed = 3;
    return RenderRoom(options);
  }();
  return *room;
}

std::vector<FrameFeatures> TrackAll(const RoomSequence& room, const FeatureTrackerOptions& options,
                                    bool with_rotation_prior = false) {
  FeatureTracker tracker(room.options.camera, options);
  std::vector<FrameFeatures> out;
  for (size_t k = 0; k < room.frames.size(); ++k) {
    std::optional<Eigen::Quaterniond> prior;
    if (with_rotation_prior && k > 0) {
      prior = (room.CamFromWorld(k) * room.CamFromWorld(k - 1).Inverse()).rotation;
    }
    out.push_back(tracker.Track(room.stamps[k], room.frames[k], prior));
  }
  return out;
}

// TrackAll with the default options, computed once.
const std::vector<FrameFeatures>& DefaultTracks() {
  static const std::vector<FrameFeatures> tracks = TrackAll(Room(), FeatureTrackerOptions{});
  return tracks;
}

double MinPairwiseDistance(const FrameFeatures& frame) {
  double best = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < frame.observations.size(); ++i) {
    for (size_t j = i + 1; j < frame.observations.size(); ++j) {
      best = std::min(best, (frame.observations[i].pixel - frame.observations[j].pixel).norm());
    }
  }
  return best;
}

double Percentile(std::vector<double> values, double fraction) {
  VIOSFM_CHECK(!values.empty());
  std::sort(values.begin(), values.end());
  const size_t index = std::min(values.size() - 1, static_cast<size_t>(fraction * values.size()));
  return values[index];
}

// Epipolar errors (px) of the tracks shared by frames i and j under the
// ground-truth relative pose: the distance of the undistorted position in j
// from the epipolar line of the undistorted position in i, both expressed as
// pixels of a pinhole camera with the camera's mean focal length.
std::vector<double> EpipolarErrors(const RoomSequence& room, const std::vector<FrameFeatures>& out,
                                   size_t i, size_t j) {
  const double f = MeanFocalLength(room.options.camera);
  Eigen::Matrix3d k = Eigen::Matrix3d::Identity();
  k(0, 0) = k(1, 1) = f;
  const Rigid3d cam_j_from_cam_i = room.CamFromWorld(j) * room.CamFromWorld(i).Inverse();
  const Eigen::Matrix3d fundamental = FundamentalFromRelativePose(cam_j_from_cam_i, k, k);
  std::map<uint64_t, Eigen::Vector2d> in_i;
  for (const FeatureObservation& o : out[i].observations) in_i[o.track_id] = o.normalized;
  std::vector<double> errors;
  for (const FeatureObservation& o : out[j].observations) {
    const auto it = in_i.find(o.track_id);
    if (it == in_i.end()) continue;
    errors.push_back(EpipolarLineDistance(fundamental, f * it->second, f * o.normalized));
  }
  return errors;
}

TEST(FeatureTrackerOptions, DefaultsAreValidAndBadFieldsAreNamed) {
  EXPECT_TRUE(FeatureTrackerOptions{}.Check());
  FeatureTrackerOptions options;
  options.klt_window_size = 20;
  EXPECT_THAT(options.Validate(), ::testing::HasSubstr("klt_window_size"));
  options = FeatureTrackerOptions{};
  options.keyframe_min_tracked_ratio = 1.5;
  EXPECT_THAT(options.Validate(), ::testing::HasSubstr("keyframe_min_tracked_ratio"));
  options = FeatureTrackerOptions{};
  options.max_num_features = 0;
  EXPECT_THAT(testing::InputErrorMessage(
                  [&] { FeatureTracker(SimulationOptions::DefaultCamera(), options); }),
              ::testing::HasSubstr("max_num_features"));
}

// (1) On every textured frame at least 90% of the target is tracked and no
// two corners are closer than the minimum distance.
TEST(FeatureTracker, FeaturesAreSpreadEvenly) {
  const RoomSequence& room = Room();
  const FeatureTrackerOptions options;
  const std::vector<FrameFeatures>& out = DefaultTracks();
  ASSERT_EQ(out.size(), room.frames.size());
  double total = 0.0;
  for (size_t k = 0; k < out.size(); ++k) {
    SCOPED_TRACE(k);
    EXPECT_GE(out[k].observations.size(), 0.9 * options.max_num_features);
    EXPECT_LE(out[k].observations.size(), static_cast<size_t>(options.max_num_features));
    EXPECT_GE(MinPairwiseDistance(out[k]), options.min_distance_px);
    EXPECT_EQ(out[k].timestamp_ns, room.stamps[k]);
    // Every corner lies inside the border margin and its normalised
    // coordinates are the undistortion of its pixel.
    for (const FeatureObservation& o : out[k].observations) {
      EXPECT_GE(o.pixel.minCoeff(), options.border_margin_px);
      EXPECT_LE(o.pixel.x(), 751 - options.border_margin_px);
      EXPECT_LE(o.pixel.y(), 479 - options.border_margin_px);
      EXPECT_LT((CamToImage(room.options.camera, o.normalized) - o.pixel).norm(), 1e-6);
    }
    total += static_cast<double>(out[k].observations.size());
  }
  std::cout << "features per frame: mean " << total / out.size() << "\n";
  // Corners are spread: each quarter of the image holds at least 10% of them.
  const FrameFeatures& last = out.back();
  int quadrant[4] = {0, 0, 0, 0};
  for (const FeatureObservation& o : last.observations) {
    ++quadrant[(o.pixel.x() >= 376 ? 1 : 0) + (o.pixel.y() >= 240 ? 2 : 0)];
  }
  for (const int count : quadrant) EXPECT_GE(count, 0.1 * last.observations.size());
}

// (2) Tracks agree with the ground-truth motion: epipolar errors between
// consecutive frames and over 5-frame spans of the moving part have median
// < 0.3 px and 95th percentile < 1 px; ids persist while the camera stands
// still.
TEST(FeatureTracker, TracksAreAccurateAndIdsPersist) {
  const RoomSequence& room = Room();
  for (const bool with_prior : {false, true}) {
    SCOPED_TRACE(with_prior ? "with rotation prior" : "without rotation prior");
    const std::vector<FrameFeatures> out =
        with_prior ? TrackAll(room, FeatureTrackerOptions{}, true) : DefaultTracks();
    std::vector<double> consecutive;
    std::vector<double> span5;
    for (size_t k = 1; k < out.size(); ++k) {
      if (room.IsStatic(k - 1)) continue;
      const std::vector<double> errors = EpipolarErrors(room, out, k - 1, k);
      consecutive.insert(consecutive.end(), errors.begin(), errors.end());
      if (k >= 5 && !room.IsStatic(k - 5)) {
        const std::vector<double> errors5 = EpipolarErrors(room, out, k - 5, k);
        span5.insert(span5.end(), errors5.begin(), errors5.end());
      }
    }
    ASSERT_GT(consecutive.size(), 2000u);
    ASSERT_GT(span5.size(), 1000u);
    const double median1 = Percentile(consecutive, 0.5);
    const double p95_1 = Percentile(consecutive, 0.95);
    const double median5 = Percentile(span5, 0.5);
    const double p95_5 = Percentile(span5, 0.95);
    std::cout << (with_prior ? "[prior] " : "[no prior] ") << "epipolar error consecutive: n "
              << consecutive.size() << " median " << median1 << " p95 " << p95_1 << " max "
              << Percentile(consecutive, 1.0) << " px; 5-frame span: n " << span5.size()
              << " median " << median5 << " p95 " << p95_5 << " px\n";
    EXPECT_LT(median1, 0.3);
    EXPECT_LT(p95_1, 1.0);
    EXPECT_LT(median5, 0.3);
    EXPECT_LT(p95_5, 1.0);

    // While static, the first frame's tracks are all still there at the end
    // of the static part, in place (< 0.2 px) and with their lengths counted.
    size_t last_static = 0;
    while (last_static + 1 < out.size() && room.IsStatic(last_static + 1)) ++last_static;
    ASSERT_GE(last_static, 15u);
    std::map<uint64_t, Eigen::Vector2d> first;
    for (const FeatureObservation& o : out[0].observations) first[o.track_id] = o.pixel;
    size_t persisted = 0;
    for (const FeatureObservation& o : out[last_static].observations) {
      const auto it = first.find(o.track_id);
      if (it == first.end()) continue;
      ++persisted;
      EXPECT_LT((o.pixel - it->second).norm(), 0.2);
      EXPECT_EQ(o.track_length, static_cast<int>(last_static) + 1);
    }
    EXPECT_GE(persisted, 0.95 * first.size());
  }
}

// A camera of twice the resolution and focal length (1504x960, 916 px)
// tracks on its half-resolution level, as the reference camera does on its
// full image: the corners are given in the full image's pixels, over all of
// it, and agree with the ground-truth motion as closely in angle (errors in
// its pixels twice the reference bounds), and as the full image tracked.
TEST(FeatureTracker, ALargeCameraTracksOnItsReducedLevel) {
  static const RoomSequence* large = [] {
    SimulationOptions options = Room().options;
    options.duration_s = 2.0;
    options.camera.width *= 2;
    options.camera.height *= 2;
    for (size_t i = 0; i < 4; ++i) options.camera.params[i] *= 2.0;
    return RenderRoom(options);
  }();
  FeatureTrackerOptions full_image;
  full_image.tracking_pyramid_level = 0;
  for (const FeatureTrackerOptions& options : {FeatureTrackerOptions{}, full_image}) {
    SCOPED_TRACE("tracking_pyramid_level " + std::to_string(options.tracking_pyramid_level));
    const std::vector<FrameFeatures> out = TrackAll(*large, options);
    std::vector<double> consecutive;
    double max_x = 0.0;
    double max_y = 0.0;
    for (size_t k = 1; k < out.size(); ++k) {
      for (const FeatureObservation& o : out[k].observations) {
        max_x = std::max(max_x, o.pixel.x());
        max_y = std::max(max_y, o.pixel.y());
      }
      if (large->IsStatic(k - 1)) continue;
      const std::vector<double> errors = EpipolarErrors(*large, out, k - 1, k);
      consecutive.insert(consecutive.end(), errors.begin(), errors.end());
    }
    ASSERT_GT(consecutive.size(), 1000u);
    std::cout << "level " << options.tracking_pyramid_level << ": epipolar error median "
              << Percentile(consecutive, 0.5) << " p95 " << Percentile(consecutive, 0.95)
              << " px of the 1504x960 camera\n";
    EXPECT_LT(Percentile(consecutive, 0.5), 2 * 0.3);
    EXPECT_LT(Percentile(consecutive, 0.95), 2 * 1.0);
    EXPECT_GT(max_x, 0.85 * static_cast<double>(large->options.camera.width));
    EXPECT_GT(max_y, 0.85 * static_cast<double>(large->options.camera.height));
  }
}

// (3) A patch of the next frame shifted across the epipolar lines: KLT
// follows it (so without RANSAC the shifted corners survive) and RANSAC
// removes them.
TEST(FeatureTracker, RansacRemovesAShiftedPatch) {
  const RoomSequence& room = Room();
  // The consecutive pair with the longest baseline.
  size_t a = 0;
  double baseline = 0.0;
  for (size_t k = 0; k + 1 < room.frames.size(); ++k) {
    const double t = (room.CamFromWorld(k + 1) * room.CamFromWorld(k).Inverse()).translation.norm();
    if (t > baseline) {
      baseline = t;
      a = k;
    }
  }
  const size_t b = a + 1;
  const double f = MeanFocalLength(room.options.camera);
  Eigen::Matrix3d k = Eigen::Matrix3d::Identity();
  k(0, 0) = k(1, 1) = f;
  const Rigid3d cam_b_from_cam_a = room.CamFromWorld(b) * room.CamFromWorld(a).Inverse();
  const Eigen::Matrix3d fundamental = FundamentalFromRelativePose(cam_b_from_cam_a, k, k);
  // The patch is centred in the image quarter farthest from the epipole
  // (near it, epipolar lines turn quickly and a shift across one line runs
  // along another), and is shifted by 8 px perpendicular to the ground-truth
  // epipolar line through its centre.
  // Epipole in normalised coordinates (possibly far outside the image).
  const Eigen::Vector2d epipole = cam_b_from_cam_a.translation.hnormalized();
  const std::vector<Eigen::Vector2d> candidates = {
      Eigen::Vector2d(190, 130), Eigen::Vector2d(562, 130), Eigen::Vector2d(190, 350),
      Eigen::Vector2d(562, 350)};
  Eigen::Vector2d centre = candidates[0];
  for (const Eigen::Vector2d& candidate : candidates) {
    if ((ImageToCam(room.options.camera, candidate) - epipole).norm() >
        (ImageToCam(room.options.camera, centre) - epipole).norm()) {
      centre = candidate;
    }
  }
  const Eigen::Vector3d line =
      fundamental * (f * ImageToCam(room.options.camera, centre)).homogeneous();
  const Eigen::Vector2d normal = line.head<2>().normalized();
  const int shift_x = static_cast<int>(std::lround(8.0 * normal.x()));
  const int shift_y = static_cast<int>(std::lround(8.0 * normal.y()));
  ASSERT_GE(std::hypot(shift_x, shift_y), 7.0);
  // Patch 200 x 160 px around the centre, moved by (shift_x, shift_y).
  const int x0 = static_cast<int>(centre.x()) - 100, x1 = x0 + 200;
  const int y0 = static_cast<int>(centre.y()) - 80, y1 = y0 + 160;
  GreyImage shifted = room.frames[b];
  for (int y = y0; y < y1; ++y) {
    for (int x = x0; x < x1; ++x) shifted.at(x, y) = room.frames[b].at(x - shift_x, y - shift_y);
  }

  struct Outcome {
    int inside = 0, inside_kept = 0;    // corners well inside the patch
    int outside = 0, outside_kept = 0;  // corners well away from it
    int kept_off_line = 0;              // kept tracks > 2 px from their epipolar line
    double max_kept_error = 0.0;        // px, largest epipolar error of a kept track
  };
  auto track_pair = [&](bool ransac) {
    FeatureTrackerOptions options;
    options.ransac = ransac;
    FeatureTracker tracker(room.options.camera, options);
    const FrameFeatures first = tracker.Track(room.stamps[a], room.frames[a]);
    const FrameFeatures second = tracker.Track(room.stamps[b], shifted);
    // Corners well inside the patch (away from its edges, where the KLT
    // window straddles both motions) and well outside it.
    std::map<uint64_t, Eigen::Vector2d> first_normalized;
    std::set<uint64_t> inside, outside;
    for (const FeatureObservation& o : first.observations) {
      first_normalized[o.track_id] = o.normalized;
      const bool in = o.pixel.x() > x0 + 15 && o.pixel.x() < x1 - 15 && o.pixel.y() > y0 + 15 &&
                      o.pixel.y() < y1 - 15;
      const bool out = o.pixel.x() < x0 - 25 || o.pixel.x() > x1 + 25 || o.pixel.y() < y0 - 25 ||
                       o.pixel.y() > y1 + 25;
      if (in) inside.insert(o.track_id);
      if (out) outside.insert(o.track_id);
    }
    Outcome outcome;
    outcome.inside = static_cast<int>(inside.size());
    outcome.outside = static_cast<int>(outside.size());
    for (const FeatureObservation& o : second.observations) {
      outcome.inside_kept += static_cast<int>(inside.count(o.track_id));
      outcome.outside_kept += static_cast<int>(outside.count(o.track_id));
      const auto it = first_normalized.find(o.track_id);
      if (it == first_normalized.end()) continue;
      const double error = EpipolarLineDistance(fundamental, f * it->second, f * o.normalized);
      outcome.max_kept_error = std::max(outcome.max_kept_error, error);
      if (error > 2.0) ++outcome.kept_off_line;
    }
    return outcome;
  };
  const Outcome without = track_pair(false);
  const Outcome with = track_pair(true);
  std::cout << "frames " << a << "-" << b << " (baseline " << baseline << " m), patch shifted by ("
            << shift_x << ", " << shift_y << ") px: " << without.inside
            << " corners inside, kept without RANSAC " << without.inside_kept << ", with "
            << with.inside_kept << "; " << without.outside << " outside, kept "
            << without.outside_kept << " / " << with.outside_kept
            << "; kept tracks > 2 px off their epipolar line " << without.kept_off_line << " / "
            << with.kept_off_line << ", max error " << without.max_kept_error << " / "
            << with.max_kept_error << " px\n";
  ASSERT_GE(without.inside, 8);
  // KLT follows the shifted patch: without RANSAC the outliers survive.
  EXPECT_GE(without.inside_kept, 0.8 * without.inside);
  EXPECT_GE(without.kept_off_line, 0.6 * without.inside);
  // RANSAC removes them (all tracks left lie within 2 px of their
  // ground-truth epipolar line; at most one corner of the patch, straddling
  // a KLT window's worth of both motions, may survive) and keeps the
  // consistent ones.
  EXPECT_EQ(with.kept_off_line, 0);
  EXPECT_LE(with.inside_kept, 1);
  EXPECT_GE(with.outside_kept, 0.9 * with.outside);
}

// (4) No keyframe while the camera stands still (after the first frame),
// keyframes while it moves, each with >= 10 px parallax or few shared tracks.
TEST(FeatureTracker, KeyframesOnlyWithMotion) {
  const RoomSequence& room = Room();
  const FeatureTrackerOptions options;
  const std::vector<FrameFeatures>& out = DefaultTracks();
  EXPECT_TRUE(out[0].is_keyframe);
  int moving_keyframes = 0;
  for (size_t k = 1; k < out.size(); ++k) {
    SCOPED_TRACE(k);
    if (room.IsStatic(k)) {
      EXPECT_FALSE(out[k].is_keyframe);
      EXPECT_LT(out[k].parallax_px, 0.2);
      EXPECT_GE(out[k].num_tracked_from_keyframe, 0.9 * options.max_num_features);
    } else if (out[k].is_keyframe) {
      ++moving_keyframes;
      EXPECT_TRUE(out[k].parallax_px >= options.keyframe_parallax_px ||
                  out[k].num_tracked_from_keyframe <
                      options.keyframe_min_tracked_ratio * options.max_num_features);
    } else {
      EXPECT_LT(out[k].parallax_px, options.keyframe_parallax_px);
    }
  }
  std::cout << "keyframes while moving: " << moving_keyframes << " of "
            << std::count_if(room.stamps.begin(), room.stamps.end(),
                             [&](timestamp_ns_t t) {
                               return NsToSeconds(t - room.stamps[0]) >= kStaticStartS;
                             })
            << " frames\n";
  EXPECT_GE(moving_keyframes, 3);
}

// (5) Black and empty images: no crash, no corners; tracking resumes on the
// next textured image with fresh ids.
TEST(FeatureTracker, BlackAndEmptyImagesGiveNoFeatures) {
  const RoomSequence& room = Room();
  FeatureTracker tracker(room.options.camera, FeatureTrackerOptions{});
  const FrameFeatures textured = tracker.Track(room.stamps[0], room.frames[0]);
  ASSERT_FALSE(textured.observations.empty());
  const FrameFeatures black = tracker.Track(room.stamps[1], GreyImage(752, 480, 0));
  EXPECT_TRUE(black.observations.empty());
  EXPECT_FALSE(black.is_keyframe);
  const FrameFeatures empty = tracker.Track(room.stamps[2], GreyImage());
  EXPECT_TRUE(empty.observations.empty());
  EXPECT_FALSE(empty.is_keyframe);
  const FrameFeatures grey = tracker.Track(room.stamps[3], GreyImage(752, 480, 128));
  EXPECT_TRUE(grey.observations.empty());
  const FrameFeatures again = tracker.Track(room.stamps[4], room.frames[4]);
  EXPECT_GE(again.observations.size(), 135u);
  uint64_t max_old_id = 0;
  for (const FeatureObservation& o : textured.observations) {
    max_old_id = std::max(max_old_id, o.track_id);
  }
  for (const FeatureObservation& o : again.observations) {
    EXPECT_GT(o.track_id, max_old_id);
    EXPECT_EQ(o.track_length, 1);
  }
  // A wrong image size and a stamp going back are input errors.
  EXPECT_THAT(
      testing::InputErrorMessage([&] { tracker.Track(room.stamps[5], GreyImage(640, 480, 0)); }),
      ::testing::HasSubstr("640x480"));
  EXPECT_THAT(testing::InputErrorMessage([&] { tracker.Track(room.stamps[0], room.frames[0]); }),
              ::testing::HasSubstr("not after"));
}

// The same images give the same features.
TEST(FeatureTracker, IsDeterministic) {
  const RoomSequence& room = Room();
  FeatureTracker a(room.options.camera, FeatureTrackerOptions{});
  FeatureTracker b(room.options.camera, FeatureTrackerOptions{});
  for (size_t k = 15; k < 45; ++k) {
    const FrameFeatures fa = a.Track(room.stamps[k], room.frames[k]);
    const FrameFeatures fb = b.Track(room.stamps[k], room.frames[k]);
    ASSERT_EQ(fa.observations.size(), fb.observations.size());
    for (size_t i = 0; i < fa.observations.size(); ++i) {
      EXPECT_EQ(fa.observations[i].track_id, fb.observations[i].track_id);
      EXPECT_EQ(fa.observations[i].pixel, fb.observations[i].pixel);
    }
    EXPECT_EQ(fa.is_keyframe, fb.is_keyframe);
  }
}

// Images fading to dark (grey levels x 0.85 a frame from frame 35 until
// x 0.1 at frame 49):
// with CLAHE (always, or switched on when the images turn dark) the tracks
// survive the fade and the switch, corners are still found in the dark part
// and tracked accurately. The input images are left untouched.
TEST(FeatureTracker, EqualizationOfDarkImagesKeepsTracks) {
  const RoomSequence& room = Room();
  auto faded = [&](size_t k) {
    const double gain = std::clamp(std::pow(0.85, static_cast<double>(k) - 34.0), 0.1, 1.0);
    GreyImage image = room.frames[k];
    for (uint8_t& p : image.pixels) p = static_cast<uint8_t>(std::lround(p * gain));
    return image;
  };
  for (const ContrastEqualization equalization :
       {ContrastEqualization::kWhenDark, ContrastEqualization::kAlways}) {
    SCOPED_TRACE(static_cast<int>(equalization));
    FeatureTrackerOptions options;
    options.equalization = equalization;
    FeatureTracker tracker(room.options.camera, options);
    std::vector<FrameFeatures> out(room.frames.size());
    double min_kept_fraction = 1.0;
    for (size_t k = 30; k < 60; ++k) {
      const GreyImage image = faded(k);
      const GreyImage copy = image;
      out[k] = tracker.Track(room.stamps[k], image);
      ASSERT_EQ(image.pixels, copy.pixels);
      if (k == 30) continue;
      std::set<uint64_t> before;
      for (const FeatureObservation& o : out[k - 1].observations) before.insert(o.track_id);
      size_t kept = 0;
      for (const FeatureObservation& o : out[k].observations) kept += before.count(o.track_id);
      min_kept_fraction = std::min(min_kept_fraction, static_cast<double>(kept) / before.size());
    }
    std::vector<double> errors;
    for (size_t k = 50; k < 60; ++k) {
      EXPECT_GE(out[k].observations.size(), 0.9 * options.max_num_features);
      const std::vector<double> e = EpipolarErrors(room, out, k - 1, k);
      errors.insert(errors.end(), e.begin(), e.end());
    }
    std::cout << "fading to dark, equalisation " << static_cast<int>(equalization) << ": at least "
              << min_kept_fraction
              << " of the tracks kept from frame to frame; dark part's epipolar error median "
              << Percentile(errors, 0.5) << " p95 " << Percentile(errors, 0.95) << " px\n";
    EXPECT_GE(min_kept_fraction, 0.8);
    EXPECT_LT(Percentile(errors, 0.5), 0.3);
    EXPECT_LT(Percentile(errors, 0.95), 1.0);
  }
}

}  // namespace
}  // namespace viosfm

// Ground truth for image-pair verification on simulated sequences: does a
// pair of frames see the same physical surface, and do the inlier matches a
// verification run kept agree with the true geometry?
//
// The scene is the simulator's scene.csv (io/scene_structure_io.h: every
// textured quad of the scene, so the first quad a ray hits is the surface a
// pixel shows); the camera poses are the ground truth of the sequence
// (mav0/state_groundtruth_estimate0 with the rig's body_from_cam).
//
// Covisibility of frame 1 in frame 2: the fraction of a regular grid of
// pixels of image 1 whose surface point (the nearest quad hit of the pixel's
// ray) is visible in image 2: it projects inside image 2, in front of the
// camera, and the ray from camera 2 towards it hits nothing nearer (not
// occluded). The pair's covisibility is the larger of the two directions
// (symmetric max), so that a pair whose one view holds a small part of the
// other (a camera walking towards a wall) counts as overlapping.
//
// Match agreement: the fraction of a pair's matches whose keypoint in image 1
// lies on a surface point that is visible in image 2 and projects within
// max_match_error_px of the matched keypoint in image 2.
//
// Labels (see PairTruthOptions): a candidate pair is "correct" when its
// covisibility is at least min_covisibility; an accepted pair is "wrong" when
// fewer than min_inlier_agreement of its verified inliers agree with the
// ground truth.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "viosfm/geometry/rigid3.h"
#include "viosfm/scene/features.h"
#include "viosfm/scene/pair_decision.h"
#include "viosfm/scene/scene_structure.h"
#include "viosfm/sensor/camera.h"
#include "viosfm/util/timestamp.h"

namespace viosfm {

struct PairTruthOptions {
  // Spacing of the covisibility pixel grid, pixels. Default 16 (47 x 30 rays
  // for 752 x 480).
  int grid_step_px = 16;
  // A point counts as unoccluded from a camera when the first hit towards it
  // is at most this much nearer than the point: occlusion_tolerance_m +
  // occlusion_tolerance_relative * distance. Defaults 0.02 m and 0.01.
  double occlusion_tolerance_m = 0.02;
  double occlusion_tolerance_relative = 0.01;
  // A match agrees with the ground truth when the true projection of its
  // first keypoint's surface point lies this close to its second keypoint,
  // pixels. Default 5.
  double max_match_error_px = 5.0;
  // A pair is correct (sees the same surface) at this covisibility or more,
  // in [0, 1]. Default 0.05: 5 % of a 752 x 480 image is 18000 pixels, a
  // 134 x 134 pixel patch that holds about 5 % of the keypoints (~100 of
  // ~2000), several times the 15 inliers a pair needs; below it a pair
  // cannot be verified reliably and the overlap is an edge sliver.
  double min_covisibility = 0.05;
  // An accepted pair is wrong when fewer than this fraction of its inliers
  // agree with the ground truth, in [0, 1]. Default 0.5.
  double min_inlier_agreement = 0.5;
  // Threads over pairs; <= 0: all. Default 2.
  int num_threads = 2;

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }
};

// Nearest-hit ray casting against the quads of a scene (both sides of every
// quad are surfaces).
class SceneRayCaster {
 public:
  explicit SceneRayCaster(const SceneStructure& structure);

  // Distance along the unit `direction` from `origin` to the nearest quad
  // hit farther than 1e-6 m; nullopt if the ray hits nothing.
  std::optional<double> Cast(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction) const;
  // No quad lies between `centre` and `point` (see PairTruthOptions for the
  // tolerance).
  bool Unoccluded(const Eigen::Vector3d& centre, const Eigen::Vector3d& point,
                  const PairTruthOptions& options) const;

 private:
  struct Quad {
    Eigen::Vector3d origin;
    Eigen::Vector3d normal;             // unit
    Eigen::Matrix<double, 2, 3> to_uv;  // (point - origin) -> (a, b)
  };
  std::vector<Quad> quads_;
};

// One frame with a ground-truth camera pose.
struct PairTruthFrame {
  std::string name;  // database image name (the image file name)
  timestamp_ns_t timestamp_ns = 0;
  Rigid3d cam_from_world;
};

class PairTruthLabeller {
 public:
  PairTruthLabeller(const SceneStructure& structure, const Camera& camera,
                    std::vector<PairTruthFrame> frames, const PairTruthOptions& options);

  // Reads <folder>/scene.csv and the EuRoC sequence in <folder> (camera,
  // body_from_cam, ground truth at the image stamps). Throws InputError for
  // a missing scene.csv or ground truth, or an image without a ground-truth
  // state within 1 ms.
  static PairTruthLabeller FromSimulation(const std::filesystem::path& folder,
                                          const PairTruthOptions& options);

  const PairTruthOptions& options() const { return options_; }
  const Camera& camera() const { return camera_; }
  const std::vector<PairTruthFrame>& frames() const { return frames_; }
  // Index of the frame with this database image name.
  std::optional<size_t> FindFrame(const std::string& name) const;

  // Fraction of frame1's grid pixels whose surface point frame2 sees.
  double DirectedCovisibility(size_t frame1, size_t frame2) const;
  // max(DirectedCovisibility(1, 2), DirectedCovisibility(2, 1)).
  double Covisibility(size_t frame1, size_t frame2) const;
  // Fraction of `matches` (into the keypoints, in pixels of this camera)
  // that agree with the ground truth; NaN when there are none.
  double MatchAgreement(size_t frame1, size_t frame2, const FeatureKeypoints& keypoints1,
                        const FeatureKeypoints& keypoints2, const FeatureMatches& matches) const;

 private:
  // The surface point of a pixel of frame `index`, if its ray hits.
  std::optional<Eigen::Vector3d> SurfacePoint(size_t index, const Eigen::Vector2d& pixel) const;
  // `point` projects inside frame `index`'s image and is unoccluded; the
  // pixel.
  std::optional<Eigen::Vector2d> VisiblePixel(size_t index, const Eigen::Vector3d& point) const;

  PairTruthOptions options_;
  Camera camera_;
  std::vector<PairTruthFrame> frames_;
  SceneRayCaster caster_;
  std::unordered_map<std::string, size_t> index_by_name_;
  // Per frame: the surface points of its grid pixels (rays that hit).
  std::vector<std::vector<Eigen::Vector3d>> grid_points_;
  std::vector<size_t> grid_size_;  // grid pixels per frame (hit or not)
};

// The ground-truth label of one verified pair of one run.
struct PairTruthLabel {
  double covisibility = 0.0;
  bool correct = false;  // covisibility >= min_covisibility
  // Of the stored inliers of an accepted pair (NaN if not accepted).
  double inlier_agreement = std::numeric_limits<double>::quiet_NaN();
  bool accepted_wrong = false;  // accepted, agreement < min_inlier_agreement
};

// One verification run to evaluate: its pair decisions (pairs.csv) and the
// database holding its inliers.
struct VerificationRunInput {
  std::string name;  // e.g. the report folder
  std::vector<PairDecision> decisions;
  std::filesystem::path database;
};

// Evaluates the runs against the labeller's ground truth. The first run is
// the baseline (RANSAC only) for the recall. Throws InputError for a pair
// whose image has no ground-truth frame or a missing database.
std::vector<VerificationTruthSummary> EvaluateVerificationRuns(
    const PairTruthLabeller& labeller, const std::vector<VerificationRunInput>& runs);

// A text table of the summaries, one row a run.
std::string FormatVerificationTruthTable(const std::vector<VerificationTruthSummary>& summaries);

}  // namespace viosfm

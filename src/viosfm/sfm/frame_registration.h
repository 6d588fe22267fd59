// Verified registration of one frame into the batched mapper's model: its
// pose predicted by the VIO (relative to a registered frame of the same VIO
// segment) is checked against its 2D-3D matches (PnP-RANSAC seeded by the
// prediction, estimators/absolute_pose.h). A prediction the images confirm
// is kept; one they contradict is replaced by the images' pose; a frame
// without a prediction (no VIO pose, or the first frame of a VIO segment
// after a re-initialisation) is registered from the images when they allow.
// After mapping, a frame's pose is "supported by the images" when enough of
// its observations of well-established points (seen by at least two other
// frames) reproject closely.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "viosfm/estimators/absolute_pose.h"
#include "viosfm/scene/features.h"
#include "viosfm/scene/reconstruction.h"
#include "viosfm/sfm/tracks.h"
#include "viosfm/util/option_fields.h"

namespace viosfm {

struct FrameRegistrationOptions {
  // Check every VIO-placed frame against its 2D-3D matches and register
  // frames without a usable VIO prediction from them. Default true; false:
  // the paper's placement by the VIO alone (frames without a VIO pose, or
  // in a VIO segment not yet joined, are then left out).
  bool verify_with_images = true;
  // PnP-RANSAC (8 px, at least 15 inliers).
  AbsolutePoseOptions pnp;
  // PnP is tried with at least this many 2D-3D matches. Default 20.
  int min_num_correspondences = 20;
  // How a frame with a VIO prediction and a PnP pose is placed:
  //  - the prediction stands (kVioVerified) when it has at least
  //    pnp.min_num_inliers inliers and at least min_predicted_inlier_ratio
  //    of the PnP pose's (within pnp.max_error_px);
  //  - otherwise the PnP pose replaces it (kImagesReposed) when it has at
  //    least min_reposing_inliers inliers and lies within the drift the VIO
  //    model allows since the reference frame (break_sigmas standard
  //    deviations plus the floors below, for the PnP's own error): the
  //    images refine a drifted prediction;
  //  - a PnP pose beyond that drift replaces the prediction only when the
  //    prediction has fewer than pnp.min_num_inliers inliers, the PnP pose
  //    at least twice min_reposing_inliers, and the frame's verified matches
  //    with the registered frames do not show the prediction clearly better
  //    than the PnP pose (more than twice as many of them fitting it,
  //    CountExplainedPairMatches within support_max_error_px):
  //    the VIO jumped (a reset the stamps do not show); no relative-pose
  //    prior crosses such a break and later frames are predicted from the
  //    images' pose;
  //  - otherwise (a weak PnP, or an ambiguous one: repeated structure, where
  //    the images support the prediction and another pose far from it) the
  //    prediction stands.
  // Defaults 0.7, 30, 5, 0.1 m and 0.05 rad: a weak PnP in a textureless
  // stretch, or a strong one on the next identical door, can be far off a
  // correct VIO, and the frame's own matches tell a look-alike place from a
  // VIO jump. See docs/history/benchmarks-2026.md, section
  // "A look-alike place is not a VIO jump".
  double min_predicted_inlier_ratio = 0.7;
  int min_reposing_inliers = 30;
  double break_sigmas = 5.0;
  double break_min_translation_m = 0.1;
  double break_min_rotation_rad = 0.05;
  // A frame is supported by the images with at least this many observations
  // (of points seen by two or more other frames) within support_max_error_px.
  // Defaults 15 and 4 px.
  int min_supporting_observations = 15;
  double support_max_error_px = 4.0;
  // After each batch's adjustment, a second look at the frames placed by the
  // VIO alone that the images do not support (the gauge frame, a first
  // batch's frames, frames registered before their points existed): their
  // 2D-3D matches against the adjusted model, re-posed from them under the
  // rules above (at least min_reposing_inliers inliers, within the drift).
  // Default true: on real photos with a drifting VIO the gauge frame is
  // otherwise left where the VIO put it and the whole model leans on it.
  // See docs/benchmarks.md, section "Real photos with a drifting VIO: Strecha's fountain-P11".
  bool recheck_after_adjustment = true;

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }

  // Of pnp only max_error_px and min_num_inliers are options of a run.
  template <class Self, class Visitor>
  static void VisitFields(Self& self, Visitor&& visit) {
    visit({"verify_with_images", "check each frame's VIO pose against the model", kRunOnly},
          self.verify_with_images);
    visit({"pnp.max_error_px", "px, PnP RANSAC inlier threshold", kRunOnly}, self.pnp.max_error_px);
    visit({"pnp.min_num_inliers", "PnP inliers needed", kRunOnly}, self.pnp.min_num_inliers);
    visit({"min_num_correspondences", "2D-3D correspondences needed to check a frame", kRunOnly},
          self.min_num_correspondences);
    visit({"min_predicted_inlier_ratio", "the VIO pose is kept above this inlier ratio", kRunOnly},
          self.min_predicted_inlier_ratio);
    visit({"min_reposing_inliers", "PnP inliers needed to re-pose a frame", kRunOnly},
          self.min_reposing_inliers);
    visit({"break_sigmas", "sigmas of the VIO's expected drift that make a break", kRunOnly},
          self.break_sigmas);
    visit({"min_supporting_observations", "observations that support a frame's pose", kRunOnly},
          self.min_supporting_observations);
    visit({"support_max_error_px", "px, largest error of a supporting observation", kRunOnly},
          self.support_max_error_px);
    visit(
        {"recheck_after_adjustment",
         "re-pose frames placed by the VIO alone from the images after each adjustment", kRunOnly},
        self.recheck_after_adjustment);
  }
};

// Where a frame's pose came from.
enum class FramePoseSource {
  kNone,              // not registered
  kVio,               // placed by the VIO (too few 2D-3D matches to check it)
  kVioVerified,       // placed by the VIO, and the images agree
  kImagesReposed,     // the VIO's prediction disagreed with the images: re-posed from them
  kImagesWithoutVio,  // no usable VIO prediction: registered from the images
};
const char* FramePoseSourceName(FramePoseSource source);

// A frame's 2D-3D matches: its keypoints (undistorted normalised
// coordinates) whose tracks have a 3D point in the model, and those points.
struct FrameCorrespondences {
  std::vector<Eigen::Vector2d> points_normalized;
  std::vector<Eigen::Vector3d> points_in_world;
  size_t size() const { return points_normalized.size(); }
};

// The matches of image `image_id` through `tracks` (indices into
// `all_tracks` of the tracks that observe it) to the points of the model's
// registered images.
FrameCorrespondences CollectFrameCorrespondences(const Reconstruction& reconstruction,
                                                 const std::vector<Track>& all_tracks,
                                                 const std::vector<size_t>& tracks,
                                                 image_t image_id);

// The verified two-view matches of image `image_id` with registered images
// (those of `pairs` that hold it) that a pose `cam_from_world` of it
// explains: their Sampson error under the relative pose to the other
// image's model pose is within max_error_px (at the camera's mean focal
// length). A check that needs no 3D point: where a frame's 2D-3D matches
// hold only points of a look-alike place (a wrong pair merged into its
// tracks, so that they all agree on a pose far from the VIO's), its own
// matches to the registered frames it was verified with still tell which
// pose they show. Unaffected by the baseline's length (Sampson errors do
// not change with the scale of the essential matrix); a pose at the other
// image's centre explains none.
int CountExplainedPairMatches(const Reconstruction& reconstruction, image_t image_id,
                              const Rigid3d& cam_from_world,
                              const std::vector<ImagePairMatches>& pairs, double max_error_px);

// Observations of a registered image, of points observed by at least two
// other registered images, that reproject within max_error_px.
int CountSupportingObservations(const Reconstruction& reconstruction, image_t image_id,
                                double max_error_px);

}  // namespace viosfm

// The VIO front end: corners tracked from image to image by pyramidal KLT,
// in the manner of VINS-Mono's feature tracker.
//
// For each image, in order:
//  1. optional contrast equalisation (CLAHE) of dark images;
//  2. KLT tracking of the previous image's corners (seeded by a gyro rotation
//     prior if given), kept only if the backward track returns within
//     max_forward_backward_error_px of the start and the corner stays
//     border_margin_px inside the image;
//  3. RANSAC on an essential (or fundamental) matrix between the undistorted
//     positions (expressed as pixels of a virtual pinhole camera with the
//     camera's mean focal length) removes tracks inconsistent with a rigid
//     motion;
//  4. crowded tracks are thinned (the longer-tracked one of two closer than
//     min_distance_px survives), then new Shi-Tomasi corners are detected
//     (cv::goodFeaturesToTrack) outside discs of radius min_distance_px
//     around the surviving tracks, up to max_num_features in all: the
//     corners spread evenly and no two are closer than min_distance_px;
//  5. the keyframe decision against the last keyframe: mean parallax of the
//     shared tracks >= keyframe_parallax_px, or fewer shared tracks than
//     keyframe_min_tracked_ratio * max_num_features.
//
// Deterministic: the same images give the same output (OpenCV's RANSAC uses
// a fixed seed; nothing else is random).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>
#include <optional>
#include <string>

#include "viosfm/sensor/camera.h"
#include "viosfm/sensor/grey_image.h"
#include "viosfm/util/timestamp.h"
#include "viosfm/vio/frame_features.h"

namespace viosfm {

// When to equalise the image's contrast (CLAHE) before tracking.
enum class ContrastEqualization {
  kNever,
  kAlways,
  // When the image's mean grey level falls below dark_mean_intensity; once
  // on, it stays on until the mean rises above 1.5 x dark_mean_intensity (so
  // that consecutive images are processed alike).
  kWhenDark,
};

struct FeatureTrackerOptions {
  // Corners tracked per image (VINS-Mono: 150); new ones are detected while
  // fewer are tracked.
  int max_num_features = 150;
  // px, minimum distance between two corners of an image (VINS-Mono: 30).
  double min_distance_px = 30.0;
  // Shi-Tomasi quality: corners weaker than this fraction of the image's
  // strongest are not detected (default 0.01).
  double min_corner_quality = 0.01;
  // Pyramid level of the tracked image on which new corners are detected: 0
  // the tracked image, 1 (default) half its resolution, 4x cheaper; KLT then
  // refines them on the tracked image.
  int detection_pyramid_level = 1;
  // px, corners closer to the image border are not detected and tracks that
  // come closer are dropped (default 5).
  int border_margin_px = 5;

  // Pyramid level of the image KLT tracks on: 0 the full image, -1 (default)
  // the level whose focal length is nearest kReferenceFocalLengthPx (a 906 px
  // camera tracks at half resolution, a 460 px one at full), where the
  // window and the pyramid span the scene they were chosen for at a quarter
  // of the pixels. Corner positions are always given in full-image pixels.
  int tracking_pyramid_level = -1;
  // px at kReferenceFocalLengthPx (frame_features.h), side of the KLT window
  // (odd, default 21; scaled with the focal length of the tracked level and
  // rounded to odd).
  int klt_window_size = 21;
  // Pyramid levels above the tracked image (default 3, as VINS-Mono).
  int klt_max_level = 3;
  // Pyramid levels of the backward track of the forward-backward check
  // (default 1, as VINS-Mono: it starts where the corner was, so it needs
  // little range).
  int klt_backward_max_level = 1;
  // Iteration limit and stopping step (px) of KLT at each level (defaults 30
  // and 0.01 px).
  int klt_max_iterations = 30;
  double klt_epsilon_px = 0.01;
  // px, forward-backward check: a track is dropped if tracking it back into
  // the previous image lands farther than this from where it started
  // (default 0.5 px, as VINS-Mono).
  double max_forward_backward_error_px = 0.5;

  // RANSAC between consecutive images (default on), on the essential matrix
  // (5-point, calibrated: default) or on the fundamental matrix (7/8-point,
  // as VINS-Mono) of the undistorted points.
  bool ransac = true;
  bool ransac_essential = true;
  // px at kReferenceFocalLengthPx, RANSAC inlier threshold (distance to the
  // epipolar line) between the undistorted positions (default 1 px, as
  // VINS-Mono, whose virtual camera this is).
  double ransac_threshold_px = 1.0;
  double ransac_confidence = 0.99;  // default 0.99
  // RANSAC runs only with at least this many tracks (default 15; fewer are
  // kept as they are).
  int ransac_min_tracks = 15;

  // Contrast equalisation (default kWhenDark) with its CLAHE parameters.
  ContrastEqualization equalization = ContrastEqualization::kWhenDark;
  double dark_mean_intensity = 50.0;  // grey levels (0-255), default 50
  double clahe_clip_limit = 3.0;      // default 3
  int clahe_tile_grid_size = 8;       // tiles per image side, default 8

  // Keyframe when the mean parallax (px at kReferenceFocalLengthPx) of the
  // tracks shared with the last keyframe reaches this (default 10 px, as
  // VINS-Mono) ...
  double keyframe_parallax_px = 10.0;
  // ... or fewer than this fraction of max_num_features are shared with it
  // (default 0.5).
  double keyframe_min_tracked_ratio = 0.5;

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }
};

class FeatureTracker {
 public:
  // Throws InputError if the options are invalid or the camera model cannot
  // project.
  FeatureTracker(const Camera& camera, const FeatureTrackerOptions& options);
  ~FeatureTracker();
  FeatureTracker(FeatureTracker&&) noexcept;
  FeatureTracker& operator=(FeatureTracker&&) noexcept;

  // Tracks the previous image's corners into `image` and tops them up with
  // new ones. Images must come in order of time. An empty image (0 x 0)
  // returns no features and ends every track; an image whose size differs
  // from the camera's throws InputError.
  FrameFeatures Track(timestamp_ns_t timestamp_ns, const GreyImage& image);
  // As above; rotation_prior (cam_now_from_cam_prev, e.g. integrated gyro)
  // predicts where each corner moves, which seeds KLT.
  FrameFeatures Track(timestamp_ns_t timestamp_ns, const GreyImage& image,
                      const std::optional<Eigen::Quaterniond>& rotation_prior);

  const FeatureTrackerOptions& options() const;
  const Camera& camera() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace viosfm

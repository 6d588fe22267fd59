#include "viosfm/vio/feature_tracker.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>
#include <sstream>
#include <unordered_map>
#include <utility>
#include <vector>

#include "viosfm/sensor/camera_models.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/logging.h"

namespace viosfm {

std::string FeatureTrackerOptions::Validate() const {
  if (max_num_features < 1) return "max_num_features must be >= 1";
  if (!(min_distance_px >= 1.0)) return "min_distance_px must be >= 1";
  if (!(min_corner_quality > 0.0 && min_corner_quality < 1.0)) {
    return "min_corner_quality must be in (0, 1)";
  }
  if (border_margin_px < 0) return "border_margin_px must be >= 0";
  if (detection_pyramid_level < 0 || detection_pyramid_level > klt_max_level) {
    return "detection_pyramid_level must be in [0, klt_max_level]";
  }
  if (tracking_pyramid_level < -1 || tracking_pyramid_level > 3) {
    return "tracking_pyramid_level must be in [-1, 3] (-1: chosen by the focal length)";
  }
  if (klt_window_size < 3 || klt_window_size % 2 == 0) {
    return "klt_window_size must be odd and >= 3";
  }
  if (klt_max_level < 0 || klt_max_level > 8) return "klt_max_level must be in [0, 8]";
  if (klt_backward_max_level < 0 || klt_backward_max_level > klt_max_level) {
    return "klt_backward_max_level must be in [0, klt_max_level]";
  }
  if (klt_max_iterations < 1) return "klt_max_iterations must be >= 1";
  if (!(klt_epsilon_px > 0.0)) return "klt_epsilon_px must be > 0";
  if (!(max_forward_backward_error_px > 0.0)) return "max_forward_backward_error_px must be > 0";
  if (!(ransac_threshold_px > 0.0)) return "ransac_threshold_px must be > 0";
  if (!(ransac_confidence > 0.0 && ransac_confidence < 1.0)) {
    return "ransac_confidence must be in (0, 1)";
  }
  if (ransac_min_tracks < 8) return "ransac_min_tracks must be >= 8";
  if (!(dark_mean_intensity >= 0.0 && dark_mean_intensity <= 255.0)) {
    return "dark_mean_intensity must be in [0, 255]";
  }
  if (!(clahe_clip_limit > 0.0)) return "clahe_clip_limit must be > 0";
  if (clahe_tile_grid_size < 1) return "clahe_tile_grid_size must be >= 1";
  if (!(keyframe_parallax_px > 0.0)) return "keyframe_parallax_px must be > 0";
  if (!(keyframe_min_tracked_ratio >= 0.0 && keyframe_min_tracked_ratio <= 1.0)) {
    return "keyframe_min_tracked_ratio must be in [0, 1]";
  }
  return "";
}

namespace {

// A corner followed from image to image.
struct TrackedCorner {
  uint64_t track_id = 0;
  cv::Point2f pixel;
  Eigen::Vector2d normalized = Eigen::Vector2d::Zero();
  int track_length = 1;
};

// Squared-distance lookups among points on a grid of cells of side `radius`:
// whether some inserted point lies closer than `radius` to a query point.
class ProximityGrid {
 public:
  ProximityGrid(int width, int height, double radius)
      : radius_sq_(radius * radius),
        cell_(radius),
        cols_(std::max(1, static_cast<int>(std::ceil(width / radius)) + 1)),
        rows_(std::max(1, static_cast<int>(std::ceil(height / radius)) + 1)),
        cells_(static_cast<size_t>(cols_) * rows_) {}

  bool HasPointCloserThanRadius(const cv::Point2f& p) const {
    const int cx = CellX(p.x);
    const int cy = CellY(p.y);
    for (int y = std::max(0, cy - 1); y <= std::min(rows_ - 1, cy + 1); ++y) {
      for (int x = std::max(0, cx - 1); x <= std::min(cols_ - 1, cx + 1); ++x) {
        for (const cv::Point2f& q : cells_[static_cast<size_t>(y) * cols_ + x]) {
          const double dx = static_cast<double>(p.x) - q.x;
          const double dy = static_cast<double>(p.y) - q.y;
          if (dx * dx + dy * dy < radius_sq_) return true;
        }
      }
    }
    return false;
  }
  void Insert(const cv::Point2f& p) {
    cells_[static_cast<size_t>(CellY(p.y)) * cols_ + CellX(p.x)].push_back(p);
  }

 private:
  int CellX(float x) const { return std::clamp(static_cast<int>(x / cell_), 0, cols_ - 1); }
  int CellY(float y) const { return std::clamp(static_cast<int>(y / cell_), 0, rows_ - 1); }
  double radius_sq_;
  double cell_;
  int cols_;
  int rows_;
  std::vector<std::vector<cv::Point2f>> cells_;
};

template <typename T>
void KeepWhere(const std::vector<uint8_t>& keep, std::vector<T>* values) {
  size_t j = 0;
  for (size_t i = 0; i < values->size(); ++i) {
    if (keep[i]) (*values)[j++] = std::move((*values)[i]);
  }
  values->resize(j);
}

}  // namespace

struct FeatureTracker::State {
  Camera camera;
  FeatureTrackerOptions options;
  int width = 0;
  int height = 0;
  // The camera's mean focal length over kReferenceFocalLengthPx.
  double pixel_scale = 1.0;
  // The tracked image is the full image reduced tracking_level times by two:
  // a full-image pixel p is at p / tracking_scale on it.
  int tracking_level = 0;
  float tracking_scale = 1.0f;
  cv::Ptr<cv::CLAHE> clahe;

  // The previous image: its pyramid (with derivatives), the raw image (to
  // rebuild the pyramid if the equalisation switches), its corners.
  bool has_previous = false;
  bool equalizing = false;          // kWhenDark's state
  bool previous_equalized = false;  // whether previous_pyramid was equalised
  cv::Mat previous_raw;
  std::vector<cv::Mat> previous_pyramid;
  std::vector<TrackedCorner> corners;
  uint64_t next_track_id = 0;
  timestamp_ns_t last_timestamp_ns = 0;
  bool has_timestamp = false;

  // Pixel positions of the last keyframe's corners by track id.
  bool has_keyframe = false;
  std::unordered_map<uint64_t, Eigen::Vector2d> keyframe_pixels;

  cv::Size WindowSize() const {
    const int side =
        2 * static_cast<int>(
                std::lround(0.5 * (options.klt_window_size * pixel_scale / tracking_scale - 1.0))) +
        1;
    return {std::max(3, side), std::max(3, side)};
  }

  bool InsideBorder(const cv::Point2f& p) const {
    const float m = static_cast<float>(options.border_margin_px);
    return p.x >= m && p.y >= m && p.x <= static_cast<float>(width - 1) - m &&
           p.y <= static_cast<float>(height - 1) - m;
  }

  // Whether the image should be equalised, updating the hysteresis state.
  bool DecideEqualization(const cv::Mat& raw) {
    switch (options.equalization) {
      case ContrastEqualization::kNever: return false;
      case ContrastEqualization::kAlways: return true;
      case ContrastEqualization::kWhenDark: break;
    }
    const double mean = cv::mean(raw)[0];
    if (equalizing) {
      if (mean > 1.5 * options.dark_mean_intensity) equalizing = false;
    } else if (mean < options.dark_mean_intensity) {
      equalizing = true;
    }
    return equalizing;
  }

  // The pyramid of the tracked image: `raw` reduced tracking_level times,
  // equalised if asked, then klt_max_level levels with their derivatives.
  void BuildPyramid(const cv::Mat& raw, bool equalize, std::vector<cv::Mat>* pyramid) {
    cv::Mat reduced = raw;
    for (int level = 0; level < tracking_level; ++level) {
      cv::Mat half;
      cv::pyrDown(reduced, half);
      reduced = half;
    }
    // A fresh output: CLAHE must not write into `raw` (the caller's pixels).
    cv::Mat processed;
    if (equalize) {
      clahe->apply(reduced, processed);
    } else {
      processed = reduced;
    }
    cv::buildOpticalFlowPyramid(processed, *pyramid, WindowSize(), options.klt_max_level,
                                /*withDerivatives=*/true, cv::BORDER_REFLECT_101,
                                cv::BORDER_CONSTANT, /*tryReuseInputImage=*/false);
  }

  // Undistorted normalised coordinates of a pixel; nullopt where undefined.
  std::optional<Eigen::Vector2d> Normalize(const cv::Point2f& p) const {
    const Eigen::Vector2d n = ImageToCam(camera, Eigen::Vector2d(p.x, p.y));
    if (!n.allFinite()) return std::nullopt;
    return n;
  }

  // Step 2: KLT with the forward-backward check; replaces `corners` by the
  // survivors at their new positions.
  void TrackCorners(const std::vector<cv::Mat>& pyramid, const cv::Mat& raw, bool equalize,
                    const std::optional<Eigen::Quaterniond>& rotation_prior) {
    if (corners.empty()) return;
    const float to_level = 1.0f / tracking_scale;
    std::vector<cv::Point2f> previous(corners.size());
    for (size_t i = 0; i < corners.size(); ++i) previous[i] = corners[i].pixel * to_level;
    std::vector<cv::Point2f> current = previous;
    if (rotation_prior) {
      const Eigen::Matrix3d rotation = rotation_prior->normalized().toRotationMatrix();
      for (size_t i = 0; i < corners.size(); ++i) {
        const Eigen::Vector3d ray = rotation * corners[i].normalized.homogeneous();
        if (ray.z() < 1e-3) continue;
        const Eigen::Vector2d predicted = CamToImage(camera, ray.hnormalized());
        const cv::Point2f p(static_cast<float>(predicted.x()), static_cast<float>(predicted.y()));
        if (predicted.allFinite() && InsideBorder(p)) current[i] = p * to_level;
      }
    }
    const cv::TermCriteria criteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS,
                                    options.klt_max_iterations, options.klt_epsilon_px);
    std::vector<uint8_t> forward_ok;
    std::vector<float> errors;
    cv::calcOpticalFlowPyrLK(previous_pyramid, pyramid, previous, current, forward_ok, errors,
                             WindowSize(), options.klt_max_level, criteria,
                             cv::OPTFLOW_USE_INITIAL_FLOW);
    std::vector<cv::Point2f> back = previous;
    std::vector<uint8_t> backward_ok;
    cv::calcOpticalFlowPyrLK(pyramid, previous_pyramid, current, back, backward_ok, errors,
                             WindowSize(), options.klt_backward_max_level, criteria,
                             cv::OPTFLOW_USE_INITIAL_FLOW);
    // The forward-backward check compares the level's own tracks; only then
    // are the forward ones refined.
    if (tracking_level > 0 && !equalize) RefineOnFullImage(raw, forward_ok, &current);
    const double max_fb_sq =
        options.max_forward_backward_error_px * options.max_forward_backward_error_px;
    std::vector<uint8_t> keep(corners.size(), 0);
    for (size_t i = 0; i < corners.size(); ++i) {
      if (!forward_ok[i] || !backward_ok[i]) continue;
      const cv::Point2f pixel = current[i] * tracking_scale;
      if (!InsideBorder(pixel)) continue;
      const double dx = (static_cast<double>(back[i].x) - previous[i].x) * tracking_scale;
      const double dy = (static_cast<double>(back[i].y) - previous[i].y) * tracking_scale;
      if (dx * dx + dy * dy > max_fb_sq) continue;
      const std::optional<Eigen::Vector2d> normalized = Normalize(pixel);
      if (!normalized) continue;
      corners[i].pixel = pixel;
      corners[i].normalized = *normalized;
      ++corners[i].track_length;
      keep[i] = 1;
    }
    KeepWhere(keep, &corners);
  }

  // Step 2b, when tracking on a reduced level: the tracked positions refined
  // on the full images by KLT on that level alone, which gives back the full
  // image's precision; a refinement that fails or moves a corner by more
  // than a reduced pixel is not taken.
  void RefineOnFullImage(const cv::Mat& raw, const std::vector<uint8_t>& tracked,
                         std::vector<cv::Point2f>* current_at_level) {
    std::vector<cv::Point2f> previous(corners.size());
    std::vector<cv::Point2f> refined(corners.size());
    for (size_t i = 0; i < corners.size(); ++i) {
      previous[i] = corners[i].pixel;
      refined[i] = (*current_at_level)[i] * tracking_scale;
    }
    const std::vector<cv::Point2f> start = refined;
    const cv::TermCriteria criteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS,
                                    options.klt_max_iterations, options.klt_epsilon_px);
    std::vector<uint8_t> ok;
    std::vector<float> errors;
    cv::calcOpticalFlowPyrLK(previous_raw, raw, previous, refined, ok, errors, WindowSize(), 0,
                             criteria, cv::OPTFLOW_USE_INITIAL_FLOW);
    const double max_move_sq = static_cast<double>(tracking_scale) * tracking_scale;
    for (size_t i = 0; i < corners.size(); ++i) {
      if (!tracked[i] || !ok[i]) continue;
      const double dx = static_cast<double>(refined[i].x) - start[i].x;
      const double dy = static_cast<double>(refined[i].y) - start[i].y;
      if (dx * dx + dy * dy > max_move_sq) continue;
      (*current_at_level)[i] = refined[i] * (1.0f / tracking_scale);
    }
  }

  // Step 3: essential- or fundamental-matrix RANSAC between the previous and the current
  // undistorted positions. `previous_normalized` is aligned with `corners`.
  void RejectOutliers(const std::vector<Eigen::Vector2d>& previous_normalized) {
    if (!options.ransac || static_cast<int>(corners.size()) < options.ransac_min_tracks) return;
    const double cx = 0.5 * (width - 1);
    const double cy = 0.5 * (height - 1);
    std::vector<cv::Point2f> a(corners.size());
    std::vector<cv::Point2f> b(corners.size());
    for (size_t i = 0; i < corners.size(); ++i) {
      a[i] = cv::Point2f(
          static_cast<float>(kReferenceFocalLengthPx * previous_normalized[i].x() + cx),
          static_cast<float>(kReferenceFocalLengthPx * previous_normalized[i].y() + cy));
      b[i] =
          cv::Point2f(static_cast<float>(kReferenceFocalLengthPx * corners[i].normalized.x() + cx),
                      static_cast<float>(kReferenceFocalLengthPx * corners[i].normalized.y() + cy));
    }
    std::vector<uint8_t> inliers;
    const cv::Mat model =
        options.ransac_essential
            ? cv::findEssentialMat(a, b, kReferenceFocalLengthPx, cv::Point2d(cx, cy), cv::RANSAC,
                                   options.ransac_confidence, options.ransac_threshold_px, inliers)
            : cv::findFundamentalMat(a, b, cv::FM_RANSAC, options.ransac_threshold_px,
                                     options.ransac_confidence, inliers);
    // No model (degenerate input): keep the tracks rather than drop them all.
    if (model.empty() || inliers.size() != corners.size()) return;
    KeepWhere(inliers, &corners);
  }

  // Step 4a: of two tracks closer than min_distance_px, the longer one stays
  // (ties: the older id).
  void ThinCrowdedTracks(ProximityGrid* grid) {
    std::vector<size_t> order(corners.size());
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](size_t i, size_t j) {
      if (corners[i].track_length != corners[j].track_length) {
        return corners[i].track_length > corners[j].track_length;
      }
      return corners[i].track_id < corners[j].track_id;
    });
    std::vector<uint8_t> keep(corners.size(), 0);
    for (const size_t i : order) {
      if (grid->HasPointCloserThanRadius(corners[i].pixel)) continue;
      grid->Insert(corners[i].pixel);
      keep[i] = 1;
    }
    KeepWhere(keep, &corners);
  }

  // Step 4b: new corners away from the tracked ones, detected on pyramid
  // level detection_pyramid_level of the tracked image (its pyramid
  // alternates image and derivative levels).
  void DetectNewCorners(const std::vector<cv::Mat>& pyramid, ProximityGrid* grid) {
    const int wanted = options.max_num_features - static_cast<int>(corners.size());
    if (wanted <= 0) return;
    const int level =
        std::min(options.detection_pyramid_level, static_cast<int>(pyramid.size() / 2) - 1);
    const cv::Mat& image = pyramid[2 * level];
    const float scale = tracking_scale * static_cast<float>(1 << level);
    const int margin = static_cast<int>(std::ceil(options.border_margin_px / scale));
    if (image.cols <= 2 * margin || image.rows <= 2 * margin) return;
    cv::Mat mask(image.rows, image.cols, CV_8UC1, cv::Scalar(0));
    mask(cv::Rect(margin, margin, image.cols - 2 * margin, image.rows - 2 * margin)).setTo(255);
    const int radius = static_cast<int>(std::ceil(options.min_distance_px / scale));
    for (const TrackedCorner& corner : corners) {
      cv::circle(mask, cv::Point(cvRound(corner.pixel.x / scale), cvRound(corner.pixel.y / scale)),
                 radius, cv::Scalar(0), cv::FILLED);
    }
    std::vector<cv::Point2f> detected;
    cv::goodFeaturesToTrack(image, detected, wanted, options.min_corner_quality,
                            options.min_distance_px / scale, mask, /*blockSize=*/3);
    for (const cv::Point2f& detected_at_level : detected) {
      const cv::Point2f p = detected_at_level * scale;
      if (!InsideBorder(p) || grid->HasPointCloserThanRadius(p)) continue;
      const std::optional<Eigen::Vector2d> normalized = Normalize(p);
      if (!normalized) continue;
      grid->Insert(p);
      TrackedCorner corner;
      corner.track_id = next_track_id++;
      corner.pixel = p;
      corner.normalized = *normalized;
      corners.push_back(corner);
    }
  }

  // Step 5.
  void DecideKeyframe(FrameFeatures* frame) {
    double parallax_sum = 0.0;
    int shared = 0;
    for (const FeatureObservation& observation : frame->observations) {
      const auto it = keyframe_pixels.find(observation.track_id);
      if (it == keyframe_pixels.end()) continue;
      parallax_sum += (observation.pixel - it->second).norm();
      ++shared;
    }
    frame->num_tracked_from_keyframe = shared;
    frame->parallax_px = shared > 0 ? parallax_sum / shared : 0.0;
    if (frame->observations.empty()) {
      frame->is_keyframe = false;
    } else if (!has_keyframe) {
      frame->is_keyframe = true;
    } else {
      frame->is_keyframe = frame->parallax_px >= options.keyframe_parallax_px * pixel_scale ||
                           shared < options.keyframe_min_tracked_ratio * options.max_num_features;
    }
    if (frame->is_keyframe) {
      has_keyframe = true;
      keyframe_pixels.clear();
      for (const FeatureObservation& observation : frame->observations) {
        keyframe_pixels.emplace(observation.track_id, observation.pixel);
      }
    }
  }
};

FeatureTracker::FeatureTracker(const Camera& camera, const FeatureTrackerOptions& options)
    : state_(std::make_unique<State>()) {
  const std::string error = options.Validate();
  if (!error.empty()) throw InputError("feature tracker options: " + error);
  if (!IsCameraModelSupported(camera.model_id)) {
    throw InputError(UnsupportedCameraModelMessage(camera.model_id));
  }
  state_->camera = camera;
  state_->options = options;
  state_->width = static_cast<int>(camera.width);
  state_->height = static_cast<int>(camera.height);
  state_->pixel_scale = MeanFocalLength(camera) / kReferenceFocalLengthPx;
  state_->tracking_level = options.tracking_pyramid_level;
  if (state_->tracking_level < 0) {
    // The level nearest the reference focal length, keeping 160 px of width.
    state_->tracking_level =
        std::max(0, static_cast<int>(std::lround(std::log2(std::max(1.0, state_->pixel_scale)))));
    while (state_->tracking_level > 0 && (state_->width >> state_->tracking_level) < 160) {
      --state_->tracking_level;
    }
  }
  state_->tracking_scale = static_cast<float>(1 << state_->tracking_level);
  state_->clahe = cv::createCLAHE(options.clahe_clip_limit, cv::Size(options.clahe_tile_grid_size,
                                                                     options.clahe_tile_grid_size));
}

FeatureTracker::~FeatureTracker() = default;
FeatureTracker::FeatureTracker(FeatureTracker&&) noexcept = default;
FeatureTracker& FeatureTracker::operator=(FeatureTracker&&) noexcept = default;

const FeatureTrackerOptions& FeatureTracker::options() const {
  return state_->options;
}
const Camera& FeatureTracker::camera() const {
  return state_->camera;
}

FrameFeatures FeatureTracker::Track(timestamp_ns_t timestamp_ns, const GreyImage& image) {
  return Track(timestamp_ns, image, std::nullopt);
}

FrameFeatures FeatureTracker::Track(timestamp_ns_t timestamp_ns, const GreyImage& image,
                                    const std::optional<Eigen::Quaterniond>& rotation_prior) {
  State& s = *state_;
  if (s.has_timestamp && timestamp_ns <= s.last_timestamp_ns) {
    std::ostringstream what;
    what << "feature tracker: image stamp " << timestamp_ns << " ns is not after the previous "
         << s.last_timestamp_ns << " ns";
    throw InputError(what.str());
  }
  s.has_timestamp = true;
  s.last_timestamp_ns = timestamp_ns;

  FrameFeatures frame;
  frame.timestamp_ns = timestamp_ns;
  if (image.empty() || image.width == 0 || image.height == 0) {
    s.has_previous = false;
    s.corners.clear();
    return frame;
  }
  if (image.width != s.width || image.height != s.height) {
    std::ostringstream what;
    what << "feature tracker: image at " << timestamp_ns << " ns is " << image.width << "x"
         << image.height << " px, expected the camera's " << s.width << "x" << s.height;
    throw InputError(what.str());
  }
  VIOSFM_CHECK_EQ(image.pixels.size(), static_cast<size_t>(image.width) * image.height);

  const cv::Mat raw(image.height, image.width, CV_8UC1, const_cast<uint8_t*>(image.pixels.data()));
  const bool equalize = s.DecideEqualization(raw);
  std::vector<cv::Mat> pyramid;
  s.BuildPyramid(raw, equalize, &pyramid);

  if (s.has_previous) {
    if (equalize != s.previous_equalized) {
      // Both images must be processed alike for KLT's brightness constancy.
      s.BuildPyramid(s.previous_raw, equalize, &s.previous_pyramid);
    }
    std::unordered_map<uint64_t, Eigen::Vector2d> previous_normalized_by_id;
    previous_normalized_by_id.reserve(s.corners.size());
    for (const TrackedCorner& corner : s.corners) {
      previous_normalized_by_id.emplace(corner.track_id, corner.normalized);
    }
    const size_t num_before = s.corners.size();
    s.TrackCorners(pyramid, raw, equalize, rotation_prior);
    const size_t num_tracked = s.corners.size();
    std::vector<Eigen::Vector2d> previous_normalized(s.corners.size());
    for (size_t i = 0; i < s.corners.size(); ++i) {
      previous_normalized[i] = previous_normalized_by_id.at(s.corners[i].track_id);
    }
    s.RejectOutliers(previous_normalized);
    VIOSFM_LOG(DEBUG) << "tracker: " << num_before << " corners, " << num_tracked << " tracked, "
                      << s.corners.size() << " after RANSAC";
  } else {
    s.corners.clear();
  }

  ProximityGrid grid(s.width, s.height, s.options.min_distance_px);
  s.ThinCrowdedTracks(&grid);
  s.DetectNewCorners(pyramid, &grid);

  frame.observations.reserve(s.corners.size());
  for (const TrackedCorner& corner : s.corners) {
    FeatureObservation observation;
    observation.track_id = corner.track_id;
    observation.pixel = Eigen::Vector2d(corner.pixel.x, corner.pixel.y);
    observation.normalized = corner.normalized;
    observation.track_length = corner.track_length;
    frame.observations.push_back(observation);
  }
  s.DecideKeyframe(&frame);

  s.previous_raw = raw.clone();
  s.previous_pyramid = std::move(pyramid);
  s.previous_equalized = equalize;
  s.has_previous = true;
  return frame;
}

}  // namespace viosfm

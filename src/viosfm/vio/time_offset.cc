#include "viosfm/vio/time_offset.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <optional>
#include <sstream>
#include <unordered_map>

#include "viosfm/geometry/lie.h"
#include "viosfm/util/errors.h"
#include "viosfm/vio/imu_preintegration.h"

namespace viosfm {
namespace {

// body_from_body_to rotation over [from, to] by midpoint integration of the
// gyro (no bias), readings at the ends interpolated; nullopt without coverage.
std::optional<Eigen::Quaterniond> GyroRotation(const std::vector<ImuSample>& imu,
                                               timestamp_ns_t from, timestamp_ns_t to) {
  if (imu.size() < 2 || to <= from || imu.front().timestamp_ns > from ||
      imu.back().timestamp_ns < to) {
    return std::nullopt;
  }
  auto it =
      std::upper_bound(imu.begin(), imu.end(), from,
                       [](timestamp_ns_t t, const ImuSample& s) { return t < s.timestamp_ns; });
  ImuSample previous = InterpolateImu(*(it - 1), *it, from);
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
  const auto step = [&](const ImuSample& a, const ImuSample& b) {
    const double dt = NsToSeconds(b.timestamp_ns - a.timestamp_ns);
    rotation = rotation * So3Exp(0.5 * (a.gyro + b.gyro) * dt);
  };
  for (; it != imu.end() && it->timestamp_ns < to; ++it) {
    step(previous, *it);
    previous = *it;
  }
  if (it == imu.end()) return std::nullopt;
  step(previous, InterpolateImu(previous, *it, to));
  return rotation.normalized();
}

// The corners tracked in both frames of a pair: rays1 in the first, points2
// in the second.
struct FramePair {
  timestamp_ns_t t1 = 0;
  timestamp_ns_t t2 = 0;
  std::vector<Eigen::Vector3d> rays1;  // normalised (x, y, 1)
  std::vector<Eigen::Vector2d> points2;
};

// Pairs of frames 1 to max_gap apart with at least min_tracks common corners.
std::vector<FramePair> MakePairs(const std::vector<FrameFeatures>& frames, int min_tracks,
                                 int max_gap) {
  std::vector<FramePair> pairs;
  for (size_t k = 0; k + 1 < frames.size(); ++k) {
    std::unordered_map<uint64_t, Eigen::Vector2d> first;
    for (const FeatureObservation& observation : frames[k].observations) {
      first.emplace(observation.track_id, observation.normalized);
    }
    for (size_t j = k + 1; j < frames.size() && j <= k + static_cast<size_t>(max_gap); ++j) {
      FramePair pair;
      pair.t1 = frames[k].timestamp_ns;
      pair.t2 = frames[j].timestamp_ns;
      for (const FeatureObservation& observation : frames[j].observations) {
        const auto it = first.find(observation.track_id);
        if (it == first.end()) continue;
        pair.rays1.push_back(it->second.homogeneous());
        pair.points2.push_back(observation.normalized);
      }
      if (static_cast<int>(pair.rays1.size()) >= min_tracks) pairs.push_back(std::move(pair));
    }
  }
  return pairs;
}

// Mean over the pairs of the median distance (normalised) between the
// gyro-rotated corners of the first frame and the tracked ones of the
// second; pairs without IMU coverage are skipped (nullopt if all are).
std::optional<double> RotationFlowCost(const std::vector<FramePair>& pairs,
                                       const std::vector<ImuSample>& imu,
                                       const Eigen::Quaterniond& body_from_cam,
                                       timestamp_ns_t offset_ns) {
  double sum = 0.0;
  int count = 0;
  std::vector<double> errors;
  for (const FramePair& pair : pairs) {
    const std::optional<Eigen::Quaterniond> body1_from_body2 =
        GyroRotation(imu, pair.t1 + offset_ns, pair.t2 + offset_ns);
    if (!body1_from_body2) continue;
    // cam2_from_cam1 = (cam_from_body * body1_from_body2 * body_from_cam)^-1.
    const Eigen::Matrix3d cam2_from_cam1 =
        (body_from_cam.conjugate() * *body1_from_body2 * body_from_cam)
            .conjugate()
            .toRotationMatrix();
    // Epipolar residuals with the rotation fixed: for the unit translation
    // t, x2^T [t]x R x1 = t . ((R x1) x x2) = t . a. t is the eigenvector of
    // the smallest eigenvalue of sum a a^T (least squares), refitted on the
    // better 70 % of the corners; the pair's cost is the median |t . a|.
    std::vector<Eigen::Vector3d> rows;
    rows.reserve(pair.rays1.size());
    for (size_t i = 0; i < pair.rays1.size(); ++i) {
      const Eigen::Vector3d rotated = cam2_from_cam1 * pair.rays1[i];
      rows.push_back(rotated.cross(pair.points2[i].homogeneous()));
    }
    const auto fit = [](const std::vector<Eigen::Vector3d>& a, const std::vector<size_t>& use) {
      Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
      for (const size_t i : use) normal += a[i] * a[i].transpose();
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(normal);
      return Eigen::Vector3d(solver.eigenvectors().col(0));
    };
    std::vector<size_t> all(rows.size());
    for (size_t i = 0; i < rows.size(); ++i) all[i] = i;
    Eigen::Vector3d t = fit(rows, all);
    errors.clear();
    for (const Eigen::Vector3d& row : rows) errors.push_back(std::abs(t.dot(row)));
    std::vector<size_t> order = all;
    std::sort(order.begin(), order.end(),
              [&](size_t a, size_t b) { return errors[a] < errors[b]; });
    order.resize(std::max<size_t>(5, order.size() * 7 / 10));
    t = fit(rows, order);
    errors.clear();
    for (const Eigen::Vector3d& row : rows) errors.push_back(std::abs(t.dot(row)));
    if (errors.empty()) continue;
    std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
    sum += errors[errors.size() / 2];
    ++count;
  }
  if (count == 0) return std::nullopt;
  return sum / count;
}

}  // namespace

std::string TimeOffsetOptions::Validate() const {
  if (!(max_offset_s > 0)) return "max_offset_s must be > 0";
  if (!(coarse_step_s > 0) || coarse_step_s > max_offset_s) {
    return "coarse_step_s must be in (0, max_offset_s]";
  }
  if (!(fine_step_s > 0) || fine_step_s > coarse_step_s) {
    return "fine_step_s must be in (0, coarse_step_s]";
  }
  if (min_tracks_per_pair < 5) return "min_tracks_per_pair must be >= 5";
  if (max_frame_gap < 1) return "max_frame_gap must be >= 1";
  if (!(min_total_rotation_deg >= 0)) return "min_total_rotation_deg must be >= 0";
  if (!(max_wait_s > 0)) return "max_wait_s must be > 0";
  if (!(min_cost_reduction >= 0) || !(min_cost_reduction < 1)) {
    return "min_cost_reduction must be in [0, 1)";
  }
  return "";
}

double GyroRotationSumDeg(const std::vector<FrameFeatures>& frames,
                          const std::vector<ImuSample>& imu, timestamp_ns_t offset_ns) {
  double sum = 0.0;
  for (size_t k = 0; k + 1 < frames.size(); ++k) {
    const std::optional<Eigen::Quaterniond> rotation = GyroRotation(
        imu, frames[k].timestamp_ns + offset_ns, frames[k + 1].timestamp_ns + offset_ns);
    if (rotation) sum += So3Log(*rotation).norm();
  }
  return sum * 180.0 / M_PI;
}

TimeOffsetEstimate EstimateTimeOffset(const std::vector<FrameFeatures>& frames,
                                      const std::vector<ImuSample>& imu,
                                      const Rigid3d& body_from_cam,
                                      timestamp_ns_t calibration_offset_ns, double focal_length_px,
                                      const TimeOffsetOptions& options) {
  VIOSFM_CHECK(options.Check()) << options.Validate();
  TimeOffsetEstimate estimate;
  estimate.offset_ns = calibration_offset_ns;
  estimate.calibration_offset_ns = calibration_offset_ns;
  const std::vector<FramePair> pairs =
      MakePairs(frames, options.min_tracks_per_pair, options.max_frame_gap);
  estimate.num_pairs = static_cast<int>(pairs.size());
  estimate.total_rotation_deg = GyroRotationSumDeg(frames, imu, calibration_offset_ns);
  const Eigen::Quaterniond& rotation = body_from_cam.rotation;
  const auto cost = [&](timestamp_ns_t offset) {
    return RotationFlowCost(pairs, imu, rotation, offset);
  };
  std::ostringstream message;
  message << std::fixed << std::setprecision(1);
  const std::optional<double> calibration_cost = cost(calibration_offset_ns);
  if (!calibration_cost || pairs.size() < 5) {
    message << "too few tracked frame pairs with IMU (" << pairs.size()
            << "); the calibration's offset is kept";
    estimate.message = message.str();
    return estimate;
  }
  estimate.calibration_cost_px = *calibration_cost * focal_length_px;
  estimate.cost_px = estimate.calibration_cost_px;
  if (estimate.total_rotation_deg < options.min_total_rotation_deg) {
    message << "too little rotation (" << estimate.total_rotation_deg << " deg over "
            << pairs.size() << " frame pairs, " << options.min_total_rotation_deg
            << " needed); the calibration's offset is kept";
    estimate.message = message.str();
    return estimate;
  }

  // Coarse grid, then a fine grid around its best point.
  const timestamp_ns_t range_ns = SecondsToNs(options.max_offset_s);
  const timestamp_ns_t coarse_ns = std::max<timestamp_ns_t>(1, SecondsToNs(options.coarse_step_s));
  const timestamp_ns_t fine_ns = std::max<timestamp_ns_t>(1, SecondsToNs(options.fine_step_s));
  timestamp_ns_t best = calibration_offset_ns;
  double best_cost = *calibration_cost;
  for (timestamp_ns_t d = -range_ns; d <= range_ns; d += coarse_ns) {
    const std::optional<double> c = cost(calibration_offset_ns + d);
    if (c && *c < best_cost) {
      best_cost = *c;
      best = calibration_offset_ns + d;
    }
  }
  const bool at_edge = std::abs(best - calibration_offset_ns) + coarse_ns > range_ns;
  std::vector<std::pair<timestamp_ns_t, double>> fine;
  for (timestamp_ns_t d = -coarse_ns; d <= coarse_ns; d += fine_ns) {
    const std::optional<double> c = cost(best + d);
    if (c) fine.emplace_back(best + d, *c);
  }
  auto min_it = std::min_element(fine.begin(), fine.end(),
                                 [](const auto& a, const auto& b) { return a.second < b.second; });
  timestamp_ns_t refined = min_it->first;
  double refined_cost = min_it->second;
  if (min_it != fine.begin() && min_it + 1 != fine.end()) {
    // Parabola through the best point and its neighbours.
    const double y0 = (min_it - 1)->second;
    const double y1 = min_it->second;
    const double y2 = (min_it + 1)->second;
    const double denominator = y0 - 2.0 * y1 + y2;
    if (denominator > 0) {
      const double shift = 0.5 * (y0 - y2) / denominator;  // in fine steps, |shift| <= 0.5
      refined += static_cast<timestamp_ns_t>(std::llround(shift * static_cast<double>(fine_ns)));
    }
  }
  if (refined_cost < best_cost) best_cost = refined_cost;

  const double reduction = 1.0 - best_cost / *calibration_cost;
  message << std::setprecision(1) << "camera-IMU time offset " << NsToSeconds(refined) * 1e3
          << " ms (calibration " << NsToSeconds(calibration_offset_ns) * 1e3
          << " ms): median epipolar residual with the gyro's "
          << "rotation " << std::setprecision(2) << best_cost * focal_length_px << " px against "
          << *calibration_cost * focal_length_px << " px at the calibration's offset, "
          << pairs.size() << " frame pairs, " << std::setprecision(0) << estimate.total_rotation_deg
          << " deg of rotation";
  if (at_edge) {
    message << "; not trusted: the minimum is at the edge of the +-" << options.max_offset_s * 1e3
            << " ms search range";
  } else if (reduction < options.min_cost_reduction) {
    estimate.offset_ns = calibration_offset_ns;
    estimate.estimated = false;
    message << "; the calibration's offset is as good (kept)";
    estimate.message = message.str();
    return estimate;
  } else {
    estimate.estimated = true;
    estimate.offset_ns = refined;
    estimate.cost_px = best_cost * focal_length_px;
  }
  estimate.message = message.str();
  return estimate;
}

}  // namespace viosfm

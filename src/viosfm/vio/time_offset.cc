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
#include "viosfm/vio/rolling_shutter.h"

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
// in the second, with the image rows they were seen on.
struct FramePair {
  timestamp_ns_t t1 = 0;
  timestamp_ns_t t2 = 0;
  std::vector<Eigen::Vector3d> rays1;  // normalised (x, y, 1)
  std::vector<Eigen::Vector2d> points2;
  std::vector<double> rows1;  // pixel rows, for a rolling shutter's row times
  std::vector<double> rows2;
};

// Pairs of frames 1 to max_gap apart with at least min_tracks common corners.
std::vector<FramePair> MakePairs(const std::vector<FrameFeatures>& frames, int min_tracks,
                                 int max_gap) {
  std::vector<FramePair> pairs;
  for (size_t k = 0; k + 1 < frames.size(); ++k) {
    std::unordered_map<uint64_t, const FeatureObservation*> first;
    for (const FeatureObservation& observation : frames[k].observations) {
      first.emplace(observation.track_id, &observation);
    }
    for (size_t j = k + 1; j < frames.size() && j <= k + static_cast<size_t>(max_gap); ++j) {
      FramePair pair;
      pair.t1 = frames[k].timestamp_ns;
      pair.t2 = frames[j].timestamp_ns;
      for (const FeatureObservation& observation : frames[j].observations) {
        const auto it = first.find(observation.track_id);
        if (it == first.end()) continue;
        pair.rays1.push_back(it->second->normalized.homogeneous());
        pair.rows1.push_back(it->second->pixel.y());
        pair.points2.push_back(observation.normalized);
        pair.rows2.push_back(observation.pixel.y());
      }
      if (static_cast<int>(pair.rays1.size()) >= min_tracks) pairs.push_back(std::move(pair));
    }
  }
  return pairs;
}

// The gyro's orientation (no bias) through a stretch of IMU samples, by
// midpoint integration from the first: body0_from_body at each sample, and
// between samples at the interval's mean rate.
class GyroOrientation {
 public:
  GyroOrientation(const std::vector<ImuSample>& imu, timestamp_ns_t from, timestamp_ns_t to) {
    const auto by_time = [](const ImuSample& sample, timestamp_ns_t t) {
      return sample.timestamp_ns < t;
    };
    auto it = std::lower_bound(imu.begin(), imu.end(), from, by_time);
    if (it != imu.begin()) --it;
    Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
    for (; it != imu.end(); ++it) {
      if (!stamps_.empty()) {
        const Eigen::Vector3d rate = 0.5 * (rates_.back() + it->gyro);
        rates_.back() = rate;
        orientation = (orientation * So3Exp(rate * NsToSeconds(it->timestamp_ns - stamps_.back())))
                          .normalized();
      }
      stamps_.push_back(it->timestamp_ns);
      orientations_.push_back(orientation);
      rates_.push_back(it->gyro);  // replaced by the interval's mean at the next sample
      if (it->timestamp_ns > to) break;
    }
  }

  // The rotation of a rotation vector of at most one IMU interval's turn, by
  // its series to the fourth order (no trigonometry): exact to 1e-10 below 0.05 rad.
  static Eigen::Quaterniond SmallRotation(const Eigen::Vector3d& omega) {
    const double theta_sq = omega.squaredNorm();
    if (theta_sq > 0.0025) return So3Exp(omega);
    const double w = 1.0 - theta_sq / 8.0 + theta_sq * theta_sq / 384.0;
    const Eigen::Vector3d xyz = (0.5 - theta_sq / 48.0) * omega;
    return Eigen::Quaterniond(w, xyz.x(), xyz.y(), xyz.z()).normalized();
  }

  // body0_from_body at t; nullopt outside the samples.
  std::optional<Eigen::Quaterniond> At(timestamp_ns_t t) const {
    if (stamps_.size() < 2 || t < stamps_.front() || t > stamps_.back()) return std::nullopt;
    const size_t k =
        std::min<size_t>(std::upper_bound(stamps_.begin(), stamps_.end(), t) - stamps_.begin() - 1,
                         stamps_.size() - 2);
    return orientations_[k] * SmallRotation(rates_[k] * NsToSeconds(t - stamps_[k]));
  }

 private:
  std::vector<timestamp_ns_t> stamps_;
  std::vector<Eigen::Quaterniond> orientations_;
  std::vector<Eigen::Vector3d> rates_;  // mean rate over [stamps_[k], stamps_[k + 1]]
};

// The median epipolar residual (normalised) of one pair's corners under the
// gyro's rotation between their observation times: the stamps shifted by
// offset_ns, plus each row's time for a rolling shutter of readout_s (0: a
// global shutter); nullopt without IMU coverage.
std::optional<double> PairRotationFlowCost(const FramePair& pair, const GyroOrientation& gyro,
                                           const Eigen::Quaterniond& body_from_cam,
                                           timestamp_ns_t offset_ns, double readout_s, int height) {
  // cam2_from_cam1 for a rotation body1_from_body2.
  const auto cam2_from_cam1 = [&](const Eigen::Quaterniond& body1_from_body2) {
    return (body_from_cam.conjugate() * body1_from_body2 * body_from_cam)
        .conjugate()
        .toRotationMatrix();
  };
  const std::optional<Eigen::Quaterniond> q1 = gyro.At(pair.t1 + offset_ns);
  const std::optional<Eigen::Quaterniond> q2 = gyro.At(pair.t2 + offset_ns);
  if (!q1 || !q2) return std::nullopt;
  // Epipolar residuals with the rotation fixed: for the unit translation
  // t, x2^T [t]x R x1 = t . ((R x1) x x2) = t . a. t is the eigenvector of
  // the smallest eigenvalue of sum a a^T (least squares), refitted on the
  // better 70 % of the corners; the pair's cost is the median |t . a|.
  std::vector<Eigen::Vector3d> rows;
  rows.reserve(pair.rays1.size());
  if (readout_s == 0.0) {
    const Eigen::Matrix3d rotation = cam2_from_cam1(q1->conjugate() * *q2);
    for (size_t i = 0; i < pair.rays1.size(); ++i) {
      rows.push_back((rotation * pair.rays1[i]).cross(pair.points2[i].homogeneous()));
    }
  } else {
    for (size_t i = 0; i < pair.rays1.size(); ++i) {
      const std::optional<Eigen::Quaterniond> a = gyro.At(
          pair.t1 + offset_ns + SecondsToNs(RowTimeOffset(pair.rows1[i], height, readout_s)));
      const std::optional<Eigen::Quaterniond> b = gyro.At(
          pair.t2 + offset_ns + SecondsToNs(RowTimeOffset(pair.rows2[i], height, readout_s)));
      if (!a || !b) return std::nullopt;
      rows.push_back((cam2_from_cam1(a->conjugate() * *b) * pair.rays1[i])
                         .cross(pair.points2[i].homogeneous()));
    }
  }
  if (rows.empty()) return std::nullopt;
  const auto fit = [](const std::vector<Eigen::Vector3d>& a, const std::vector<size_t>& use) {
    Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
    for (const size_t i : use) normal += a[i] * a[i].transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(normal);
    return Eigen::Vector3d(solver.eigenvectors().col(0));
  };
  std::vector<size_t> all(rows.size());
  for (size_t i = 0; i < rows.size(); ++i) all[i] = i;
  Eigen::Vector3d t = fit(rows, all);
  std::vector<double> errors;
  errors.reserve(rows.size());
  for (const Eigen::Vector3d& row : rows) errors.push_back(std::abs(t.dot(row)));
  std::vector<size_t> order = all;
  const size_t num_kept = std::min(order.size(), std::max<size_t>(5, order.size() * 7 / 10));
  std::nth_element(order.begin(), order.begin() + (num_kept - 1), order.end(),
                   [&](size_t a, size_t b) { return errors[a] < errors[b]; });
  order.resize(num_kept);
  t = fit(rows, order);
  errors.clear();
  for (const Eigen::Vector3d& row : rows) errors.push_back(std::abs(t.dot(row)));
  std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
  return errors[errors.size() / 2];
}

// Mean over the pairs of PairRotationFlowCost; pairs without IMU coverage
// are skipped (nullopt if all are).
std::optional<double> RotationFlowCost(const std::vector<FramePair>& pairs,
                                       const GyroOrientation& gyro,
                                       const Eigen::Quaterniond& body_from_cam,
                                       timestamp_ns_t offset_ns, double readout_s, int height) {
  double sum = 0.0;
  int count = 0;
  for (const FramePair& pair : pairs) {
    const std::optional<double> cost =
        PairRotationFlowCost(pair, gyro, body_from_cam, offset_ns, readout_s, height);
    if (!cost) continue;
    sum += *cost;
    ++count;
  }
  if (count == 0) return std::nullopt;
  return sum / count;
}

// The minimum of `cost` over [low, high]: a coarse grid, a fine grid around
// its best point, and a parabola through the fine grid's best point and its
// neighbours. `at_edge` when the coarse minimum is within a step of an end.
struct LineMinimum {
  double x = 0.0;
  double cost = 0.0;
  bool found = false;
  bool at_edge = false;
};

template <class Cost>
LineMinimum MinimizeOnLine(const Cost& cost, double low, double high, double coarse_step,
                           double fine_step) {
  LineMinimum minimum;
  const int num_coarse = static_cast<int>(std::floor((high - low) / coarse_step + 1e-9));
  for (int i = 0; i <= num_coarse; ++i) {
    const double x = low + i * coarse_step;
    const std::optional<double> c = cost(x);
    if (c && (!minimum.found || *c < minimum.cost)) minimum = {x, *c, true, false};
  }
  if (!minimum.found) return minimum;
  minimum.at_edge = minimum.x - coarse_step < low - 1e-12 || minimum.x + coarse_step > high + 1e-12;
  std::vector<std::pair<double, double>> fine;
  const int num_fine = static_cast<int>(std::floor(coarse_step / fine_step + 1e-9));
  for (int i = -num_fine; i <= num_fine; ++i) {
    const double x = minimum.x + i * fine_step;
    if (x < low - 1e-12 || x > high + 1e-12) continue;
    const std::optional<double> c = cost(x);
    if (c) fine.emplace_back(x, *c);
  }
  auto best = std::min_element(fine.begin(), fine.end(),
                               [](const auto& a, const auto& b) { return a.second < b.second; });
  if (best == fine.end()) return minimum;
  double x = best->first;
  if (best != fine.begin() && best + 1 != fine.end()) {
    const double y0 = (best - 1)->second;
    const double y1 = best->second;
    const double y2 = (best + 1)->second;
    const double denominator = y0 - 2.0 * y1 + y2;
    if (denominator > 0) x += 0.5 * (y0 - y2) / denominator * fine_step;  // |shift| <= half a step
  }
  if (best->second < minimum.cost) minimum.cost = best->second;
  minimum.x = x;
  return minimum;
}

// Contiguous blocks of frame pairs the jackknife leaves out in turn.
constexpr int kJackknifeBlocks = 10;

// The spread of the offset minimising the mean pair cost: a delete-one-block
// jackknife over the pairs (kJackknifeBlocks contiguous blocks in time; the
// pairs' errors are correlated over neighbouring frames, not between
// distant ones), each block's minimum found on a grid of `step_ms` within
// +-half_range_ms of center_ms (ms from the calibration's offset). Not
// bounded when some block's minimum lies on the grid's edge: the data then
// leave the offset undetermined over that range.
struct OffsetSpread {
  double sigma_ms = 0.0;
  bool bounded = false;
};

OffsetSpread JackknifeOffsetSpread(const std::vector<FramePair>& pairs, const GyroOrientation& gyro,
                                   const Eigen::Quaterniond& body_from_cam,
                                   timestamp_ns_t calibration_offset_ns, double center_ms,
                                   double readout_s, int height, double half_range_ms,
                                   double step_ms) {
  OffsetSpread spread;
  const int half = std::max(2, static_cast<int>(std::floor(half_range_ms / step_ms + 1e-9)));
  const int num_points = 2 * half + 1;
  // Each pair's cost at every grid point; pairs not covered at every point are left out.
  std::vector<std::vector<double>> costs;
  std::vector<double> row(num_points);
  for (const FramePair& pair : pairs) {
    bool covered = true;
    for (int i = 0; i < num_points && covered; ++i) {
      const double offset_ms = center_ms + (i - half) * step_ms;
      const std::optional<double> cost = PairRotationFlowCost(
          pair, gyro, body_from_cam, calibration_offset_ns + SecondsToNs(offset_ms * 1e-3),
          readout_s, height);
      covered = cost.has_value();
      if (covered) row[i] = *cost;
    }
    if (covered) costs.push_back(row);
  }
  const int num_blocks = std::min<int>(kJackknifeBlocks, static_cast<int>(costs.size()));
  if (num_blocks < 2) return spread;
  std::vector<double> estimates;
  std::vector<double> curve(num_points);
  for (int block = 0; block < num_blocks; ++block) {
    const size_t skip_from = costs.size() * block / num_blocks;
    const size_t skip_to = costs.size() * (block + 1) / num_blocks;
    std::fill(curve.begin(), curve.end(), 0.0);
    for (size_t p = 0; p < costs.size(); ++p) {
      if (p >= skip_from && p < skip_to) continue;
      for (int i = 0; i < num_points; ++i) curve[i] += costs[p][i];
    }
    const int best = static_cast<int>(std::min_element(curve.begin(), curve.end()) - curve.begin());
    if (best == 0 || best == num_points - 1) return spread;  // not bounded
    double x = best;
    const double denominator = curve[best - 1] - 2.0 * curve[best] + curve[best + 1];
    if (denominator > 0) x += 0.5 * (curve[best - 1] - curve[best + 1]) / denominator;
    estimates.push_back(center_ms + (x - half) * step_ms);
  }
  double mean = 0.0;
  for (const double estimate : estimates) mean += estimate;
  mean /= static_cast<double>(estimates.size());
  double sum_sq = 0.0;
  for (const double estimate : estimates) sum_sq += (estimate - mean) * (estimate - mean);
  spread.sigma_ms = std::sqrt(sum_sq * (num_blocks - 1) / num_blocks);
  spread.bounded = true;
  return spread;
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
  if (!(max_readout_s > 0) || max_readout_s > 0.2) return "max_readout_s must be in (0, 0.2]";
  if (!(readout_coarse_step_s >= fine_step_s) || readout_coarse_step_s > max_readout_s) {
    return "readout_coarse_step_s must be in [fine_step_s, max_readout_s]";
  }
  if (!(min_total_rotation_deg >= 0)) return "min_total_rotation_deg must be >= 0";
  if (!(target_rotation_deg >= min_total_rotation_deg)) {
    return "target_rotation_deg must be >= min_total_rotation_deg";
  }
  if (!(max_wait_s > 0)) return "max_wait_s must be > 0";
  if (!(min_cost_reduction >= 0) || !(min_cost_reduction < 1)) {
    return "min_cost_reduction must be in [0, 1)";
  }
  if (!(uncertainty_range_s >= fine_step_s) || uncertainty_range_s > max_offset_s) {
    return "uncertainty_range_s must be in [fine_step_s, max_offset_s]";
  }
  if (!(max_sigma_s > 0)) return "max_sigma_s must be > 0";
  if (!(min_significance >= 0)) return "min_significance must be >= 0";
  return "";
}

std::string TimeOffsetHeadline(const TimeOffsetEstimate& estimate) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(1) << "camera-IMU time offset ";
  const double calibration_ms = NsToSeconds(estimate.calibration_offset_ns) * 1e3;
  if (estimate.estimated) {
    out << NsToSeconds(estimate.offset_ns) * 1e3 << " ms, +- " << estimate.sigma_s * 1e3
        << " ms (the calibration's " << calibration_ms << " ms replaced)";
  } else {
    out << "of the calibration kept (" << calibration_ms << " ms)";
  }
  if (estimate.readout_estimated) {
    out << "; readout " << estimate.readout_s * 1e3 << " ms";
  }
  return out.str();
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

namespace {

// The rolling shutter's readout at the offset found as a global shutter,
// then the offset again at that readout within three coarse steps of where
// it was, twice; kept when it lowers the cost by min_cost_reduction, which
// then updates `offset`, `best_cost` and `estimate`. Returns the readout, s
// (0: a global shutter), and says what was found in `message`.
template <class Cost, class OffsetCost>
double SearchReadout(const Cost& cost, const OffsetCost& offset_cost,
                     timestamp_ns_t calibration_offset_ns, double focal_length_px,
                     const TimeOffsetOptions& options, LineMinimum* offset, double* best_cost,
                     TimeOffsetEstimate* estimate, std::ostringstream* message) {
  const double coarse_ms = options.coarse_step_s * 1e3;
  const double fine_ms = options.fine_step_s * 1e3;
  const double global_cost = offset->cost;
  estimate->global_shutter_cost_px = global_cost * focal_length_px;
  const double max_readout_ms = options.max_readout_s * 1e3;
  const double readout_step_ms = options.readout_coarse_step_s * 1e3;
  LineMinimum at = *offset;
  LineMinimum readout;
  bool kept = false;
  for (int round = 0; round < 2; ++round) {
    const timestamp_ns_t at_ns = calibration_offset_ns + SecondsToNs(at.x * 1e-3);
    readout = MinimizeOnLine([&](double readout_ms) { return cost(at_ns, readout_ms * 1e-3); }, 0.0,
                             max_readout_ms, readout_step_ms, fine_ms);
    kept = readout.found && readout.x + readout_step_ms <= max_readout_ms &&
           readout.cost < (1.0 - options.min_cost_reduction) * global_cost;
    if (!kept) break;
    const LineMinimum again = MinimizeOnLine(offset_cost(readout.x * 1e-3), at.x - 3.0 * coarse_ms,
                                             at.x + 3.0 * coarse_ms, coarse_ms, fine_ms);
    at.cost = readout.cost;
    if (again.found && again.cost <= readout.cost) {
      at.x = again.x;
      at.cost = again.cost;
    }
  }
  if (kept) {
    *offset = at;
    *best_cost = offset->cost;
    const double readout_s = readout.x * 1e-3;
    estimate->readout_estimated = true;
    estimate->readout_s = readout_s;
    estimate->rolling_shutter_cost_px = *best_cost * focal_length_px;
    *message << std::setprecision(1) << "; rolling-shutter readout " << readout_s * 1e3
             << " ms (residual " << std::setprecision(2) << *best_cost * focal_length_px
             << " px against " << global_cost * focal_length_px << " px as a global shutter)";
    return readout_s;
  }
  if (readout.found) {
    *message << std::setprecision(2) << "; a global shutter explains the images as well "
             << "(" << global_cost * focal_length_px << " px; with a readout of "
             << std::setprecision(1) << readout.x << " ms " << std::setprecision(2)
             << readout.cost * focal_length_px << " px)";
  }
  return 0.0;
}

}  // namespace

TimeOffsetEstimate EstimateTimeOffset(const std::vector<FrameFeatures>& frames,
                                      const std::vector<ImuSample>& imu,
                                      const Rigid3d& body_from_cam,
                                      timestamp_ns_t calibration_offset_ns, double focal_length_px,
                                      const TimeOffsetOptions& options, int image_height) {
  VIOSFM_CHECK(options.Check()) << options.Validate();
  TimeOffsetEstimate estimate;
  estimate.offset_ns = calibration_offset_ns;
  estimate.calibration_offset_ns = calibration_offset_ns;
  const std::vector<FramePair> pairs =
      MakePairs(frames, options.min_tracks_per_pair, options.max_frame_gap);
  estimate.num_pairs = static_cast<int>(pairs.size());
  estimate.total_rotation_deg = GyroRotationSumDeg(frames, imu, calibration_offset_ns);
  const timestamp_ns_t range_ns = SecondsToNs(options.max_offset_s);
  const timestamp_ns_t margin_ns = range_ns + SecondsToNs(options.max_readout_s) + 1'000'000;
  const GyroOrientation gyro(
      imu, frames.empty() ? 0 : frames.front().timestamp_ns + calibration_offset_ns - margin_ns,
      frames.empty() ? 0 : frames.back().timestamp_ns + calibration_offset_ns + margin_ns);
  const Eigen::Quaterniond& rotation = body_from_cam.rotation;
  const auto cost = [&](timestamp_ns_t offset, double readout_s) {
    return RotationFlowCost(pairs, gyro, rotation, offset, readout_s, image_height);
  };
  std::ostringstream message;
  message << std::fixed << std::setprecision(1);
  const std::optional<double> calibration_cost = cost(calibration_offset_ns, 0.0);
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

  // The offset (ms on the line) as a global shutter, then, when asked, the
  // readout at that offset and the offset again at that readout.
  const auto offset_cost = [&](double readout_s) {
    return [&cost, calibration_offset_ns, readout_s](double offset_ms) {
      return cost(calibration_offset_ns + SecondsToNs(offset_ms * 1e-3), readout_s);
    };
  };
  const double range_ms = options.max_offset_s * 1e3;
  const double coarse_ms = options.coarse_step_s * 1e3;
  const double fine_ms = options.fine_step_s * 1e3;
  LineMinimum offset = MinimizeOnLine(offset_cost(0.0), -range_ms, range_ms, coarse_ms, fine_ms);
  double best_cost = offset.found ? offset.cost : *calibration_cost;
  double readout_s = 0.0;
  std::ostringstream readout_message;
  readout_message << std::fixed;
  if (options.estimate_readout && image_height > 0 && offset.found && !offset.at_edge) {
    readout_s = SearchReadout(cost, offset_cost, calibration_offset_ns, focal_length_px, options,
                              &offset, &best_cost, &estimate, &readout_message);
  }
  const timestamp_ns_t refined = calibration_offset_ns + SecondsToNs(offset.x * 1e-3);
  // The offset against the calibration's, both with the readout chosen.
  const double reference_cost =
      readout_s > 0.0 ? cost(calibration_offset_ns, readout_s).value_or(*calibration_cost)
                      : *calibration_cost;
  const double reduction = 1.0 - best_cost / reference_cost;
  OffsetSpread spread;
  if (!offset.at_edge) {
    spread =
        JackknifeOffsetSpread(pairs, gyro, rotation, calibration_offset_ns, offset.x, readout_s,
                              image_height, options.uncertainty_range_s * 1e3, fine_ms);
    estimate.sigma_bounded = spread.bounded;
    estimate.sigma_s = spread.bounded ? spread.sigma_ms * 1e-3 : options.uncertainty_range_s;
  }
  message << std::setprecision(1) << "camera-IMU time offset " << NsToSeconds(refined) * 1e3
          << " ms";
  if (spread.bounded) {
    message << " (standard error " << spread.sigma_ms << " ms)";
  } else if (!offset.at_edge) {
    message << " (undetermined within +-" << options.uncertainty_range_s * 1e3 << " ms)";
  }
  message << ", calibration " << NsToSeconds(calibration_offset_ns) * 1e3
          << " ms: median epipolar residual with the gyro's "
          << "rotation " << std::setprecision(2) << best_cost * focal_length_px << " px against "
          << reference_cost * focal_length_px << " px at the calibration's offset, " << pairs.size()
          << " frame pairs, " << std::setprecision(0) << estimate.total_rotation_deg
          << " deg of rotation" << readout_message.str();
  const double shift_ms = offset.x;  // from the calibration's
  if (offset.at_edge) {
    message << "; not trusted: the minimum is at the edge of the +-" << options.max_offset_s * 1e3
            << " ms search range";
  } else if (reduction < options.min_cost_reduction) {
    message << "; the calibration's offset is as good (kept)";
  } else if (!spread.bounded || spread.sigma_ms > options.max_sigma_s * 1e3) {
    message << "; the images and the gyro do not determine it (its standard error exceeds "
            << std::setprecision(1) << options.max_sigma_s * 1e3
            << " ms): the calibration's offset is kept";
  } else if (std::abs(shift_ms) < options.min_significance * spread.sigma_ms) {
    message << "; within " << std::setprecision(1) << options.min_significance
            << " standard errors of the calibration's: the calibration's offset is kept";
  } else {
    estimate.estimated = true;
    estimate.offset_ns = refined;
    estimate.cost_px = best_cost * focal_length_px;
  }
  estimate.message = message.str();
  return estimate;
}

}  // namespace viosfm

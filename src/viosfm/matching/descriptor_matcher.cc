#include "viosfm/matching/descriptor_matcher.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

#include "viosfm/matching/descriptor_dot.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/parallel.h"
#include "viosfm/util/progress.h"

namespace viosfm {
namespace {

// The largest and second-largest dot product seen for one descriptor, and
// the index of the largest. `second` starts at 0: a second neighbour beyond
// an orthogonal descriptor counts as orthogonal.
struct BestTwo {
  float best = -std::numeric_limits<float>::infinity();
  float second = 0.0f;
  int32_t index = -1;

  void Add(float dot, int32_t other) {
    if (dot > best) {
      second = std::max(second, best);
      best = dot;
      index = other;
    } else if (dot > second) {
      second = dot;
    }
  }

  // Combines the summaries of two disjoint sets of candidates; the result is
  // the same in either order (equal bests are a tie, resolved to the
  // smaller index, and then fail the ratio test anyway).
  void Merge(const BestTwo& other) {
    const float new_second = std::max({second, other.second, std::min(best, other.best)});
    if (other.best > best ||
        (other.best == best && other.index >= 0 && (index < 0 || other.index < index))) {
      best = other.best;
      index = other.index;
    }
    second = new_second;
  }
};

// Distance and ratio tests on squared Euclidean distances of unit vectors.
class MatchTest {
 public:
  explicit MatchTest(const DescriptorMatchingOptions& options)
      : max_distance_sq_(options.max_distance * options.max_distance),
        max_ratio_sq_(options.max_ratio * options.max_ratio) {}

  bool Passes(const BestTwo& candidate) const {
    if (candidate.index < 0) return false;
    const double best_sq = std::max(0.0, 2.0 - 2.0 * static_cast<double>(candidate.best));
    const double second_sq = std::max(0.0, 2.0 - 2.0 * static_cast<double>(candidate.second));
    return best_sq <= max_distance_sq_ && best_sq < max_ratio_sq_ * second_sq;
  }

 private:
  double max_distance_sq_;
  double max_ratio_sq_;
};

// Row and per-thread column summaries -> matches sorted by row.
FeatureMatches CollectMatches(const std::vector<BestTwo>& rows,
                              std::vector<std::vector<BestTwo>>& columns_per_thread,
                              const DescriptorMatchingOptions& options) {
  const MatchTest test(options);
  std::vector<BestTwo>* columns = nullptr;
  if (options.cross_check) {
    columns = &columns_per_thread.front();
    for (size_t t = 1; t < columns_per_thread.size(); ++t) {
      for (size_t j = 0; j < columns->size(); ++j) (*columns)[j].Merge(columns_per_thread[t][j]);
    }
  }
  FeatureMatches matches;
  for (size_t i = 0; i < rows.size(); ++i) {
    if (!test.Passes(rows[i])) continue;
    const auto j = static_cast<size_t>(rows[i].index);
    if (columns != nullptr) {
      const BestTwo& column = (*columns)[j];
      if (column.index != static_cast<int32_t>(i) || !test.Passes(column)) continue;
    }
    matches.push_back({static_cast<point2D_t>(i), static_cast<point2D_t>(j)});
  }
  return matches;
}

}  // namespace

std::string DescriptorMatchingOptions::Validate() const {
  if (!(max_ratio > 0.0 && max_ratio <= 1.0)) return "max_ratio must be in (0, 1]";
  if (!(max_distance > 0.0 && max_distance <= 2.0)) return "max_distance must be in (0, 2]";
  if (block_size < 1) return "block_size must be at least 1";
  if (num_threads == 0 || num_threads < -1) return "num_threads must be -1 (all) or at least 1";
  return "";
}

std::string GuidedMatchingOptions::Validate() const {
  if (std::string error = matching.Validate(); !error.empty()) return "matching." + error;
  if (!(max_epipolar_distance_px > 0.0 && std::isfinite(max_epipolar_distance_px))) {
    return "max_epipolar_distance_px must be positive and finite";
  }
  if (!(cell_size_px >= 0.0 && std::isfinite(cell_size_px))) {
    return "cell_size_px must be 0 (automatic) or positive";
  }
  return "";
}

FloatDescriptors NormalizeDescriptors(const FeatureDescriptors& descriptors) {
  FloatDescriptors normalized = descriptors.cast<float>();
  for (Eigen::Index i = 0; i < normalized.rows(); ++i) {
    const float norm = normalized.row(i).norm();
    if (norm > 0.0f) normalized.row(i) /= norm;
  }
  return normalized;
}

FeatureMatches MatchDescriptors(const FloatDescriptors& descriptors1,
                                const FloatDescriptors& descriptors2,
                                const DescriptorMatchingOptions& options) {
  VIOSFM_CHECK(options.Check()) << options.Validate();
  if (descriptors1.rows() == 0 || descriptors2.rows() == 0) return {};
  VIOSFM_CHECK_EQ(descriptors1.cols(), descriptors2.cols());
  const int64_t num_rows = descriptors1.rows();
  const int64_t num_columns = descriptors2.rows();
  const int64_t block = options.block_size;
  const int64_t num_blocks = (num_rows + block - 1) / block;
  const int num_threads = NumThreadsFor(num_blocks, options.num_threads);

  std::vector<BestTwo> rows(num_rows);
  std::vector<std::vector<BestTwo>> columns(
      num_threads, std::vector<BestTwo>(options.cross_check ? num_columns : 0));
  ParallelFor(num_blocks, num_threads, [&](int64_t b, int thread) {
    const int64_t row0 = b * block;
    const int64_t count = std::min(block, num_rows - row0);
    const FloatDescriptors dots = descriptors1.middleRows(row0, count) * descriptors2.transpose();
    std::vector<BestTwo>& thread_columns = columns[thread];
    for (int64_t r = 0; r < count; ++r) {
      const float* dot = dots.row(r).data();
      BestTwo& row = rows[row0 + r];
      for (int64_t j = 0; j < num_columns; ++j) row.Add(dot[j], static_cast<int32_t>(j));
      if (options.cross_check) {
        const auto i = static_cast<int32_t>(row0 + r);
        for (int64_t j = 0; j < num_columns; ++j) thread_columns[j].Add(dot[j], i);
      }
    }
  });
  return CollectMatches(rows, columns, options);
}

FeatureMatches MatchDescriptors(const FeatureDescriptors& descriptors1,
                                const FeatureDescriptors& descriptors2,
                                const DescriptorMatchingOptions& options) {
  return MatchDescriptors(NormalizeDescriptors(descriptors1), NormalizeDescriptors(descriptors2),
                          options);
}

namespace {

// 1 / the L2 norm of each uint8 row (exact: the sum of squares is an
// integer), 0 for a row of zeros (which then scores 0 against everything,
// as its normalised float row does).
std::vector<double> InverseRowNorms(const FeatureDescriptors& descriptors) {
  std::vector<double> inverse(descriptors.rows(), 0.0);
  for (Eigen::Index i = 0; i < descriptors.rows(); ++i) {
    int64_t sum = 0;
    for (Eigen::Index d = 0; d < descriptors.cols(); ++d) {
      sum += static_cast<int64_t>(descriptors(i, d)) * descriptors(i, d);
    }
    if (sum > 0) inverse[i] = 1.0 / std::sqrt(static_cast<double>(sum));
  }
  return inverse;
}

// Points of image 2 bucketed in square cells over their bounding box, in two
// layouts: column by column (the cells of one column are consecutive) and
// row by row. A walk along x visits, per column, a range of consecutive
// cells of the first layout, so their points are one contiguous run of
// memory; a walk along y does the same in the second.
class PointGrid {
 public:
  PointGrid(const std::vector<Eigen::Vector2d>& points, double cell_size) : cell_(cell_size) {
    min_ = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
    Eigen::Vector2d max = -min_;
    for (const Eigen::Vector2d& p : points) {
      if (!p.allFinite()) continue;
      min_ = min_.cwiseMin(p);
      max = max.cwiseMax(p);
    }
    if (!(min_.x() <= max.x())) return;  // no finite point
    // Coarser cells if the points are spread far beyond an image's size.
    const double max_cells = std::max<double>(4096.0, 16.0 * static_cast<double>(points.size()));
    while (((max.x() - min_.x()) / cell_ + 1) * ((max.y() - min_.y()) / cell_ + 1) > max_cells) {
      cell_ *= 2.0;
    }
    nx_ = static_cast<int64_t>(std::floor((max.x() - min_.x()) / cell_)) + 1;
    ny_ = static_cast<int64_t>(std::floor((max.y() - min_.y()) / cell_)) + 1;
    Fill(points, /*by_column=*/true, &by_column_);
    Fill(points, /*by_column=*/false, &by_row_);
  }

  // Calls visit(indices, points, count) for every run of points in
  // consecutive cells the band |a x + b y + c| <= half_width crosses (a^2 +
  // b^2 = 1): a superset of the points in the band, each point at most once.
  template <typename Visit>
  void ForEachRunNearLine(double a, double b, double c, double half_width, Visit&& visit) const {
    if (nx_ == 0) return;
    // Walk along the axis the line is closer to, so the band covers few cells
    // per step: y as a function of x when |b| >= |a|, else x of y.
    const bool along_x = std::abs(b) >= std::abs(a);
    const Layout& layout = along_x ? by_column_ : by_row_;
    const double u_coef = along_x ? a : b;  // line: u_coef * u + v_coef * v + c = 0
    const double v_coef = along_x ? b : a;
    const int64_t nu = along_x ? nx_ : ny_;
    const int64_t nv = along_x ? ny_ : nx_;
    const double u_min = along_x ? min_.x() : min_.y();
    const double v_min = along_x ? min_.y() : min_.x();
    const double v_pad = half_width / std::abs(v_coef);
    // The line's v at the columns' edges, in cells from v_min: with v(u) =
    // -(u_coef u + c) / v_coef, edge k (u = u_min + k cell) is at
    // v_first + k v_step cells; the right edge of a column is the left edge
    // of the next. (Rounding moves the band by far less than the pixel of
    // slack the caller's half width has.)
    const double pad_cells = v_pad / cell_;
    const double v_first = (-(u_coef * u_min + c) / v_coef - v_min) / cell_;
    const double v_step = -u_coef / v_coef;
    double v1 = v_first;
    for (int64_t cu = 0; cu < nu; ++cu) {
      const double v0 = v1;
      v1 = v_first + static_cast<double>(cu + 1) * v_step;
      const double low = std::min(v0, v1) - pad_cells;
      const double high = std::max(v0, v1) + pad_cells;
      if (!(high >= 0.0) || low >= static_cast<double>(nv)) continue;
      // high >= 0, and low is clamped to 0: truncation is the floor here.
      const int64_t cv0 = low > 0.0 ? static_cast<int64_t>(low) : 0;
      const int64_t cv1 = std::min<int64_t>(nv - 1, static_cast<int64_t>(high));
      // Cells (cu, cv0..cv1) are consecutive in this layout.
      const int64_t begin = layout.start[cu * nv + cv0];
      const int64_t end = layout.start[cu * nv + cv1 + 1];
      if (end > begin)
        visit(layout.index.data() + begin, layout.points.data() + begin, end - begin);
    }
  }

 private:
  struct Layout {
    std::vector<int64_t> start;           // CSR offsets, one per cell + 1
    std::vector<int32_t> index;           // point indices, ascending within a cell
    std::vector<Eigen::Vector2d> points;  // the points, in the same order
  };

  // Cell (cx, cy) is number cx * ny + cy by column, cy * nx + cx by row.
  void Fill(const std::vector<Eigen::Vector2d>& points, bool by_column, Layout* layout) const {
    layout->start.assign(nx_ * ny_ + 1, 0);
    std::vector<int64_t> cell_of(points.size(), -1);
    for (size_t j = 0; j < points.size(); ++j) {
      if (!points[j].allFinite()) continue;
      const int64_t cx = CellX(points[j].x());
      const int64_t cy = CellY(points[j].y());
      cell_of[j] = by_column ? cx * ny_ + cy : cy * nx_ + cx;
      ++layout->start[cell_of[j] + 1];
    }
    for (size_t c = 1; c < layout->start.size(); ++c) layout->start[c] += layout->start[c - 1];
    layout->index.resize(layout->start.back());
    layout->points.resize(layout->start.back());
    std::vector<int64_t> fill(layout->start.begin(), layout->start.end() - 1);
    for (size_t j = 0; j < points.size(); ++j) {
      if (cell_of[j] < 0) continue;
      const int64_t k = fill[cell_of[j]]++;
      layout->index[k] = static_cast<int32_t>(j);
      layout->points[k] = points[j];
    }
  }

  int64_t CellX(double x) const {
    return std::clamp<int64_t>(static_cast<int64_t>(std::floor((x - min_.x()) / cell_)), 0,
                               nx_ - 1);
  }
  int64_t CellY(double y) const {
    return std::clamp<int64_t>(static_cast<int64_t>(std::floor((y - min_.y()) / cell_)), 0,
                               ny_ - 1);
  }

  double cell_;
  Eigen::Vector2d min_;
  int64_t nx_ = 0;
  int64_t ny_ = 0;
  Layout by_column_;
  Layout by_row_;
};

}  // namespace

FeatureMatches MatchDescriptorsGuided(const FeatureDescriptors& descriptors1,
                                      const FeatureDescriptors& descriptors2,
                                      const std::vector<Eigen::Vector2d>& points1,
                                      const std::vector<Eigen::Vector2d>& points2,
                                      const Eigen::Matrix3d& fundamental,
                                      const GuidedMatchingOptions& options) {
  VIOSFM_CHECK(options.Check()) << options.Validate();
  VIOSFM_CHECK_EQ(static_cast<size_t>(descriptors1.rows()), points1.size());
  VIOSFM_CHECK_EQ(static_cast<size_t>(descriptors2.rows()), points2.size());
  if (points1.empty() || points2.empty()) return {};
  VIOSFM_CHECK_EQ(descriptors1.cols(), descriptors2.cols());
  const DescriptorMatchingOptions& matching = options.matching;
  const double max_distance = options.max_epipolar_distance_px;
  const double cell_size =
      options.cell_size_px > 0.0 ? options.cell_size_px : std::max(8.0, max_distance);
  // The cells visited cover the band plus a pixel, so that rounding never
  // drops a point the exact test below accepts.
  const double search_half_width = max_distance + 1.0;
  const PointGrid grid(points2, cell_size);
  const std::vector<double> inverse_norms1 = InverseRowNorms(descriptors1);
  const std::vector<double> inverse_norms2 = InverseRowNorms(descriptors2);
  const int dims = static_cast<int>(descriptors1.cols());

  const int64_t num_rows = descriptors1.rows();
  const int64_t num_columns = descriptors2.rows();
  constexpr int64_t kRowsPerTask = 256;
  const int64_t num_tasks = (num_rows + kRowsPerTask - 1) / kRowsPerTask;
  const int num_threads = NumThreadsFor(num_tasks, matching.num_threads);
  std::vector<BestTwo> rows(num_rows);
  std::vector<std::vector<BestTwo>> columns(
      num_threads, std::vector<BestTwo>(matching.cross_check ? num_columns : 0));
  ParallelFor(num_tasks, num_threads, [&](int64_t task, int thread) {
    std::vector<BestTwo>& thread_columns = columns[thread];
    // Room for every point of image 2: the band visits each at most once.
    std::vector<int32_t> candidates(points2.size());
    std::vector<int32_t> dots(points2.size());
    const int64_t end = std::min(num_rows, (task + 1) * kRowsPerTask);
    for (int64_t i = task * kRowsPerTask; i < end; ++i) {
      const Eigen::Vector2d& point1 = points1[i];
      const Eigen::Vector3d line = fundamental * point1.homogeneous();
      const double norm = line.head<2>().norm();
      if (!(norm > 0.0) || !line.allFinite()) continue;
      const double max_line_value = max_distance * norm;
      // EpipolarLineDistance(fundamental, point1, points2[j]) <= max_distance,
      // with the line and its norm computed once per row.
      // Each visited point is written, and kept when inside the band
      // (without a branch: about half the visited points are outside).
      int32_t num_candidates = 0;
      int32_t* const candidate = candidates.data();
      grid.ForEachRunNearLine(
          line.x() / norm, line.y() / norm, line.z() / norm, search_half_width,
          [&](const int32_t* indices, const Eigen::Vector2d* points, int64_t count) {
            for (int64_t k = 0; k < count; ++k) {
              candidate[num_candidates] = indices[k];
              num_candidates += std::abs(line.dot(points[k].homogeneous())) <= max_line_value;
            }
          });
      if (num_candidates == 0 || inverse_norms1[i] == 0.0) continue;
      DescriptorDotProducts(descriptors1.row(i).data(), descriptors2.data(), descriptors2.cols(),
                            dims, candidates.data(), num_candidates, dots.data());
      BestTwo& row = rows[i];
      const auto row_index = static_cast<int32_t>(i);
      for (int32_t k = 0; k < num_candidates; ++k) {
        const int32_t j = candidates[k];
        const auto score = static_cast<float>(static_cast<double>(dots[k]) * inverse_norms1[i] *
                                              inverse_norms2[j]);
        row.Add(score, j);
        if (matching.cross_check) thread_columns[j].Add(score, row_index);
      }
    }
  });
  return CollectMatches(rows, columns, matching);
}

std::vector<FeatureMatches> MatchImagePairs(const std::vector<ImagePair>& pairs,
                                            const DescriptorProvider& descriptors,
                                            const DescriptorMatchingOptions& options) {
  VIOSFM_CHECK(options.Check()) << options.Validate();
  DescriptorMatchingOptions one_thread = options;
  one_thread.num_threads = 1;
  std::vector<FeatureMatches> matches(pairs.size());
  ProgressBar progress("Matching", static_cast<int64_t>(pairs.size()));
  ParallelFor(static_cast<int64_t>(pairs.size()), options.num_threads, [&](int64_t k, int) {
    const std::shared_ptr<const FloatDescriptors> descriptors1 = descriptors(pairs[k].image_id1);
    const std::shared_ptr<const FloatDescriptors> descriptors2 = descriptors(pairs[k].image_id2);
    VIOSFM_CHECK(descriptors1 != nullptr && descriptors2 != nullptr)
        << "no descriptors for pair " << pairs[k].image_id1 << "-" << pairs[k].image_id2;
    matches[k] = MatchDescriptors(*descriptors1, *descriptors2, one_thread);
    progress.Update();
  });
  return matches;
}

}  // namespace viosfm

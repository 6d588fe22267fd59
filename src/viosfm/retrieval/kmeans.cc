#include "viosfm/retrieval/kmeans.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "viosfm/util/errors.h"
#include "viosfm/util/parallel.h"
#include "viosfm/util/random.h"

namespace viosfm {
namespace {

// Rows per chunk of the assignment step. Fixed, so that the chunking (and
// with it every floating-point result) is independent of the thread count.
constexpr int64_t kAssignChunk = 256;
// Below this many multiply-adds per assignment step, threads do not pay off.
constexpr int64_t kMinParallelWork = int64_t{1} << 21;

float SquaredDistance(const FloatDescriptors& points, int32_t row, const FloatDescriptors& centers,
                      int center) {
  return (points.row(row) - centers.row(center)).squaredNorm();
}

// Every row's squared distance to centre `center`, capped by `cap` (when
// given): the distances in parallel chunks, each the same computation as
// alone, so the values do not depend on the thread count.
void DistancesToCenter(const FloatDescriptors& points, const std::vector<int32_t>& rows,
                       const FloatDescriptors& centers, int center, const std::vector<double>* cap,
                       int num_threads, std::vector<double>* distances) {
  const int64_t n = static_cast<int64_t>(rows.size());
  const int threads = n * points.cols() >= kMinParallelWork ? ResolveNumThreads(num_threads) : 1;
  ParallelForChunks(n, threads, kAssignChunk, [&](int64_t begin, int64_t end) {
    for (int64_t i = begin; i < end; ++i) {
      const double distance = SquaredDistance(points, rows[i], centers, center);
      (*distances)[i] = cap ? std::min<double>((*cap)[i], distance) : distance;
    }
  });
}

// The sum in row order (deterministic).
double Sum(const std::vector<double>& values) {
  double total = 0.0;
  for (const double value : values) total += value;
  return total;
}

// Greedy k-means++ (Arthur & Vassilvitskii 2007): the first centre uniformly;
// for each next one, 2 + floor(ln k) candidates drawn with probability
// proportional to the squared distance to the nearest centre so far, keeping
// the candidate that lowers the sum of those squared distances most.
FloatDescriptors SeedCenters(const FloatDescriptors& points, const std::vector<int32_t>& rows,
                             int k, int num_threads, Random* random) {
  const int64_t n = static_cast<int64_t>(rows.size());
  const int dim = static_cast<int>(points.cols());
  const int num_candidates = 2 + static_cast<int>(std::log(static_cast<double>(k)));
  FloatDescriptors centers(k, dim);
  centers.row(0) = points.row(rows[random->UniformInt(0, n - 1)]);
  std::vector<double> nearest(n);
  DistancesToCenter(points, rows, centers, 0, nullptr, num_threads, &nearest);
  double total = Sum(nearest);
  std::vector<double> candidate_nearest(n);
  std::vector<double> best_nearest(n);
  for (int c = 1; c < k; ++c) {
    if (total <= 0.0) {
      // Every point coincides with a centre: the remaining centres duplicate
      // one and end up empty (dropped after the iterations).
      centers.row(c) = points.row(rows[random->UniformInt(0, n - 1)]);
      continue;
    }
    double best_total = std::numeric_limits<double>::infinity();
    int64_t best_candidate = 0;
    for (int trial = 0; trial < num_candidates; ++trial) {
      double target = random->Uniform(0.0, total);
      int64_t candidate = n - 1;
      for (int64_t i = 0; i < n; ++i) {
        target -= nearest[i];
        if (target < 0.0 && nearest[i] > 0.0) {
          candidate = i;
          break;
        }
      }
      centers.row(c) = points.row(rows[candidate]);
      DistancesToCenter(points, rows, centers, c, &nearest, num_threads, &candidate_nearest);
      const double candidate_total = Sum(candidate_nearest);
      if (candidate_total < best_total) {
        best_total = candidate_total;
        best_candidate = candidate;
        best_nearest.swap(candidate_nearest);
      }
    }
    centers.row(c) = points.row(rows[best_candidate]);
    nearest.swap(best_nearest);
    total = best_total;
  }
  return centers;
}

// Assigns every row to its nearest centre; returns the number of changed labels.
int64_t Assign(const FloatDescriptors& points, const std::vector<int32_t>& rows,
               const FloatDescriptors& centers, int num_threads, std::vector<int32_t>* labels) {
  const int64_t n = static_cast<int64_t>(rows.size());
  const int k = static_cast<int>(centers.rows());
  const int dim = static_cast<int>(points.cols());
  const Eigen::VectorXf center_norms = centers.rowwise().squaredNorm();
  const int threads = n * k * dim >= kMinParallelWork ? ResolveNumThreads(num_threads) : 1;
  std::vector<int64_t> changed_per_chunk((n + kAssignChunk - 1) / kAssignChunk, 0);
  ParallelForChunks(n, threads, kAssignChunk, [&](int64_t begin, int64_t end) {
    FloatDescriptors block(end - begin, dim);
    for (int64_t i = begin; i < end; ++i) block.row(i - begin) = points.row(rows[i]);
    // ||x - c||^2 = ||x||^2 - 2 x.c + ||c||^2; ||x||^2 does not change the argmin.
    const Eigen::MatrixXf dots = block * centers.transpose();
    int64_t changed = 0;
    for (int64_t i = begin; i < end; ++i) {
      int best = 0;
      float best_distance = std::numeric_limits<float>::infinity();
      for (int c = 0; c < k; ++c) {
        const float distance = center_norms[c] - 2.0f * dots(i - begin, c);
        if (distance < best_distance) {
          best_distance = distance;
          best = c;
        }
      }
      if ((*labels)[i] != best) {
        (*labels)[i] = best;
        ++changed;
      }
    }
    changed_per_chunk[begin / kAssignChunk] = changed;
  });
  int64_t changed = 0;
  for (const int64_t value : changed_per_chunk) changed += value;
  return changed;
}

}  // namespace

std::string KMeansOptions::Validate() const {
  if (num_clusters < 1) return "num_clusters must be >= 1";
  if (max_iterations < 1) return "max_iterations must be >= 1";
  return "";
}

KMeansResult KMeans(const FloatDescriptors& points, const std::vector<int32_t>& rows,
                    const KMeansOptions& options) {
  VIOSFM_CHECK(options.Check()) << options.Validate();
  KMeansResult result;
  const int64_t n = static_cast<int64_t>(rows.size());
  const int dim = static_cast<int>(points.cols());
  if (n == 0) {
    result.centers.resize(0, dim);
    return result;
  }
  for (const int32_t row : rows) VIOSFM_CHECK(row >= 0 && row < points.rows()) << row;
  const int k = static_cast<int>(std::min<int64_t>(options.num_clusters, n));
  Random random(options.seed);
  FloatDescriptors centers = SeedCenters(points, rows, k, options.num_threads, &random);

  std::vector<int32_t> labels(n, -1);
  std::vector<int64_t> sizes(k, 0);
  Eigen::MatrixXd sums(k, dim);
  for (int iteration = 0; iteration < options.max_iterations; ++iteration) {
    const int64_t changed = Assign(points, rows, centers, options.num_threads, &labels);
    result.iterations = iteration + 1;
    if (changed == 0) break;
    // Means in double, summed in row order (deterministic).
    sums.setZero();
    std::fill(sizes.begin(), sizes.end(), 0);
    for (int64_t i = 0; i < n; ++i) {
      sums.row(labels[i]) += points.row(rows[i]).cast<double>();
      ++sizes[labels[i]];
    }
    for (int c = 0; c < k; ++c) {
      if (sizes[c] > 0)
        centers.row(c) = (sums.row(c) / static_cast<double>(sizes[c])).cast<float>();
    }
    // Labels must be consistent with the final centres.
    if (iteration + 1 == options.max_iterations) {
      Assign(points, rows, centers, options.num_threads, &labels);
    }
  }

  // Drop empty clusters and renumber.
  std::fill(sizes.begin(), sizes.end(), 0);
  for (const int32_t label : labels) ++sizes[label];
  std::vector<int32_t> new_index(k, -1);
  int kept = 0;
  for (int c = 0; c < k; ++c) {
    if (sizes[c] > 0) new_index[c] = kept++;
  }
  result.centers.resize(kept, dim);
  for (int c = 0; c < k; ++c) {
    if (new_index[c] >= 0) result.centers.row(new_index[c]) = centers.row(c);
  }
  for (int32_t& label : labels) label = new_index[label];
  result.labels = std::move(labels);
  return result;
}

}  // namespace viosfm

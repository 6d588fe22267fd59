// Seeded k-means (k-means++ seeding, then Lloyd iterations) on float
// descriptors, the building block of the vocabulary tree.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

namespace viosfm {

// One descriptor a row.
using FloatDescriptors = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

struct KMeansOptions {
  int num_clusters = 10;  // k, >= 1 (fewer clusters come out if there are fewer distinct points)
  int max_iterations =
      10;               // Lloyd iterations after seeding, >= 1; stops early once no label changes
  uint64_t seed = 0;    // seed of the k-means++ sampling
  int num_threads = 1;  // threads for the assignment step (<= 0: all hardware threads)

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }
};

struct KMeansResult {
  FloatDescriptors centers;     // k' x dim, k' <= num_clusters (empty clusters are dropped)
  std::vector<int32_t> labels;  // per clustered row, index of its centre in [0, k')
  int iterations = 0;           // Lloyd iterations run
};

// Clusters the rows points.row(rows[i]) of `points`; labels[i] belongs to
// rows[i]. The result depends on the seed only, not on num_threads.
KMeansResult KMeans(const FloatDescriptors& points, const std::vector<int32_t>& rows,
                    const KMeansOptions& options);

}  // namespace viosfm

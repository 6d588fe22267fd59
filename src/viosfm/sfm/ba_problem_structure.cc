#include "viosfm/sfm/ba_problem_structure.h"

#include <Eigen/OrderingMethods>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <bit>
#include <cstdint>
#include <unordered_map>
#include <unordered_set>

namespace viosfm {

double BaProblemStructure::FillPerObservation() const {
  if (num_free_images == 0 || num_observations == 0) return 0.0;
  const double pairs = static_cast<double>(num_covisible_pairs);
  return pairs * pairs /
         (static_cast<double>(num_free_images) * static_cast<double>(num_observations));
}

double BaProblemStructure::FactorizationPerObservation() const {
  if (num_observations == 0) return 0.0;
  return factorization_block_flops / static_cast<double>(num_observations);
}

double BaProblemStructure::FactorizationPerImage() const {
  if (num_free_images == 0) return 0.0;
  return factorization_block_flops / static_cast<double>(num_free_images);
}

namespace {

// sum_j c_j^2 over the columns of the Cholesky factor of the symmetric
// pattern `bits` (row i: the upper triangle's columns j > i as n bits),
// ordered by AMD. The values make the matrix strictly diagonally dominant
// (diagonal = degree + 1, -1 elsewhere), hence positive definite: no
// cancellation, so the numeric factor's pattern is the symbolic one.
double FactorizationBlockFlops(const std::vector<uint64_t>& bits, size_t n, size_t words) {
  std::vector<Eigen::Triplet<double, int>> entries;
  std::vector<int> degree(n, 0);
  for (size_t i = 0; i < n; ++i) {
    for (size_t w = 0; w < words; ++w) {
      uint64_t word = bits[i * words + w];
      while (word != 0) {
        const size_t j = w * 64 + static_cast<size_t>(std::countr_zero(word));
        word &= word - 1;
        entries.emplace_back(static_cast<int>(j), static_cast<int>(i), -1.0);  // lower
        ++degree[i];
        ++degree[j];
      }
    }
  }
  for (size_t i = 0; i < n; ++i) {
    entries.emplace_back(static_cast<int>(i), static_cast<int>(i), degree[i] + 1.0);
  }
  Eigen::SparseMatrix<double, Eigen::ColMajor, int> matrix(static_cast<int>(n),
                                                           static_cast<int>(n));
  matrix.setFromTriplets(entries.begin(), entries.end());
  const Eigen::SimplicialLLT<Eigen::SparseMatrix<double, Eigen::ColMajor, int>, Eigen::Lower,
                             Eigen::AMDOrdering<int>>
      cholesky(matrix);
  if (cholesky.info() != Eigen::Success) return 0.0;
  const Eigen::SparseMatrix<double, Eigen::ColMajor, int> factor = cholesky.matrixL();
  double flops = 0.0;
  for (int j = 0; j < factor.outerSize(); ++j) {
    const double count = factor.outerIndexPtr()[j + 1] - factor.outerIndexPtr()[j];
    flops += count * count;
  }
  return flops;
}

}  // namespace

BaProblemStructure ComputeBaProblemStructure(const Reconstruction& reconstruction,
                                             const std::vector<image_t>& free_images,
                                             bool with_factorization) {
  BaProblemStructure structure;
  std::unordered_map<image_t, uint32_t> index;  // free image -> 0..n-1
  for (const image_t image_id : free_images) {
    if (reconstruction.ExistsImage(image_id) && reconstruction.GetImage(image_id).registered) {
      index.emplace(image_id, static_cast<uint32_t>(index.size()));
    }
  }
  const size_t n = index.size();
  structure.num_free_images = n;
  if (n == 0) return structure;

  // Row i of the upper triangle as a bit set of n bits.
  const size_t words = (n + 63) / 64;
  std::vector<uint64_t> bits(n * words, 0);
  std::unordered_set<point3D_t> visited;
  std::vector<uint32_t> members;
  for (const image_t image_id : free_images) {
    if (index.count(image_id) == 0) continue;
    for (const Point2D& point2D : reconstruction.GetImage(image_id).points2D) {
      if (!point2D.HasPoint3D() || !visited.insert(point2D.point3D_id).second) continue;
      members.clear();
      for (const TrackElement& element : reconstruction.GetPoint3D(point2D.point3D_id).track) {
        const auto it = index.find(element.image_id);
        if (it != index.end()) {
          members.push_back(it->second);
        } else if (!reconstruction.GetImage(element.image_id).registered) {
          continue;
        }
        ++structure.num_observations;
      }
      ++structure.num_points;
      std::sort(members.begin(), members.end());
      members.erase(std::unique(members.begin(), members.end()), members.end());
      for (size_t a = 0; a < members.size(); ++a) {
        uint64_t* row = &bits[members[a] * words];
        for (size_t b = a + 1; b < members.size(); ++b) {
          row[members[b] / 64] |= uint64_t{1} << (members[b] % 64);
        }
      }
    }
  }
  for (const uint64_t word : bits) structure.num_covisible_pairs += std::popcount(word);
  if (with_factorization)
    structure.factorization_block_flops = FactorizationBlockFlops(bits, n, words);
  return structure;
}

}  // namespace viosfm

#include "viosfm/sfm/ba_problem_structure.h"

#include <gtest/gtest.h>

#include <set>
#include <utility>
#include <vector>

#include "viosfm/sensor/camera_models.h"

namespace viosfm {
namespace {

// A reconstruction of `num_images` images (ids 1..n, registered unless
// listed in `unregistered`) and one point per track in `tracks` (image ids).
Reconstruction MakeReconstruction(int num_images, const std::vector<std::vector<image_t>>& tracks,
                                  const std::set<image_t>& unregistered = {}) {
  Reconstruction reconstruction;
  Camera camera = MakeCamera(CameraModelId::kPinhole, 640, 480, {500, 500, 320, 240});
  camera.camera_id = 1;
  reconstruction.AddCamera(camera);
  std::vector<int> num_keypoints(num_images + 1, 0);
  for (const auto& track : tracks) {
    for (const image_t image_id : track) ++num_keypoints[image_id];
  }
  for (int i = 1; i <= num_images; ++i) {
    Image image;
    image.image_id = static_cast<image_t>(i);
    image.camera_id = 1;
    image.name = std::to_string(i) + ".png";
    image.registered = unregistered.count(static_cast<image_t>(i)) == 0;
    image.points2D.resize(num_keypoints[i]);
    reconstruction.AddImage(image);
  }
  std::vector<point2D_t> next(num_images + 1, 0);
  for (const auto& track : tracks) {
    Point3D point;
    for (const image_t image_id : track) point.track.push_back({image_id, next[image_id]++});
    reconstruction.AddPoint3D(point);
  }
  return reconstruction;
}

// The independent count: every pair of free images in a common track.
size_t BruteForcePairs(const std::vector<std::vector<image_t>>& tracks,
                       const std::set<image_t>& free) {
  std::set<std::pair<image_t, image_t>> pairs;
  for (const auto& track : tracks) {
    for (const image_t a : track) {
      for (const image_t b : track) {
        if (a < b && free.count(a) > 0 && free.count(b) > 0) pairs.emplace(a, b);
      }
    }
  }
  return pairs.size();
}

std::vector<image_t> Ids(int first, int last) {
  std::vector<image_t> ids;
  for (int i = first; i <= last; ++i) ids.push_back(static_cast<image_t>(i));
  return ids;
}

TEST(BaProblemStructure, EveryCameraSeesEveryOther) {
  // A room: 70 images (more than 64, two words a row), 30 points seen by all.
  const int n = 70;
  const std::vector<std::vector<image_t>> tracks(30, Ids(1, n));
  const BaProblemStructure structure =
      ComputeBaProblemStructure(MakeReconstruction(n, tracks), Ids(1, n));
  EXPECT_EQ(structure.num_free_images, 70u);
  EXPECT_EQ(structure.num_points, 30u);
  EXPECT_EQ(structure.num_observations, 30u * 70u);
  EXPECT_EQ(structure.num_covisible_pairs, 70u * 69u / 2u);
  const double pairs = 70.0 * 69.0 / 2.0;
  EXPECT_DOUBLE_EQ(structure.FillPerObservation(), pairs * pairs / (70.0 * 2100.0));
}

TEST(BaProblemStructure, BandedTracksLikeAPath) {
  // A corridor: point k seen by images k..k+3 (a band of 3 neighbours).
  const int n = 100;
  std::vector<std::vector<image_t>> tracks;
  for (int k = 1; k + 3 <= n; ++k) tracks.push_back(Ids(k, k + 3));
  const std::vector<image_t> free = Ids(1, n);
  const BaProblemStructure structure =
      ComputeBaProblemStructure(MakeReconstruction(n, tracks), free);
  EXPECT_EQ(structure.num_covisible_pairs, static_cast<size_t>((n - 1) + (n - 2) + (n - 3)));
  EXPECT_EQ(structure.num_covisible_pairs,
            BruteForcePairs(tracks, std::set<image_t>(free.begin(), free.end())));
  EXPECT_EQ(structure.num_observations, 4u * tracks.size());
  // X grows with n when every camera sees every other, stays put along a path.
  EXPECT_LT(structure.FillPerObservation(), 3.0);
}

TEST(BaProblemStructure, FactorizationWorkOfADenseAndABandedMatrix) {
  // Every camera sees every other: the factor is dense whatever the order,
  // its column k (from the last) holds k blocks: sum k^2 = n(n+1)(2n+1)/6.
  const int n = 70;
  const std::vector<std::vector<image_t>> all(30, Ids(1, n));
  const Reconstruction room = MakeReconstruction(n, all);
  EXPECT_EQ(ComputeBaProblemStructure(room, Ids(1, n)).factorization_block_flops, 0.0);
  const BaProblemStructure dense =
      ComputeBaProblemStructure(room, Ids(1, n), /*with_factorization=*/true);
  EXPECT_DOUBLE_EQ(dense.factorization_block_flops, 70.0 * 71.0 * 141.0 / 6.0);
  EXPECT_DOUBLE_EQ(dense.FactorizationPerObservation(), 70.0 * 71.0 * 141.0 / 6.0 / 2100.0);

  // A band of 3 neighbours (a path): in the path's order the factor keeps
  // the band (4 blocks a column, fewer in the last 3: 16 * 97 + 9 + 4 + 1);
  // the minimum degree order does no worse, and every column holds at least
  // its diagonal block and its pairs with later columns.
  const int m = 100;
  std::vector<std::vector<image_t>> band;
  for (int k = 1; k + 3 <= m; ++k) band.push_back(Ids(k, k + 3));
  const BaProblemStructure path =
      ComputeBaProblemStructure(MakeReconstruction(m, band), Ids(1, m), true);
  EXPECT_LE(path.factorization_block_flops, 16.0 * 97.0 + 14.0);
  EXPECT_GE(path.factorization_block_flops, static_cast<double>(m + path.num_covisible_pairs));
  // A fiftieth of the 70-camera room's work, with more cameras.
  EXPECT_LT(path.factorization_block_flops * 50.0, dense.factorization_block_flops);
}

TEST(BaProblemStructure, HeldAndUnregisteredImages) {
  // Images 1-5 free, 6-7 held (registered, not free), 8 unregistered.
  const std::vector<std::vector<image_t>> tracks = {{1, 2, 6}, {2, 7, 8}, {3, 4, 5, 8},
                                                    {6, 7},    {1, 5},    {2, 3, 2}};
  // (The last track lists image 2 twice: two keypoints of one image, as a
  // corrupt track could; it makes no pair with itself.)
  const std::vector<image_t> free = Ids(1, 5);
  const BaProblemStructure structure =
      ComputeBaProblemStructure(MakeReconstruction(8, tracks, {8}), free);
  EXPECT_EQ(structure.num_free_images, 5u);
  // Points seen by a free image: all but {6, 7}.
  EXPECT_EQ(structure.num_points, 5u);
  // Their observations in registered images: 3 + 2 + 3 + 2 + 3.
  EXPECT_EQ(structure.num_observations, 13u);
  EXPECT_EQ(structure.num_covisible_pairs,
            BruteForcePairs(tracks, std::set<image_t>(free.begin(), free.end())));
  EXPECT_EQ(structure.num_covisible_pairs, 1u + 3u + 1u + 1u);  // 12; 34 35 45; 15; 23
  // Unknown or unregistered free images are not cameras of the problem.
  EXPECT_EQ(ComputeBaProblemStructure(MakeReconstruction(8, tracks, {8}), {8, 99}).num_free_images,
            0u);
  EXPECT_EQ(BaProblemStructure{}.FillPerObservation(), 0.0);
}

}  // namespace
}  // namespace viosfm

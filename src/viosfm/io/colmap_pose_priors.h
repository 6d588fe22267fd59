// Position priors in a COLMAP database, for COLMAP 3.8 and COLMAP 3.10+ at
// once, so that `colmap pose_prior_mapper` (3.10+) and `colmap mapper` can
// start from viosfm's poses.
//
// COLMAP 3.10 and 3.11 keep priors in their own table (their
// Database::CreatePosePriorTable):
//
//   CREATE TABLE IF NOT EXISTS pose_priors
//      (image_id                   INTEGER  PRIMARY KEY  NOT NULL,
//       position                   BLOB,
//       coordinate_system          INTEGER               NOT NULL,
//       position_covariance        BLOB,
//   FOREIGN KEY(image_id) REFERENCES images(image_id) ON DELETE CASCADE);
//
//   position             3 float64: the camera centre in the world (metres)
//   coordinate_system    -1 undefined, 0 WGS84, 1 Cartesian (viosfm: 1)
//   position_covariance  3x3 float64, column-major (Eigen's order; the
//                        matrix is symmetric, so the order does not matter)
//
// COLMAP 3.8 does not know this table and ignores it; it reads the images
// table's prior_qw..prior_qz, prior_tx..prior_tz columns instead, which
// WriteColmapPosePriors fills too (prior_q = cam_from_world rotation, w
// first; prior_t = the camera centre, as 3.8's spatial matcher reads it).
// COLMAP 3.12 and 4.x migrate the 3.11 table into their own layout
// (pose_prior_id, corr_data_id, corr_sensor_id, corr_sensor_type, ...) when
// they open the database.
//
// Errors (InputError naming the database): a file that is not a COLMAP
// database, an image id without an images row, a non-finite position or a
// covariance that is not symmetric positive semi-definite.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <filesystem>
#include <vector>

#include "viosfm/util/types.h"

namespace viosfm {

// COLMAP's PosePrior::CoordinateSystem.
enum class ColmapCoordinateSystem : int { kUndefined = -1, kWgs84 = 0, kCartesian = 1 };

struct ColmapPosePrior {
  image_t image_id = kInvalidImageId;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // camera centre in the world, metres
  Eigen::Matrix3d position_covariance = Eigen::Matrix3d::Identity();  // m^2
  ColmapCoordinateSystem coordinate_system = ColmapCoordinateSystem::kCartesian;
  // The rotation written to 3.8's prior_q columns (cam_from_world).
  Eigen::Quaterniond cam_from_world_rotation = Eigen::Quaterniond::Identity();
};

// The CREATE statement above, as COLMAP 3.11 writes it.
extern const char kColmapPosePriorsTableSql[];

// Creates the pose_priors table if missing and writes (replaces) one row per
// prior, and the images table's prior columns, in one transaction.
void WriteColmapPosePriors(const std::filesystem::path& database,
                           const std::vector<ColmapPosePrior>& priors);

// Copies a database (SQLite's VACUUM INTO: a consistent, compact copy, also
// of a database in WAL mode). `destination` must not exist.
void CopyColmapDatabase(const std::filesystem::path& source,
                        const std::filesystem::path& destination);

// Reads the pose_priors table, ordered by image_id (the rotation is read
// from the images table's prior_q columns, identity where NULL).
std::vector<ColmapPosePrior> ReadColmapPosePriors(const std::filesystem::path& database);

}  // namespace viosfm

// A feature and match database in COLMAP 3.8's SQLite format, so that
// `colmap gui`, `colmap exhaustive_matcher`, `colmap mapper` ... open what
// viosfm writes and viosfm reads what COLMAP writes.
//
// Schema: the tables cameras, images, keypoints, descriptors, matches and
// two_view_geometries with COLMAP 3.8's CREATE statements (byte for byte)
// and PRAGMA user_version 3800. Blob layouts (little-endian, row-major):
//   cameras.params               num_params x float64
//   keypoints.data               rows x 6 float32: x, y, a11, a12, a21, a22
//                                (COLMAP also writes 2 columns x, y or 4 columns
//                                x, y, scale, orientation; all three are read)
//   descriptors.data             rows x cols uint8 (cols = 128 for SIFT)
//   matches.data                 rows x 2 uint32: keypoint index in image 1, in image 2
//   two_view_geometries.data     rows x 2 uint32: the inlier matches
//   two_view_geometries.F, E, H  3x3 float64 row-major (empty if no inliers)
//   two_view_geometries.qvec     4 float64 (w, x, y, z) of cam2_from_cam1
//   two_view_geometries.tvec     3 float64 of cam2_from_cam1
// Pairs are keyed by COLMAP's pair id (scene/features.h): image 1 is the one
// with the smaller id, so matches and geometries given for
// (image_id1 > image_id2) are stored swapped (match columns exchanged,
// geometry inverted) and swapped back when read in that order.
//
// Pixel conventions: keypoints are stored as viosfm holds them, in COLMAP's
// convention (the centre of the top-left pixel is (0.5, 0.5)). Cameras in
// viosfm carry intrinsics in the convention they were calibrated in, OpenCV's
// ((0, 0) is the centre of the top-left pixel; EuRoC, Kalibr, the simulator).
// WriteCamera therefore adds 0.5 to the principal point (cx, cy) and
// ReadCamera subtracts it, so the database is self-consistent for COLMAP and
// a camera round-trips unchanged in viosfm.
//
// Durability: the file is opened in WAL journal mode with synchronous=NORMAL.
// Every write is atomic; a crash or Ctrl-C loses at most the transaction in
// progress and leaves a valid database (SQLite rolls it back on the next
// open). Group the writes of one item (e.g. an image's keypoints and
// descriptors: WriteFeatures) so that an item is either complete or absent.
//
// Writes of keypoints, descriptors, matches and two-view geometries replace
// an existing row (so an interrupted or repeated stage can rewrite them).
//
// Errors: a file that cannot be opened or is not a SQLite database, a failing
// SQL statement (disk full, read-only file) and malformed rows (a blob whose
// size does not match its rows and cols, an unknown camera model) throw
// InputError naming the database file and the table row.
//
// Thread safety: one ColmapDatabase may be used by one thread at a time (it
// holds prepared statements); use one writer thread and hand it the results
// of the workers.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "viosfm/scene/features.h"
#include "viosfm/scene/two_view_geometry.h"
#include "viosfm/sensor/camera.h"
#include "viosfm/util/types.h"

namespace viosfm {

// An image's pose prior, COLMAP's prior_qw..prior_qz and prior_tx..prior_tz
// columns. COLMAP 3.8 reads prior_t as the image's position (its spatial
// matcher and model aligner use it so), hence the names.
struct ImagePosePrior {
  Eigen::Quaterniond cam_from_world_rotation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d position_in_world = Eigen::Vector3d::Zero();  // metres
};

// A row of the images table.
struct DatabaseImage {
  image_t image_id = kInvalidImageId;
  std::string name;  // unique; by convention the path relative to the image folder
  camera_t camera_id = kInvalidCameraId;
  std::optional<ImagePosePrior> prior;  // none: the prior columns are NULL
};

// A row of sqlite_master: "table", "cameras", "CREATE TABLE cameras ...".
struct DatabaseSchemaEntry {
  std::string type;
  std::string name;
  std::string sql;
};

// viosfm's record in a database it writes: what the database's rows were
// made from (the run fingerprint's entries, pipeline/run_fingerprint.h) and
// each image file's size and content hash (XXH3), in tables of its own
// (viosfm_fingerprint, viosfm_image_files) that COLMAP ignores. Written
// before the rows it describes, so a database whose rows another input or
// command made is told apart from the one its folder's fingerprint.json
// describes.
struct ViosfmDatabaseRecord {
  struct ImageFile {
    std::string name;  // as the images table names it
    uint64_t size = 0;
    uint64_t xxh3 = 0;
    bool operator==(const ImageFile&) const = default;
  };
  std::vector<std::pair<std::string, std::string>> fingerprint;
  std::vector<ImageFile> image_files;
};

// COLMAP 3.8 writes this PRAGMA user_version.
inline constexpr int kColmapDatabaseUserVersion = 3800;

class ColmapDatabase {
 public:
  // Opens the database at `path`, creating the file and any missing table.
  // The parent folder must exist.
  static ColmapDatabase Open(const std::filesystem::path& path);

  ColmapDatabase(ColmapDatabase&& other) noexcept;
  ColmapDatabase& operator=(ColmapDatabase&& other) noexcept;
  ColmapDatabase(const ColmapDatabase&) = delete;
  ColmapDatabase& operator=(const ColmapDatabase&) = delete;
  ~ColmapDatabase();

  const std::filesystem::path& path() const;

  // Copies the write-ahead log into the database file and syncs both to
  // disk (a full checkpoint: with synchronous=NORMAL, SQLite syncs the log
  // before and the file after it), so that every committed transaction
  // survives a power loss. Throws InputError naming the file if the
  // checkpoint cannot complete.
  void SyncToDisk();

  // A transaction (a SAVEPOINT, so transactions nest): the writes between
  // construction and Commit() are stored together or not at all. Destroyed
  // without Commit(), it rolls them back.
  class Transaction {
   public:
    explicit Transaction(ColmapDatabase& database);
    ~Transaction();
    Transaction(const Transaction&) = delete;
    Transaction& operator=(const Transaction&) = delete;
    void Commit();

   private:
    ColmapDatabase* database_;
    bool done_ = false;
  };

  // Cameras. WriteCamera returns the new camera_id (the next free one, or
  // camera.camera_id if use_camera_id; an existing id is then an InputError).
  // The principal point is converted between the conventions (see above).
  camera_t WriteCamera(const Camera& camera, bool use_camera_id = false);
  bool ExistsCamera(camera_t camera_id) const;
  // Throws InputError if there is no such camera.
  Camera ReadCamera(camera_t camera_id) const;
  std::vector<Camera> ReadAllCameras() const;  // ordered by camera_id

  // Images. WriteImage returns the new image_id; a name already present or
  // an unknown camera_id is an InputError.
  image_t WriteImage(const std::string& name, camera_t camera_id,
                     const std::optional<ImagePosePrior>& prior = std::nullopt);
  bool ExistsImage(image_t image_id) const;
  bool ExistsImageWithName(const std::string& name) const;
  // Throws InputError if there is no such image.
  DatabaseImage ReadImage(image_t image_id) const;
  std::optional<DatabaseImage> ReadImageWithName(const std::string& name) const;
  std::vector<DatabaseImage> ReadAllImages() const;  // ordered by image_id

  // Keypoints and descriptors of one image. Reading an image without a row
  // returns an empty set.
  void WriteKeypoints(image_t image_id, const FeatureKeypoints& keypoints);
  void WriteDescriptors(image_t image_id, const FeatureDescriptors& descriptors);
  // Both in one transaction (an image is then either complete or absent).
  void WriteFeatures(image_t image_id, const FeatureKeypoints& keypoints,
                     const FeatureDescriptors& descriptors);
  FeatureKeypoints ReadKeypoints(image_t image_id) const;
  FeatureDescriptors ReadDescriptors(image_t image_id) const;
  bool ExistsKeypoints(image_t image_id) const;
  bool ExistsDescriptors(image_t image_id) const;
  // Whether both keypoints and descriptors exist (what a resumed extraction
  // skips).
  bool ExistsFeatures(image_t image_id) const {
    return ExistsKeypoints(image_id) && ExistsDescriptors(image_id);
  }

  // Matches of a pair, point2D_idx1 indexing image_id1's keypoints. Reading
  // a pair without a row returns no matches.
  void WriteMatches(image_t image_id1, image_t image_id2, const FeatureMatches& matches);
  FeatureMatches ReadMatches(image_t image_id1, image_t image_id2) const;
  bool ExistsMatches(image_t image_id1, image_t image_id2) const;
  // Every row as (pair_id, matches in pair-id order).
  std::vector<std::pair<image_pair_t, FeatureMatches>> ReadAllMatches() const;

  // Verified geometry of a pair, image 1 = image_id1. Reading a pair without
  // a row returns a default TwoViewGeometry (config kUndefined, no inliers).
  void WriteTwoViewGeometry(image_t image_id1, image_t image_id2, const TwoViewGeometry& geometry);
  TwoViewGeometry ReadTwoViewGeometry(image_t image_id1, image_t image_id2) const;
  bool ExistsTwoViewGeometry(image_t image_id1, image_t image_id2) const;
  // Every row as (pair_id, geometry in pair-id order).
  std::vector<std::pair<image_pair_t, TwoViewGeometry>> ReadAllTwoViewGeometries() const;

  // Counts, as COLMAP's: rows of the cameras and images tables, sums of the
  // rows column of keypoints, descriptors and matches, and rows of matches /
  // two_view_geometries.
  size_t NumCameras() const;
  size_t NumImages() const;
  size_t NumKeypoints() const;
  size_t NumDescriptors() const;
  size_t NumMatches() const;
  size_t NumMatchedImagePairs() const;
  size_t NumVerifiedImagePairs() const;

  // viosfm's record (above): replaced as a whole in one transaction; read
  // back, or none in a database without one (another tool's, an older
  // viosfm's).
  void WriteViosfmRecord(const ViosfmDatabaseRecord& record);
  std::optional<ViosfmDatabaseRecord> ReadViosfmRecord() const;
  // The record of the database file at `path`, read through a read-only
  // connection (the file is not changed). InputError naming the file if it
  // is not a SQLite database.
  static std::optional<ViosfmDatabaseRecord> ReadViosfmRecordOf(const std::filesystem::path& path);

  // The rows of sqlite_master that have SQL, in creation order, and the
  // PRAGMA user_version (for comparing with a database COLMAP created).
  std::vector<DatabaseSchemaEntry> ReadSchema() const;
  int UserVersion() const;

  // The SQLite connection and its prepared statements (defined in the .cc).
  struct Impl;

 private:
  explicit ColmapDatabase(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace viosfm

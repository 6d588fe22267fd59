#include "viosfm/io/colmap_database.h"

#include <sqlite3.h>

#include <cstdlib>
#include <cstring>
#include <limits>
#include <map>
#include <sstream>

#include "viosfm/io/colmap_convention.h"
#include "viosfm/io/rotation_checks.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/hash.h"
#include "viosfm/util/logging.h"

namespace viosfm {
namespace {

// COLMAP 3.8's CREATE statements (src/base/database.cc), in its creation
// order; SQLite stores them without "IF NOT EXISTS", which gives exactly the
// text of a database COLMAP created (see testdata/colmap38_database_schema.txt).
const char* const kCreateStatements[] = {
    "CREATE TABLE IF NOT EXISTS cameras   (camera_id            INTEGER  PRIMARY KEY "
    "AUTOINCREMENT  NOT NULL,"
    "    model                INTEGER                             NOT NULL,"
    "    width                INTEGER                             NOT NULL,"
    "    height               INTEGER                             NOT NULL,"
    "    params               BLOB,"
    "    prior_focal_length   INTEGER                             NOT NULL)",

    "CREATE TABLE IF NOT EXISTS images   (image_id   INTEGER  PRIMARY KEY AUTOINCREMENT  NOT "
    "NULL,"
    "    name       TEXT                                NOT NULL UNIQUE,"
    "    camera_id  INTEGER                             NOT NULL,"
    "    prior_qw   REAL,"
    "    prior_qx   REAL,"
    "    prior_qy   REAL,"
    "    prior_qz   REAL,"
    "    prior_tx   REAL,"
    "    prior_ty   REAL,"
    "    prior_tz   REAL,"
    "CONSTRAINT image_id_check CHECK(image_id >= 0 and image_id < 2147483647),"
    "FOREIGN KEY(camera_id) REFERENCES cameras(camera_id))",

    "CREATE UNIQUE INDEX IF NOT EXISTS index_name ON images(name)",

    "CREATE TABLE IF NOT EXISTS keypoints   (image_id  INTEGER  PRIMARY KEY  NOT NULL,"
    "    rows      INTEGER               NOT NULL,"
    "    cols      INTEGER               NOT NULL,"
    "    data      BLOB,"
    "FOREIGN KEY(image_id) REFERENCES images(image_id) ON DELETE CASCADE)",

    "CREATE TABLE IF NOT EXISTS descriptors   (image_id  INTEGER  PRIMARY KEY  NOT NULL,"
    "    rows      INTEGER               NOT NULL,"
    "    cols      INTEGER               NOT NULL,"
    "    data      BLOB,"
    "FOREIGN KEY(image_id) REFERENCES images(image_id) ON DELETE CASCADE)",

    "CREATE TABLE IF NOT EXISTS matches   (pair_id  INTEGER  PRIMARY KEY  NOT NULL,"
    "    rows     INTEGER               NOT NULL,"
    "    cols     INTEGER               NOT NULL,"
    "    data     BLOB)",

    "CREATE TABLE IF NOT EXISTS two_view_geometries   (pair_id  INTEGER  PRIMARY KEY  NOT NULL,"
    "    rows     INTEGER               NOT NULL,"
    "    cols     INTEGER               NOT NULL,"
    "    data     BLOB,"
    "    config   INTEGER               NOT NULL,"
    "    F        BLOB,"
    "    E        BLOB,"
    "    H        BLOB,"
    "    qvec     BLOB,"
    "    tvec     BLOB)",
};

using RowMajorMatrix3d = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;

}  // namespace

struct ColmapDatabase::Impl {
  std::filesystem::path path;
  sqlite3* db = nullptr;
  std::map<std::string, sqlite3_stmt*> statements;

  ~Impl() {
    for (auto& [sql, statement] : statements) sqlite3_finalize(statement);
    if (db != nullptr) sqlite3_close_v2(db);
  }

  [[noreturn]] void Fail(const std::string& what) const {
    throw InputError(path.string(), 0,
                     what + ": " + (db != nullptr ? sqlite3_errmsg(db) : "cannot open"));
  }

  void Execute(const std::string& sql) {
    char* message = nullptr;
    if (sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &message) != SQLITE_OK) {
      const std::string text = message != nullptr ? message : "unknown error";
      sqlite3_free(message);
      throw InputError(path.string(), 0, "SQLite statement '" + sql + "' failed: " + text);
    }
  }

  sqlite3_stmt* Prepare(const std::string& sql) {
    auto it = statements.find(sql);
    if (it != statements.end()) return it->second;
    sqlite3_stmt* statement = nullptr;
    if (sqlite3_prepare_v2(db, sql.c_str(), -1, &statement, nullptr) != SQLITE_OK) {
      Fail("cannot prepare '" + sql + "'");
    }
    statements.emplace(sql, statement);
    return statement;
  }
};

namespace {

// One use of a cached prepared statement; resets it (and its bindings) when
// done.
class Query {
 public:
  Query(ColmapDatabase::Impl& impl, const std::string& sql)
      : impl_(impl), sql_(sql), statement_(impl.Prepare(sql)) {}
  ~Query() {
    sqlite3_reset(statement_);
    sqlite3_clear_bindings(statement_);
  }
  Query(const Query&) = delete;
  Query& operator=(const Query&) = delete;

  void Int64(int index, int64_t value) { Check(sqlite3_bind_int64(statement_, index, value)); }
  void Double(int index, double value) { Check(sqlite3_bind_double(statement_, index, value)); }
  void Null(int index) { Check(sqlite3_bind_null(statement_, index)); }
  void Text(int index, const std::string& value) {
    Check(sqlite3_bind_text(statement_, index, value.data(), static_cast<int>(value.size()),
                            SQLITE_TRANSIENT));
  }
  // An empty blob is stored as NULL, as COLMAP does.
  void Blob(int index, const void* data, size_t num_bytes) {
    if (num_bytes == 0) {
      Null(index);
      return;
    }
    VIOSFM_CHECK(num_bytes < static_cast<size_t>(std::numeric_limits<int>::max()))
        << "blob of " << num_bytes << " bytes is too large for SQLite";
    Check(
        sqlite3_bind_blob(statement_, index, data, static_cast<int>(num_bytes), SQLITE_TRANSIENT));
  }

  // True while there is a row; throws on errors.
  bool Step() {
    const int rc = sqlite3_step(statement_);
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) return false;
    impl_.Fail("SQLite statement '" + sql_ + "' failed");
  }

  int64_t ColumnInt64(int column) const { return sqlite3_column_int64(statement_, column); }
  double ColumnDouble(int column) const { return sqlite3_column_double(statement_, column); }
  bool ColumnIsNull(int column) const {
    return sqlite3_column_type(statement_, column) == SQLITE_NULL;
  }
  std::string ColumnText(int column) const {
    const unsigned char* text = sqlite3_column_text(statement_, column);
    return text == nullptr ? std::string()
                           : std::string(reinterpret_cast<const char*>(text),
                                         sqlite3_column_bytes(statement_, column));
  }
  // Pointer and size of a blob column (nullptr, 0 for NULL).
  std::pair<const void*, size_t> ColumnBlob(int column) const {
    const void* data = sqlite3_column_blob(statement_, column);
    const int num_bytes = sqlite3_column_bytes(statement_, column);
    return {data, static_cast<size_t>(num_bytes)};
  }

 private:
  void Check(int rc) {
    if (rc != SQLITE_OK) impl_.Fail("cannot bind a value of '" + sql_ + "'");
  }

  ColmapDatabase::Impl& impl_;
  std::string sql_;
  sqlite3_stmt* statement_;
};

// A rows x cols blob of `Scalar` from columns (col, col + 1, col + 2) =
// (rows, cols, data) into row-major `values`; InputError naming `where` if
// its size is not rows * cols * sizeof(Scalar).
template <typename Scalar>
void ReadMatrixBlob(const ColmapDatabase::Impl& impl, const Query& query, int col,
                    const std::string& where, int64_t* rows, int64_t* cols,
                    std::vector<Scalar>* values) {
  *rows = query.ColumnInt64(col);
  *cols = query.ColumnInt64(col + 1);
  const auto [data, num_bytes] = query.ColumnBlob(col + 2);
  // The size check is overflow-safe (a hostile rows x cols must not wrap
  // around to the blob's size), and rows without columns are no matrix
  // (they would pass with an empty blob and size a huge result).
  size_t expected_bytes = 0;
  if (*rows < 0 || *cols < 0 || (*rows > 0 && *cols == 0) ||
      __builtin_mul_overflow(static_cast<size_t>(*rows), static_cast<size_t>(*cols),
                             &expected_bytes) ||
      __builtin_mul_overflow(expected_bytes, sizeof(Scalar), &expected_bytes) ||
      expected_bytes != num_bytes) {
    std::ostringstream message;
    message << where << ": blob of " << num_bytes << " bytes does not hold " << *rows << " x "
            << *cols << " values of " << sizeof(Scalar) << " bytes";
    throw InputError(impl.path.string(), 0, message.str());
  }
  values->resize(num_bytes / sizeof(Scalar));
  if (num_bytes > 0) std::memcpy(values->data(), data, num_bytes);
}

// A fixed-size blob of doubles (NULL or empty: nullopt).
std::optional<std::vector<double>> ReadFixedBlob(const ColmapDatabase::Impl& impl,
                                                 const Query& query, int col, size_t count,
                                                 const std::string& where) {
  const auto [data, num_bytes] = query.ColumnBlob(col);
  if (num_bytes == 0) return std::nullopt;
  if (num_bytes != count * sizeof(double)) {
    std::ostringstream message;
    message << where << ": blob of " << num_bytes << " bytes, expected " << count
            << " float64 values";
    throw InputError(impl.path.string(), 0, message.str());
  }
  std::vector<double> values(count);
  std::memcpy(values.data(), data, num_bytes);
  return values;
}

std::vector<uint32_t> MatchesToBlob(const FeatureMatches& matches, bool swap) {
  std::vector<uint32_t> blob(2 * matches.size());
  for (size_t i = 0; i < matches.size(); ++i) {
    blob[2 * i + 0] = swap ? matches[i].point2D_idx2 : matches[i].point2D_idx1;
    blob[2 * i + 1] = swap ? matches[i].point2D_idx1 : matches[i].point2D_idx2;
  }
  return blob;
}

FeatureMatches MatchesFromBlob(const ColmapDatabase::Impl& impl, const Query& query, int col,
                               const std::string& where, bool swap) {
  int64_t rows = 0;
  int64_t cols = 0;
  std::vector<uint32_t> blob;
  ReadMatrixBlob(impl, query, col, where, &rows, &cols, &blob);
  if (rows > 0 && cols != 2) {
    throw InputError(impl.path.string(), 0,
                     where + ": " + std::to_string(cols) + " columns, expected 2");
  }
  FeatureMatches matches(static_cast<size_t>(rows));
  for (size_t i = 0; i < matches.size(); ++i) {
    matches[i].point2D_idx1 = blob[2 * i + (swap ? 1 : 0)];
    matches[i].point2D_idx2 = blob[2 * i + (swap ? 0 : 1)];
  }
  return matches;
}

std::string PairWhere(const char* table, image_t image_id1, image_t image_id2) {
  std::ostringstream where;
  where << "table " << table << ", pair (" << image_id1 << ", " << image_id2 << ")";
  return where.str();
}

std::string ImageWhere(const char* table, image_t image_id) {
  return std::string("table ") + table + ", image_id " + std::to_string(image_id);
}

// Reads a two_view_geometries row with columns
// (rows, cols, data, config, F, E, H, qvec, tvec) starting at `col`.
TwoViewGeometry TwoViewGeometryFromRow(const ColmapDatabase::Impl& impl, const Query& query,
                                       int col, const std::string& where) {
  TwoViewGeometry geometry;
  geometry.inlier_matches = MatchesFromBlob(impl, query, col, where, /*swap=*/false);
  const int64_t config = query.ColumnInt64(col + 3);
  if (!IsKnownTwoViewGeometryConfig(static_cast<int>(config))) {
    throw InputError(impl.path.string(), 0,
                     where + ": unknown config " + std::to_string(config) + " (expected 0..8)");
  }
  geometry.config = static_cast<TwoViewGeometryConfig>(config);
  Eigen::Matrix3d* matrices[3] = {&geometry.F, &geometry.E, &geometry.H};
  const char* names[3] = {"F", "E", "H"};
  for (int i = 0; i < 3; ++i) {
    const auto values = ReadFixedBlob(impl, query, col + 4 + i, 9, where + ", " + names[i]);
    if (values) *matrices[i] = Eigen::Map<const RowMajorMatrix3d>(values->data());
  }
  const auto qvec = ReadFixedBlob(impl, query, col + 7, 4, where + ", qvec");
  const auto tvec = ReadFixedBlob(impl, query, col + 8, 3, where + ", tvec");
  if (qvec) {
    const Eigen::Quaterniond rotation((*qvec)[0], (*qvec)[1], (*qvec)[2], (*qvec)[3]);
    // A zero quaternion (a row without a pose) stays the identity; others
    // must be unit within the tolerance of every reader (rotation_checks.h).
    if (rotation.coeffs() != Eigen::Vector4d::Zero()) {
      if (const std::string problem = CheckFileQuaternion(rotation); !problem.empty()) {
        throw InputError(impl.path.string(), 0,
                         where + ", qvec: expected a unit quaternion: " + problem);
      }
      geometry.cam2_from_cam1.rotation = rotation.normalized();
    }
  }
  if (tvec) geometry.cam2_from_cam1.translation = Eigen::Map<const Eigen::Vector3d>(tvec->data());
  return geometry;
}

}  // namespace

ColmapDatabase::ColmapDatabase(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
ColmapDatabase::ColmapDatabase(ColmapDatabase&& other) noexcept = default;
ColmapDatabase& ColmapDatabase::operator=(ColmapDatabase&& other) noexcept = default;
ColmapDatabase::~ColmapDatabase() = default;

const std::filesystem::path& ColmapDatabase::path() const {
  return impl_->path;
}

void ColmapDatabase::SyncToDisk() {
  impl_->Execute("PRAGMA wal_checkpoint(FULL)");
}

ColmapDatabase ColmapDatabase::Open(const std::filesystem::path& path) {
  auto impl = std::make_unique<Impl>();
  impl->path = path;
  if (path.has_parent_path() && !std::filesystem::is_directory(path.parent_path())) {
    throw InputError(
        path.string(), 0,
        "cannot create the database: folder " + path.parent_path().string() + " does not exist");
  }
  const int rc =
      sqlite3_open_v2(path.c_str(), &impl->db,
                      SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_NOMUTEX, nullptr);
  if (rc != SQLITE_OK) impl->Fail("cannot open the SQLite database");
  // The first statement reads the file: a file that is not a SQLite
  // database fails here.
  impl->Execute("PRAGMA journal_mode=WAL");
  // With WAL, NORMAL keeps the database valid after a crash (the last
  // transactions may be lost on power loss, never on a process kill, until
  // SyncToDisk, which a run calls before its summary.json).
  impl->Execute("PRAGMA synchronous=NORMAL");
  impl->Execute("PRAGMA temp_store=MEMORY");
  impl->Execute("PRAGMA foreign_keys=ON");

  ColmapDatabase database(std::move(impl));
  Transaction transaction(database);
  for (const char* sql : kCreateStatements) database.impl_->Execute(sql);
  if (database.UserVersion() == 0) {
    database.impl_->Execute("PRAGMA user_version = " + std::to_string(kColmapDatabaseUserVersion));
  }
  transaction.Commit();
  return database;
}

// ------------------------------------------------------------- viosfm's record

namespace {

constexpr const char* kCreateViosfmTables[] = {
    "CREATE TABLE IF NOT EXISTS viosfm_fingerprint (position INTEGER PRIMARY KEY NOT NULL, "
    "key TEXT NOT NULL, value TEXT NOT NULL)",
    "CREATE TABLE IF NOT EXISTS viosfm_image_files (name TEXT PRIMARY KEY NOT NULL, "
    "size INTEGER NOT NULL, xxh3 TEXT NOT NULL)",
};

}  // namespace

void ColmapDatabase::WriteViosfmRecord(const ViosfmDatabaseRecord& record) {
  Transaction transaction(*this);
  for (const char* sql : kCreateViosfmTables) impl_->Execute(sql);
  impl_->Execute("DELETE FROM viosfm_fingerprint");
  impl_->Execute("DELETE FROM viosfm_image_files");
  for (size_t i = 0; i < record.fingerprint.size(); ++i) {
    Query query(*impl_, "INSERT INTO viosfm_fingerprint (position, key, value) VALUES (?, ?, ?)");
    query.Int64(1, static_cast<int64_t>(i));
    query.Text(2, record.fingerprint[i].first);
    query.Text(3, record.fingerprint[i].second);
    query.Step();
  }
  for (const ViosfmDatabaseRecord::ImageFile& file : record.image_files) {
    Query query(*impl_,
                "INSERT OR REPLACE INTO viosfm_image_files (name, size, xxh3) VALUES (?, ?, ?)");
    query.Text(1, file.name);
    query.Int64(2, static_cast<int64_t>(file.size));
    query.Text(3, HashToHex(file.xxh3));
    query.Step();
  }
  transaction.Commit();
}

std::optional<ViosfmDatabaseRecord> ColmapDatabase::ReadViosfmRecord() const {
  {
    Query query(*impl_,
                "SELECT COUNT(*) FROM sqlite_master WHERE type = 'table' AND name IN "
                "('viosfm_fingerprint', 'viosfm_image_files')");
    if (!query.Step() || query.ColumnInt64(0) != 2) return std::nullopt;
  }
  ViosfmDatabaseRecord record;
  {
    Query query(*impl_, "SELECT key, value FROM viosfm_fingerprint ORDER BY position");
    while (query.Step()) record.fingerprint.emplace_back(query.ColumnText(0), query.ColumnText(1));
  }
  Query query(*impl_, "SELECT name, size, xxh3 FROM viosfm_image_files ORDER BY name");
  while (query.Step()) {
    ViosfmDatabaseRecord::ImageFile file;
    file.name = query.ColumnText(0);
    file.size = static_cast<uint64_t>(query.ColumnInt64(1));
    const std::string hex = query.ColumnText(2);
    file.xxh3 = hex.size() == 16 ? std::strtoull(hex.c_str(), nullptr, 16) : 0;
    record.image_files.push_back(std::move(file));
  }
  return record;
}

std::optional<ViosfmDatabaseRecord> ColmapDatabase::ReadViosfmRecordOf(
    const std::filesystem::path& path) {
  auto impl = std::make_unique<Impl>();
  impl->path = path;
  // Opened for writing but only read: as the last connection to close, it
  // removes the -wal and -shm files a WAL database makes it open (a
  // read-only connection would leave them behind), and the file itself is
  // not written.
  if (sqlite3_open_v2(path.c_str(), &impl->db, SQLITE_OPEN_READWRITE | SQLITE_OPEN_NOMUTEX,
                      nullptr) != SQLITE_OK) {
    sqlite3_close_v2(impl->db);
    impl->db = nullptr;
    if (sqlite3_open_v2(path.c_str(), &impl->db, SQLITE_OPEN_READONLY | SQLITE_OPEN_NOMUTEX,
                        nullptr) != SQLITE_OK) {
      impl->Fail("cannot open the SQLite database to read it");
    }
  }
  const ColmapDatabase database(std::move(impl));
  return database.ReadViosfmRecord();
}

// ---------------------------------------------------------------- transactions

ColmapDatabase::Transaction::Transaction(ColmapDatabase& database) : database_(&database) {
  database_->impl_->Execute("SAVEPOINT viosfm_transaction");
}

ColmapDatabase::Transaction::~Transaction() {
  if (done_) return;
  try {
    database_->impl_->Execute("ROLLBACK TO viosfm_transaction");
    database_->impl_->Execute("RELEASE viosfm_transaction");
  } catch (const std::exception& e) {
    VIOSFM_LOG(ERROR) << "rolling back a database transaction failed: " << e.what();
  }
}

void ColmapDatabase::Transaction::Commit() {
  VIOSFM_CHECK(!done_) << "transaction committed twice";
  database_->impl_->Execute("RELEASE viosfm_transaction");
  done_ = true;
}

// --------------------------------------------------------------------- cameras

camera_t ColmapDatabase::WriteCamera(const Camera& camera, bool use_camera_id) {
  if (!camera.HasValidParams()) {
    throw InputError(impl_->path.string(), 0,
                     "cannot write camera: model '" + camera.ModelName() + "' (id " +
                         std::to_string(static_cast<int>(camera.model_id)) + ") with " +
                         std::to_string(camera.params.size()) + " parameters");
  }
  if (use_camera_id && ExistsCamera(camera.camera_id)) {
    throw InputError(impl_->path.string(), 0,
                     "camera_id " + std::to_string(camera.camera_id) + " already exists");
  }
  const Camera stored = CameraToColmapConvention(camera);
  Query query(*impl_,
              "INSERT INTO cameras(camera_id, model, width, height, params, prior_focal_length) "
              "VALUES(?, ?, ?, ?, ?, ?)");
  if (use_camera_id) {
    query.Int64(1, camera.camera_id);
  } else {
    query.Null(1);
  }
  query.Int64(2, static_cast<int64_t>(stored.model_id));
  query.Int64(3, static_cast<int64_t>(stored.width));
  query.Int64(4, static_cast<int64_t>(stored.height));
  query.Blob(5, stored.params.data(), stored.params.size() * sizeof(double));
  query.Int64(6, stored.has_prior_focal_length ? 1 : 0);
  query.Step();
  return static_cast<camera_t>(sqlite3_last_insert_rowid(impl_->db));
}

bool ColmapDatabase::ExistsCamera(camera_t camera_id) const {
  Query query(*impl_, "SELECT 1 FROM cameras WHERE camera_id = ?");
  query.Int64(1, camera_id);
  return query.Step();
}

namespace {

Camera CameraFromRow(const ColmapDatabase::Impl& impl, const Query& query) {
  Camera camera;
  camera.camera_id = static_cast<camera_t>(query.ColumnInt64(0));
  const std::string where = "table cameras, camera_id " + std::to_string(camera.camera_id);
  const int64_t model = query.ColumnInt64(1);
  if (!IsKnownCameraModelId(static_cast<int>(model))) {
    throw InputError(impl.path.string(), 0,
                     where + ": unknown camera model id " + std::to_string(model));
  }
  camera.model_id = static_cast<CameraModelId>(model);
  camera.width = static_cast<uint64_t>(query.ColumnInt64(2));
  camera.height = static_cast<uint64_t>(query.ColumnInt64(3));
  const auto [data, num_bytes] = query.ColumnBlob(4);
  const size_t expected = static_cast<size_t>(CameraModelNumParams(camera.model_id));
  if (num_bytes != expected * sizeof(double)) {
    throw InputError(impl.path.string(), 0,
                     where + ": params blob of " + std::to_string(num_bytes) + " bytes, expected " +
                         std::to_string(expected) + " float64 for " + camera.ModelName());
  }
  camera.params.resize(expected);
  std::memcpy(camera.params.data(), data, num_bytes);
  camera.has_prior_focal_length = query.ColumnInt64(5) != 0;
  return CameraFromColmapConvention(std::move(camera));
}

constexpr const char* kSelectCamera =
    "SELECT camera_id, model, width, height, params, prior_focal_length FROM cameras";

}  // namespace

Camera ColmapDatabase::ReadCamera(camera_t camera_id) const {
  Query query(*impl_, std::string(kSelectCamera) + " WHERE camera_id = ?");
  query.Int64(1, camera_id);
  if (!query.Step()) {
    throw InputError(impl_->path.string(), 0,
                     "no camera with camera_id " + std::to_string(camera_id));
  }
  return CameraFromRow(*impl_, query);
}

std::vector<Camera> ColmapDatabase::ReadAllCameras() const {
  Query query(*impl_, std::string(kSelectCamera) + " ORDER BY camera_id");
  std::vector<Camera> cameras;
  while (query.Step()) cameras.push_back(CameraFromRow(*impl_, query));
  return cameras;
}

// ---------------------------------------------------------------------- images

image_t ColmapDatabase::WriteImage(const std::string& name, camera_t camera_id,
                                   const std::optional<ImagePosePrior>& prior) {
  if (name.empty()) throw InputError(impl_->path.string(), 0, "cannot write an image without name");
  if (ExistsImageWithName(name)) {
    throw InputError(impl_->path.string(), 0, "an image named '" + name + "' already exists");
  }
  if (!ExistsCamera(camera_id)) {
    throw InputError(impl_->path.string(), 0,
                     "image '" + name + "' refers to camera_id " + std::to_string(camera_id) +
                         ", which does not exist");
  }
  Query query(*impl_,
              "INSERT INTO images(image_id, name, camera_id, prior_qw, prior_qx, prior_qy, "
              "prior_qz, prior_tx, prior_ty, prior_tz) VALUES(NULL, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
  query.Text(1, name);
  query.Int64(2, camera_id);
  if (prior) {
    const Eigen::Quaterniond& q = prior->cam_from_world_rotation;
    const double values[7] = {q.w(),
                              q.x(),
                              q.y(),
                              q.z(),
                              prior->position_in_world.x(),
                              prior->position_in_world.y(),
                              prior->position_in_world.z()};
    for (int i = 0; i < 7; ++i) query.Double(3 + i, values[i]);
  } else {
    for (int i = 0; i < 7; ++i) query.Null(3 + i);
  }
  query.Step();
  return static_cast<image_t>(sqlite3_last_insert_rowid(impl_->db));
}

bool ColmapDatabase::ExistsImage(image_t image_id) const {
  Query query(*impl_, "SELECT 1 FROM images WHERE image_id = ?");
  query.Int64(1, image_id);
  return query.Step();
}

bool ColmapDatabase::ExistsImageWithName(const std::string& name) const {
  Query query(*impl_, "SELECT 1 FROM images WHERE name = ?");
  query.Text(1, name);
  return query.Step();
}

namespace {

constexpr const char* kSelectImage =
    "SELECT image_id, name, camera_id, prior_qw, prior_qx, prior_qy, prior_qz, prior_tx, "
    "prior_ty, prior_tz FROM images";

DatabaseImage ImageFromRow(const Query& query) {
  DatabaseImage image;
  image.image_id = static_cast<image_t>(query.ColumnInt64(0));
  image.name = query.ColumnText(1);
  image.camera_id = static_cast<camera_t>(query.ColumnInt64(2));
  bool has_prior = true;
  for (int i = 3; i < 10; ++i) has_prior = has_prior && !query.ColumnIsNull(i);
  if (has_prior) {
    ImagePosePrior prior;
    prior.cam_from_world_rotation = Eigen::Quaterniond(
        query.ColumnDouble(3), query.ColumnDouble(4), query.ColumnDouble(5), query.ColumnDouble(6));
    prior.position_in_world =
        Eigen::Vector3d(query.ColumnDouble(7), query.ColumnDouble(8), query.ColumnDouble(9));
    image.prior = prior;
  }
  return image;
}

}  // namespace

DatabaseImage ColmapDatabase::ReadImage(image_t image_id) const {
  Query query(*impl_, std::string(kSelectImage) + " WHERE image_id = ?");
  query.Int64(1, image_id);
  if (!query.Step()) {
    throw InputError(impl_->path.string(), 0, "no image with image_id " + std::to_string(image_id));
  }
  return ImageFromRow(query);
}

std::optional<DatabaseImage> ColmapDatabase::ReadImageWithName(const std::string& name) const {
  Query query(*impl_, std::string(kSelectImage) + " WHERE name = ?");
  query.Text(1, name);
  if (!query.Step()) return std::nullopt;
  return ImageFromRow(query);
}

std::vector<DatabaseImage> ColmapDatabase::ReadAllImages() const {
  Query query(*impl_, std::string(kSelectImage) + " ORDER BY image_id");
  std::vector<DatabaseImage> images;
  while (query.Step()) images.push_back(ImageFromRow(query));
  return images;
}

// ------------------------------------------------------- keypoints/descriptors

void ColmapDatabase::WriteKeypoints(image_t image_id, const FeatureKeypoints& keypoints) {
  constexpr int kCols = 6;
  std::vector<float> blob(kCols * keypoints.size());
  for (size_t i = 0; i < keypoints.size(); ++i) {
    const FeatureKeypoint& k = keypoints[i];
    // Positions in COLMAP's pixel convention.
    const float row[kCols] = {k.x + static_cast<float>(kColmapPixelOffset),
                              k.y + static_cast<float>(kColmapPixelOffset),
                              k.a11,
                              k.a12,
                              k.a21,
                              k.a22};
    std::copy(row, row + kCols, blob.begin() + kCols * i);
  }
  Query query(*impl_,
              "INSERT OR REPLACE INTO keypoints(image_id, rows, cols, data) VALUES(?, ?, ?, ?)");
  query.Int64(1, image_id);
  query.Int64(2, static_cast<int64_t>(keypoints.size()));
  query.Int64(3, kCols);
  query.Blob(4, blob.data(), blob.size() * sizeof(float));
  query.Step();
}

void ColmapDatabase::WriteDescriptors(image_t image_id, const FeatureDescriptors& descriptors) {
  Query query(*impl_,
              "INSERT OR REPLACE INTO descriptors(image_id, rows, cols, data) VALUES(?, ?, ?, ?)");
  query.Int64(1, image_id);
  query.Int64(2, descriptors.rows());
  query.Int64(3, descriptors.cols());
  query.Blob(4, descriptors.data(), static_cast<size_t>(descriptors.size()));
  query.Step();
}

void ColmapDatabase::WriteFeatures(image_t image_id, const FeatureKeypoints& keypoints,
                                   const FeatureDescriptors& descriptors) {
  VIOSFM_CHECK(static_cast<size_t>(descriptors.rows()) == keypoints.size())
      << keypoints.size() << " keypoints but " << descriptors.rows() << " descriptors";
  Transaction transaction(*this);
  WriteKeypoints(image_id, keypoints);
  WriteDescriptors(image_id, descriptors);
  transaction.Commit();
}

FeatureKeypoints ColmapDatabase::ReadKeypoints(image_t image_id) const {
  Query query(*impl_, "SELECT rows, cols, data FROM keypoints WHERE image_id = ?");
  query.Int64(1, image_id);
  if (!query.Step()) return {};
  const std::string where = ImageWhere("keypoints", image_id);
  int64_t rows = 0;
  int64_t cols = 0;
  std::vector<float> blob;
  ReadMatrixBlob(*impl_, query, 0, where, &rows, &cols, &blob);
  FeatureKeypoints keypoints(static_cast<size_t>(rows));
  if (rows == 0) return keypoints;
  if (cols != 2 && cols != 4 && cols != 6) {
    throw InputError(impl_->path.string(), 0,
                     where + ": " + std::to_string(cols) + " columns, expected 2, 4 or 6");
  }
  for (size_t i = 0; i < keypoints.size(); ++i) {
    const float* row = blob.data() + cols * i;
    // Positions from COLMAP's pixel convention to viosfm's.
    const float x = row[0] - static_cast<float>(kColmapPixelOffset);
    const float y = row[1] - static_cast<float>(kColmapPixelOffset);
    if (cols == 2) {
      keypoints[i].x = x;
      keypoints[i].y = y;
    } else if (cols == 4) {
      keypoints[i] = FeatureKeypoint::FromScaleOrientation(x, y, row[2], row[3]);
    } else {
      keypoints[i] = {x, y, row[2], row[3], row[4], row[5]};
    }
  }
  return keypoints;
}

FeatureDescriptors ColmapDatabase::ReadDescriptors(image_t image_id) const {
  Query query(*impl_, "SELECT rows, cols, data FROM descriptors WHERE image_id = ?");
  query.Int64(1, image_id);
  if (!query.Step()) return {};
  int64_t rows = 0;
  int64_t cols = 0;
  std::vector<uint8_t> blob;
  ReadMatrixBlob(*impl_, query, 0, ImageWhere("descriptors", image_id), &rows, &cols, &blob);
  FeatureDescriptors descriptors(rows, cols);
  if (!blob.empty()) std::memcpy(descriptors.data(), blob.data(), blob.size());
  return descriptors;
}

bool ColmapDatabase::ExistsKeypoints(image_t image_id) const {
  Query query(*impl_, "SELECT 1 FROM keypoints WHERE image_id = ?");
  query.Int64(1, image_id);
  return query.Step();
}

bool ColmapDatabase::ExistsDescriptors(image_t image_id) const {
  Query query(*impl_, "SELECT 1 FROM descriptors WHERE image_id = ?");
  query.Int64(1, image_id);
  return query.Step();
}

// --------------------------------------------------------------------- matches

void ColmapDatabase::WriteMatches(image_t image_id1, image_t image_id2,
                                  const FeatureMatches& matches) {
  VIOSFM_CHECK(image_id1 != image_id2) << "matches of image " << image_id1 << " with itself";
  const std::vector<uint32_t> blob = MatchesToBlob(matches, SwapImagePair(image_id1, image_id2));
  Query query(*impl_,
              "INSERT OR REPLACE INTO matches(pair_id, rows, cols, data) VALUES(?, ?, ?, ?)");
  query.Int64(1, static_cast<int64_t>(ImagePairToPairId(image_id1, image_id2)));
  query.Int64(2, static_cast<int64_t>(matches.size()));
  query.Int64(3, 2);
  query.Blob(4, blob.data(), blob.size() * sizeof(uint32_t));
  query.Step();
}

FeatureMatches ColmapDatabase::ReadMatches(image_t image_id1, image_t image_id2) const {
  Query query(*impl_, "SELECT rows, cols, data FROM matches WHERE pair_id = ?");
  query.Int64(1, static_cast<int64_t>(ImagePairToPairId(image_id1, image_id2)));
  if (!query.Step()) return {};
  return MatchesFromBlob(*impl_, query, 0, PairWhere("matches", image_id1, image_id2),
                         SwapImagePair(image_id1, image_id2));
}

bool ColmapDatabase::ExistsMatches(image_t image_id1, image_t image_id2) const {
  Query query(*impl_, "SELECT 1 FROM matches WHERE pair_id = ?");
  query.Int64(1, static_cast<int64_t>(ImagePairToPairId(image_id1, image_id2)));
  return query.Step();
}

std::vector<std::pair<image_pair_t, FeatureMatches>> ColmapDatabase::ReadAllMatches() const {
  Query query(*impl_, "SELECT pair_id, rows, cols, data FROM matches ORDER BY pair_id");
  std::vector<std::pair<image_pair_t, FeatureMatches>> all;
  while (query.Step()) {
    const auto pair_id = static_cast<image_pair_t>(query.ColumnInt64(0));
    const auto [id1, id2] = PairIdToImagePair(pair_id);
    all.emplace_back(pair_id,
                     MatchesFromBlob(*impl_, query, 1, PairWhere("matches", id1, id2), false));
  }
  return all;
}

// --------------------------------------------------------- two-view geometries

void ColmapDatabase::WriteTwoViewGeometry(image_t image_id1, image_t image_id2,
                                          const TwoViewGeometry& geometry) {
  VIOSFM_CHECK(image_id1 != image_id2) << "geometry of image " << image_id1 << " with itself";
  const TwoViewGeometry stored =
      SwapImagePair(image_id1, image_id2) ? geometry.Inverted() : geometry;
  const std::vector<uint32_t> blob = MatchesToBlob(stored.inlier_matches, false);
  Query query(*impl_,
              "INSERT OR REPLACE INTO two_view_geometries(pair_id, rows, cols, data, config, F, "
              "E, H, qvec, tvec) VALUES(?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
  query.Int64(1, static_cast<int64_t>(ImagePairToPairId(image_id1, image_id2)));
  query.Int64(2, static_cast<int64_t>(stored.inlier_matches.size()));
  query.Int64(3, 2);
  query.Blob(4, blob.data(), blob.size() * sizeof(uint32_t));
  query.Int64(5, static_cast<int64_t>(stored.config));
  // As COLMAP: the matrices and the pose are stored only with inliers.
  if (!stored.inlier_matches.empty()) {
    const RowMajorMatrix3d F = stored.F;
    const RowMajorMatrix3d E = stored.E;
    const RowMajorMatrix3d H = stored.H;
    const Eigen::Quaterniond& q = stored.cam2_from_cam1.rotation;
    const double qvec[4] = {q.w(), q.x(), q.y(), q.z()};
    const Eigen::Vector3d& tvec = stored.cam2_from_cam1.translation;
    query.Blob(6, F.data(), 9 * sizeof(double));
    query.Blob(7, E.data(), 9 * sizeof(double));
    query.Blob(8, H.data(), 9 * sizeof(double));
    query.Blob(9, qvec, 4 * sizeof(double));
    query.Blob(10, tvec.data(), 3 * sizeof(double));
  } else {
    for (int i = 6; i <= 10; ++i) query.Null(i);
  }
  query.Step();
}

TwoViewGeometry ColmapDatabase::ReadTwoViewGeometry(image_t image_id1, image_t image_id2) const {
  Query query(*impl_,
              "SELECT rows, cols, data, config, F, E, H, qvec, tvec FROM two_view_geometries "
              "WHERE pair_id = ?");
  query.Int64(1, static_cast<int64_t>(ImagePairToPairId(image_id1, image_id2)));
  if (!query.Step()) return {};
  const TwoViewGeometry stored = TwoViewGeometryFromRow(
      *impl_, query, 0, PairWhere("two_view_geometries", image_id1, image_id2));
  return SwapImagePair(image_id1, image_id2) ? stored.Inverted() : stored;
}

bool ColmapDatabase::ExistsTwoViewGeometry(image_t image_id1, image_t image_id2) const {
  Query query(*impl_, "SELECT 1 FROM two_view_geometries WHERE pair_id = ?");
  query.Int64(1, static_cast<int64_t>(ImagePairToPairId(image_id1, image_id2)));
  return query.Step();
}

std::vector<std::pair<image_pair_t, TwoViewGeometry>> ColmapDatabase::ReadAllTwoViewGeometries()
    const {
  Query query(*impl_,
              "SELECT pair_id, rows, cols, data, config, F, E, H, qvec, tvec FROM "
              "two_view_geometries ORDER BY pair_id");
  std::vector<std::pair<image_pair_t, TwoViewGeometry>> all;
  while (query.Step()) {
    const auto pair_id = static_cast<image_pair_t>(query.ColumnInt64(0));
    const auto [id1, id2] = PairIdToImagePair(pair_id);
    all.emplace_back(pair_id, TwoViewGeometryFromRow(*impl_, query, 1,
                                                     PairWhere("two_view_geometries", id1, id2)));
  }
  return all;
}

// ---------------------------------------------------------------------- counts

namespace {

size_t QueryCount(ColmapDatabase::Impl& impl, const std::string& sql) {
  Query query(impl, sql);
  VIOSFM_CHECK(query.Step()) << sql << " returned no row";
  return static_cast<size_t>(query.ColumnInt64(0));  // NULL (empty SUM) reads as 0
}

}  // namespace

size_t ColmapDatabase::NumCameras() const {
  return QueryCount(*impl_, "SELECT COUNT(*) FROM cameras");
}
size_t ColmapDatabase::NumImages() const {
  return QueryCount(*impl_, "SELECT COUNT(*) FROM images");
}
size_t ColmapDatabase::NumKeypoints() const {
  return QueryCount(*impl_, "SELECT SUM(rows) FROM keypoints");
}
size_t ColmapDatabase::NumDescriptors() const {
  return QueryCount(*impl_, "SELECT SUM(rows) FROM descriptors");
}
size_t ColmapDatabase::NumMatches() const {
  return QueryCount(*impl_, "SELECT SUM(rows) FROM matches");
}
size_t ColmapDatabase::NumMatchedImagePairs() const {
  return QueryCount(*impl_, "SELECT COUNT(*) FROM matches");
}
size_t ColmapDatabase::NumVerifiedImagePairs() const {
  return QueryCount(*impl_, "SELECT COUNT(*) FROM two_view_geometries");
}

std::vector<DatabaseSchemaEntry> ColmapDatabase::ReadSchema() const {
  Query query(*impl_,
              "SELECT type, name, sql FROM sqlite_master WHERE sql IS NOT NULL ORDER BY rowid");
  std::vector<DatabaseSchemaEntry> entries;
  while (query.Step()) {
    entries.push_back({query.ColumnText(0), query.ColumnText(1), query.ColumnText(2)});
  }
  return entries;
}

int ColmapDatabase::UserVersion() const {
  Query query(*impl_, "PRAGMA user_version");
  VIOSFM_CHECK(query.Step()) << "PRAGMA user_version returned no row";
  return static_cast<int>(query.ColumnInt64(0));
}

}  // namespace viosfm

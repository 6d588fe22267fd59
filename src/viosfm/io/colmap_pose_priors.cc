#include "viosfm/io/colmap_pose_priors.h"

#include <sqlite3.h>

#include <Eigen/Eigenvalues>
#include <cstring>
#include <memory>
#include <string>

#include "viosfm/util/errors.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;

// One SQLite connection; every failure is an InputError naming the file.
class Connection {
 public:
  explicit Connection(const fs::path& path, bool write) : path_(path.string()) {
    std::error_code error;
    if (!fs::is_regular_file(path, error)) {
      throw InputError(path_, 0, "COLMAP database not found");
    }
    const int flags = write ? SQLITE_OPEN_READWRITE : SQLITE_OPEN_READONLY;
    if (sqlite3_open_v2(path_.c_str(), &db_, flags, nullptr) != SQLITE_OK) {
      const std::string message = db_ ? sqlite3_errmsg(db_) : "out of memory";
      sqlite3_close(db_);
      db_ = nullptr;
      throw InputError(path_, 0, "cannot open the database: " + message);
    }
    sqlite3_busy_timeout(db_, 5000);
    // The destructor does not run for a constructor that throws: close here.
    bool has_images = false;
    try {
      has_images = HasTable("images");
    } catch (...) {
      sqlite3_close(db_);
      throw;
    }
    if (!has_images) {
      sqlite3_close(db_);
      throw InputError(path_, 0, "not a COLMAP database (no images table)");
    }
  }
  ~Connection() { sqlite3_close(db_); }
  Connection(const Connection&) = delete;
  Connection& operator=(const Connection&) = delete;

  void Execute(const std::string& sql) {
    char* message = nullptr;
    if (sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, &message) != SQLITE_OK) {
      const std::string text = message ? message : "unknown error";
      sqlite3_free(message);
      throw InputError(path_, 0, "SQL failed (" + text + "): " + sql.substr(0, 80));
    }
  }

  struct Statement {
    sqlite3_stmt* stmt = nullptr;
    ~Statement() { sqlite3_finalize(stmt); }
  };
  std::unique_ptr<Statement> Prepare(const std::string& sql) {
    auto statement = std::make_unique<Statement>();
    if (sqlite3_prepare_v2(db_, sql.c_str(), -1, &statement->stmt, nullptr) != SQLITE_OK) {
      throw InputError(
          path_, 0, std::string("SQL failed (") + sqlite3_errmsg(db_) + "): " + sql.substr(0, 80));
    }
    return statement;
  }
  void Step(sqlite3_stmt* stmt, int expected) {
    const int rc = sqlite3_step(stmt);
    if (rc != expected) {
      throw InputError(path_, 0, std::string("SQL step failed: ") + sqlite3_errmsg(db_));
    }
  }
  bool HasTable(const std::string& name) {
    auto statement = Prepare("SELECT 1 FROM sqlite_master WHERE type='table' AND name=?");
    sqlite3_bind_text(statement->stmt, 1, name.c_str(), -1, SQLITE_TRANSIENT);
    return sqlite3_step(statement->stmt) == SQLITE_ROW;
  }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  sqlite3* db_ = nullptr;
};

template <typename Matrix>
Matrix ReadBlob(sqlite3_stmt* stmt, int column, const std::string& path, int64_t image_id,
                const char* name) {
  Matrix matrix;
  const int bytes = sqlite3_column_bytes(stmt, column);
  if (bytes != static_cast<int>(sizeof(double) * matrix.size())) {
    throw InputError(path, 0,
                     "pose_priors row of image " + std::to_string(image_id) + ": " + name +
                         " has " + std::to_string(bytes) + " bytes, expected " +
                         std::to_string(sizeof(double) * matrix.size()));
  }
  std::memcpy(matrix.data(), sqlite3_column_blob(stmt, column), bytes);
  return matrix;
}

}  // namespace

const char kColmapPosePriorsTableSql[] =
    "CREATE TABLE IF NOT EXISTS pose_priors"
    "   (image_id                   INTEGER  PRIMARY KEY  NOT NULL,"
    "    position                   BLOB,"
    "    coordinate_system          INTEGER               NOT NULL,"
    "    position_covariance        BLOB,"
    "FOREIGN KEY(image_id) REFERENCES images(image_id) ON DELETE CASCADE);";

void WriteColmapPosePriors(const fs::path& database, const std::vector<ColmapPosePrior>& priors) {
  Connection connection(database, /*write=*/true);
  const std::string& p = connection.path();
  for (const ColmapPosePrior& prior : priors) {
    const std::string what = "pose prior of image " + std::to_string(prior.image_id);
    if (!prior.position.allFinite()) throw InputError(p, 0, what + ": non-finite position");
    const Eigen::Matrix3d& c = prior.position_covariance;
    if (!c.allFinite() ||
        (c - c.transpose()).cwiseAbs().maxCoeff() > 1e-12 * c.cwiseAbs().maxCoeff()) {
      throw InputError(p, 0, what + ": the position covariance is not a finite symmetric matrix");
    }
    const Eigen::Vector3d eigenvalues =
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(c).eigenvalues();
    if (eigenvalues.minCoeff() < -1e-12 * std::max(1.0, eigenvalues.maxCoeff())) {
      throw InputError(p, 0, what + ": the position covariance is not positive semi-definite");
    }
  }
  connection.Execute("BEGIN");
  connection.Execute(kColmapPosePriorsTableSql);
  auto exists = connection.Prepare("SELECT 1 FROM images WHERE image_id=?");
  auto insert = connection.Prepare(
      "INSERT OR REPLACE INTO pose_priors(image_id, position, coordinate_system, "
      "position_covariance) VALUES(?, ?, ?, ?)");
  auto update = connection.Prepare(
      "UPDATE images SET prior_qw=?, prior_qx=?, prior_qy=?, prior_qz=?, prior_tx=?, "
      "prior_ty=?, prior_tz=? WHERE image_id=?");
  for (const ColmapPosePrior& prior : priors) {
    sqlite3_reset(exists->stmt);
    sqlite3_bind_int64(exists->stmt, 1, static_cast<sqlite3_int64>(prior.image_id));
    if (sqlite3_step(exists->stmt) != SQLITE_ROW) {
      connection.Execute("ROLLBACK");
      throw InputError(p, 0,
                       "pose prior for image " + std::to_string(prior.image_id) +
                           ", which the images table does not have");
    }
    sqlite3_reset(insert->stmt);
    sqlite3_bind_int64(insert->stmt, 1, static_cast<sqlite3_int64>(prior.image_id));
    sqlite3_bind_blob(insert->stmt, 2, prior.position.data(), 3 * sizeof(double), SQLITE_TRANSIENT);
    sqlite3_bind_int64(insert->stmt, 3, static_cast<int>(prior.coordinate_system));
    sqlite3_bind_blob(insert->stmt, 4, prior.position_covariance.data(), 9 * sizeof(double),
                      SQLITE_TRANSIENT);
    connection.Step(insert->stmt, SQLITE_DONE);
    const Eigen::Quaterniond& q = prior.cam_from_world_rotation;
    const double values[7] = {
        q.w(), q.x(), q.y(), q.z(), prior.position.x(), prior.position.y(), prior.position.z()};
    sqlite3_reset(update->stmt);
    for (int i = 0; i < 7; ++i) sqlite3_bind_double(update->stmt, i + 1, values[i]);
    sqlite3_bind_int64(update->stmt, 8, static_cast<sqlite3_int64>(prior.image_id));
    connection.Step(update->stmt, SQLITE_DONE);
  }
  connection.Execute("COMMIT");
}

void CopyColmapDatabase(const fs::path& source, const fs::path& destination) {
  if (fs::exists(destination)) {
    throw InputError(destination.string(), 0, "exists already (not overwritten)");
  }
  // Opened for writing, only read: as the last connection it removes the
  // -wal and -shm files it made beside the source (a read-only connection
  // would leave them in the run's folder).
  Connection connection(source, /*write=*/true);
  auto vacuum = connection.Prepare("VACUUM INTO ?");
  const std::string target = destination.string();
  sqlite3_bind_text(vacuum->stmt, 1, target.c_str(), -1, SQLITE_TRANSIENT);
  connection.Step(vacuum->stmt, SQLITE_DONE);
}

std::vector<ColmapPosePrior> ReadColmapPosePriors(const fs::path& database) {
  Connection connection(database, /*write=*/false);
  std::vector<ColmapPosePrior> priors;
  if (!connection.HasTable("pose_priors")) return priors;
  auto select = connection.Prepare(
      "SELECT p.image_id, p.position, p.coordinate_system, p.position_covariance, i.prior_qw, "
      "i.prior_qx, i.prior_qy, i.prior_qz FROM pose_priors p LEFT JOIN images i ON "
      "p.image_id = i.image_id ORDER BY p.image_id");
  while (sqlite3_step(select->stmt) == SQLITE_ROW) {
    ColmapPosePrior prior;
    const int64_t id = sqlite3_column_int64(select->stmt, 0);
    prior.image_id = static_cast<image_t>(id);
    prior.position = ReadBlob<Eigen::Vector3d>(select->stmt, 1, connection.path(), id, "position");
    prior.coordinate_system =
        static_cast<ColmapCoordinateSystem>(sqlite3_column_int64(select->stmt, 2));
    prior.position_covariance =
        ReadBlob<Eigen::Matrix3d>(select->stmt, 3, connection.path(), id, "position_covariance");
    if (sqlite3_column_type(select->stmt, 4) != SQLITE_NULL) {
      prior.cam_from_world_rotation = Eigen::Quaterniond(
          sqlite3_column_double(select->stmt, 4), sqlite3_column_double(select->stmt, 5),
          sqlite3_column_double(select->stmt, 6), sqlite3_column_double(select->stmt, 7));
    }
    priors.push_back(prior);
  }
  return priors;
}

}  // namespace viosfm

#include "viosfm/io/colmap_pose_priors.h"

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>

#include "viosfm/io/colmap_database.h"
#include "viosfm/sensor/camera_models.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {
namespace fs = std::filesystem;

// COLMAP's own statements about the table (testdata/colmap_pose_priors_sql.txt).
std::map<std::string, std::string> ColmapStatements() {
  std::ifstream file(testing::SourcePath("io/testdata/colmap_pose_priors_sql.txt"));
  std::map<std::string, std::string> statements;
  for (std::string line; std::getline(file, line);) {
    if (line.empty() || line[0] == '#') continue;
    statements[line.substr(0, line.find('|'))] = line.substr(line.find('|') + 1);
  }
  EXPECT_EQ(statements.size(), 5u);
  return statements;
}

// A COLMAP 3.8 database with one camera and three images.
fs::path MakeDatabase(const fs::path& folder) {
  const fs::path path = folder / "database.db";
  ColmapDatabase database = ColmapDatabase::Open(path);
  const camera_t camera =
      database.WriteCamera(MakeCamera(CameraModelId::kPinhole, 640, 480, {500, 501, 320, 240}));
  for (const char* name : {"a.png", "b.png", "c.png"}) database.WriteImage(name, camera);
  return path;
}

std::vector<ColmapPosePrior> MakePriors() {
  std::vector<ColmapPosePrior> priors(2);
  priors[0].image_id = 1;
  priors[0].position = Eigen::Vector3d(1.0 / 3.0, -2.5, 1e-9);
  priors[0].position_covariance << 0.01, 0.002, 0.0, 0.002, 0.02, -0.001, 0.0, -0.001, 0.04;
  priors[0].cam_from_world_rotation = Eigen::Quaterniond(0.5, 0.5, -0.5, 0.5);
  priors[1].image_id = 3;
  priors[1].position = Eigen::Vector3d(10, 20, 30);
  priors[1].position_covariance = 0.25 * Eigen::Matrix3d::Identity();
  return priors;
}

std::string TableSql(const fs::path& database, const std::string& table) {
  sqlite3* db = nullptr;
  sqlite3_open_v2(database.c_str(), &db, SQLITE_OPEN_READONLY, nullptr);
  sqlite3_stmt* stmt = nullptr;
  sqlite3_prepare_v2(db, "SELECT sql FROM sqlite_master WHERE name=?", -1, &stmt, nullptr);
  sqlite3_bind_text(stmt, 1, table.c_str(), -1, SQLITE_TRANSIENT);
  std::string sql;
  if (sqlite3_step(stmt) == SQLITE_ROW) {
    sql = reinterpret_cast<const char*>(sqlite3_column_text(stmt, 0));
  }
  sqlite3_finalize(stmt);
  sqlite3_close(db);
  return sql;
}

TEST(ColmapPosePriors, WritesCOLMAP311sTableAndReadsItBack) {
  const fs::path folder = testing::MakeScratchFolder("pose_priors");
  const fs::path path = MakeDatabase(folder);
  const std::vector<ColmapPosePrior> priors = MakePriors();
  WriteColmapPosePriors(path, priors);
  // SQLite stores "CREATE TABLE name" for "CREATE TABLE IF NOT EXISTS name",
  // without the final semicolon.
  std::string expected = ColmapStatements().at("create_311");
  expected.replace(0, std::string("CREATE TABLE IF NOT EXISTS").size(), "CREATE TABLE");
  expected.pop_back();
  EXPECT_EQ(TableSql(path, "pose_priors"), expected);

  const std::vector<ColmapPosePrior> read = ReadColmapPosePriors(path);
  ASSERT_EQ(read.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(read[i].image_id, priors[i].image_id);
    EXPECT_EQ(read[i].position, priors[i].position);
    EXPECT_EQ(read[i].position_covariance, priors[i].position_covariance);
    EXPECT_EQ(read[i].coordinate_system, ColmapCoordinateSystem::kCartesian);
    EXPECT_EQ(read[i].cam_from_world_rotation.coeffs(), priors[i].cam_from_world_rotation.coeffs());
  }
  // COLMAP 3.8's columns, through viosfm's 3.8 database reader.
  ColmapDatabase database = ColmapDatabase::Open(path);
  const DatabaseImage image = database.ReadImage(1);
  ASSERT_TRUE(image.prior.has_value());
  EXPECT_EQ(image.prior->position_in_world, priors[0].position);
  EXPECT_FALSE(database.ReadImage(2).prior.has_value());

  // Writing again replaces the rows.
  std::vector<ColmapPosePrior> again = MakePriors();
  again[1].position.x() = -1;
  WriteColmapPosePriors(path, again);
  EXPECT_EQ(ReadColmapPosePriors(path)[1].position.x(), -1.0);
}

// COLMAP 4.0's migration of the 3.11 table, run with COLMAP's statements on
// a database viosfm wrote: every prior lands in the new layout, attached to
// its image and camera.
TEST(ColmapPosePriors, COLMAP4MigrationKeepsThePriors) {
  const fs::path folder = testing::MakeScratchFolder("pose_priors_migration");
  const fs::path path = MakeDatabase(folder);
  const std::vector<ColmapPosePrior> priors = MakePriors();
  WriteColmapPosePriors(path, priors);
  const std::map<std::string, std::string> sql = ColmapStatements();

  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  for (const char* key : {"rename_400", "create_400"}) {
    ASSERT_EQ(sqlite3_exec(db, sql.at(key).c_str(), nullptr, nullptr, nullptr), SQLITE_OK) << key;
  }
  sqlite3_stmt* migrate = nullptr;
  ASSERT_EQ(sqlite3_prepare_v2(db, sql.at("migrate_400").c_str(), -1, &migrate, nullptr),
            SQLITE_OK);
  const double nan3[3] = {std::numeric_limits<double>::quiet_NaN(),
                          std::numeric_limits<double>::quiet_NaN(),
                          std::numeric_limits<double>::quiet_NaN()};
  sqlite3_bind_int64(migrate, 1, 0);  // SensorType::CAMERA
  sqlite3_bind_blob(migrate, 2, nan3, sizeof(nan3), SQLITE_TRANSIENT);
  ASSERT_EQ(sqlite3_step(migrate), SQLITE_DONE);
  sqlite3_finalize(migrate);
  ASSERT_EQ(sqlite3_exec(db, sql.at("drop_400").c_str(), nullptr, nullptr, nullptr), SQLITE_OK);

  sqlite3_stmt* select = nullptr;
  sqlite3_prepare_v2(db,
                     "SELECT pose_prior_id, corr_data_id, corr_sensor_id, corr_sensor_type, "
                     "position, position_covariance, coordinate_system FROM pose_priors ORDER BY "
                     "pose_prior_id",
                     -1, &select, nullptr);
  for (const ColmapPosePrior& prior : priors) {
    ASSERT_EQ(sqlite3_step(select), SQLITE_ROW);
    EXPECT_EQ(sqlite3_column_int64(select, 0), prior.image_id);
    EXPECT_EQ(sqlite3_column_int64(select, 1), prior.image_id);
    EXPECT_EQ(sqlite3_column_int64(select, 2), 1);  // the camera
    EXPECT_EQ(sqlite3_column_int64(select, 3), 0);
    ASSERT_EQ(sqlite3_column_bytes(select, 4), 24);
    Eigen::Vector3d position;
    std::memcpy(position.data(), sqlite3_column_blob(select, 4), 24);
    EXPECT_EQ(position, prior.position);
    ASSERT_EQ(sqlite3_column_bytes(select, 5), 72);
    Eigen::Matrix3d covariance;
    std::memcpy(covariance.data(), sqlite3_column_blob(select, 5), 72);
    EXPECT_EQ(covariance, prior.position_covariance);
    EXPECT_EQ(sqlite3_column_int64(select, 6), 1);  // CARTESIAN
  }
  EXPECT_EQ(sqlite3_step(select), SQLITE_DONE);
  sqlite3_finalize(select);
  sqlite3_close(db);
}

TEST(ColmapPosePriors, BadPriorsAreInputErrors) {
  const fs::path folder = testing::MakeScratchFolder("pose_priors_bad");
  const fs::path path = MakeDatabase(folder);
  std::vector<ColmapPosePrior> priors = MakePriors();
  priors[1].image_id = 7;
  EXPECT_NE(testing::InputErrorMessage([&] {
              WriteColmapPosePriors(path, priors);
            }).find("image 7, which the images table does not have"),
            std::string::npos);
  EXPECT_TRUE(ReadColmapPosePriors(path).empty());  // rolled back
  priors = MakePriors();
  priors[0].position_covariance(0, 1) = 0.5;
  EXPECT_NE(testing::InputErrorMessage([&] {
              WriteColmapPosePriors(path, priors);
            }).find("not a finite symmetric matrix"),
            std::string::npos);
  priors = MakePriors();
  priors[0].position_covariance(2, 2) = -1.0;
  EXPECT_NE(testing::InputErrorMessage([&] {
              WriteColmapPosePriors(path, priors);
            }).find("not positive semi-definite"),
            std::string::npos);
  testing::WriteTextFile(folder / "empty.db", "");
  EXPECT_NE(testing::InputErrorMessage([&] {
              WriteColmapPosePriors(folder / "empty.db", {});
            }).find("not a COLMAP database"),
            std::string::npos);
}

TEST(ColmapPosePriors, CopyIsConsistent) {
  const fs::path folder = testing::MakeScratchFolder("pose_priors_copy");
  const fs::path path = MakeDatabase(folder);
  CopyColmapDatabase(path, folder / "copy.db");
  ColmapDatabase copy = ColmapDatabase::Open(folder / "copy.db");
  EXPECT_EQ(copy.NumImages(), 3u);
  EXPECT_NE(testing::InputErrorMessage([&] {
              CopyColmapDatabase(path, folder / "copy.db");
            }).find("exists already"),
            std::string::npos);
}

}  // namespace
}  // namespace viosfm

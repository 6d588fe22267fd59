#include "viosfm/io/colmap_database.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sqlite3.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <numeric>
#include <random>
#include <string>

#include "viosfm/sensor/camera_models.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;

Camera EurocLikeCamera() {
  return MakeCamera(
      CameraModelId::kOpenCV, 752, 480,
      {458.654, 457.296, 367.215, 248.375, -0.28340811, 0.07395907, 0.00019359, 1.76187114e-05});
}

// The raw bytes of one blob column of one row, read directly with SQLite.
std::vector<uint8_t> RawBlob(const fs::path& db_path, const std::string& sql) {
  sqlite3* db = nullptr;
  EXPECT_EQ(sqlite3_open_v2(db_path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr), SQLITE_OK);
  sqlite3_stmt* statement = nullptr;
  EXPECT_EQ(sqlite3_prepare_v2(db, sql.c_str(), -1, &statement, nullptr), SQLITE_OK) << sql;
  std::vector<uint8_t> bytes;
  if (sqlite3_step(statement) == SQLITE_ROW) {
    const auto* data = static_cast<const uint8_t*>(sqlite3_column_blob(statement, 0));
    bytes.assign(data, data + sqlite3_column_bytes(statement, 0));
  }
  sqlite3_finalize(statement);
  sqlite3_close(db);
  return bytes;
}

template <typename T>
std::vector<T> BytesAs(const std::vector<uint8_t>& bytes) {
  std::vector<T> values(bytes.size() / sizeof(T));
  std::memcpy(values.data(), bytes.data(), values.size() * sizeof(T));
  return values;
}

// The committed fixture: "type|name|sql" rows, then "user_version|N".
std::vector<DatabaseSchemaEntry> ReadSchemaFixture(int* user_version) {
  std::ifstream file(testing::SourcePath("io/testdata/colmap38_database_schema.txt"));
  EXPECT_TRUE(file.good());
  std::vector<DatabaseSchemaEntry> entries;
  std::string line;
  while (std::getline(file, line)) {
    if (line.empty() || line[0] == '#') continue;
    const size_t first = line.find('|');
    const size_t second = line.find('|', first + 1);
    if (line.substr(0, first) == "user_version") {
      *user_version = std::stoi(line.substr(first + 1));
      continue;
    }
    entries.push_back({line.substr(0, first), line.substr(first + 1, second - first - 1),
                       line.substr(second + 1)});
  }
  return entries;
}

void ExpectSameSchema(const std::vector<DatabaseSchemaEntry>& actual,
                      const std::vector<DatabaseSchemaEntry>& expected) {
  ASSERT_EQ(actual.size(), expected.size());
  for (size_t i = 0; i < actual.size(); ++i) {
    EXPECT_EQ(actual[i].type, expected[i].type) << i;
    EXPECT_EQ(actual[i].name, expected[i].name) << i;
    EXPECT_EQ(actual[i].sql, expected[i].sql) << i;
  }
}

bool HaveColmap() {
  return std::system("command -v colmap > /dev/null 2>&1") == 0;
}

TEST(ColmapDatabase, SchemaIsColmap38s) {
  const fs::path folder = testing::MakeScratchFolder("db_schema");
  int expected_version = 0;
  const std::vector<DatabaseSchemaEntry> expected = ReadSchemaFixture(&expected_version);
  ASSERT_EQ(expected.size(), 8u);  // 6 tables, sqlite_sequence and the name index
  EXPECT_EQ(expected_version, kColmapDatabaseUserVersion);
  {
    ColmapDatabase database = ColmapDatabase::Open(folder / "ours.db");
    ExpectSameSchema(database.ReadSchema(), expected);
    EXPECT_EQ(database.UserVersion(), kColmapDatabaseUserVersion);
  }
  // Re-opening an existing database leaves it as it is.
  ColmapDatabase reopened = ColmapDatabase::Open(folder / "ours.db");
  ExpectSameSchema(reopened.ReadSchema(), expected);

  if (!HaveColmap()) {
    std::cout << "colmap not found: compared with the committed fixture only\n";
    return;
  }
  const fs::path theirs = folder / "colmap.db";
  const std::string command = "QT_QPA_PLATFORM=offscreen colmap database_creator --database_path " +
                              theirs.string() + " > /dev/null 2>&1";
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
  ColmapDatabase colmap_created = ColmapDatabase::Open(theirs);
  ExpectSameSchema(reopened.ReadSchema(), colmap_created.ReadSchema());
  EXPECT_EQ(colmap_created.UserVersion(), kColmapDatabaseUserVersion);
}

TEST(ColmapDatabase, CameraRoundTripAndPrincipalPointConvention) {
  const fs::path path = testing::MakeScratchFolder("db_camera") / "db.db";
  const Camera camera = EurocLikeCamera();
  Camera pinhole = MakeCamera(CameraModelId::kSimpleRadial, 640, 480, {500.0, 320.0, 240.0, 0.01});
  pinhole.has_prior_focal_length = true;
  {
    ColmapDatabase database = ColmapDatabase::Open(path);
    EXPECT_EQ(database.WriteCamera(camera), 1u);
    EXPECT_EQ(database.WriteCamera(pinhole), 2u);
    Camera with_id = pinhole;
    with_id.camera_id = 7;
    EXPECT_EQ(database.WriteCamera(with_id, /*use_camera_id=*/true), 7u);
    EXPECT_THROW(database.WriteCamera(with_id, true), InputError);
    Camera bad = pinhole;
    bad.params.pop_back();
    EXPECT_THROW(database.WriteCamera(bad), InputError);

    const Camera read = database.ReadCamera(1);
    EXPECT_EQ(read.camera_id, 1u);
    EXPECT_EQ(read.model_id, CameraModelId::kOpenCV);
    EXPECT_EQ(read.width, 752u);
    EXPECT_EQ(read.height, 480u);
    EXPECT_FALSE(read.has_prior_focal_length);
    ASSERT_EQ(read.params.size(), camera.params.size());
    for (size_t i = 0; i < camera.params.size(); ++i) {
      EXPECT_NEAR(read.params[i], camera.params[i], 1e-12) << i;
    }
    const std::vector<Camera> all = database.ReadAllCameras();
    ASSERT_EQ(all.size(), 3u);
    EXPECT_EQ(all[1].model_id, CameraModelId::kSimpleRadial);
    EXPECT_TRUE(all[1].has_prior_focal_length);
    EXPECT_NEAR(all[1].params[1], 320.0, 1e-12);
    EXPECT_EQ(all[2].camera_id, 7u);
    EXPECT_THROW(database.ReadCamera(3), InputError);
    EXPECT_EQ(database.NumCameras(), 3u);
  }
  // On disk the principal point is in COLMAP's convention: +0.5 pixel.
  const std::vector<double> stored =
      BytesAs<double>(RawBlob(path, "SELECT params FROM cameras WHERE camera_id = 1"));
  ASSERT_EQ(stored.size(), 8u);
  EXPECT_EQ(stored[0], 458.654);
  EXPECT_EQ(stored[1], 457.296);
  EXPECT_DOUBLE_EQ(stored[2], 367.715);
  EXPECT_DOUBLE_EQ(stored[3], 248.875);
  EXPECT_EQ(stored[4], camera.params[4]);
  const std::vector<double> simple =
      BytesAs<double>(RawBlob(path, "SELECT params FROM cameras WHERE camera_id = 2"));
  EXPECT_EQ(simple, (std::vector<double>{500.0, 320.5, 240.5, 0.01}));
}

TEST(ColmapDatabase, ImagesWithAndWithoutPrior) {
  const fs::path path = testing::MakeScratchFolder("db_images") / "db.db";
  ColmapDatabase database = ColmapDatabase::Open(path);
  const camera_t camera_id = database.WriteCamera(EurocLikeCamera());
  ImagePosePrior prior;
  prior.cam_from_world_rotation = Eigen::Quaterniond(0.5, 0.5, -0.5, 0.5);
  prior.position_in_world = Eigen::Vector3d(1.0, -2.0, 3.5);
  EXPECT_EQ(database.WriteImage("a.png", camera_id), 1u);
  EXPECT_EQ(database.WriteImage("sub/b.png", camera_id, prior), 2u);
  EXPECT_THROW(database.WriteImage("a.png", camera_id), InputError);
  EXPECT_THROW(database.WriteImage("c.png", camera_id + 10), InputError);

  EXPECT_TRUE(database.ExistsImageWithName("sub/b.png"));
  EXPECT_FALSE(database.ExistsImageWithName("b.png"));
  EXPECT_TRUE(database.ExistsImage(1));
  EXPECT_FALSE(database.ExistsImage(3));
  const DatabaseImage a = database.ReadImage(1);
  EXPECT_EQ(a.name, "a.png");
  EXPECT_EQ(a.camera_id, camera_id);
  EXPECT_FALSE(a.prior.has_value());
  const std::optional<DatabaseImage> b = database.ReadImageWithName("sub/b.png");
  ASSERT_TRUE(b.has_value());
  EXPECT_EQ(b->image_id, 2u);
  ASSERT_TRUE(b->prior.has_value());
  EXPECT_EQ(b->prior->cam_from_world_rotation.coeffs(), prior.cam_from_world_rotation.coeffs());
  EXPECT_EQ(b->prior->position_in_world, prior.position_in_world);
  EXPECT_FALSE(database.ReadImageWithName("nothing.png").has_value());
  EXPECT_THROW(database.ReadImage(5), InputError);
  EXPECT_EQ(database.ReadAllImages().size(), 2u);
  EXPECT_EQ(database.NumImages(), 2u);
}

FeatureKeypoints RandomKeypoints(int count, std::mt19937* rng) {
  std::uniform_real_distribution<float> uniform(0.0f, 700.0f);
  FeatureKeypoints keypoints;
  for (int i = 0; i < count; ++i) {
    keypoints.push_back(FeatureKeypoint::FromScaleOrientation(
        uniform(*rng), uniform(*rng), 1.0f + uniform(*rng) / 100.0f, uniform(*rng) / 100.0f));
  }
  return keypoints;
}

FeatureDescriptors RandomDescriptors(int count, std::mt19937* rng) {
  std::uniform_int_distribution<int> byte(0, 255);
  FeatureDescriptors descriptors(count, 128);
  for (int i = 0; i < descriptors.size(); ++i) descriptors.data()[i] = byte(*rng);
  return descriptors;
}

TEST(ColmapDatabase, KeypointAndDescriptorBlobs) {
  const fs::path path = testing::MakeScratchFolder("db_features") / "db.db";
  std::mt19937 rng(3);
  const FeatureKeypoints keypoints = RandomKeypoints(50, &rng);
  const FeatureDescriptors descriptors = RandomDescriptors(50, &rng);
  {
    ColmapDatabase database = ColmapDatabase::Open(path);
    const camera_t camera_id = database.WriteCamera(EurocLikeCamera());
    const image_t image_id = database.WriteImage("a.png", camera_id);
    const image_t empty_id = database.WriteImage("b.png", camera_id);
    EXPECT_FALSE(database.ExistsFeatures(image_id));
    database.WriteFeatures(image_id, keypoints, descriptors);
    database.WriteFeatures(empty_id, {}, FeatureDescriptors(0, 128));
    EXPECT_TRUE(database.ExistsFeatures(image_id));
    EXPECT_TRUE(database.ExistsFeatures(empty_id));

    const FeatureKeypoints read = database.ReadKeypoints(image_id);
    ASSERT_EQ(read.size(), keypoints.size());
    for (size_t i = 0; i < read.size(); ++i) {
      EXPECT_EQ(std::memcmp(&read[i], &keypoints[i], sizeof(FeatureKeypoint)), 0) << i;
    }
    EXPECT_EQ(database.ReadDescriptors(image_id), descriptors);
    EXPECT_TRUE(database.ReadKeypoints(empty_id).empty());
    EXPECT_EQ(database.ReadDescriptors(empty_id).rows(), 0);
    EXPECT_TRUE(database.ReadKeypoints(99).empty());
    EXPECT_EQ(database.NumKeypoints(), 50u);
    EXPECT_EQ(database.NumDescriptors(), 50u);
  }
  // Layout: rows x 6 float32 (x, y, a11, a12, a21, a22) and rows x 128 uint8;
  // positions in COLMAP's pixel convention (viosfm's + 0.5).
  const std::vector<float> stored =
      BytesAs<float>(RawBlob(path, "SELECT data FROM keypoints WHERE image_id = 1"));
  ASSERT_EQ(stored.size(), 6u * 50u);
  for (size_t i = 0; i < keypoints.size(); ++i) {
    const FeatureKeypoint& k = keypoints[i];
    EXPECT_EQ(std::vector<float>(stored.begin() + 6 * i, stored.begin() + 6 * i + 6),
              (std::vector<float>{k.x + 0.5f, k.y + 0.5f, k.a11, k.a12, k.a21, k.a22}));
  }
  const std::vector<uint8_t> bytes =
      RawBlob(path, "SELECT data FROM descriptors WHERE image_id = 1");
  ASSERT_EQ(bytes.size(), 50u * 128u);
  EXPECT_EQ(bytes[128 * 7 + 5], descriptors(7, 5));
}

void ExecuteRaw(const fs::path& db_path, const std::string& sql) {
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(db_path.c_str(), &db), SQLITE_OK);
  EXPECT_EQ(sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr), SQLITE_OK) << sql;
  sqlite3_close(db);
}

TEST(ColmapDatabase, ReadsOtherKeypointLayoutsAndRejectsBadBlobs) {
  const fs::path path = testing::MakeScratchFolder("db_layouts") / "db.db";
  {
    ColmapDatabase database = ColmapDatabase::Open(path);
    const camera_t camera_id = database.WriteCamera(EurocLikeCamera());
    for (const char* name : {"1.png", "2.png", "3.png", "4.png"}) {
      database.WriteImage(name, camera_id);
    }
  }
  // Older COLMAP layouts: 4 columns (x, y, scale, orientation) and 2 (x, y);
  // then a blob of 7 bytes that claims one 6-column row, and an unknown
  // camera model.
  ExecuteRaw(path,
             "INSERT INTO keypoints VALUES(1, 1, 4, "
             "X'0000204100002041000000400000803F');"  // 10, 10, 2, 1 (float32 LE)
             "INSERT INTO keypoints VALUES(2, 1, 2, X'0000A0400000C040');"  // 5, 6
             "INSERT INTO keypoints VALUES(3, 1, 6, X'00000000000000');"
             "INSERT INTO cameras VALUES(9, 42, 10, 10, NULL, 0);");
  ColmapDatabase database = ColmapDatabase::Open(path);
  const FeatureKeypoints four = database.ReadKeypoints(1);
  ASSERT_EQ(four.size(), 1u);
  EXPECT_EQ(four[0].x, 9.5f);  // COLMAP's 10 in viosfm's convention
  EXPECT_FLOAT_EQ(four[0].Scale(), 2.0f);
  EXPECT_FLOAT_EQ(four[0].Orientation(), 1.0f);
  const FeatureKeypoints two = database.ReadKeypoints(2);
  ASSERT_EQ(two.size(), 1u);
  EXPECT_EQ(two[0].y, 5.5f);
  EXPECT_EQ(two[0].a11, 1.0f);
  try {
    database.ReadKeypoints(3);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("table keypoints, image_id 3"));
    EXPECT_THAT(e.what(), ::testing::HasSubstr(path.string()));
  }
  EXPECT_THROW(database.ReadCamera(9), InputError);
}

// Found by fuzz/fuzz_colmap_database: rows x cols of a blob is checked
// without overflow, and rows without columns are no matrix (they used to
// pass with an empty blob and size a vector of 2^40 keypoints:
// std::length_error, an internal error instead of bad input).
TEST(ColmapDatabase, HostileBlobSizesAreInputErrors) {
  const fs::path path = testing::MakeScratchFolder("db_hostile_sizes") / "db.db";
  { ColmapDatabase::Open(path); }
  ExecuteRaw(path,
             "INSERT INTO keypoints VALUES(1, 1099511627776, 0, NULL);"
             // 2^62 x 4 float32 = 2^66 bytes, 0 modulo 2^64: an empty blob.
             "INSERT INTO keypoints VALUES(2, 4611686018427387904, 4, NULL);"
             "INSERT INTO descriptors VALUES(3, 1099511627776, 0, NULL);"
             "INSERT INTO descriptors VALUES(4, -1, 128, NULL);"
             "INSERT INTO matches VALUES(2147483649, 4611686018427387904, 2, NULL);");
  ColmapDatabase database = ColmapDatabase::Open(path);
  const auto expect_error = [&](const auto& read, const std::string& where) {
    try {
      read();
      ADD_FAILURE() << "expected an InputError for " << where;
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), ::testing::HasSubstr(path.string() + ": " + where));
      EXPECT_THAT(e.what(), ::testing::HasSubstr("does not hold"));
    }
  };
  expect_error([&] { database.ReadKeypoints(1); }, "table keypoints, image_id 1");
  expect_error([&] { database.ReadKeypoints(2); }, "table keypoints, image_id 2");
  expect_error([&] { database.ReadDescriptors(3); }, "table descriptors, image_id 3");
  expect_error([&] { database.ReadDescriptors(4); }, "table descriptors, image_id 4");
  expect_error([&] { database.ReadMatches(1, 2); }, "table matches, pair (1, 2)");
  expect_error([&] { database.ReadAllMatches(); }, "table matches, pair (1, 2)");
}

TEST(ColmapDatabase, MatchesAreStoredInPairIdOrder) {
  const fs::path path = testing::MakeScratchFolder("db_matches") / "db.db";
  const FeatureMatches matches = {{1, 10}, {2, 20}, {3, 30}};
  {
    ColmapDatabase database = ColmapDatabase::Open(path);
    const camera_t camera_id = database.WriteCamera(EurocLikeCamera());
    for (const char* name : {"1.png", "2.png", "3.png", "4.png", "5.png"}) {
      database.WriteImage(name, camera_id);
    }
    database.WriteMatches(5, 2, matches);  // image 5 first: stored swapped
    database.WriteMatches(1, 3, matches);
    EXPECT_TRUE(database.ExistsMatches(2, 5));
    EXPECT_TRUE(database.ExistsMatches(5, 2));
    EXPECT_FALSE(database.ExistsMatches(1, 2));

    const FeatureMatches same_order = database.ReadMatches(5, 2);
    ASSERT_EQ(same_order.size(), 3u);
    EXPECT_EQ(same_order[1].point2D_idx1, 2u);
    EXPECT_EQ(same_order[1].point2D_idx2, 20u);
    const FeatureMatches pair_order = database.ReadMatches(2, 5);
    ASSERT_EQ(pair_order.size(), 3u);
    EXPECT_EQ(pair_order[1].point2D_idx1, 20u);
    EXPECT_EQ(pair_order[1].point2D_idx2, 2u);
    EXPECT_TRUE(database.ReadMatches(3, 4).empty());

    const auto all = database.ReadAllMatches();
    ASSERT_EQ(all.size(), 2u);
    EXPECT_EQ(all[0].first, ImagePairToPairId(1, 3));
    EXPECT_EQ(all[1].first, ImagePairToPairId(2, 5));
    EXPECT_EQ(all[1].second[0].point2D_idx1, 10u);
    EXPECT_EQ(database.NumMatches(), 6u);
    EXPECT_EQ(database.NumMatchedImagePairs(), 2u);
  }
  // COLMAP's pair id 2 * (2^31 - 1) + 5 and the columns (image 2, image 5).
  const std::string sql =
      "SELECT data FROM matches WHERE pair_id = " + std::to_string(2ull * 2147483647ull + 5ull);
  EXPECT_EQ(BytesAs<uint32_t>(RawBlob(path, sql)), (std::vector<uint32_t>{10, 1, 20, 2, 30, 3}));
}

TwoViewGeometry ExampleGeometry() {
  TwoViewGeometry geometry;
  geometry.config = TwoViewGeometryConfig::kCalibrated;
  geometry.inlier_matches = {{0, 4}, {1, 5}, {2, 9}};
  geometry.cam2_from_cam1 =
      Rigid3d(Eigen::Quaterniond(Eigen::AngleAxisd(0.2, Eigen::Vector3d(0, 1, 0))),
              Eigen::Vector3d(0.6, 0.0, 0.8));
  geometry.F << 1, 2, 3, 4, 5, 6, 7, 8, 10;
  geometry.E << 0, -0.8, 0, 0.8, 0, -0.6, 0, 0.6, 0;
  geometry.H << 1, 0.2, 5, -0.1, 1.1, 3, 0.001, 0.002, 1;
  return geometry;
}

TEST(ColmapDatabase, TwoViewGeometryRoundTripAndSwap) {
  const fs::path path = testing::MakeScratchFolder("db_geometry") / "db.db";
  const TwoViewGeometry geometry = ExampleGeometry();
  {
    ColmapDatabase database = ColmapDatabase::Open(path);
    const camera_t camera_id = database.WriteCamera(EurocLikeCamera());
    for (const char* name : {"1.png", "2.png", "3.png"}) database.WriteImage(name, camera_id);
    database.WriteTwoViewGeometry(1, 2, geometry);
    database.WriteTwoViewGeometry(3, 1, geometry);  // stored inverted, as (1, 3)
    TwoViewGeometry degenerate;
    degenerate.config = TwoViewGeometryConfig::kDegenerate;
    database.WriteTwoViewGeometry(2, 3, degenerate);

    for (const auto& [id1, id2] : {std::pair<image_t, image_t>{1, 2}, {3, 1}}) {
      const TwoViewGeometry read = database.ReadTwoViewGeometry(id1, id2);
      EXPECT_EQ(read.config, geometry.config);
      ASSERT_EQ(read.inlier_matches.size(), 3u);
      EXPECT_EQ(read.inlier_matches[2].point2D_idx1, 2u);
      EXPECT_EQ(read.inlier_matches[2].point2D_idx2, 9u);
      EXPECT_TRUE(read.F.isApprox(geometry.F, 1e-14));
      EXPECT_TRUE(read.E.isApprox(geometry.E, 1e-14));
      EXPECT_TRUE(read.H.isApprox(geometry.H, 1e-12));
      EXPECT_LT(read.cam2_from_cam1.rotation.angularDistance(geometry.cam2_from_cam1.rotation),
                1e-12);
      EXPECT_LT((read.cam2_from_cam1.translation - geometry.cam2_from_cam1.translation).norm(),
                1e-12);
    }
    const TwoViewGeometry pair_order = database.ReadTwoViewGeometry(1, 3);
    EXPECT_EQ(pair_order.inlier_matches[2].point2D_idx1, 9u);
    EXPECT_TRUE(pair_order.F.isApprox(geometry.F.transpose(), 1e-14));

    const TwoViewGeometry read_degenerate = database.ReadTwoViewGeometry(3, 2);
    EXPECT_EQ(read_degenerate.config, TwoViewGeometryConfig::kDegenerate);
    EXPECT_TRUE(read_degenerate.inlier_matches.empty());
    EXPECT_TRUE(read_degenerate.F.isZero(0.0));
    EXPECT_FALSE(database.ExistsTwoViewGeometry(1, 4));
    EXPECT_EQ(database.ReadTwoViewGeometry(1, 4).config, TwoViewGeometryConfig::kUndefined);
    EXPECT_EQ(database.ReadAllTwoViewGeometries().size(), 3u);
    EXPECT_EQ(database.NumVerifiedImagePairs(), 3u);
  }
  // F row-major, qvec w x y z, config 2; empty blobs for the degenerate pair.
  const std::string pair12 = std::to_string(ImagePairToPairId(1, 2));
  EXPECT_EQ(
      BytesAs<double>(RawBlob(path, "SELECT F FROM two_view_geometries WHERE pair_id = " + pair12)),
      (std::vector<double>{1, 2, 3, 4, 5, 6, 7, 8, 10}));
  const std::vector<double> qvec = BytesAs<double>(
      RawBlob(path, "SELECT qvec FROM two_view_geometries WHERE pair_id = " + pair12));
  ASSERT_EQ(qvec.size(), 4u);
  EXPECT_DOUBLE_EQ(qvec[0], std::cos(0.1));
  EXPECT_DOUBLE_EQ(qvec[2], std::sin(0.1));
  EXPECT_EQ(BytesAs<double>(
                RawBlob(path, "SELECT tvec FROM two_view_geometries WHERE pair_id = " + pair12)),
            (std::vector<double>{0.6, 0.0, 0.8}));
  EXPECT_TRUE(RawBlob(path, "SELECT F FROM two_view_geometries WHERE pair_id = " +
                                std::to_string(ImagePairToPairId(2, 3)))
                  .empty());
}

TEST(ColmapDatabase, ResumeKeepsCommittedDataAndDropsTheRest) {
  const fs::path path = testing::MakeScratchFolder("db_resume") / "db.db";
  std::mt19937 rng(5);
  const FeatureKeypoints keypoints = RandomKeypoints(20, &rng);
  const FeatureDescriptors descriptors = RandomDescriptors(20, &rng);
  {
    ColmapDatabase database = ColmapDatabase::Open(path);
    const camera_t camera_id = database.WriteCamera(EurocLikeCamera());
    database.WriteFeatures(database.WriteImage("a.png", camera_id), keypoints, descriptors);
    {
      // Not committed: rolled back.
      ColmapDatabase::Transaction transaction(database);
      database.WriteImage("b.png", camera_id);
    }
    EXPECT_FALSE(database.ExistsImageWithName("b.png"));
  }
  // A process killed in the middle of a transaction.
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    ColmapDatabase database = ColmapDatabase::Open(path);
    database.WriteImage("c.png", 1);  // committed
    ColmapDatabase::Transaction transaction(database);
    const image_t image_id = database.WriteImage("d.png", 1);
    database.WriteKeypoints(image_id, keypoints);
    std::_Exit(0);  // no rollback, no close
  }
  int status = 0;
  waitpid(child, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));

  ColmapDatabase database = ColmapDatabase::Open(path);
  EXPECT_EQ(database.NumImages(), 2u);
  const std::optional<DatabaseImage> a = database.ReadImageWithName("a.png");
  ASSERT_TRUE(a.has_value());
  EXPECT_TRUE(database.ExistsFeatures(a->image_id));
  EXPECT_EQ(database.ReadDescriptors(a->image_id), descriptors);
  EXPECT_EQ(database.ReadKeypoints(a->image_id).size(), 20u);
  EXPECT_TRUE(database.ExistsImageWithName("c.png"));
  EXPECT_FALSE(database.ExistsImageWithName("d.png"));
  EXPECT_EQ(database.NumKeypoints(), 20u);
}

TEST(ColmapDatabase, NotADatabaseNamesTheFile) {
  const fs::path folder = testing::MakeScratchFolder("db_bad");
  const fs::path path = folder / "text.db";
  std::ofstream(path) << "this is not a SQLite database, just some text that is long enough to "
                         "fill the 100-byte header SQLite checks when opening a file......\n";
  try {
    ColmapDatabase::Open(path);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr(path.string()));
  }
  EXPECT_THROW(ColmapDatabase::Open(folder / "missing" / "db.db"), InputError);
}

// Descriptors as RootSIFT-quantised ones look: non-negative, L2 norm ~512.
FeatureDescriptors UnitDescriptors(int count, std::mt19937* rng) {
  std::exponential_distribution<float> exponential(1.0f);
  FeatureDescriptors descriptors(count, 128);
  for (int i = 0; i < count; ++i) {
    Eigen::VectorXf row(128);
    for (int j = 0; j < 128; ++j) row[j] = exponential(*rng);
    row *= 512.0f / row.norm();
    for (int j = 0; j < 128; ++j) descriptors(i, j) = std::min(255.0f, std::round(row[j]));
  }
  return descriptors;
}

// COLMAP itself reads a database viosfm wrote: its exhaustive matcher matches
// the stored features and writes matches and geometries viosfm reads back.
TEST(ColmapDatabase, ColmapMatchesOurFeatures) {
  if (!HaveColmap()) GTEST_SKIP() << "colmap binary not found; skipping";
  const fs::path path = testing::MakeScratchFolder("db_colmap") / "db.db";
  constexpr int kNum = 300;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  // Image 2 sees the points of image 1 through a homography (a plane), in a
  // shuffled order.
  Eigen::Matrix3d homography;
  homography << 0.95, 0.05, 20.0, -0.04, 1.02, 10.0, 1e-5, 2e-5, 1.0;
  std::vector<int> order(kNum);
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), rng);
  FeatureKeypoints keypoints1;
  FeatureKeypoints keypoints2(kNum);
  const FeatureDescriptors descriptors1 = UnitDescriptors(kNum, &rng);
  FeatureDescriptors descriptors2(kNum, 128);
  for (int i = 0; i < kNum; ++i) {
    const Eigen::Vector3d x1(40.0 + 560.0 * uniform(rng), 40.0 + 400.0 * uniform(rng), 1.0);
    const Eigen::Vector3d x2 = homography * x1;
    keypoints1.push_back(FeatureKeypoint::FromScaleOrientation(x1.x(), x1.y(), 2.0f, 0.0f));
    keypoints2[order[i]] =
        FeatureKeypoint::FromScaleOrientation(x2.x() / x2.z(), x2.y() / x2.z(), 2.0f, 0.0f);
    descriptors2.row(order[i]) = descriptors1.row(i);
  }
  {
    ColmapDatabase database = ColmapDatabase::Open(path);
    const camera_t camera_id = database.WriteCamera(
        MakeCamera(CameraModelId::kSimpleRadial, 640, 480, {500.0, 319.5, 239.5, 0.0}));
    database.WriteFeatures(database.WriteImage("1.png", camera_id), keypoints1, descriptors1);
    database.WriteFeatures(database.WriteImage("2.png", camera_id), keypoints2, descriptors2);
  }
  const std::string command =
      "QT_QPA_PLATFORM=offscreen colmap exhaustive_matcher --database_path " + path.string() +
      " --SiftMatching.use_gpu 0 --SiftMatching.num_threads 1 > " + path.string() + ".log 2>&1";
  ASSERT_EQ(std::system(command.c_str()), 0) << command << "\n"
                                             << ReadTextFile(path.string() + ".log");

  ColmapDatabase database = ColmapDatabase::Open(path);
  const FeatureMatches matches = database.ReadMatches(1, 2);
  int correct = 0;
  for (const FeatureMatch& match : matches) {
    correct += order[match.point2D_idx1] == static_cast<int>(match.point2D_idx2);
  }
  EXPECT_GE(correct, kNum * 9 / 10);
  EXPECT_EQ(correct, static_cast<int>(matches.size()));
  const TwoViewGeometry geometry = database.ReadTwoViewGeometry(2, 1);
  EXPECT_GE(geometry.inlier_matches.size(), static_cast<size_t>(kNum * 9 / 10));
  for (const FeatureMatch& match : geometry.inlier_matches) {
    EXPECT_EQ(order[match.point2D_idx2], static_cast<int>(match.point2D_idx1));
  }
  std::cout << "colmap: " << matches.size() << " matches, " << geometry.inlier_matches.size()
            << " inliers, config " << TwoViewGeometryConfigName(geometry.config) << "\n";
}

}  // namespace
}  // namespace viosfm

// libFuzzer target: the COLMAP database reader (io/colmap_database.h).
//
// The first byte chooses how the rest is used:
//  - odd: the rest is the database file itself (a SQLite file as COLMAP or
//    viosfm wrote it, or garbage);
//  - even: a well-formed database with the COLMAP 3.8 schema is created and
//    the rest, read with FuzzedDataProvider, is a list of rows inserted
//    straight through SQLite, with any value of any type in any column (so
//    that the fuzzer reaches the reader's handling of hostile rows: wrong
//    blob sizes, negative or huge counts, unknown models and configs, ...).
// Then every read function runs on the database.
#include <fuzzer/FuzzedDataProvider.h>
#include <sqlite3.h>

#include "fuzz_util.h"
#include "viosfm/io/colmap_database.h"

namespace {

namespace fs = std::filesystem;

struct Table {
  const char* name;
  int num_columns;
};
constexpr Table kTables[] = {{"cameras", 6},     {"images", 10}, {"keypoints", 4},
                             {"descriptors", 4}, {"matches", 4}, {"two_view_geometries", 10}};

void BindValue(FuzzedDataProvider& provider, sqlite3_stmt* statement, int index) {
  switch (provider.ConsumeIntegralInRange<int>(0, 5)) {
    case 0: sqlite3_bind_null(statement, index); break;
    case 1: sqlite3_bind_int64(statement, index, provider.ConsumeIntegral<int64_t>()); break;
    case 2:
      sqlite3_bind_int64(statement, index, provider.ConsumeIntegralInRange<int64_t>(-2, 300));
      break;
    case 3: sqlite3_bind_double(statement, index, provider.ConsumeFloatingPoint<double>()); break;
    case 4: {
      const std::string text = provider.ConsumeRandomLengthString(64);
      sqlite3_bind_text(statement, index, text.data(), static_cast<int>(text.size()),
                        SQLITE_TRANSIENT);
      break;
    }
    default: {
      const std::vector<uint8_t> blob =
          provider.ConsumeBytes<uint8_t>(provider.ConsumeIntegralInRange<size_t>(0, 4096));
      sqlite3_bind_blob(statement, index, blob.data(), static_cast<int>(blob.size()),
                        SQLITE_TRANSIENT);
    }
  }
}

void InsertRows(const fs::path& path, FuzzedDataProvider& provider) {
  sqlite3* db = nullptr;
  if (sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READWRITE, nullptr) != SQLITE_OK) {
    sqlite3_close_v2(db);
    return;
  }
  sqlite3_exec(db, "BEGIN", nullptr, nullptr, nullptr);
  for (int row = 0; row < 64 && provider.remaining_bytes() > 0; ++row) {
    const Table& table = kTables[provider.ConsumeIntegralInRange<size_t>(0, 5)];
    std::string sql = std::string("INSERT OR REPLACE INTO ") + table.name + " VALUES(?";
    for (int i = 1; i < table.num_columns; ++i) sql += ", ?";
    sql += ")";
    sqlite3_stmt* statement = nullptr;
    if (sqlite3_prepare_v2(db, sql.c_str(), -1, &statement, nullptr) == SQLITE_OK) {
      for (int i = 1; i <= table.num_columns; ++i) BindValue(provider, statement, i);
      sqlite3_step(statement);  // constraint violations are fine
    }
    sqlite3_finalize(statement);
  }
  sqlite3_exec(db, "COMMIT", nullptr, nullptr, nullptr);
  sqlite3_close_v2(db);
}

// The image ids of the keypoints and descriptors tables (rows need not have
// an image: the fuzzer's rows ignore foreign keys).
std::vector<int64_t> FeatureImageIds(const fs::path& path) {
  std::vector<int64_t> ids;
  sqlite3* db = nullptr;
  if (sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr) == SQLITE_OK) {
    sqlite3_stmt* statement = nullptr;
    if (sqlite3_prepare_v2(db,
                           "SELECT image_id FROM keypoints UNION SELECT image_id FROM descriptors",
                           -1, &statement, nullptr) == SQLITE_OK) {
      while (sqlite3_step(statement) == SQLITE_ROW)
        ids.push_back(sqlite3_column_int64(statement, 0));
    }
    sqlite3_finalize(statement);
  }
  sqlite3_close_v2(db);
  return ids;
}

void ReadEverything(const fs::path& path) {
  using namespace viosfm;
  const std::vector<int64_t> feature_image_ids = FeatureImageIds(path);
  ColmapDatabase database = ColmapDatabase::Open(path);
  for (const int64_t id : feature_image_ids) {
    // As the library's callers do: image ids are uint32 (image_t).
    const image_t image_id = static_cast<image_t>(id);
    viosfm::fuzz::AcceptsInput([&] { database.ReadKeypoints(image_id); });
    viosfm::fuzz::AcceptsInput([&] { database.ReadDescriptors(image_id); });
  }
  database.ReadSchema();
  database.UserVersion();
  database.NumCameras();
  database.NumImages();
  database.NumKeypoints();
  database.NumDescriptors();
  database.NumMatches();
  database.NumMatchedImagePairs();
  database.NumVerifiedImagePairs();
  for (const Camera& camera : database.ReadAllCameras()) database.ReadCamera(camera.camera_id);
  for (const DatabaseImage& image : database.ReadAllImages()) {
    database.ReadImage(image.image_id);
    database.ReadImageWithName(image.name);
    if (database.ExistsFeatures(image.image_id)) {
      const FeatureKeypoints keypoints = database.ReadKeypoints(image.image_id);
      const FeatureDescriptors descriptors = database.ReadDescriptors(image.image_id);
      (void)keypoints;
      (void)descriptors;
    }
  }
  for (const auto& [pair_id, matches] : database.ReadAllMatches()) {
    const auto [id1, id2] = PairIdToImagePair(pair_id);
    if (id1 != id2) {
      database.ReadMatches(id1, id2);
      database.ReadMatches(id2, id1);
    }
  }
  for (const auto& [pair_id, geometry] : database.ReadAllTwoViewGeometries()) {
    const auto [id1, id2] = PairIdToImagePair(pair_id);
    if (id1 != id2) {
      database.ReadTwoViewGeometry(id1, id2);
      database.ReadTwoViewGeometry(id2, id1);
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace viosfm::fuzz;
  if (size == 0) return 0;
  const fs::path folder = ScratchFolder() / "db";
  std::error_code ignored;
  fs::remove_all(folder, ignored);
  fs::create_directories(folder);
  const fs::path path = folder / "database.db";
  if (data[0] % 2 == 1) {
    WriteBytes(path, AsText(data + 1, size - 1));
  } else {
    AcceptsInput([&] { viosfm::ColmapDatabase::Open(path); });
    FuzzedDataProvider provider(data + 1, size - 1);
    InsertRows(path, provider);
  }
  AcceptsInput([&] { ReadEverything(path); });
  return 0;
}

#include "viosfm/io/rosbag2.h"

#include <sqlite3.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <atomic>
#include <cstring>
#include <fstream>
#include <map>
#include <set>
#include <system_error>

#include "viosfm/io/compression.h"
#include "viosfm/io/mcap.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/logging.h"
#include "viosfm/util/string_util.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;

// Largest message a per-message-compressed bag may decompress to.
constexpr uint64_t kMaxMessageBytes = uint64_t{1} << 30;
constexpr char kSqliteMagic[] = "SQLite format 3";  // and a NUL: the first 16 bytes

// The metadata version and table layout written (rosbag2 since Jazzy).
constexpr int kWrittenMetadataVersion = 7;
constexpr int kWrittenSchemaVersion = 4;

std::string FileName(const fs::path& path) {
  return path.filename().string();
}

// ---------------------------------------------------------------------------
// metadata.yaml

int64_t YamlInt(const YAML::Node& node, const char* key, const std::string& where) {
  const YAML::Node value = node[key];
  if (!value) return 0;
  try {
    return value.as<int64_t>();
  } catch (const YAML::Exception&) {
    throw InputError(where + ": '" + key + "' is not an integer");
  }
}

std::string YamlString(const YAML::Node& node, const char* key, const std::string& where) {
  const YAML::Node value = node[key];
  if (!value || value.IsNull()) return "";
  if (!value.IsScalar()) throw InputError(where + ": '" + key + "' is not a string");
  return value.as<std::string>();
}

// ---------------------------------------------------------------------------
// SQLite

struct SqliteCloser {
  void operator()(sqlite3* db) const { sqlite3_close_v2(db); }
};
struct StatementFinalizer {
  void operator()(sqlite3_stmt* statement) const { sqlite3_finalize(statement); }
};
using Statement = std::unique_ptr<sqlite3_stmt, StatementFinalizer>;

// A file: URI for `path` (for SQLite's immutable mode).
std::string FileUri(const fs::path& path) {
  const std::string text = fs::absolute(path).string();
  std::string uri = "file:";
  for (const char c : text) {
    if (c == '%' || c == '?' || c == '#' || static_cast<unsigned char>(c) < 0x21) {
      static const char kHex[] = "0123456789abcdef";
      uri += '%';
      uri += kHex[(static_cast<unsigned char>(c) >> 4) & 15];
      uri += kHex[static_cast<unsigned char>(c) & 15];
    } else {
      uri += c;
    }
  }
  return uri;
}

}  // namespace

Rosbag2Metadata ParseRosbag2Metadata(const std::string& text, const std::string& where) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw InputError(where + ": not valid YAML: " + e.what());
  }
  YAML::Node info = root["rosbag2_bagfile_information"];
  if (!info) info = root;  // the metadata table holds the inner mapping
  if (!info.IsMap() || !info["storage_identifier"]) {
    throw InputError(where +
                     ": no rosbag2_bagfile_information with a storage_identifier (not a "
                     "rosbag2 metadata.yaml)");
  }
  Rosbag2Metadata metadata;
  metadata.version = static_cast<int>(YamlInt(info, "version", where));
  metadata.storage_identifier = YamlString(info, "storage_identifier", where);
  metadata.compression_format = YamlString(info, "compression_format", where);
  metadata.compression_mode = YamlString(info, "compression_mode", where);
  metadata.message_count =
      static_cast<uint64_t>(std::max<int64_t>(0, YamlInt(info, "message_count", where)));
  if (const YAML::Node start = info["starting_time"]) {
    metadata.starting_time_ns = YamlInt(start, "nanoseconds_since_epoch", where);
  }
  if (const YAML::Node duration = info["duration"]) {
    metadata.duration_ns = YamlInt(duration, "nanoseconds", where);
  }
  if (const YAML::Node paths = info["relative_file_paths"]) {
    if (!paths.IsSequence()) throw InputError(where + ": 'relative_file_paths' is not a list");
    for (const YAML::Node& path : paths) {
      if (!path.IsScalar()) throw InputError(where + ": 'relative_file_paths' holds a non-string");
      metadata.relative_file_paths.push_back(path.as<std::string>());
    }
  }
  if (const YAML::Node topics = info["topics_with_message_count"]; topics && topics.IsSequence()) {
    for (const YAML::Node& entry : topics) {
      const YAML::Node topic = entry["topic_metadata"];
      if (!topic || !topic.IsMap()) continue;
      Rosbag2Metadata::Topic t;
      t.name = YamlString(topic, "name", where);
      t.type = YamlString(topic, "type", where);
      t.serialization_format = YamlString(topic, "serialization_format", where);
      t.message_count =
          static_cast<uint64_t>(std::max<int64_t>(0, YamlInt(entry, "message_count", where)));
      metadata.topics.push_back(std::move(t));
    }
  }
  return metadata;
}

std::string Rosbag2MetadataYaml(const Rosbag2Metadata& metadata) {
  YAML::Emitter out;
  out << YAML::BeginMap << YAML::Key << "rosbag2_bagfile_information" << YAML::Value
      << YAML::BeginMap;
  out << YAML::Key << "version" << YAML::Value << metadata.version;
  out << YAML::Key << "storage_identifier" << YAML::Value << metadata.storage_identifier;
  out << YAML::Key << "duration" << YAML::Value << YAML::BeginMap << YAML::Key << "nanoseconds"
      << YAML::Value << metadata.duration_ns << YAML::EndMap;
  out << YAML::Key << "starting_time" << YAML::Value << YAML::BeginMap << YAML::Key
      << "nanoseconds_since_epoch" << YAML::Value << metadata.starting_time_ns << YAML::EndMap;
  out << YAML::Key << "message_count" << YAML::Value << metadata.message_count;
  out << YAML::Key << "topics_with_message_count" << YAML::Value << YAML::BeginSeq;
  for (const Rosbag2Metadata::Topic& topic : metadata.topics) {
    out << YAML::BeginMap << YAML::Key << "topic_metadata" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "name" << YAML::Value << topic.name;
    out << YAML::Key << "type" << YAML::Value << topic.type;
    out << YAML::Key << "serialization_format" << YAML::Value << topic.serialization_format;
    out << YAML::Key << "offered_qos_profiles" << YAML::Value << YAML::DoubleQuoted << "";
    out << YAML::Key << "type_description_hash" << YAML::Value << YAML::DoubleQuoted << "";
    out << YAML::EndMap;
    out << YAML::Key << "message_count" << YAML::Value << topic.message_count << YAML::EndMap;
  }
  out << YAML::EndSeq;
  out << YAML::Key << "compression_format" << YAML::Value << YAML::DoubleQuoted
      << metadata.compression_format;
  out << YAML::Key << "compression_mode" << YAML::Value << YAML::DoubleQuoted
      << metadata.compression_mode;
  out << YAML::Key << "relative_file_paths" << YAML::Value << YAML::BeginSeq;
  for (const std::string& path : metadata.relative_file_paths) out << path;
  out << YAML::EndSeq;
  out << YAML::Key << "files" << YAML::Value << YAML::BeginSeq;
  for (const std::string& path : metadata.relative_file_paths) {
    out << YAML::BeginMap << YAML::Key << "path" << YAML::Value << path;
    out << YAML::Key << "starting_time" << YAML::Value << YAML::BeginMap << YAML::Key
        << "nanoseconds_since_epoch" << YAML::Value << metadata.starting_time_ns << YAML::EndMap;
    out << YAML::Key << "duration" << YAML::Value << YAML::BeginMap << YAML::Key << "nanoseconds"
        << YAML::Value << metadata.duration_ns << YAML::EndMap;
    out << YAML::Key << "message_count" << YAML::Value << metadata.message_count << YAML::EndMap;
  }
  out << YAML::EndSeq;
  out << YAML::Key << "custom_data" << YAML::Value << YAML::Null;
  out << YAML::EndMap << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

// ---------------------------------------------------------------------------
// sqlite3 storage: reading

struct Rosbag2SqliteFile::Database {
  std::unique_ptr<sqlite3, SqliteCloser> db;
};

namespace {

[[noreturn]] void FailSqlite(const fs::path& path, sqlite3* db, const std::string& what) {
  const int code = db != nullptr ? sqlite3_errcode(db) : SQLITE_ERROR;
  std::string detail = db != nullptr ? sqlite3_errmsg(db) : "cannot open";
  if (code == SQLITE_NOTADB) detail += ": not an SQLite database";
  if (code == SQLITE_CORRUPT) detail += ": the database is corrupt (a truncated or damaged file?)";
  throw InputError(path.string(), 0, what + ": " + detail);
}

Statement Prepare(sqlite3* db, const fs::path& path, const std::string& sql) {
  sqlite3_stmt* statement = nullptr;
  if (sqlite3_prepare_v2(db, sql.c_str(), -1, &statement, nullptr) != SQLITE_OK) {
    FailSqlite(path, db, "SQL '" + sql.substr(0, 60) + "'");
  }
  return Statement(statement);
}

std::string ColumnText(sqlite3_stmt* statement, int column) {
  const unsigned char* text = sqlite3_column_text(statement, column);
  return text != nullptr ? std::string(reinterpret_cast<const char*>(text),
                                       static_cast<size_t>(sqlite3_column_bytes(statement, column)))
                         : std::string();
}

std::set<std::string> TableNames(sqlite3* db, const fs::path& path) {
  std::set<std::string> tables;
  const Statement statement =
      Prepare(db, path, "SELECT name FROM sqlite_master WHERE type = 'table'");
  int status = SQLITE_ROW;
  while ((status = sqlite3_step(statement.get())) == SQLITE_ROW) {
    tables.insert(ColumnText(statement.get(), 0));
  }
  if (status != SQLITE_DONE) FailSqlite(path, db, "reading the list of tables");
  return tables;
}

std::set<std::string> ColumnNames(sqlite3* db, const fs::path& path, const std::string& table) {
  std::set<std::string> columns;
  const Statement statement = Prepare(db, path, "PRAGMA table_info(" + table + ")");
  int status = SQLITE_ROW;
  while ((status = sqlite3_step(statement.get())) == SQLITE_ROW) {
    columns.insert(ColumnText(statement.get(), 1));
  }
  if (status != SQLITE_DONE) FailSqlite(path, db, "reading the columns of " + table);
  return columns;
}

}  // namespace

Rosbag2SqliteFile::Rosbag2SqliteFile(const fs::path& path)
    : path_(path), database_(std::make_unique<Database>()) {
  CheckSqliteMagic(path);
  OpenDatabase();
  const std::set<std::string> tables = TableNames(database_->db.get(), path);
  const bool has_qos = CheckLayout(tables);
  ReadSchemaAndMetadata(tables);
  ReadTopics(has_qos);
  CountMessages();
}

void Rosbag2SqliteFile::CheckSqliteMagic(const fs::path& path) {
  std::error_code error;
  if (!fs::is_regular_file(path, error)) throw InputError(path.string(), 0, "file not found");
  std::ifstream file(path, std::ios::binary);
  char magic[16] = {};
  file.read(magic, sizeof(magic));
  if (file.gcount() < 16 || std::memcmp(magic, kSqliteMagic, sizeof(kSqliteMagic)) != 0) {
    throw InputError(path.string(), 0,
                     "not an SQLite database (expected 'SQLite format 3' at byte 0): not a "
                     "rosbag2 .db3 file");
  }
}

bool Rosbag2SqliteFile::Open(const std::string& name, int flags) {
  sqlite3* db = nullptr;
  const int status = sqlite3_open_v2(name.c_str(), &db, flags, nullptr);
  database_->db.reset(db);
  return status == SQLITE_OK;
}

void Rosbag2SqliteFile::OpenDatabase() {
  // Reading the table list is the first access that needs a lock; on
  // read-only media, or a folder where SQLite cannot create its lock files
  // (a WAL bag without its -shm file), immutable mode reads the file as it
  // is. That is safe only when no -wal file holds unmerged pages.
  bool opened = Open(path_.string(), SQLITE_OPEN_READONLY | SQLITE_OPEN_NOMUTEX);
  if (opened) {
    sqlite3* db = database_->db.get();
    sqlite3_busy_timeout(db, 2000);
    sqlite3_stmt* statement = nullptr;
    const Statement probe = sqlite3_prepare_v2(db, "SELECT name FROM sqlite_master", -1, &statement,
                                               nullptr) == SQLITE_OK
                                ? Statement(statement)
                                : Statement();
    const int status = probe ? sqlite3_step(probe.get()) : SQLITE_ERROR;
    opened = status == SQLITE_ROW || status == SQLITE_DONE;
    if (!opened &&
        (sqlite3_errcode(db) == SQLITE_NOTADB || sqlite3_errcode(db) == SQLITE_CORRUPT)) {
      FailSqlite(path_, db, "cannot read the database");
    }
  }
  if (opened) return;
  std::error_code error;
  fs::path wal = path_;
  wal += "-wal";
  const bool wal_has_pages = fs::exists(wal, error) && fs::file_size(wal, error) > 0;
  if (wal_has_pages) {
    FailSqlite(path_, database_->db.get(),
               "cannot open the database (its write-ahead log " + FileName(wal) +
                   " holds pages not yet in the file, and the folder is not writable for "
                   "SQLite to merge them: copy the bag to a writable folder)");
  }
  if (!Open(FileUri(path_) + "?immutable=1",
            SQLITE_OPEN_READONLY | SQLITE_OPEN_URI | SQLITE_OPEN_NOMUTEX)) {
    FailSqlite(path_, database_->db.get(), "cannot open the database");
  }
}

bool Rosbag2SqliteFile::CheckLayout(const std::set<std::string>& tables) const {
  sqlite3* db = database_->db.get();
  if (tables.count("topics") == 0 || tables.count("messages") == 0) {
    throw InputError(path_.string(), 0,
                     "an SQLite database without rosbag2's tables 'topics' and 'messages': not a "
                     "ROS 2 bag");
  }
  const std::set<std::string> topic_columns = ColumnNames(db, path_, "topics");
  const std::set<std::string> message_columns = ColumnNames(db, path_, "messages");
  const auto require = [this](const std::set<std::string>& columns, const char* table,
                              std::initializer_list<const char*> names) {
    for (const char* column : names) {
      if (columns.count(column) == 0) {
        throw InputError(path_.string(), 0,
                         std::string("table '") + table + "' has no column '" + column +
                             "' (not a rosbag2 bag, or a layout viosfm does not know)");
      }
    }
  };
  require(topic_columns, "topics", {"id", "name", "type", "serialization_format"});
  require(message_columns, "messages", {"topic_id", "timestamp", "data"});
  return topic_columns.count("offered_qos_profiles") > 0;
}

void Rosbag2SqliteFile::ReadSchemaAndMetadata(const std::set<std::string>& tables) {
  sqlite3* db = database_->db.get();
  if (tables.count("schema") > 0) {
    const Statement statement = Prepare(
        db, path_, "SELECT schema_version FROM schema ORDER BY schema_version DESC LIMIT 1");
    if (sqlite3_step(statement.get()) == SQLITE_ROW) {
      schema_version_ = sqlite3_column_int(statement.get(), 0);
    }
  }
  if (tables.count("metadata") > 0) {
    const Statement statement =
        Prepare(db, path_, "SELECT metadata FROM metadata ORDER BY id DESC LIMIT 1");
    if (sqlite3_step(statement.get()) == SQLITE_ROW) {
      metadata_ = ParseRosbag2Metadata(ColumnText(statement.get(), 0),
                                       path_.string() + ": table 'metadata'");
    }
  }
}

void Rosbag2SqliteFile::ReadTopics(bool has_qos) {
  sqlite3* db = database_->db.get();
  const Statement statement =
      Prepare(db, path_,
              std::string("SELECT id, name, type, serialization_format") +
                  (has_qos ? ", offered_qos_profiles" : "") + " FROM topics ORDER BY id");
  int status = SQLITE_ROW;
  while ((status = sqlite3_step(statement.get())) == SQLITE_ROW) {
    Topic topic;
    topic.id = sqlite3_column_int64(statement.get(), 0);
    topic.name = ColumnText(statement.get(), 1);
    topic.type = ColumnText(statement.get(), 2);
    topic.serialization_format = ColumnText(statement.get(), 3);
    if (has_qos) topic.offered_qos_profiles = ColumnText(statement.get(), 4);
    topics_.push_back(std::move(topic));
  }
  if (status != SQLITE_DONE) FailSqlite(path_, db, "reading table 'topics'");
}

void Rosbag2SqliteFile::CountMessages() {
  sqlite3* db = database_->db.get();
  const Statement statement =
      Prepare(db, path_, "SELECT topic_id, COUNT(*) FROM messages GROUP BY topic_id");
  int status = SQLITE_ROW;
  while ((status = sqlite3_step(statement.get())) == SQLITE_ROW) {
    const int64_t id = sqlite3_column_int64(statement.get(), 0);
    const auto it = std::find_if(topics_.begin(), topics_.end(),
                                 [id](const Topic& topic) { return topic.id == id; });
    const uint64_t count = static_cast<uint64_t>(sqlite3_column_int64(statement.get(), 1));
    if (it == topics_.end()) {
      throw InputError(path_.string(), 0,
                       std::to_string(count) + " messages on topic id " + std::to_string(id) +
                           ", which table 'topics' does not define");
    }
    it->num_messages = count;
  }
  if (status != SQLITE_DONE) FailSqlite(path_, db, "counting the messages");
}

Rosbag2SqliteFile::~Rosbag2SqliteFile() = default;

void Rosbag2SqliteFile::ReadMessages(
    const std::function<bool(const Topic&)>& wanted,
    const std::function<void(const Topic&, timestamp_ns_t, std::span<const uint8_t>, int64_t)>&
        visit) {
  std::map<int64_t, const Topic*> selected;
  std::string ids;
  for (const Topic& topic : topics_) {
    if (!wanted(topic)) continue;
    selected[topic.id] = &topic;
    if (!ids.empty()) ids.push_back(',');
    ids.append(std::to_string(topic.id));
  }
  if (selected.empty()) return;
  sqlite3* db = database_->db.get();
  const Statement statement = Prepare(db, path_,
                                      "SELECT id, topic_id, timestamp, data FROM messages WHERE "
                                      "topic_id IN (" +
                                          ids + ") ORDER BY id");
  int status = SQLITE_ROW;
  while ((status = sqlite3_step(statement.get())) == SQLITE_ROW) {
    const int64_t row = sqlite3_column_int64(statement.get(), 0);
    const Topic& topic = *selected.at(sqlite3_column_int64(statement.get(), 1));
    const timestamp_ns_t time_ns = sqlite3_column_int64(statement.get(), 2);
    const void* blob = sqlite3_column_blob(statement.get(), 3);
    const int size = sqlite3_column_bytes(statement.get(), 3);
    const std::span<const uint8_t> data(static_cast<const uint8_t*>(blob),
                                        blob != nullptr ? static_cast<size_t>(size) : 0);
    visit(topic, time_ns, data, row);
  }
  if (status != SQLITE_DONE) FailSqlite(path_, db, "reading table 'messages'");
}

// ---------------------------------------------------------------------------
// The bag

struct Rosbag2Reader::File {
  fs::path path;     // what is read (a decompressed copy for FILE compression)
  std::string name;  // the file as the bag names it, for messages
  std::unique_ptr<Rosbag2SqliteFile> sqlite;
  std::unique_ptr<McapReader> mcap;
};

namespace {

enum class FileKind { kSqlite, kMcap, kZstd, kUnknown };

FileKind KindOfFile(const fs::path& path) {
  std::ifstream file(path, std::ios::binary);
  uint8_t magic[16] = {};
  file.read(reinterpret_cast<char*>(magic), sizeof(magic));
  const size_t size = static_cast<size_t>(file.gcount());
  if (size >= 16 && std::memcmp(magic, kSqliteMagic, sizeof(kSqliteMagic)) == 0) {
    return FileKind::kSqlite;
  }
  if (size >= 5 && std::memcmp(magic, kMcapMagic, 5) == 0) return FileKind::kMcap;
  if (StartsWithZstdFrame(std::span<const uint8_t>(magic, size))) return FileKind::kZstd;
  return FileKind::kUnknown;
}

std::string KindDescription(FileKind kind) {
  switch (kind) {
    case FileKind::kSqlite: return "sqlite3";
    case FileKind::kMcap: return "mcap";
    case FileKind::kZstd: return "zstd";
    case FileKind::kUnknown: break;
  }
  return "unknown";
}

// Where the file metadata.yaml lists as `relative` is: in the folder, in
// the folder by its name alone, or (rosbag2 before Foxy stored the bag
// folder's name in the path) beside the folder; "" when it is nowhere.
// A FILE-compressed bag's files may be listed without their ".zstd".
fs::path FindListedFile(const fs::path& folder, const std::string& relative) {
  std::error_code error;
  const fs::path listed(relative);
  for (const fs::path& candidate :
       {folder / listed, folder / listed.filename(), folder.parent_path() / listed}) {
    if (fs::is_regular_file(candidate, error)) return candidate;
    fs::path compressed = candidate;
    compressed += ".zstd";
    if (fs::is_regular_file(compressed, error)) return compressed;
  }
  return {};
}

fs::path MakeTempFolder() {
  static std::atomic<int> counter{0};
  const fs::path folder =
      fs::temp_directory_path() /
      ("viosfm-rosbag2-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
  fs::create_directories(folder);
  return folder;
}

}  // namespace

std::vector<fs::path> Rosbag2FolderFiles(const fs::path& folder) {
  std::error_code error;
  const fs::path yaml = folder / "metadata.yaml";
  if (!fs::is_regular_file(yaml, error)) return {};
  std::vector<fs::path> files = {yaml};
  try {
    const Rosbag2Metadata metadata = ParseRosbag2Metadata(ReadTextFile(yaml), yaml.string());
    for (const std::string& relative : metadata.relative_file_paths) {
      const fs::path file = FindListedFile(folder, relative);
      if (!file.empty()) files.push_back(file);
    }
  } catch (const InputError&) {
    // The reader names the problem; the yaml file alone is what there is.
  }
  return files;
}

Rosbag2Reader::Rosbag2Reader(const fs::path& path) : path_(path) {
  const std::string p = path.string();
  std::error_code error;
  std::vector<fs::path> listed;
  std::optional<Rosbag2Metadata> metadata;
  std::string metadata_where;
  if (fs::is_directory(path, error)) {
    const fs::path yaml = path / "metadata.yaml";
    if (!fs::is_regular_file(yaml, error)) {
      throw InputError(p, 0,
                       "a folder without metadata.yaml: not a ROS 2 bag (give one of its .db3 or "
                       ".mcap files to read that file alone)");
    }
    metadata_where = yaml.string();
    metadata = ParseRosbag2Metadata(ReadTextFile(yaml), metadata_where);
    if (metadata->relative_file_paths.empty()) {
      throw InputError(metadata_where, 0, "'relative_file_paths' lists no storage file");
    }
    for (const std::string& relative : metadata->relative_file_paths) {
      const fs::path file = FindListedFile(path, relative);
      if (file.empty()) {
        throw InputError(metadata_where, 0,
                         "relative_file_paths lists '" + relative + "', which is not in " + p +
                             " (a file of the bag is missing)");
      }
      listed.push_back(file);
    }
  } else if (fs::is_regular_file(path, error)) {
    listed.push_back(path);
    const fs::path yaml = path.parent_path() / "metadata.yaml";
    if (fs::is_regular_file(yaml, error)) {
      Rosbag2Metadata beside;
      try {
        beside = ParseRosbag2Metadata(ReadTextFile(yaml), yaml.string());
      } catch (const InputError& e) {
        VIOSFM_LOG(WARNING) << p << ": ignoring the metadata.yaml beside it: " << e.what();
      }
      std::string name = FileName(path);
      if (ToLower(fs::path(name).extension().string()) == ".zstd")
        name = fs::path(name).stem().string();
      const auto lists = [&name](const std::string& relative) {
        std::string listed_name = fs::path(relative).filename().string();
        if (ToLower(fs::path(listed_name).extension().string()) == ".zstd") {
          listed_name = fs::path(listed_name).stem().string();
        }
        return listed_name == name;
      };
      if (std::any_of(beside.relative_file_paths.begin(), beside.relative_file_paths.end(),
                      lists)) {
        metadata = beside;
        metadata_where = yaml.string();
        if (beside.relative_file_paths.size() > 1) {
          VIOSFM_LOG(WARNING) << p << " is one of the " << beside.relative_file_paths.size()
                              << " files of the bag " << path.parent_path().string()
                              << " (metadata.yaml): reading this file only; give the folder to "
                                 "read them all";
        }
      }
    }
  } else {
    throw InputError(p, 0,
                     "ROS 2 bag not found (expected a .db3 or .mcap file, or a folder with "
                     "metadata.yaml)");
  }

  if (metadata) {
    const std::string format = ToLower(metadata->compression_format);
    const std::string mode = ToLower(metadata->compression_mode);
    if (!format.empty() && format != "zstd") {
      throw InputError(metadata_where, 0,
                       "compression_format '" + metadata->compression_format +
                           "' is not read (expected zstd, rosbag2's compressor)");
    }
    if (mode == "file") {
      compression_ = Rosbag2Compression::kFile;
    } else if (mode == "message") {
      compression_ = Rosbag2Compression::kMessage;
    } else if (!mode.empty() && mode != "none") {
      throw InputError(metadata_where, 0,
                       "compression_mode '" + metadata->compression_mode +
                           "' is not known (expected NONE, FILE or MESSAGE)");
    }
    if (compression_ != Rosbag2Compression::kNone && format.empty()) {
      throw InputError(
          metadata_where, 0,
          "compression_mode " + metadata->compression_mode + " without a compression_format");
    }
    compression_declared_ = true;
    const std::string storage = ToLower(metadata->storage_identifier);
    if (!storage.empty() && storage != "sqlite3" && storage != "mcap") {
      throw InputError(metadata_where, 0,
                       "storage_identifier '" + metadata->storage_identifier +
                           "' is not read (expected sqlite3 or mcap)");
    }
  }
  OpenFiles(listed);
  if (!compression_declared_ && storage_ == Rosbag2Storage::kSqlite3) {
    // A current .db3 carries its metadata in a table.
    for (const std::unique_ptr<File>& file : opened_) {
      const std::optional<Rosbag2Metadata>& inner = file->sqlite->metadata();
      if (inner && ToLower(inner->compression_mode) == "message") {
        compression_ = Rosbag2Compression::kMessage;
        compression_declared_ = true;
      }
    }
  }
  const bool any_cdr = std::any_of(connections_.begin(), connections_.end(),
                                   [](const BagConnection& c) { return c.serialization == "cdr"; });
  if (!connections_.empty() && !any_cdr) {
    std::set<std::string> formats;
    for (const BagConnection& connection : connections_) formats.insert(connection.serialization);
    std::string list;
    for (const std::string& format : formats) list += (list.empty() ? "'" : ", '") + format + "'";
    throw InputError(p, 0,
                     "no topic is serialized as CDR (the bag states " + list +
                         "): viosfm reads ROS 2 messages in CDR, as rmw_fastrtps_cpp and "
                         "rmw_cyclonedds_cpp record them");
  }
}

Rosbag2Reader::~Rosbag2Reader() = default;

Rosbag2Reader::TempFolder::~TempFolder() {
  if (path.empty()) return;
  std::error_code ignored;
  fs::remove_all(path, ignored);
}

void Rosbag2Reader::OpenFiles(const std::vector<fs::path>& listed) {
  std::optional<FileKind> storage_kind;
  for (const fs::path& listed_path : listed) {
    auto file = std::make_unique<File>();
    file->name = FileName(listed_path);
    file->path = listed_path;
    FileKind kind = KindOfFile(listed_path);
    if (kind == FileKind::kZstd) {
      // Per-file compression: decompress into a folder of our own.
      if (temp_folder_.path.empty()) temp_folder_.path = MakeTempFolder();
      fs::path inner = temp_folder_.path / listed_path.filename();
      if (ToLower(inner.extension().string()) == ".zstd") inner.replace_extension();
      VIOSFM_LOG(INFO) << listed_path.string() << ": zstd-compressed, decompressing to "
                       << inner.string();
      DecompressZstdFile(listed_path, inner);
      file->path = inner;
      kind = KindOfFile(inner);
      compression_ = Rosbag2Compression::kFile;
    }
    if (kind != FileKind::kSqlite && kind != FileKind::kMcap) {
      throw InputError(listed_path.string(), 0,
                       "neither an SQLite database (rosbag2 .db3) nor an MCAP file (by its first "
                       "bytes): not a ROS 2 storage file");
    }
    if (storage_kind && *storage_kind != kind) {
      throw InputError(listed_path.string(), 0,
                       "a " + KindDescription(kind) + " file in a bag whose first file is " +
                           KindDescription(*storage_kind));
    }
    storage_kind = kind;
    if (kind == FileKind::kSqlite) {
      storage_ = Rosbag2Storage::kSqlite3;
      file->sqlite = std::make_unique<Rosbag2SqliteFile>(file->path);
      for (const Rosbag2SqliteFile::Topic& topic : file->sqlite->topics()) {
        AddConnection(file->name,
                      {topic.name, topic.type, topic.serialization_format, "", topic.num_messages});
      }
    } else {
      storage_ = Rosbag2Storage::kMcap;
      file->mcap = std::make_unique<McapReader>(file->path);
      if (!file->mcap->profile().empty() && file->mcap->profile() != "ros2") {
        throw InputError(
            listed_path.string(), 0,
            "MCAP profile '" + file->mcap->profile() + "', not a ROS 2 bag (profile ros2)");
      }
      for (const McapChannel& channel : file->mcap->channels()) {
        AddConnection(file->name, {channel.topic, channel.schema_name, channel.message_encoding, "",
                                   channel.num_messages});
      }
    }
    files_.push_back(file->path);
    opened_.push_back(std::move(file));
  }
}

void Rosbag2Reader::AddConnection(const std::string& file, BagConnection connection) {
  for (BagConnection& known : connections_) {
    if (known.topic != connection.topic) continue;
    if (NormalizeRos2TypeName(known.type) != NormalizeRos2TypeName(connection.type) ||
        known.serialization != connection.serialization) {
      throw InputError(path_.string(), 0,
                       file + ": topic '" + connection.topic + "' has type " + connection.type +
                           " (" + connection.serialization +
                           "), another file or channel of the "
                           "bag " +
                           known.type + " (" + known.serialization + ")");
    }
    known.num_messages += connection.num_messages;
    return;
  }
  connections_.push_back(std::move(connection));
  std::sort(connections_.begin(), connections_.end(),
            [](const BagConnection& a, const BagConnection& b) { return a.topic < b.topic; });
}

std::string Rosbag2Reader::Describe() const {
  std::string text = std::string("ROS 2 bag (") +
                     (storage_ == Rosbag2Storage::kSqlite3 ? "sqlite3" : "mcap") + ", " +
                     std::to_string(files_.size()) + (files_.size() == 1 ? " file" : " files");
  if (compression_ == Rosbag2Compression::kFile) text += ", zstd-compressed files";
  if (compression_ == Rosbag2Compression::kMessage) text += ", zstd-compressed messages";
  return text + ")";
}

void Rosbag2Reader::ReadMessages(const std::function<bool(const BagConnection&)>& wanted,
                                 const std::function<void(const BagMessage&)>& visit) {
  std::map<std::string, const BagConnection*> by_topic;
  for (const BagConnection& connection : connections_) by_topic[connection.topic] = &connection;
  const auto deliver = [&](const BagConnection& connection, timestamp_ns_t time_ns,
                           std::span<const uint8_t> data, const std::string& location) {
    BagMessage message;
    message.connection = &connection;
    message.time_ns = time_ns;
    message.location = location;
    std::vector<uint8_t> decompressed;
    const bool compressed = StartsWithZstdFrame(data);
    if (compression_ == Rosbag2Compression::kMessage && !compressed) {
      throw InputError(path_.string(), 0,
                       location + " (" + connection.topic +
                           "): the bag compresses each message with zstd, this one does not "
                           "start with the zstd magic 28 b5 2f fd");
    }
    if (compressed && (compression_ == Rosbag2Compression::kMessage || !compression_declared_)) {
      decompressed =
          DecompressZstd(data, std::nullopt, kMaxMessageBytes,
                         path_.string() + ": " + location + " (" + connection.topic + ")");
      data = decompressed;
    }
    message.data = data;
    visit(message);
  };
  for (const std::unique_ptr<File>& file : opened_) {
    if (file->sqlite) {
      file->sqlite->ReadMessages(
          [&](const Rosbag2SqliteFile::Topic& topic) { return wanted(*by_topic.at(topic.name)); },
          [&](const Rosbag2SqliteFile::Topic& topic, timestamp_ns_t time_ns,
              std::span<const uint8_t> data, int64_t row) {
            deliver(*by_topic.at(topic.name), time_ns, data,
                    file->name + ", message " + std::to_string(row));
          });
    } else {
      file->mcap->ReadMessages(
          [&](const McapChannel& channel) { return wanted(*by_topic.at(channel.topic)); },
          [&](const McapMessage& message) {
            deliver(*by_topic.at(message.channel->topic), message.log_time_ns, message.data,
                    file->name + ", " + message.location);
          });
    }
  }
}

// ---------------------------------------------------------------------------
// sqlite3 storage: writing

struct Rosbag2SqliteWriter::Database {
  std::unique_ptr<sqlite3, SqliteCloser> db;
  Statement insert_message;
};

namespace {

void Execute(sqlite3* db, const fs::path& path, const std::string& sql) {
  char* message = nullptr;
  if (sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &message) != SQLITE_OK) {
    const std::string text = message != nullptr ? message : "unknown error";
    sqlite3_free(message);
    throw InputError(path.string(), 0, "cannot write the bag: " + text);
  }
}

}  // namespace

Rosbag2SqliteWriter::Rosbag2SqliteWriter(const fs::path& path, bool compress_messages)
    : path_(path), compress_messages_(compress_messages), database_(std::make_unique<Database>()) {
  temp_path_ = path;
  temp_path_ += ".tmp-" + std::to_string(::getpid());
  std::error_code ignored;
  fs::remove(temp_path_, ignored);
  sqlite3* db = nullptr;
  const int status =
      sqlite3_open_v2(temp_path_.c_str(), &db,
                      SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_NOMUTEX, nullptr);
  database_->db.reset(db);
  if (status != SQLITE_OK) {
    throw InputError(path.string(), 0, "cannot write the bag (is the folder writable?)");
  }
  Execute(db, path_,
          "PRAGMA journal_mode=MEMORY; PRAGMA synchronous=OFF;"
          "CREATE TABLE schema(schema_version INTEGER PRIMARY KEY,ros_distro TEXT NOT NULL);"
          "INSERT INTO schema VALUES(" +
              std::to_string(kWrittenSchemaVersion) +
              ", 'jazzy');"
              "CREATE TABLE metadata(id INTEGER PRIMARY KEY,metadata_version INTEGER NOT "
              "NULL,metadata TEXT NOT NULL);"
              "CREATE TABLE topics(id INTEGER PRIMARY KEY,name TEXT NOT NULL,type TEXT NOT "
              "NULL,serialization_format TEXT NOT NULL,offered_qos_profiles TEXT NOT "
              "NULL,type_description_hash TEXT NOT NULL);"
              "CREATE TABLE message_definitions(id INTEGER PRIMARY KEY,topic_type TEXT NOT "
              "NULL,encoding TEXT NOT NULL,encoded_message_definition TEXT NOT "
              "NULL,type_description_hash TEXT NOT NULL);"
              "CREATE TABLE messages(id INTEGER PRIMARY KEY,topic_id INTEGER NOT NULL,timestamp "
              "INTEGER NOT NULL, data BLOB NOT NULL);"
              "CREATE INDEX timestamp_idx ON messages (timestamp ASC);"
              "BEGIN;");
  database_->insert_message =
      Prepare(db, path_, "INSERT INTO messages (topic_id, timestamp, data) VALUES (?, ?, ?)");
  metadata_.version = kWrittenMetadataVersion;
  metadata_.storage_identifier = "sqlite3";
  metadata_.relative_file_paths = {FileName(path)};
  if (compress_messages_) {
    metadata_.compression_format = "zstd";
    metadata_.compression_mode = "MESSAGE";
  }
}

Rosbag2SqliteWriter::~Rosbag2SqliteWriter() {
  if (!closed_) {
    database_.reset();
    std::error_code ignored;
    fs::remove(temp_path_, ignored);
  }
}

int64_t Rosbag2SqliteWriter::AddTopic(const std::string& name, const RosMessageType& type) {
  VIOSFM_CHECK(!closed_) << "bag already closed";
  sqlite3* db = database_->db.get();
  const int64_t id = static_cast<int64_t>(metadata_.topics.size()) + 1;
  {
    const Statement statement = Prepare(db, path_,
                                        "INSERT INTO topics (id, name, type, serialization_format, "
                                        "offered_qos_profiles, type_description_hash) VALUES (?, "
                                        "?, ?, 'cdr', '', '')");
    sqlite3_bind_int64(statement.get(), 1, id);
    sqlite3_bind_text(statement.get(), 2, name.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(statement.get(), 3, type.name, -1, SQLITE_TRANSIENT);
    if (sqlite3_step(statement.get()) != SQLITE_DONE) FailSqlite(path_, db, "adding a topic");
  }
  if (std::find(topic_types_.begin(), topic_types_.end(), type.name) == topic_types_.end()) {
    topic_types_.push_back(type.name);
    const Statement statement =
        Prepare(db, path_,
                "INSERT INTO message_definitions (topic_type, encoding, "
                "encoded_message_definition, type_description_hash) VALUES (?, 'ros2msg', ?, '')");
    sqlite3_bind_text(statement.get(), 1, type.name, -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(statement.get(), 2, type.definition, -1, SQLITE_TRANSIENT);
    if (sqlite3_step(statement.get()) != SQLITE_DONE) {
      FailSqlite(path_, db, "adding a message definition");
    }
  }
  metadata_.topics.push_back({name, type.name, "cdr", 0});
  return id;
}

void Rosbag2SqliteWriter::Write(int64_t topic_id, timestamp_ns_t time_ns,
                                std::span<const uint8_t> cdr) {
  VIOSFM_CHECK(!closed_) << "bag already closed";
  VIOSFM_CHECK(topic_id >= 1 && topic_id <= static_cast<int64_t>(metadata_.topics.size()));
  std::vector<uint8_t> compressed;
  std::span<const uint8_t> data = cdr;
  if (compress_messages_) {
    compressed = CompressZstd(cdr, 1);
    data = compressed;
  }
  sqlite3* db = database_->db.get();
  sqlite3_stmt* insert = database_->insert_message.get();
  sqlite3_reset(insert);
  sqlite3_bind_int64(insert, 1, topic_id);
  sqlite3_bind_int64(insert, 2, time_ns);
  sqlite3_bind_blob64(insert, 3, data.data(), data.size(), SQLITE_STATIC);
  if (sqlite3_step(insert) != SQLITE_DONE) FailSqlite(path_, db, "writing a message (disk full?)");
  if (metadata_.message_count == 0) {
    metadata_.starting_time_ns = time_ns;
  }
  const timestamp_ns_t end = std::max(metadata_.starting_time_ns + metadata_.duration_ns, time_ns);
  metadata_.starting_time_ns = std::min(metadata_.starting_time_ns, time_ns);
  metadata_.duration_ns = end - metadata_.starting_time_ns;
  ++metadata_.message_count;
  ++metadata_.topics[static_cast<size_t>(topic_id - 1)].message_count;
}

void Rosbag2SqliteWriter::Close() {
  VIOSFM_CHECK(!closed_) << "bag already closed";
  sqlite3* db = database_->db.get();
  database_->insert_message.reset();
  {
    const std::string yaml = Rosbag2MetadataYaml(metadata_);
    // The table holds the inner mapping, as rosbag2 stores it.
    const std::string inner = yaml.substr(yaml.find('\n') + 1);
    std::string dedented;
    size_t start = 0;
    while (start < inner.size()) {
      const size_t end = inner.find('\n', start);
      std::string line =
          inner.substr(start, end == std::string::npos ? std::string::npos : end - start);
      if (line.starts_with("  ")) line = line.substr(2);
      dedented += line + "\n";
      if (end == std::string::npos) break;
      start = end + 1;
    }
    const Statement statement =
        Prepare(db, path_, "INSERT INTO metadata (metadata_version, metadata) VALUES (?, ?)");
    sqlite3_bind_int(statement.get(), 1, kWrittenMetadataVersion);
    sqlite3_bind_text(statement.get(), 2, dedented.c_str(), -1, SQLITE_TRANSIENT);
    if (sqlite3_step(statement.get()) != SQLITE_DONE) FailSqlite(path_, db, "writing the metadata");
  }
  Execute(db, path_, "COMMIT;");
  if (sqlite3_close_v2(database_->db.release()) != SQLITE_OK) {
    throw InputError(path_.string(), 0, "cannot close the bag (disk full?)");
  }
  SyncToDisk(temp_path_);
  std::error_code error;
  fs::rename(temp_path_, path_, error);
  if (error) {
    fs::remove(temp_path_, error);
    throw InputError(path_.string(), 0, "cannot rename the temporary bag: " + error.message());
  }
  closed_ = true;
}

}  // namespace viosfm

// ROS 2 bags (rosbag2): one or more storage files, each an SQLite database
// (".db3", the sqlite3 storage, Foxy to Humble's default) or an MCAP file
// (".mcap", mcap.h, the default since Iron), with a metadata.yaml beside
// them that lists the files of a bag split while it was recorded.
//
// sqlite3 storage, two table layouts:
//   2019 (Dashing, Eloquent)  topics(id, name, type, serialization_format),
//                             messages(id, topic_id, timestamp, data); types
//                             named without "/msg/" ("sensor_msgs/Image")
//   current                   topics(..., offered_qos_profiles[,
//                             type_description_hash]), messages as above,
//                             schema(schema_version, ros_distro), and since
//                             Iron metadata(id, metadata_version, metadata: the
//                             metadata.yaml text) and message_definitions
// MCAP storage: profile "ros2", a channel per topic (message encoding
// "cdr", metadata offered_qos_profiles), a schema per type ("ros2msg").
// timestamp / log_time is when the message was recorded (int64 ns).
//
// metadata.yaml (rosbag2_bagfile_information): version, storage_identifier
// ("sqlite3" or "mcap"), relative_file_paths, compression_format ("" or
// "zstd") and compression_mode ("", "NONE", "FILE": each storage file is a
// zstd file "x.db3.zstd"; "MESSAGE": each message's data is a zstd frame).
// A .db3 without metadata.yaml whose messages start with the zstd magic
// (28 b5 2f fd; a CDR message starts with 00) is read as compressed per
// message too.
//
// Errors (InputError) name the storage file and the message (sqlite3: its
// row id in messages; MCAP: its byte offset), or metadata.yaml and the key.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <vector>

#include "viosfm/io/bag_container.h"

namespace viosfm {

enum class Rosbag2Storage { kSqlite3, kMcap };
enum class Rosbag2Compression { kNone, kFile, kMessage };  // zstd, per file or per message

// The files of the rosbag2 folder `folder`: its metadata.yaml and the
// storage files it lists that exist (as the reader finds them). Empty when
// the folder has no readable metadata.yaml.
std::vector<std::filesystem::path> Rosbag2FolderFiles(const std::filesystem::path& folder);

// What a bag's metadata.yaml (or a current .db3's metadata table) says.
struct Rosbag2Metadata {
  int version = 0;
  std::string storage_identifier;                // "sqlite3", "mcap"
  std::vector<std::string> relative_file_paths;  // "rec_0.db3", ...
  std::string compression_format;                // "" or "zstd"
  std::string compression_mode;                  // "", "NONE", "FILE", "MESSAGE"
  struct Topic {
    std::string name;
    std::string type;
    std::string serialization_format;
    uint64_t message_count = 0;
  };
  std::vector<Topic> topics;
  uint64_t message_count = 0;
  timestamp_ns_t starting_time_ns = 0;
  timestamp_ns_t duration_ns = 0;
};

// Parses metadata.yaml text; `where` names it in errors ("bag/metadata.yaml").
Rosbag2Metadata ParseRosbag2Metadata(const std::string& text, const std::string& where);
// The YAML text of `metadata` (the keys rosbag2 writes at version 7).
std::string Rosbag2MetadataYaml(const Rosbag2Metadata& metadata);

// One sqlite3 storage file, read-only. Opens bags on read-only media too
// (with SQLite's immutable mode when the folder cannot hold a lock file).
class Rosbag2SqliteFile {
 public:
  struct Topic {
    int64_t id = 0;
    std::string name;
    std::string type;
    std::string serialization_format;
    std::string offered_qos_profiles;
    uint64_t num_messages = 0;
  };
  explicit Rosbag2SqliteFile(const std::filesystem::path& path);
  ~Rosbag2SqliteFile();
  Rosbag2SqliteFile(const Rosbag2SqliteFile&) = delete;
  Rosbag2SqliteFile& operator=(const Rosbag2SqliteFile&) = delete;

  const std::filesystem::path& path() const { return path_; }
  const std::vector<Topic>& topics() const { return topics_; }
  // 0 for the 2019 layout (no schema table).
  int schema_version() const { return schema_version_; }
  // The metadata table's latest entry (current layout), if any.
  const std::optional<Rosbag2Metadata>& metadata() const { return metadata_; }

  // Calls `visit(topic, timestamp, data, row id)` for each message of a
  // topic `wanted` accepts, in the order recorded (row id), which needs no
  // sort (the 2019 layout has no timestamp index).
  void ReadMessages(const std::function<bool(const Topic&)>& wanted,
                    const std::function<void(const Topic&, timestamp_ns_t, std::span<const uint8_t>,
                                             int64_t)>& visit);

 private:
  struct Database;
  // The constructor's steps: the file's SQLite magic, the database opened
  // (immutable when SQLite cannot lock it), rosbag2's tables and columns
  // checked (returns whether topics have QoS profiles), the schema version
  // and metadata, the topics and their message counts.
  static void CheckSqliteMagic(const std::filesystem::path& path);
  bool Open(const std::string& name, int flags);
  void OpenDatabase();
  bool CheckLayout(const std::set<std::string>& tables) const;
  void ReadSchemaAndMetadata(const std::set<std::string>& tables);
  void ReadTopics(bool has_qos);
  void CountMessages();

  std::filesystem::path path_;
  std::unique_ptr<Database> database_;
  std::vector<Topic> topics_;
  int schema_version_ = 0;
  std::optional<Rosbag2Metadata> metadata_;
};

// A ROS 2 bag: a folder with metadata.yaml, or one storage file (.db3,
// .mcap, or either zstd-compressed as .db3.zstd / .mcap.zstd). A storage
// file given alone that metadata.yaml lists with others is read alone, with
// a warning that names the others.
class Rosbag2Reader : public BagReader {
 public:
  explicit Rosbag2Reader(const std::filesystem::path& path);
  ~Rosbag2Reader() override;

  const std::filesystem::path& path() const override { return path_; }
  BagFormat format() const override { return BagFormat::kRos2; }
  std::string Describe() const override;
  const std::vector<BagConnection>& connections() const override { return connections_; }
  void ReadMessages(const std::function<bool(const BagConnection&)>& wanted,
                    const std::function<void(const BagMessage&)>& visit) override;

  Rosbag2Storage storage() const { return storage_; }
  Rosbag2Compression compression() const { return compression_; }
  // The storage files, in order (decompressed copies for FILE compression).
  const std::vector<std::filesystem::path>& files() const { return files_; }

 private:
  struct File;
  void OpenFiles(const std::vector<std::filesystem::path>& listed);
  void AddConnection(const std::string& file, BagConnection connection);

  // A folder of our own for decompressed files (FILE compression), removed
  // with the reader, also when its constructor throws.
  struct TempFolder {
    std::filesystem::path path;
    ~TempFolder();
  };

  std::filesystem::path path_;
  Rosbag2Storage storage_ = Rosbag2Storage::kSqlite3;
  Rosbag2Compression compression_ = Rosbag2Compression::kNone;
  bool compression_declared_ = false;
  std::vector<std::filesystem::path> files_;
  TempFolder temp_folder_;  // declared before opened_: removed after the files close
  std::vector<std::unique_ptr<File>> opened_;
  std::vector<BagConnection> connections_;  // one per topic
};

// Writes a one-file sqlite3 bag in the current layout (schema version 4,
// with the metadata and message_definitions tables), atomically; messages
// are zstd-compressed one by one when `compress_messages`.
class Rosbag2SqliteWriter {
 public:
  Rosbag2SqliteWriter(const std::filesystem::path& path, bool compress_messages);
  ~Rosbag2SqliteWriter();
  Rosbag2SqliteWriter(const Rosbag2SqliteWriter&) = delete;
  Rosbag2SqliteWriter& operator=(const Rosbag2SqliteWriter&) = delete;

  // Returns the topic's id.
  int64_t AddTopic(const std::string& name, const RosMessageType& type);
  void Write(int64_t topic_id, timestamp_ns_t time_ns, std::span<const uint8_t> cdr);
  void Close();

 private:
  struct Database;
  std::filesystem::path path_;
  std::filesystem::path temp_path_;
  bool compress_messages_ = false;
  std::unique_ptr<Database> database_;
  Rosbag2Metadata metadata_;
  std::vector<std::string> topic_types_;
  bool closed_ = false;
};

}  // namespace viosfm

#include "viosfm/pipeline/run_folder.h"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <exception>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>

#include "viosfm/io/colmap_database.h"
#include "viosfm/pipeline/pipeline_summary.h"
#include "viosfm/pipeline/run_common.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/logging.h"
#include "viosfm/util/string_util.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;

// At most this many differences are spelled out in the error message.
constexpr size_t kMaxDifferencesNamed = 8;

// Whether `name` is a leftover of an interrupted atomic write of any file:
// "<x>.tmp-<pid>", "<x>.old-<pid>", or the PNG writer's "<x>.tmp-<pid>.png".
bool IsAnyAtomicWriteLeftover(const std::string& name) {
  if (EndsWith(name, ".png") && IsAnyAtomicWriteLeftover(name.substr(0, name.size() - 4))) {
    return true;
  }
  for (const char* marker : {".tmp-", ".old-"}) {
    const size_t position = name.rfind(marker);
    if (position != std::string::npos && position > 0 &&
        IsAtomicWriteLeftover(name, name.substr(0, position))) {
      return true;
    }
  }
  return false;
}

// The run's folders whose every file is the run's (leftovers are looked for inside).
constexpr std::array<const char*, 3> kOwnedFolders = {"verification", "vio", "bag"};

// The first lines of a run's section of run.log.
std::string RunLogHeading(const PipelineOptions& options) {
  return "== viosfm " + ViosfmVersion() + " run, started " + UtcNow() + ", process " +
         std::to_string(getpid()) + "\n== dataset " + options.dataset.string() + ", output " +
         options.output_folder.string() +
         "\n== the options: options.json; the outcome: summary.json (written last)";
}

void WriteJsonFile(const fs::path& path, const std::string& text) {
  WriteFileAtomically(path, [&text](std::ostream& stream) { stream << text << "\n"; });
}

// "key was 'a', is now 'b'; ..." for at most kMaxDifferencesNamed
// differences, and whether a key one side lacks suggests another version.
std::string DescribeDifferences(const std::vector<FingerprintDifference>& differences,
                                bool* other_version) {
  std::string message;
  *other_version = false;
  for (size_t i = 0; i < differences.size() && i < kMaxDifferencesNamed; ++i) {
    const FingerprintDifference& d = differences[i];
    message += i > 0 ? "; " : "";
    if (d.stored == kFingerprintAbsent) {
      message += d.key + " is '" + d.current + "' and was not recorded then";
      *other_version = true;
    } else if (d.current == kFingerprintAbsent) {
      message += d.key + " was '" + d.stored + "' and is not recorded now";
      *other_version = true;
    } else {
      message += d.key + " was '" + d.stored + "', is now '" + d.current + "'";
    }
  }
  if (differences.size() > kMaxDifferencesNamed) {
    message += " (and " + std::to_string(differences.size() - kMaxDifferencesNamed) + " more)";
  }
  return message;
}

// " (the content of 2 image(s) changed: 1.png, 7.png)": the images whose
// size or content differ from the database's record; empty if none can be
// named.
std::string ChangedImages(const std::optional<ViosfmDatabaseRecord>& record,
                          const RunFingerprint& current) {
  if (!record || current.image_files.empty()) return "";
  std::map<std::string, const ViosfmDatabaseRecord::ImageFile*> stored;
  for (const auto& file : record->image_files) stored[file.name] = &file;
  std::vector<std::string> changed;
  size_t num_changed = 0;
  for (const auto& file : current.image_files) {
    const auto it = stored.find(file.name);
    if (it == stored.end() || !(*it->second == file)) {
      ++num_changed;
      if (changed.size() < 3) changed.push_back(file.name);
    }
  }
  if (changed.empty()) return "";
  std::string text = " (the content of " + std::to_string(num_changed) + " image(s) changed: ";
  for (size_t i = 0; i < changed.size(); ++i) text += (i > 0 ? ", " : "") + changed[i];
  return text + (num_changed > changed.size() ? ", ...)" : ")");
}

// The database's record, or InputError naming it if it cannot be read.
std::optional<ViosfmDatabaseRecord> RecordOf(const fs::path& database) {
  return ColmapDatabase::ReadViosfmRecordOf(database);
}

// InputError naming the database when it has no record of what made its
// rows, or a record that differs from `current` (on current's keys, and
// also on the record's own with `complete`): rows another run or command
// wrote, or a database copied in.
void CheckRecordMatches(const fs::path& database, const std::optional<ViosfmDatabaseRecord>& record,
                        const RunFingerprint& current, bool complete, bool allow_absent) {
  if (!record) {
    throw InputError(database.string(), 0,
                     "the database holds no record of what made its features and matches (another "
                     "tool's database, or one of an older viosfm, or one copied here); re-run "
                     "with --overwrite to remove the stored outputs and start afresh, or choose "
                     "another --out");
  }
  RunFingerprint recorded;
  recorded.entries = record->fingerprint;
  std::vector<FingerprintDifference> differences;
  for (const FingerprintDifference& d : CompareFingerprints(recorded, current, complete)) {
    if (!(allow_absent && d.stored == kFingerprintAbsent)) differences.push_back(d);
  }
  if (differences.empty()) return;
  bool other_version = false;
  throw InputError(database.string(), 0,
                   "its rows were written by another run or command than fingerprint.json beside "
                   "it says, from other inputs or options than this one's (the database's own "
                   "record: " +
                       DescribeDifferences(differences, &other_version) +
                       ChangedImages(record, current) +
                       "); re-run with --overwrite to start afresh, or choose another --out");
}

}  // namespace

void CheckStoredRunData(const fs::path& output_folder, const RunFingerprint& current,
                        bool complete) {
  const fs::path database = output_folder / "database.db";
  if (!fs::exists(database)) return;
  const fs::path file = output_folder / "fingerprint.json";
  if (!fs::exists(file)) {
    throw InputError(database.string(), 0,
                     "stored features and matches without the fingerprint.json that says what "
                     "they were made from (a folder of an older viosfm, or a database copied "
                     "here alone); re-run with --overwrite to remove the stored outputs and start "
                     "afresh, or choose another --out");
  }
  const RunFingerprint stored = ReadRunFingerprint(file);
  const std::optional<ViosfmDatabaseRecord> record = RecordOf(database);
  const std::vector<FingerprintDifference> differences =
      CompareFingerprints(stored, current, complete);
  if (!differences.empty()) {
    bool other_version = false;
    std::string message = "the features and matches stored in " + database.string() +
                          " were made from other inputs or options than this run's: " +
                          DescribeDifferences(differences, &other_version);
    for (const FingerprintDifference& d : differences) {
      if (d.key == "dataset.images") message += ChangedImages(record, current);
    }
    if (other_version) {
      message += " (a viosfm of another version made them: its fingerprint names other keys)";
    }
    message +=
        ". Re-run with --overwrite to remove that run's database and outputs and start afresh, "
        "or choose another --out";
    throw InputError(file.string(), 0, message);
  }
  CheckRecordMatches(database, record, current, complete, /*allow_absent=*/false);
}

std::vector<std::string> RunOutputNames(const PipelineOptions& options) {
  std::vector<std::string> names = {"database.db",
                                    "database.db-wal",
                                    "database.db-shm",
                                    "database.db-journal",
                                    "fingerprint.json",
                                    "options.json",
                                    "summary.json",
                                    kRunLogFileName,
                                    "model",
                                    "model_txt",
                                    "models",
                                    "verification",
                                    "vio",
                                    "live",
                                    "points.ply",
                                    "trajectory_cam.tum",
                                    "trajectory_body.tum",
                                    "vio_body.tum",
                                    "groundtruth_body.tum",
                                    "eval.json",
                                    "eval_vio.json"};
  // A bag's images go to OUT/bag unless the options send them elsewhere.
  if (options.rosbag.extract_folder.empty()) names.push_back("bag");
  return names;
}

size_t RemoveAtomicWriteLeftovers(const PipelineOptions& options) {
  const fs::path& out = options.output_folder;
  if (!fs::is_directory(out)) return 0;
  const std::vector<std::string> names = RunOutputNames(options);
  std::vector<fs::path> leftovers;
  for (const fs::directory_entry& entry : fs::directory_iterator(out)) {
    const std::string name = entry.path().filename().string();
    for (const std::string& output : names) {
      if (IsAtomicWriteLeftover(name, output)) leftovers.push_back(entry.path());
    }
  }
  for (const char* folder : kOwnedFolders) {
    if (std::find(names.begin(), names.end(), folder) == names.end()) continue;
    if (!fs::is_directory(out / folder) || fs::is_symlink(out / folder)) continue;
    for (const fs::directory_entry& entry : fs::recursive_directory_iterator(out / folder)) {
      if (IsAnyAtomicWriteLeftover(entry.path().filename().string())) {
        leftovers.push_back(entry.path());
      }
    }
  }
  size_t removed = 0;
  for (const fs::path& path : leftovers) {
    std::error_code error;
    if (fs::remove_all(path, error) > 0) ++removed;
  }
  if (removed > 0) {
    VIOSFM_LOG(INFO) << "run: removed " << removed << " leftover(s) of an interrupted run in "
                     << out.string();
  }
  return removed;
}

ManagedFolder::Options RunFolderManifestOptions() {
  ManagedFolder::Options options;
  options.kind = "run";
  options.accepted_kinds = {"run", "database"};
  options.flag = "--out";
  return options;
}

RunFolder::RunFolder(const PipelineOptions& options)
    : folder_(options.output_folder, RunFolderManifestOptions()),
      exceptions_at_start_(std::uncaught_exceptions()) {
  // A user's file under one of the run's names is refused before anything
  // changes.
  folder_.Claim(RunOutputNames(options));
  RemoveAtomicWriteLeftovers(options);
  if (options.overwrite) {
    const size_t removed = folder_.RemoveWritten();
    if (removed > 0) {
      VIOSFM_LOG(INFO) << "run: --overwrite: removed the " << removed << " file(s) viosfm wrote in "
                       << path().string();
    }
  }
  log_heading_ = RunLogHeading(options);
}

RunFolder::~RunFolder() {
  if (log_ && std::uncaught_exceptions() > exceptions_at_start_) {
    LogToFileOnly(LogLevel::kERROR,
                  "run: stopped by an error (the console's last line says which); the folder is "
                  "incomplete (no summary.json)");
  }
}

void RunFolder::CheckStoredData(const RunFingerprint& current, bool complete) const {
  CheckStoredRunData(path(), current, complete);
}

void RunFolder::MarkIncomplete() const {
  // The manifest claims run.log before it exists.
  folder_.Save();
  if (!log_) {
    const fs::path log_path = path() / kRunLogFileName;
    const bool earlier_log = fs::exists(log_path) && fs::file_size(log_path) > 0;
    log_.emplace(log_path,
                 (earlier_log ? "\n" : "") + log_heading_ +
                     (earlier_log ? "\n== an earlier run's log above (it ends where that run "
                                    "stopped)"
                                  : ""));
  }
  fs::remove(path() / "summary.json");
  // The earlier model's report and export describe a model this run
  // replaces (what the user put in export/ stays).
  for (const char* name : {"report.html", "export"}) {
    if (folder_.RemoveIfWritten(name) > 0) {
      VIOSFM_LOG(INFO) << "run: removed " << (path() / name).string() << " of the earlier model";
    }
  }
}

void RunFolder::WriteRecords(
    const RunFingerprint& fingerprint,
    const std::vector<std::pair<std::string, std::string>>& options) const {
  WriteJsonFile(path() / "fingerprint.json", RunFingerprintToJson(fingerprint));
  nlohmann::ordered_json json = nlohmann::ordered_json::object();
  for (const auto& [key, value] : options) json[key] = value;
  WriteJsonFile(path() / "options.json", json.dump(2));
  ColmapDatabase database = ColmapDatabase::Open(path() / "database.db");
  database.WriteViosfmRecord(DatabaseRecordOf(fingerprint));
}

void RunFolder::WriteSummary(const std::string& json) const {
  WriteJsonFile(path() / "summary.json", json);
  folder_.Finish();
  LogToFileOnly(LogLevel::kINFO, "run: complete (summary.json written)");
}

namespace {

ManagedFolder::Options DatabaseFolderOptions() {
  ManagedFolder::Options options;
  options.kind = "database";
  options.accepted_kinds = {"run", "database"};
  options.allow_foreign_content = true;
  options.flag = "--database";
  return options;
}

fs::path FolderOf(const fs::path& file) {
  return file.has_parent_path() ? file.parent_path() : fs::path(".");
}

}  // namespace

DatabaseFolder::DatabaseFolder(const fs::path& database, const fs::path& bag_folder)
    : database_(database), folder_(FolderOf(database), DatabaseFolderOptions()) {
  std::vector<std::string> names = {"fingerprint.json"};
  const std::string name = database.filename().string();
  // A database of another tool that the user names is written into, never
  // claimed: viosfm will not remove it.
  if (!folder_.IsForeign(name)) {
    for (const char* suffix : {"", "-wal", "-shm", "-journal"}) names.push_back(name + suffix);
  }
  if (!bag_folder.empty() &&
      fs::weakly_canonical(FolderOf(bag_folder)) == fs::weakly_canonical(folder_.path())) {
    names.push_back(bag_folder.filename().string());
  }
  folder_.Claim(names);
}

void DatabaseFolder::MarkWriting() {
  folder_.Save();
}

void DatabaseFolder::CheckAndRecord(const RunFingerprint& current) {
  const fs::path json = folder_.path() / "fingerprint.json";
  const bool has_database = fs::exists(database_);
  const std::optional<ViosfmDatabaseRecord> record =
      has_database ? RecordOf(database_) : std::nullopt;
  RunFingerprint merged;
  if (fs::exists(json)) {
    merged = ReadRunFingerprint(json);
  } else if (record) {
    merged.entries = record->fingerprint;
  }
  const std::vector<FingerprintDifference> differences =
      CompareFingerprints(merged, current, /*complete=*/false);
  std::vector<FingerprintDifference> conflicts;
  for (const FingerprintDifference& d : differences) {
    if (d.stored != kFingerprintAbsent) conflicts.push_back(d);
  }
  if (!conflicts.empty()) {
    bool other_version = false;
    std::string message = "the features and matches stored in " + database_.string() +
                          " were made from other inputs or options than this command's: " +
                          DescribeDifferences(conflicts, &other_version);
    for (const FingerprintDifference& d : conflicts) {
      if (d.key == "dataset.images") message += ChangedImages(record, current);
    }
    message += ". Nothing was written; give another --database (or remove that one)";
    throw InputError(fs::exists(json) ? json.string() : database_.string(), 0, message);
  }
  // The rows' own record says the same as fingerprint.json on what this
  // command makes.
  if (has_database && fs::exists(json)) {
    CheckRecordMatches(database_, record, current, /*complete=*/false, /*allow_absent=*/true);
  }
  for (const auto& [key, value] : current.entries) merged.Set(key, value);
  merged.image_files = !current.image_files.empty() ? current.image_files
                       : record                     ? record->image_files
                                : std::vector<ViosfmDatabaseRecord::ImageFile>();
  folder_.Save();
  WriteJsonFile(json, RunFingerprintToJson(merged));
  ColmapDatabase database = ColmapDatabase::Open(database_);
  database.WriteViosfmRecord(DatabaseRecordOf(merged));
}

void DatabaseFolder::Finish() {
  folder_.Finish();
}

}  // namespace viosfm

#include "viosfm/pipeline/run_folder.h"

#include <algorithm>
#include <array>
#include <nlohmann/json.hpp>

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

const fs::path& CreatedFolder(const fs::path& folder) {
  fs::create_directories(folder);
  return folder;
}

void WriteJsonFile(const fs::path& path, const std::string& text) {
  WriteFileAtomically(path, [&text](std::ostream& stream) { stream << text << "\n"; });
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
  const std::vector<FingerprintDifference> differences =
      CompareFingerprints(ReadRunFingerprint(file), current, complete);
  if (differences.empty()) return;
  std::string message = "the features and matches stored in " + database.string() +
                        " were made from other inputs or options than this run's: ";
  bool other_version = false;
  for (size_t i = 0; i < differences.size() && i < kMaxDifferencesNamed; ++i) {
    const FingerprintDifference& d = differences[i];
    message += i > 0 ? "; " : "";
    if (d.stored == kFingerprintAbsent) {
      message += d.key + " is '" + d.current + "' and was not recorded then";
      other_version = true;
    } else if (d.current == kFingerprintAbsent) {
      message += d.key + " was '" + d.stored + "' and is not recorded now";
      other_version = true;
    } else {
      message += d.key + " was '" + d.stored + "', is now '" + d.current + "'";
    }
  }
  if (other_version) {
    message += " (a viosfm of another version made them: its fingerprint names other keys)";
  }
  if (differences.size() > kMaxDifferencesNamed) {
    message += " (and " + std::to_string(differences.size() - kMaxDifferencesNamed) + " more)";
  }
  message +=
      ". Re-run with --overwrite to remove that run's database and outputs and start afresh, or "
      "choose another --out";
  throw InputError(file.string(), 0, message);
}

std::vector<std::string> RunOutputNames(const PipelineOptions& options) {
  std::vector<std::string> names = {"database.db",
                                    "database.db-wal",
                                    "database.db-shm",
                                    "database.db-journal",
                                    "fingerprint.json",
                                    "options.json",
                                    "summary.json",
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

size_t RemoveRunOutputs(const PipelineOptions& options) {
  const fs::path& out = options.output_folder;
  size_t removed = RemoveAtomicWriteLeftovers(options);
  for (const std::string& name : RunOutputNames(options)) {
    const fs::path path = out / name;
    if (fs::symlink_status(path).type() == fs::file_type::not_found) continue;
    fs::remove_all(path);
    ++removed;
  }
  if (removed > 0) {
    VIOSFM_LOG(INFO) << "run: --overwrite: removed " << removed << " stored output(s) of "
                     << out.string();
  }
  return removed;
}

RunFolder::RunFolder(const PipelineOptions& options)
    : path_(options.output_folder),
      lock_(CreatedFolder(options.output_folder), "another viosfm run") {
  if (options.overwrite) {
    RemoveRunOutputs(options);
  } else {
    RemoveAtomicWriteLeftovers(options);
  }
}

void RunFolder::CheckStoredData(const RunFingerprint& current, bool complete) const {
  CheckStoredRunData(path_, current, complete);
}

void RunFolder::MarkIncomplete() const {
  fs::remove(path_ / "summary.json");
}

void RunFolder::WriteRecords(
    const RunFingerprint& fingerprint,
    const std::vector<std::pair<std::string, std::string>>& options) const {
  WriteJsonFile(path_ / "fingerprint.json", RunFingerprintToJson(fingerprint));
  nlohmann::ordered_json json = nlohmann::ordered_json::object();
  for (const auto& [key, value] : options) json[key] = value;
  WriteJsonFile(path_ / "options.json", json.dump(2));
}

void RunFolder::WriteSummary(const std::string& json) const {
  WriteJsonFile(path_ / "summary.json", json);
}

}  // namespace viosfm

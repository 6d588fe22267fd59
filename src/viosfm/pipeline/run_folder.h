// The output folder of a `viosfm run` (pipeline.h): what it holds, the
// lock while a run writes into it, what viosfm wrote there
// (viosfm_manifest.json, util/folder_manifest.h: a folder viosfm did not
// make is refused unless empty, a user's file under one of the run's names
// is never written over, --overwrite removes exactly what viosfm wrote),
// the leftovers of interrupted atomic writes, the check of its stored
// features and matches against this run's fingerprint (run_fingerprint.h,
// and the database's own record of what made its rows), and the order of
// its records: fingerprint.json, options.json and the database's record
// before the database changes, summary.json removed when the folder starts
// to change and written last (a folder without it is incomplete), and the
// run's log (run.log), to which every run into the folder adds its section.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "viosfm/pipeline/pipeline_options.h"
#include "viosfm/pipeline/run_fingerprint.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/folder_manifest.h"
#include "viosfm/util/logging.h"

namespace viosfm {

// The run's log in its output folder.
inline constexpr const char* kRunLogFileName = "run.log";

// Throws InputError if `output_folder` holds stored features and matches
// (database.db) made from other inputs than `current` says: naming
// fingerprint.json, every changed key with its stored and its current value
// (and the images whose content changed), and --overwrite; or if the
// database has no fingerprint.json beside it, or its own record of what
// made its rows is missing or differs from fingerprint.json (rows another
// run or command wrote). Nothing stored: no check.
void CheckStoredRunData(const std::filesystem::path& output_folder, const RunFingerprint& current,
                        bool complete);

// The files and folders a run writes into its output folder (top level):
// database.db with its SQLite -wal, -shm and -journal files, fingerprint.json,
// options.json, summary.json, run.log, model/, model_txt/, models/ (the
// separate models), verification/, vio/, live/,
// points.ply, the .tum trajectories, eval.json, eval_vio.json, and bag/ when
// a bag is extracted to its default place.
std::vector<std::string> RunOutputNames(const PipelineOptions& options);

// Removes what interrupted atomic writes of the run's outputs left behind
// ("<output>.tmp-<pid>", "<output>.old-<pid>", util/file_util.h), at the top
// level and inside the run's own folders. Returns how many it removed.
size_t RemoveAtomicWriteLeftovers(const PipelineOptions& options);

// What ManagedFolder (util/folder_manifest.h) is told of a run's folder.
ManagedFolder::Options RunFolderManifestOptions();

// A run's output folder while the run writes into it.
class RunFolder {
 public:
  // Creates options.output_folder if missing and locks it (InputError if
  // another viosfm command holds it); refuses a folder that holds files
  // viosfm did not make (no manifest) and a user's file under one of the
  // run's names; removes everything viosfm wrote there (the manifest's
  // files, also an earlier report.html and export/) with
  // options.overwrite, else only the leftovers of interrupted writes.
  explicit RunFolder(const PipelineOptions& options);
  // Closes run.log, with a last line if the run stops on an exception.
  ~RunFolder();
  RunFolder(const RunFolder&) = delete;
  RunFolder& operator=(const RunFolder&) = delete;

  const std::filesystem::path& path() const { return folder_.path(); }
  // CheckStoredRunData on this folder.
  void CheckStoredData(const RunFingerprint& current, bool complete) const;
  // Records the run's names in the manifest (first write into the folder),
  // opens run.log, removes summary.json, and a report.html and an export/
  // of the earlier model (the files viosfm wrote there): from here on the
  // folder is incomplete until WriteSummary. Called before the first write
  // into the folder: a run refused before it leaves the folder as it was.
  // From then on every log message, the debug ones too, goes to run.log
  // while the object lives, after a heading that starts this run's section
  // and the console's lines printed before it (an earlier run's log stays
  // above; --overwrite removed it with the run's other outputs).
  void MarkIncomplete() const;
  // fingerprint.json and options.json, atomically, then the database's
  // record (created with the database), before the database's rows change.
  void WriteRecords(const RunFingerprint& fingerprint,
                    const std::vector<std::pair<std::string, std::string>>& options) const;
  // summary.json, atomically; the run's last write. The manifest then lists
  // exactly the files the run's names hold.
  void WriteSummary(const std::string& json) const;

 private:
  // mutable: the manifest follows what the const stages write.
  mutable ManagedFolder folder_;
  // Declared after folder_: closed before the folder's lock is released.
  mutable std::optional<LogFile> log_;
  std::string log_heading_;
  int exceptions_at_start_ = 0;
};

// The folder of the database that `viosfm features` or `viosfm match`
// writes: locked as a run's folder; its files that viosfm did not write are
// never written over (a database of another tool that the user names is
// added to, never removed); what viosfm writes there is in its manifest.
class DatabaseFolder {
 public:
  // `database`: the database file; a bag's images go to `bag_folder`, which
  // is viosfm's when it lies in the database's folder (empty: no bag).
  // Throws InputError as ManagedFolder does, or naming a file of the user's
  // under one of the names.
  DatabaseFolder(const std::filesystem::path& database, const std::filesystem::path& bag_folder);

  const std::filesystem::path& path() const { return folder_.path(); }
  // Records the names in the manifest before a first write that comes
  // before CheckAndRecord (a bag's images).
  void MarkWriting();
  // Checks `current` (the fingerprint part of what the command makes)
  // against the folder's fingerprint.json and the database's record (as a
  // run does, on current's keys; InputError naming the differences), then
  // writes both, the stored entries with current's set. Call it before the
  // database's rows change.
  void CheckAndRecord(const RunFingerprint& current);
  // The manifest lists what the command wrote.
  void Finish();

 private:
  std::filesystem::path database_;
  ManagedFolder folder_;
};

}  // namespace viosfm

// The output folder of a `viosfm run` (pipeline.h): what it holds, the
// lock while a run writes into it, the removal of an earlier run's outputs
// (--overwrite) or of what interrupted atomic writes left, the check of its
// stored features and matches against this run's fingerprint
// (run_fingerprint.h), and the order of its records: fingerprint.json and
// options.json before the database changes, summary.json removed when the
// folder starts to change and written last (a folder without it is
// incomplete).
#pragma once

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "viosfm/pipeline/pipeline_options.h"
#include "viosfm/pipeline/run_fingerprint.h"
#include "viosfm/util/file_util.h"

namespace viosfm {

// Throws InputError if `output_folder` holds stored features and matches
// (database.db) made from other inputs than `current` says: naming
// fingerprint.json, every changed key with its stored and its current value,
// and --overwrite; or if the database has no fingerprint.json beside it.
// Nothing stored: no check.
void CheckStoredRunData(const std::filesystem::path& output_folder, const RunFingerprint& current,
                        bool complete);

// The files and folders a run writes into its output folder (top level):
// database.db with its SQLite -wal, -shm and -journal files, fingerprint.json,
// options.json, summary.json, model/, model_txt/, verification/, vio/, live/,
// points.ply, the .tum trajectories, eval.json, eval_vio.json, and bag/ when
// a bag is extracted to its default place.
std::vector<std::string> RunOutputNames(const PipelineOptions& options);

// --overwrite: removes every output of RunOutputNames and the leftovers of
// interrupted atomic writes, nothing else. Returns how many entries it removed.
size_t RemoveRunOutputs(const PipelineOptions& options);

// Removes what interrupted atomic writes of the run's outputs left behind
// ("<output>.tmp-<pid>", "<output>.old-<pid>", util/file_util.h), at the top
// level and inside the run's own folders. Returns how many it removed.
size_t RemoveAtomicWriteLeftovers(const PipelineOptions& options);

// A run's output folder while the run writes into it.
class RunFolder {
 public:
  // Creates options.output_folder if missing and locks it (InputError if
  // another run holds it); removes an earlier run's outputs with
  // options.overwrite, else only the leftovers of interrupted writes.
  explicit RunFolder(const PipelineOptions& options);

  const std::filesystem::path& path() const { return path_; }
  // CheckStoredRunData on this folder.
  void CheckStoredData(const RunFingerprint& current, bool complete) const;
  // Removes summary.json: from here on the folder is incomplete until
  // WriteSummary. Called before the first write into the folder.
  void MarkIncomplete() const;
  // fingerprint.json and options.json, atomically, before the database changes.
  void WriteRecords(const RunFingerprint& fingerprint,
                    const std::vector<std::pair<std::string, std::string>>& options) const;
  // summary.json, atomically; the run's last write.
  void WriteSummary(const std::string& json) const;

 private:
  std::filesystem::path path_;
  FolderLock lock_;
};

}  // namespace viosfm

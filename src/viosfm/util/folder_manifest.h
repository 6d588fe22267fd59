// What viosfm wrote into a folder it writes into (a run's output folder, an
// export, the folder of a features database): the folder's
// viosfm_manifest.json. viosfm removes exactly what a manifest lists and
// never writes over a file no manifest lists, so a user's files stay as
// they were whatever command is pointed at their folder.
//
// viosfm_manifest.json:
//   {"about": "...", "kind": "run", "created_folder": true, "complete": true,
//    "files": ["database.db", "model/cameras.bin", ...],
//    "folders": ["model", ...],
//    "subfolders": ["export"],
//    "claimed": [], "foreign": []}
//   kind            what the folder is: "run", "export" or "database"
//   created_folder  viosfm created the folder itself
//   complete        false while a command writes into the folder: then
//                   `claimed` holds the names it writes (recorded before it
//                   writes them), and everything at or below a claimed name
//                   is viosfm's except the `foreign` paths (files that were
//                   there, not viosfm's, when the name was claimed)
//   files           files (and symbolic links) viosfm wrote
//   folders         folders viosfm created (removed once empty)
//   subfolders      folders viosfm made that carry a manifest of their own
//                   (a run's export/): what they hold is theirs to say
// Paths are relative to the folder, '/'-separated, without "." or "..".
#pragma once

#include <filesystem>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "viosfm/util/file_util.h"

namespace viosfm {

inline constexpr const char* kManifestFileName = "viosfm_manifest.json";

struct FolderManifest {
  std::string kind;
  bool created_folder = false;
  bool complete = true;
  std::set<std::string> files;
  std::set<std::string> folders;
  std::set<std::string> subfolders;
  std::set<std::string> claimed;
  std::set<std::string> foreign;

  // Whether viosfm wrote `relative` (a file or a folder): listed, a
  // subfolder, or at or below a claimed name and not foreign.
  bool Owns(const std::string& relative) const;
  // The manifest's JSON text, and reading it back (InputError naming `path`
  // for anything but a manifest).
  std::string ToJson() const;
  static FolderManifest FromJson(const std::string& text, const std::filesystem::path& path);
};

// The manifest of `folder`, or none. Throws InputError naming the file if
// it is there but is not a manifest.
std::optional<FolderManifest> ReadFolderManifest(const std::filesystem::path& folder);
// Writes `folder`/viosfm_manifest.json atomically.
void WriteFolderManifest(const std::filesystem::path& folder, const FolderManifest& manifest);

// Whether `folder` holds anything at all.
bool IsFolderEmpty(const std::filesystem::path& folder);

// A folder viosfm writes into, locked while the object lives.
class ManagedFolder {
 public:
  struct Options {
    // The manifest's kind for a folder without one.
    std::string kind;
    // Kinds of manifest accepted in an existing folder (`kind` if empty).
    std::vector<std::string> accepted_kinds;
    // Who holds the lock, for the message of a second writer.
    std::string holder = "another viosfm command";
    // A folder without a manifest must be empty (false) or may hold other
    // files (true: they are never written over nor removed).
    bool allow_foreign_content = false;
    // The command line's name of the folder in messages ("--out").
    std::string flag = "--out";
  };

  // Creates `folder` if missing and locks it (InputError if another viosfm
  // command holds it), then reads its manifest. Throws InputError naming
  // the folder if it exists without a manifest and holds anything (unless
  // allow_foreign_content), or if its manifest is of another kind. Nothing
  // is written until the first Save.
  ManagedFolder(const std::filesystem::path& folder, const Options& options);

  const std::filesystem::path& path() const { return path_; }
  const FolderManifest& manifest() const { return manifest_; }
  // Whether the folder had a manifest (viosfm wrote into it before).
  bool had_manifest() const { return had_manifest_; }

  // Checks that each name (relative path) is absent or viosfm's (InputError
  // naming the first one that is neither) and records it as claimed (in
  // memory: Save writes it). Files below a claimed folder that viosfm did
  // not write are recorded as foreign and stay.
  void Claim(const std::vector<std::string>& names);
  // Whether `relative` exists and viosfm did not write it.
  bool IsForeign(const std::string& relative) const;
  // Records `relative` as a folder with a manifest of its own.
  void AddSubfolder(const std::string& relative);
  // Writes the manifest, marked incomplete while names are claimed.
  void Save();

  // Removes everything viosfm wrote here (what the manifest lists, the
  // subfolders' own content by their manifests), nothing else, and saves
  // the manifest without it. Returns how many files it removed.
  size_t RemoveWritten();

  // Removes `relative` if viosfm wrote it: a listed file, or a subfolder by
  // its own manifest (what the user put there stays). Saves the manifest.
  // Returns how many files it removed.
  size_t RemoveIfWritten(const std::string& relative);

  // The claimed names as they are now: the files and folders below them
  // (foreign ones left out) become the manifest's lists, names that do not
  // exist are dropped, and the manifest is saved complete.
  void Finish();

 private:
  std::filesystem::path path_;
  std::optional<FolderLock> lock_;
  Options options_;
  FolderManifest manifest_;
  bool had_manifest_ = false;
};

// Removes what `folder`'s manifest lists (see ManagedFolder::RemoveWritten)
// without locking it; the folder itself too when viosfm created it and it is
// then empty. Returns how many files it removed. A folder without a manifest
// is left as it is.
size_t RemoveWrittenByManifest(const std::filesystem::path& folder);

}  // namespace viosfm

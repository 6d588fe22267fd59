#include "viosfm/util/folder_manifest.h"

#include <algorithm>
#include <nlohmann/json.hpp>

#include "viosfm/util/errors.h"
#include "viosfm/util/logging.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;
using ordered_json = nlohmann::ordered_json;

bool IsAtOrBelow(const std::string& path, const std::string& name) {
  return path == name || (path.size() > name.size() && path.compare(0, name.size(), name) == 0 &&
                          path[name.size()] == '/');
}

bool Exists(const fs::path& path) {
  std::error_code error;
  return fs::symlink_status(path, error).type() != fs::file_type::not_found && !error;
}

bool IsRealFolder(const fs::path& path) {
  std::error_code error;
  return fs::symlink_status(path, error).type() == fs::file_type::directory;
}

// A relative path as the manifest holds it: '/'-separated, no "." or "..",
// not absolute, not empty.
bool IsManifestPath(const std::string& text) {
  if (text.empty() || text.front() == '/' || text.back() == '/') return false;
  if (text.find('\0') != std::string::npos) return false;
  for (const fs::path& part : fs::path(text)) {
    if (part == "." || part == ".." || part.empty()) return false;
  }
  return true;
}

// Every entry below `folder` (not following symbolic links), relative to
// `base` as '/'-separated text, in a fixed order.
std::vector<std::pair<std::string, bool>> EntriesBelow(const fs::path& base,
                                                       const std::string& name) {
  std::vector<std::pair<std::string, bool>> entries;  // (path, is_folder)
  if (!IsRealFolder(base / name)) return entries;
  for (const fs::directory_entry& entry : fs::recursive_directory_iterator(base / name)) {
    const bool folder = entry.symlink_status().type() == fs::file_type::directory;
    entries.emplace_back(entry.path().lexically_relative(base).generic_string(), folder);
  }
  std::sort(entries.begin(), entries.end());
  return entries;
}

// Removes `name` (relative to `base`) and everything below it except the
// `foreign` paths, which keep the folders leading to them. Returns how many
// files and links it removed.
size_t RemoveExcept(const fs::path& base, const std::string& name,
                    const std::set<std::string>& foreign) {
  const fs::path path = base / name;
  if (!Exists(path) || foreign.count(name) > 0) return 0;
  if (!IsRealFolder(path)) {
    fs::remove(path);
    return 1;
  }
  size_t removed = 0;
  std::vector<std::string> children;
  for (const fs::directory_entry& entry : fs::directory_iterator(path)) {
    children.push_back(name + "/" + entry.path().filename().string());
  }
  std::sort(children.begin(), children.end());
  for (const std::string& child : children) removed += RemoveExcept(base, child, foreign);
  if (IsFolderEmpty(path)) fs::remove(path);
  return removed;
}

// Removes what `manifest` says viosfm wrote in `folder` and takes it off the
// lists; claimed names stay claimed (their content is gone). Returns how
// many files and links it removed.
size_t RemoveListed(const fs::path& folder, FolderManifest* manifest) {
  size_t removed = 0;
  for (const std::string& name : manifest->claimed) {
    removed += RemoveExcept(folder, name, manifest->foreign);
  }
  for (const std::string& file : manifest->files) {
    const fs::path path = folder / file;
    if (Exists(path) && !IsRealFolder(path)) {
      fs::remove(path);
      ++removed;
    }
  }
  manifest->files.clear();
  std::set<std::string> kept_subfolders;
  for (const std::string& subfolder : manifest->subfolders) {
    removed += RemoveWrittenByManifest(folder / subfolder);
    if (Exists(folder / subfolder)) kept_subfolders.insert(subfolder);
  }
  manifest->subfolders = kept_subfolders;
  // Deepest first, so that a folder's own folders go before it.
  std::vector<std::string> folders(manifest->folders.begin(), manifest->folders.end());
  std::sort(folders.begin(), folders.end(), [](const std::string& a, const std::string& b) {
    return std::count(a.begin(), a.end(), '/') > std::count(b.begin(), b.end(), '/') ||
           (std::count(a.begin(), a.end(), '/') == std::count(b.begin(), b.end(), '/') && a < b);
  });
  std::set<std::string> kept_folders;
  for (const std::string& name : folders) {
    const fs::path path = folder / name;
    if (!IsRealFolder(path)) continue;
    if (IsFolderEmpty(path)) {
      fs::remove(path);
    } else {
      kept_folders.insert(name);  // it holds a user's files: it stays, still viosfm's
    }
  }
  // Claimed folders kept for a foreign file inside: viosfm's folders still.
  for (const std::string& name : manifest->claimed) {
    if (!IsRealFolder(folder / name)) continue;
    kept_folders.insert(name);
    for (const auto& [path, is_folder] : EntriesBelow(folder, name)) {
      if (is_folder) kept_folders.insert(path);
    }
  }
  manifest->folders = kept_folders;
  return removed;
}

std::set<std::string> ReadPaths(const ordered_json& json, const char* key, const fs::path& file) {
  std::set<std::string> paths;
  if (!json.contains(key)) return paths;
  const ordered_json& list = json[key];
  if (!list.is_array()) {
    throw InputError(file.string(), 0, std::string("'") + key + "': expected a list of paths");
  }
  for (const ordered_json& element : list) {
    if (!element.is_string() || !IsManifestPath(element.get<std::string>())) {
      throw InputError(file.string(), 0,
                       std::string("'") + key +
                           "': expected relative paths inside the folder (no '..'), got " +
                           element.dump());
    }
    paths.insert(element.get<std::string>());
  }
  return paths;
}

}  // namespace

bool FolderManifest::Owns(const std::string& relative) const {
  if (files.count(relative) > 0 || folders.count(relative) > 0 || subfolders.count(relative) > 0) {
    return true;
  }
  if (foreign.count(relative) > 0) return false;
  return std::any_of(claimed.begin(), claimed.end(),
                     [&](const std::string& name) { return IsAtOrBelow(relative, name); });
}

std::string FolderManifest::ToJson() const {
  ordered_json json;
  json["about"] =
      "what viosfm wrote in this folder: viosfm removes only these (--overwrite) and never "
      "writes over anything else";
  json["kind"] = kind;
  json["created_folder"] = created_folder;
  json["complete"] = complete;
  json["files"] = files;
  json["folders"] = folders;
  json["subfolders"] = subfolders;
  json["claimed"] = claimed;
  json["foreign"] = foreign;
  return json.dump(1);
}

FolderManifest FolderManifest::FromJson(const std::string& text, const fs::path& path) {
  ordered_json json;
  try {
    json = ordered_json::parse(text);
  } catch (const nlohmann::json::exception& error) {
    throw InputError(
        path.string(), 0,
        std::string("expected viosfm's manifest of the folder, not JSON: ") + error.what());
  }
  if (!json.is_object() || !json.contains("kind") || !json["kind"].is_string() ||
      !json.contains("files")) {
    throw InputError(path.string(), 0,
                     "expected viosfm's manifest of the folder (an object with \"kind\" and "
                     "\"files\")");
  }
  FolderManifest manifest;
  manifest.kind = json["kind"].get<std::string>();
  const auto flag = [&](const char* key, bool fallback) {
    if (!json.contains(key)) return fallback;
    if (!json[key].is_boolean()) {
      throw InputError(path.string(), 0, std::string("'") + key + "': expected true or false");
    }
    return json[key].get<bool>();
  };
  manifest.created_folder = flag("created_folder", false);
  manifest.complete = flag("complete", true);
  manifest.files = ReadPaths(json, "files", path);
  manifest.folders = ReadPaths(json, "folders", path);
  manifest.subfolders = ReadPaths(json, "subfolders", path);
  manifest.claimed = ReadPaths(json, "claimed", path);
  manifest.foreign = ReadPaths(json, "foreign", path);
  return manifest;
}

std::optional<FolderManifest> ReadFolderManifest(const fs::path& folder) {
  const fs::path file = folder / kManifestFileName;
  std::error_code error;
  if (!fs::is_regular_file(file, error)) return std::nullopt;
  return FolderManifest::FromJson(ReadTextFile(file), file);
}

void WriteFolderManifest(const fs::path& folder, const FolderManifest& manifest) {
  WriteFileAtomically(folder / kManifestFileName,
                      [&manifest](std::ostream& stream) { stream << manifest.ToJson() << "\n"; });
}

bool IsFolderEmpty(const fs::path& folder) {
  return fs::directory_iterator(folder) == fs::directory_iterator();
}

ManagedFolder::ManagedFolder(const fs::path& folder, const Options& options)
    : path_(folder), options_(options) {
  const bool existed = Exists(folder);
  if (existed && !fs::is_directory(folder)) {
    throw InputError(folder.string(), 0, options.flag + ": expected a folder, this is a file");
  }
  fs::create_directories(folder);
  lock_.emplace(folder, options.holder);
  std::optional<FolderManifest> manifest = ReadFolderManifest(folder);
  if (manifest) {
    had_manifest_ = true;
    const std::vector<std::string> accepted = options.accepted_kinds.empty()
                                                  ? std::vector<std::string>{options.kind}
                                                  : options.accepted_kinds;
    if (std::find(accepted.begin(), accepted.end(), manifest->kind) == accepted.end()) {
      throw InputError(folder.string(), 0,
                       options.flag + ": viosfm made this folder as a " + manifest->kind +
                           " folder (" + kManifestFileName + "), not as a " + options.kind +
                           " folder; choose another " + options.flag);
    }
    manifest_ = std::move(*manifest);
    return;
  }
  if (!options.allow_foreign_content && !IsFolderEmpty(folder)) {
    throw InputError(folder.string(), 0,
                     options.flag +
                         ": the folder holds files and viosfm did not make it (it has no " +
                         kManifestFileName +
                         "): viosfm writes only into a new or empty folder, or one it made; "
                         "choose another " +
                         options.flag + " (nothing was changed)");
  }
  manifest_.kind = options.kind;
  manifest_.created_folder = !existed;
}

void ManagedFolder::Claim(const std::vector<std::string>& names) {
  // Every name checked before any is recorded: a refusal records nothing.
  for (const std::string& name : names) {
    VIOSFM_CHECK(IsManifestPath(name)) << "not a relative path: " << name;
    if (IsForeign(name)) {
      throw InputError((path_ / name).string(), 0,
                       "exists and viosfm did not write it (" + std::string(kManifestFileName) +
                           " does not list it): viosfm does not write over it; move it away or "
                           "choose another " +
                           options_.flag + " (nothing was changed)");
    }
  }
  for (const std::string& name : names) {
    for (const auto& [path, is_folder] : EntriesBelow(path_, name)) {
      if (!is_folder && !manifest_.Owns(path)) manifest_.foreign.insert(path);
    }
    manifest_.claimed.insert(name);
  }
}

bool ManagedFolder::IsForeign(const std::string& relative) const {
  return Exists(path_ / relative) && !manifest_.Owns(relative);
}

void ManagedFolder::AddSubfolder(const std::string& relative) {
  VIOSFM_CHECK(IsManifestPath(relative)) << "not a relative path: " << relative;
  manifest_.subfolders.insert(relative);
}

void ManagedFolder::Save() {
  manifest_.complete = manifest_.claimed.empty();
  WriteFolderManifest(path_, manifest_);
}

size_t ManagedFolder::RemoveWritten() {
  const size_t removed = RemoveListed(path_, &manifest_);
  Save();
  return removed;
}

size_t ManagedFolder::RemoveIfWritten(const std::string& relative) {
  size_t removed = 0;
  const fs::path path = path_ / relative;
  if (manifest_.files.count(relative) > 0) {
    if (Exists(path) && !IsRealFolder(path)) {
      fs::remove(path);
      ++removed;
    }
    manifest_.files.erase(relative);
  } else if (manifest_.subfolders.count(relative) > 0) {
    removed = RemoveWrittenByManifest(path);
    if (!Exists(path)) manifest_.subfolders.erase(relative);
  } else {
    return 0;
  }
  Save();
  return removed;
}

void ManagedFolder::Finish() {
  for (const std::string& name : manifest_.claimed) {
    const fs::path path = path_ / name;
    if (!Exists(path)) continue;
    if (!IsRealFolder(path)) {
      manifest_.files.insert(name);
      continue;
    }
    manifest_.folders.insert(name);
    for (const auto& [below, is_folder] : EntriesBelow(path_, name)) {
      if (is_folder) {
        manifest_.folders.insert(below);
      } else if (manifest_.foreign.count(below) == 0) {
        manifest_.files.insert(below);
      }
    }
  }
  manifest_.claimed.clear();
  manifest_.foreign.clear();
  // What a command removed again (e.g. an evaluation without ground truth).
  for (std::set<std::string>* list :
       {&manifest_.files, &manifest_.folders, &manifest_.subfolders}) {
    for (auto it = list->begin(); it != list->end();) {
      it = Exists(path_ / *it) ? std::next(it) : list->erase(it);
    }
  }
  Save();
}

size_t RemoveWrittenByManifest(const fs::path& folder) {
  std::optional<FolderManifest> manifest = ReadFolderManifest(folder);
  if (!manifest) return 0;
  size_t removed = RemoveListed(folder, &*manifest);
  manifest->claimed.clear();
  manifest->foreign.clear();
  const bool only_manifest = [&] {
    for (const fs::directory_entry& entry : fs::directory_iterator(folder)) {
      if (entry.path().filename() != kManifestFileName) return false;
    }
    return true;
  }();
  if (manifest->created_folder && only_manifest) {
    fs::remove(folder / kManifestFileName);
    fs::remove(folder);
  } else {
    manifest->complete = true;
    WriteFolderManifest(folder, *manifest);
  }
  return removed;
}

}  // namespace viosfm

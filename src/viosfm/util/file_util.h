// File helpers. Outputs are written atomically: to a temporary name in the
// same folder, synced to disk, then renamed (and the rename synced), so
// neither a crash nor a power loss leaves a half-written file that looks
// complete.
#pragma once

#include <filesystem>
#include <functional>
#include <ostream>
#include <string>

namespace viosfm {

// fsync of a file or folder (a folder: its entries, i.e. renames in it).
// Throws InputError naming the path if it cannot be opened or synced.
void SyncToDisk(const std::filesystem::path& path);

// Calls `write` with a stream on "<path>.tmp-<pid>", then renames it to
// `path`. If `write` throws or the stream fails, the temporary file is
// removed and the exception propagates (InputError for I/O failures).
void WriteFileAtomically(const std::filesystem::path& path,
                         const std::function<void(std::ostream&)>& write, bool binary = false);

// Same for a whole folder: `write` fills a temporary sibling folder, which
// then replaces `path` (an existing `path` is removed only after success).
void WriteFolderAtomically(const std::filesystem::path& path,
                           const std::function<void(const std::filesystem::path&)>& write);

// Whether `file_name` is what an interrupted WriteFileAtomically or
// WriteFolderAtomically of `target_name` leaves behind: "<target>.tmp-<pid>"
// or "<target>.old-<pid>" (a process killed between its two renames leaves
// the old folder so). Such leftovers are never taken for the target.
bool IsAtomicWriteLeftover(const std::string& file_name, const std::string& target_name);

// An exclusive advisory lock (flock) on a folder, held while the object
// lives, so that two processes never write into the same folder at once. The
// kernel releases it however the process ends, so a killed process leaves
// no stale lock behind.
class FolderLock {
 public:
  // Throws InputError naming the folder if another process holds its lock
  // (`what` says who, e.g. "another `viosfm run`"), or if it cannot be opened.
  FolderLock(const std::filesystem::path& folder, const std::string& what);
  ~FolderLock();
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;

 private:
  int fd_ = -1;
};

// Throws InputError naming `path` if it is not an existing regular file / folder.
void RequireFile(const std::filesystem::path& path, const std::string& what = "file");
void RequireFolder(const std::filesystem::path& path, const std::string& what = "folder");

std::string ReadTextFile(const std::filesystem::path& path);

}  // namespace viosfm

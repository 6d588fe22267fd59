// File helpers. Outputs are written atomically: to a temporary name in the
// same folder, then renamed, so a crash never leaves a half-written file
// that looks complete.
#pragma once

#include <filesystem>
#include <functional>
#include <ostream>
#include <string>

namespace viosfm {

// Calls `write` with a stream on "<path>.tmp-<pid>", then renames it to
// `path`. If `write` throws or the stream fails, the temporary file is
// removed and the exception propagates (InputError for I/O failures).
void WriteFileAtomically(const std::filesystem::path& path,
                         const std::function<void(std::ostream&)>& write, bool binary = false);

// Same for a whole folder: `write` fills a temporary sibling folder, which
// then replaces `path` (an existing `path` is removed only after success).
void WriteFolderAtomically(const std::filesystem::path& path,
                           const std::function<void(const std::filesystem::path&)>& write);

// Throws InputError naming `path` if it is not an existing regular file / folder.
void RequireFile(const std::filesystem::path& path, const std::string& what = "file");
void RequireFolder(const std::filesystem::path& path, const std::string& what = "folder");

std::string ReadTextFile(const std::filesystem::path& path);

}  // namespace viosfm

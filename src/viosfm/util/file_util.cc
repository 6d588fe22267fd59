#include "viosfm/util/file_util.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>

#include "viosfm/util/errors.h"

namespace viosfm {
namespace fs = std::filesystem;

namespace {

fs::path TemporarySibling(const fs::path& path) {
  fs::path tmp = path;
  tmp += ".tmp-" + std::to_string(getpid());
  return tmp;
}

}  // namespace

void SyncToDisk(const fs::path& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    throw InputError(path.string(), 0, std::string("cannot open to sync: ") + std::strerror(errno));
  }
  const int result = ::fsync(fd);
  const int error = errno;
  ::close(fd);
  // EINVAL: a file system (or special file) that has nothing to sync.
  if (result != 0 && error != EINVAL) {
    throw InputError(path.string(), 0, std::string("cannot sync to disk: ") + std::strerror(error));
  }
}

void WriteFileAtomically(const fs::path& path, const std::function<void(std::ostream&)>& write,
                         bool binary) {
  if (path.has_parent_path() && !fs::exists(path.parent_path())) {
    fs::create_directories(path.parent_path());
  }
  const fs::path tmp = TemporarySibling(path);
  try {
    {
      std::ofstream stream(tmp, binary ? std::ios::binary | std::ios::trunc : std::ios::trunc);
      if (!stream) throw InputError(tmp.string(), 0, "cannot open for writing");
      write(stream);
      stream.flush();
      if (!stream) throw InputError(tmp.string(), 0, "write failed (disk full?)");
    }
    // The content on disk before the name points at it, and the rename on
    // disk before the caller goes on (a power loss after a later write must
    // not find this file empty or missing).
    SyncToDisk(tmp);
    fs::rename(tmp, path);
    SyncToDisk(path.has_parent_path() ? path.parent_path() : fs::path("."));
  } catch (...) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    throw;
  }
}

void WriteFolderAtomically(const fs::path& path,
                           const std::function<void(const fs::path&)>& write) {
  const fs::path tmp = TemporarySibling(path);
  std::error_code ignored;
  fs::remove_all(tmp, ignored);
  fs::create_directories(tmp);
  try {
    write(tmp);
    for (const fs::directory_entry& entry : fs::recursive_directory_iterator(tmp)) {
      if (entry.is_regular_file() || entry.is_directory()) SyncToDisk(entry.path());
    }
    SyncToDisk(tmp);
    if (fs::exists(path)) {
      const fs::path old = fs::path(path.string() + ".old-" + std::to_string(getpid()));
      fs::rename(path, old);
      fs::rename(tmp, path);
      fs::remove_all(old, ignored);
    } else {
      fs::rename(tmp, path);
    }
    SyncToDisk(path.has_parent_path() ? path.parent_path() : fs::path("."));
  } catch (...) {
    fs::remove_all(tmp, ignored);
    throw;
  }
}

bool IsAtomicWriteLeftover(const std::string& file_name, const std::string& target_name) {
  for (const char* suffix : {".tmp-", ".old-"}) {
    const std::string prefix = target_name + suffix;
    if (file_name.size() <= prefix.size() || file_name.compare(0, prefix.size(), prefix) != 0) {
      continue;
    }
    bool digits = true;
    for (size_t i = prefix.size(); i < file_name.size(); ++i) {
      digits = digits && file_name[i] >= '0' && file_name[i] <= '9';
    }
    if (digits) return true;
  }
  return false;
}

FolderLock::FolderLock(const fs::path& folder, const std::string& what) {
  fd_ = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd_ < 0) {
    throw InputError(folder.string(), 0,
                     std::string("cannot open the folder to lock it: ") + std::strerror(errno));
  }
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int error = errno;
    ::close(fd_);
    fd_ = -1;
    if (error == EWOULDBLOCK) {
      throw InputError(folder.string(), 0,
                       what +
                           " is writing into this folder; wait for it to end or choose "
                           "another folder");
    }
    throw InputError(folder.string(), 0,
                     std::string("cannot lock the folder: ") + std::strerror(error));
  }
}

FolderLock::~FolderLock() {
  if (fd_ >= 0) ::close(fd_);  // closing the last descriptor releases the lock
}

void RequireFile(const fs::path& path, const std::string& what) {
  if (!fs::exists(path)) throw InputError(path.string(), 0, what + " does not exist");
  if (!fs::is_regular_file(path))
    throw InputError(path.string(), 0, what + " is not a regular file");
}

void RequireFolder(const fs::path& path, const std::string& what) {
  if (!fs::exists(path)) throw InputError(path.string(), 0, what + " does not exist");
  if (!fs::is_directory(path)) throw InputError(path.string(), 0, what + " is not a folder");
}

std::string ReadTextFile(const fs::path& path) {
  RequireFile(path);
  std::ifstream stream(path, std::ios::binary);
  if (!stream) throw InputError(path.string(), 0, "cannot open for reading");
  std::ostringstream content;
  content << stream.rdbuf();
  return content.str();
}

}  // namespace viosfm

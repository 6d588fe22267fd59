#include "viosfm/util/testing.h"

#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <mutex>
#include <vector>

namespace viosfm::testing {
namespace fs = std::filesystem;

namespace {

std::mutex g_scratch_mutex;
std::vector<fs::path>* g_scratch_folders = nullptr;

void RemoveScratchFolders() {
  if (g_scratch_folders == nullptr) return;
  std::error_code ignored;
  for (const auto& folder : *g_scratch_folders) fs::remove_all(folder, ignored);
}

}  // namespace

fs::path DataDir() {
  if (const char* env = std::getenv("VIOSFM_DATA_DIR"); env != nullptr && *env != '\0') {
    return fs::path(env);
  }
#ifdef VIOSFM_DATA_DIR
  return fs::path(VIOSFM_DATA_DIR);
#else
  return fs::path("../shared/data");
#endif
}

fs::path FindDataset(const std::string& name) {
  const fs::path path = DataDir() / name;
  return fs::exists(path) ? path : fs::path();
}

fs::path SourcePath(const std::string& relative) {
#ifdef VIOSFM_SOURCE_DIR
  return fs::path(VIOSFM_SOURCE_DIR) / "src" / "viosfm" / relative;
#else
  return fs::path("src/viosfm") / relative;
#endif
}

fs::path MakeScratchFolder(const std::string& name) {
  std::lock_guard<std::mutex> lock(g_scratch_mutex);
  if (g_scratch_folders == nullptr) {
    g_scratch_folders = new std::vector<fs::path>();
    std::atexit(RemoveScratchFolders);
  }
  const fs::path folder =
      fs::temp_directory_path() / ("viosfm_test_" + std::to_string(getpid()) + "_" +
                                   std::to_string(g_scratch_folders->size()) + "_" + name);
  fs::remove_all(folder);
  fs::create_directories(folder);
  g_scratch_folders->push_back(folder);
  return folder;
}

fs::path CopyFolderLinkingImages(const fs::path& source, const fs::path& target) {
  fs::create_directories(target);
  for (const fs::directory_entry& entry : fs::recursive_directory_iterator(source)) {
    const fs::path relative = fs::relative(entry.path(), source);
    if (entry.is_directory()) {
      fs::create_directories(target / relative);
    } else if (entry.path().extension() == ".png") {
      // A hard link (a copy across file systems): the dataset readers
      // refuse symbolic links that leave the dataset's folder.
      std::error_code error;
      fs::create_hard_link(entry.path(), target / relative, error);
      if (error) fs::copy_file(entry.path(), target / relative);
    } else {
      fs::copy_file(entry.path(), target / relative);
    }
  }
  return target;
}

void WriteTextFile(const fs::path& path, const std::string& text) {
  std::ofstream stream(path, std::ios::binary);
  stream << text;
  stream.flush();
  EXPECT_TRUE(stream.good()) << "cannot write " << path;
}

}  // namespace viosfm::testing

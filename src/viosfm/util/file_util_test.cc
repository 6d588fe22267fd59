#include "viosfm/util/file_util.h"

#include <gtest/gtest.h>

#include <fstream>
#include <stdexcept>

#include "viosfm/util/errors.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {
namespace fs = std::filesystem;

TEST(FileUtil, AtomicWriteKeepsOldContentOnFailure) {
  const fs::path dir = testing::MakeScratchFolder("atomic");
  const fs::path file = dir / "out.txt";
  WriteFileAtomically(file, [](std::ostream& out) { out << "complete\n"; });
  EXPECT_EQ(ReadTextFile(file), "complete\n");
  EXPECT_THROW(WriteFileAtomically(file,
                                   [](std::ostream& out) {
                                     out << "half";
                                     throw std::runtime_error("crash mid-write");
                                   }),
               std::runtime_error);
  EXPECT_EQ(ReadTextFile(file), "complete\n");
  size_t entries = 0;
  for ([[maybe_unused]] const auto& entry : fs::directory_iterator(dir)) ++entries;
  EXPECT_EQ(entries, 1u) << "temporary file left behind";
}

TEST(FileUtil, AtomicFolderWrite) {
  const fs::path dir = testing::MakeScratchFolder("atomic_folder");
  const fs::path model = dir / "model";
  WriteFolderAtomically(model, [](const fs::path& tmp) { std::ofstream(tmp / "a.txt") << "1"; });
  EXPECT_EQ(ReadTextFile(model / "a.txt"), "1");
  EXPECT_THROW(WriteFolderAtomically(model,
                                     [](const fs::path& tmp) {
                                       std::ofstream(tmp / "a.txt") << "2";
                                       throw std::runtime_error("fail");
                                     }),
               std::runtime_error);
  EXPECT_EQ(ReadTextFile(model / "a.txt"), "1");
  WriteFolderAtomically(model, [](const fs::path& tmp) { std::ofstream(tmp / "b.txt") << "3"; });
  EXPECT_FALSE(fs::exists(model / "a.txt"));
  EXPECT_EQ(ReadTextFile(model / "b.txt"), "3");
}

TEST(FileUtil, RequireNamesThePath) {
  try {
    RequireFile("/nonexistent/x.csv", "IMU file");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "/nonexistent/x.csv: IMU file does not exist");
  }
  EXPECT_THROW(RequireFolder("/nonexistent"), InputError);
}

}  // namespace
}  // namespace viosfm

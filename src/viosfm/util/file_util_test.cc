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

TEST(FileUtil, SyncToDiskTakesFilesAndFoldersAndNamesAMissingPath) {
  const fs::path dir = testing::MakeScratchFolder("sync");
  WriteFileAtomically(dir / "a.txt", [](std::ostream& out) { out << "a"; });
  EXPECT_NO_THROW(SyncToDisk(dir / "a.txt"));
  EXPECT_NO_THROW(SyncToDisk(dir));
  try {
    SyncToDisk(dir / "absent.txt");
    FAIL() << "a missing path was synced";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("absent.txt: cannot open to sync"), std::string::npos)
        << e.what();
  }
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

TEST(FileUtil, AtomicWriteLeftoversAreRecognised) {
  EXPECT_TRUE(IsAtomicWriteLeftover("summary.json.tmp-1234", "summary.json"));
  EXPECT_TRUE(IsAtomicWriteLeftover("model.old-7", "model"));
  EXPECT_FALSE(IsAtomicWriteLeftover("summary.json", "summary.json"));
  EXPECT_FALSE(IsAtomicWriteLeftover("summary.json.tmp-", "summary.json"));
  EXPECT_FALSE(IsAtomicWriteLeftover("summary.json.tmp-12a", "summary.json"));
  EXPECT_FALSE(IsAtomicWriteLeftover("model_txt.tmp-12", "model"));
  EXPECT_FALSE(IsAtomicWriteLeftover("my.model.tmp-12", "model"));

  // What WriteFolderAtomically leaves when its write throws: nothing; the
  // names it would leave when killed are the ones recognised above.
  const fs::path dir = testing::MakeScratchFolder("leftovers");
  EXPECT_THROW(
      WriteFolderAtomically(dir / "model",
                            [](const fs::path& tmp) {
                              EXPECT_TRUE(IsAtomicWriteLeftover(tmp.filename().string(), "model"));
                              throw std::runtime_error("crash mid-write");
                            }),
      std::runtime_error);
  EXPECT_TRUE(fs::is_empty(dir));
}

TEST(FileUtil, FolderLockIsExclusiveAndReleased) {
  const fs::path dir = testing::MakeScratchFolder("lock");
  {
    const FolderLock lock(dir, "another test");
    // flock locks belong to the open file description: a second open in the
    // same process conflicts as a second process would.
    const std::string message =
        testing::InputErrorMessage([&] { FolderLock second(dir, "another test"); });
    EXPECT_NE(message.find("another test is writing into this folder"), std::string::npos)
        << message;
  }
  EXPECT_NO_THROW(FolderLock again(dir, "another test"));
  EXPECT_THROW(FolderLock absent(dir / "absent", "x"), InputError);
}

}  // namespace
}  // namespace viosfm

#include "viosfm/util/folder_manifest.h"

#include <gtest/gtest.h>

#include <fstream>

#include "viosfm/util/errors.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {
namespace fs = std::filesystem;

// Writes `text` to `path`, creating its folders.
void Write(const fs::path& path, const std::string& text) {
  fs::create_directories(path.parent_path());
  testing::WriteTextFile(path, text);
}

ManagedFolder::Options RunKind() {
  ManagedFolder::Options options;
  options.kind = "run";
  return options;
}

// Every file below `folder` with its content, for "byte-identical afterwards".
std::map<std::string, std::string> Contents(const fs::path& folder) {
  std::map<std::string, std::string> contents;
  for (const auto& entry : fs::recursive_directory_iterator(folder)) {
    if (entry.is_regular_file()) {
      contents[entry.path().lexically_relative(folder).generic_string()] =
          ReadTextFile(entry.path());
    }
  }
  return contents;
}

TEST(FolderManifest, ANonEmptyFolderViosfmDidNotMakeIsRefusedAndLeftAsItWas) {
  const fs::path folder = testing::MakeScratchFolder("manifest_foreign") / "user";
  Write(folder / "model" / "notes.txt", "mine\n");
  Write(folder / "summary.json", "{}\n");
  const auto before = Contents(folder);
  const std::string message = testing::InputErrorMessage([&] { ManagedFolder(folder, RunKind()); });
  EXPECT_NE(message.find(folder.string()), std::string::npos) << message;
  EXPECT_NE(message.find("viosfm did not make it"), std::string::npos) << message;
  EXPECT_EQ(Contents(folder), before);
  EXPECT_FALSE(fs::exists(folder / kManifestFileName));
}

TEST(FolderManifest, AnEmptyOrNewFolderIsTakenAndANewOneMarkedAsCreated) {
  const fs::path scratch = testing::MakeScratchFolder("manifest_new");
  fs::create_directories(scratch / "empty");
  {
    ManagedFolder folder(scratch / "empty", RunKind());
    folder.Save();
    EXPECT_FALSE(folder.manifest().created_folder);
  }
  {
    ManagedFolder folder(scratch / "new", RunKind());
    folder.Save();
    EXPECT_TRUE(folder.manifest().created_folder);
  }
  EXPECT_TRUE(ReadFolderManifest(scratch / "new")->created_folder);
}

TEST(FolderManifest, ClaimedNamesBecomeTheExactListAndOnlyTheyAreRemoved) {
  const fs::path out = testing::MakeScratchFolder("manifest_exact") / "out";
  {
    ManagedFolder folder(out, RunKind());
    folder.Claim({"summary.json", "vio", "live"});
    folder.Save();
    EXPECT_FALSE(ReadFolderManifest(out)->complete);
    Write(out / "summary.json", "{}\n");
    Write(out / "vio" / "states.csv", "1\n");
    Write(out / "vio" / "deep" / "x.txt", "2\n");
    folder.Finish();
  }
  const FolderManifest manifest = *ReadFolderManifest(out);
  EXPECT_TRUE(manifest.complete);
  EXPECT_EQ(manifest.files,
            (std::set<std::string>{"summary.json", "vio/deep/x.txt", "vio/states.csv"}));
  EXPECT_EQ(manifest.folders, (std::set<std::string>{"vio", "vio/deep"}));
  EXPECT_TRUE(manifest.claimed.empty());  // "live" was never written: dropped

  // The user's files beside and inside viosfm's folders stay, byte for byte.
  Write(out / "my_notes.txt", "keep\n");
  Write(out / "vio" / "my_plot.svg", "<svg/>\n");
  Write(out / "live" / "mine.txt", "mine\n");
  {
    ManagedFolder folder(out, RunKind());
    EXPECT_EQ(folder.RemoveWritten(), 3u);
  }
  EXPECT_EQ(Contents(out), (std::map<std::string, std::string>{
                               {"live/mine.txt", "mine\n"},
                               {"my_notes.txt", "keep\n"},
                               {"vio/my_plot.svg", "<svg/>\n"},
                               {kManifestFileName, ReadTextFile(out / kManifestFileName)}}));
  EXPECT_FALSE(fs::exists(out / "vio" / "deep"));
}

TEST(FolderManifest, AClaimOfAUsersFileIsRefusedBeforeAnythingIsRecorded) {
  const fs::path out = testing::MakeScratchFolder("manifest_claim") / "out";
  {
    ManagedFolder folder(out, RunKind());
    folder.Claim({"model"});
    Write(out / "model" / "cameras.bin", "c");
    folder.Finish();
  }
  Write(out / "points.ply", "the user's\n");
  const std::string manifest_before = ReadTextFile(out / kManifestFileName);
  ManagedFolder folder(out, RunKind());
  const std::string message = testing::InputErrorMessage([&] {
    folder.Claim({"model", "points.ply"});
  });
  EXPECT_NE(message.find((out / "points.ply").string()), std::string::npos) << message;
  EXPECT_TRUE(folder.manifest().claimed.empty());
  EXPECT_EQ(ReadTextFile(out / kManifestFileName), manifest_before);
}

TEST(FolderManifest, AnInterruptedCommandsClaimsAreRemovedWholeExceptForeignFiles) {
  const fs::path out = testing::MakeScratchFolder("manifest_killed") / "out";
  {
    ManagedFolder folder(out, RunKind());
    folder.Claim({"vio"});
    Write(out / "vio" / "old.csv", "o\n");
    folder.Finish();
  }
  Write(out / "vio" / "user.txt", "u\n");
  {
    // A second command claims vio/ again and is killed after writing.
    ManagedFolder folder(out, RunKind());
    folder.Claim({"vio", "database.db"});
    folder.Save();
    Write(out / "vio" / "new.csv", "n\n");
    Write(out / "database.db", "d");
  }
  const FolderManifest killed = *ReadFolderManifest(out);
  EXPECT_FALSE(killed.complete);
  EXPECT_EQ(killed.foreign, (std::set<std::string>{"vio/user.txt"}));
  EXPECT_EQ(RemoveWrittenByManifest(out), 3u);  // old.csv, new.csv, database.db
  EXPECT_TRUE(fs::exists(out / "vio" / "user.txt"));
  EXPECT_FALSE(fs::exists(out / "vio" / "new.csv"));
  EXPECT_FALSE(fs::exists(out / "vio" / "old.csv"));
  EXPECT_FALSE(fs::exists(out / "database.db"));
}

TEST(FolderManifest, SubfoldersAreRemovedByTheirOwnManifest) {
  const fs::path run = testing::MakeScratchFolder("manifest_sub") / "run";
  {
    ManagedFolder folder(run, RunKind());
    folder.Claim({"summary.json"});
    Write(run / "summary.json", "{}\n");
    ManagedFolder::Options export_kind;
    export_kind.kind = "export";
    ManagedFolder exported(run / "export", export_kind);
    exported.Claim({"transforms.json"});
    Write(run / "export" / "transforms.json", "{}\n");
    exported.Finish();
    folder.AddSubfolder("export");
    folder.Finish();
  }
  Write(run / "export" / "colmap_sparse" / "0" / "images.bin", "user's\n");
  {
    ManagedFolder folder(run, RunKind());
    EXPECT_EQ(folder.RemoveWritten(), 2u);
  }
  EXPECT_FALSE(fs::exists(run / "summary.json"));
  EXPECT_FALSE(fs::exists(run / "export" / "transforms.json"));
  EXPECT_EQ(ReadTextFile(run / "export" / "colmap_sparse" / "0" / "images.bin"), "user's\n");

  // Without a file of the user's the export folder goes entirely.
  fs::remove_all(run / "export" / "colmap_sparse");
  {
    ManagedFolder folder(run, RunKind());
    folder.RemoveWritten();
  }
  EXPECT_FALSE(fs::exists(run / "export"));
}

TEST(FolderManifest, AFolderOfAnotherKindIsRefused) {
  const fs::path out = testing::MakeScratchFolder("manifest_kind") / "out";
  {
    ManagedFolder folder(out, RunKind());
    folder.Save();
  }
  ManagedFolder::Options export_kind;
  export_kind.kind = "export";
  const std::string message = testing::InputErrorMessage([&] { ManagedFolder(out, export_kind); });
  EXPECT_NE(message.find("as a run folder"), std::string::npos) << message;
}

TEST(FolderManifest, ALockedFolderIsRefused) {
  const fs::path out = testing::MakeScratchFolder("manifest_lock") / "out";
  ManagedFolder first(out, RunKind());
  const std::string message = testing::InputErrorMessage([&] { ManagedFolder(out, RunKind()); });
  EXPECT_NE(message.find("another viosfm command"), std::string::npos) << message;
}

TEST(FolderManifest, AManifestNamingPathsOutsideTheFolderIsRefused) {
  const fs::path out = testing::MakeScratchFolder("manifest_hostile") / "out";
  Write(out / kManifestFileName, R"({"kind": "run", "files": ["../../etc/passwd"]})");
  const std::string message = testing::InputErrorMessage([&] { ReadFolderManifest(out); });
  EXPECT_NE(message.find("relative paths inside the folder"), std::string::npos) << message;
  Write(out / kManifestFileName, R"({"kind": "run", "files": ["/etc/passwd"]})");
  testing::InputErrorMessage([&] { ReadFolderManifest(out); });
}

}  // namespace
}  // namespace viosfm

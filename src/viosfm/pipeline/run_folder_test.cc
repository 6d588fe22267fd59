#include "viosfm/pipeline/run_folder.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <set>
#include <string>

#include "viosfm/io/colmap_database.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/folder_manifest.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;

void Write(const fs::path& path, const std::string& text) {
  fs::create_directories(path.parent_path());
  testing::WriteTextFile(path, text);
}

// Every file below `folder` with its content.
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

PipelineOptions Options(const fs::path& out) {
  PipelineOptions options;
  options.dataset = "dataset";
  options.output_folder = out;
  return options;
}

RunFingerprint Fingerprint(const std::string& features) {
  RunFingerprint fingerprint;
  fingerprint.Set("fingerprint.version", kRunFingerprintVersion);
  fingerprint.Set("dataset.images", "2 images");
  fingerprint.Set("sift.max_num_features", features);
  return fingerprint;
}

// What a run writes, in the order it writes it.
void WriteARun(const PipelineOptions& options) {
  const RunFolder folder(options);
  folder.MarkIncomplete();
  folder.WriteRecords(Fingerprint("800"), options.ToKeyValues());
  const fs::path out = options.output_folder;
  Write(out / "vio" / "states.csv", "states\n");
  Write(out / "model" / "cameras.bin", "cameras");
  Write(out / "points.ply", "ply\n");
  folder.WriteSummary("{}");
}

TEST(RunFolder, AFolderViosfmDidNotMakeIsRefusedUnchanged) {
  const fs::path out = testing::MakeScratchFolder("run_folder_foreign") / "user";
  Write(out / "model" / "cameras.bin", "the user's model");
  Write(out / "points.ply", "the user's points");
  const auto before = Contents(out);
  for (const bool overwrite : {false, true}) {
    PipelineOptions options = Options(out);
    options.overwrite = overwrite;
    const InputError error = testing::ExpectInputError([&] { RunFolder folder(options); });
    EXPECT_EQ(error.path(), out.string());
    EXPECT_NE(std::string(error.what()).find("viosfm did not make it"), std::string::npos);
  }
  EXPECT_EQ(Contents(out), before);
}

TEST(RunFolder, TheManifestListsExactlyWhatTheRunWrote) {
  const fs::path out = testing::MakeScratchFolder("run_folder_manifest") / "out";
  WriteARun(Options(out));
  const FolderManifest manifest = *ReadFolderManifest(out);
  EXPECT_TRUE(manifest.complete);
  EXPECT_TRUE(manifest.created_folder);
  EXPECT_EQ(
      manifest.files,
      (std::set<std::string>{"database.db", "fingerprint.json", "model/cameras.bin", "options.json",
                             "points.ply", "run.log", "summary.json", "vio/states.csv"}));
  EXPECT_EQ(manifest.folders, (std::set<std::string>{"model", "vio"}));
}

TEST(RunFolder, OverwriteRemovesExactlyWhatViosfmWroteWithTheEarlierReportAndExport) {
  const fs::path out = testing::MakeScratchFolder("run_folder_overwrite") / "out";
  WriteARun(Options(out));
  {
    // `viosfm report` and `viosfm export` record what they write.
    ManagedFolder folder(out, RunFolderManifestOptions());
    folder.Claim({"report.html"});
    Write(out / "report.html", "<html>");
    ManagedFolder::Options export_kind;
    export_kind.kind = "export";
    ManagedFolder exported(out / "export", export_kind);
    exported.Claim({"transforms.json"});
    Write(out / "export" / "transforms.json", "{}");
    exported.Finish();
    folder.AddSubfolder("export");
    folder.Finish();
  }
  // The user's files, beside and inside viosfm's folders.
  Write(out / "notes.txt", "mine");
  Write(out / "vio" / "my_plot.svg", "<svg/>");
  Write(out / "export" / "colmap_sparse" / "0" / "images.bin", "COLMAP's, the user's");
  PipelineOptions overwrite = Options(out);
  overwrite.overwrite = true;
  {
    const RunFolder folder(overwrite);
    std::map<std::string, std::string> left = Contents(out);
    left.erase(kManifestFileName);
    left.erase(std::string("export/") + kManifestFileName);
    // This run's log starts afresh, the earlier one removed with the run's
    // outputs, when the run starts to write.
    EXPECT_EQ(left.count("run.log"), 0u);
    folder.MarkIncomplete();
    const std::string log = ReadTextFile(out / kRunLogFileName);
    EXPECT_EQ(log.find("an earlier run's log"), std::string::npos);
    EXPECT_EQ(log.find("== viosfm "), 0u);
    EXPECT_NE(log.find("--overwrite: removed the"), std::string::npos);
    EXPECT_EQ(left, (std::map<std::string, std::string>{
                        {"export/colmap_sparse/0/images.bin", "COLMAP's, the user's"},
                        {"notes.txt", "mine"},
                        {"vio/my_plot.svg", "<svg/>"}}));
  }
}

TEST(RunFolder, AUsersFileUnderOneOfTheRunsNamesIsNeverWrittenOver) {
  const fs::path out = testing::MakeScratchFolder("run_folder_user_file") / "out";
  WriteARun(Options(out));
  Write(out / "eval.json", "the user's");
  PipelineOptions overwrite = Options(out);
  overwrite.overwrite = true;
  const auto before = Contents(out);
  const InputError error = testing::ExpectInputError([&] { RunFolder folder(overwrite); });
  EXPECT_EQ(error.path(), (out / "eval.json").string());
  EXPECT_EQ(Contents(out), before);
}

TEST(RunFolder, ARunReplacingTheModelRemovesTheEarlierReport) {
  const fs::path out = testing::MakeScratchFolder("run_folder_report") / "out";
  WriteARun(Options(out));
  {
    ManagedFolder folder(out, RunFolderManifestOptions());
    folder.Claim({"report.html"});
    Write(out / "report.html", "<html>");
    folder.Finish();
  }
  const RunFolder folder(Options(out));
  EXPECT_TRUE(fs::exists(out / "report.html"));  // nothing changed yet
  folder.MarkIncomplete();
  EXPECT_FALSE(fs::exists(out / "report.html"));
  EXPECT_FALSE(fs::exists(out / "summary.json"));
}

// The sections of run.log: the lines starting with "== viosfm ".
std::vector<std::string> LogSections(const fs::path& out) {
  std::vector<std::string> sections;
  const std::string text = ReadTextFile(out / kRunLogFileName);
  for (size_t at = text.find("== viosfm "); at != std::string::npos;
       at = text.find("== viosfm ", at + 1)) {
    const size_t next = text.find("== viosfm ", at + 1);
    sections.push_back(text.substr(at, next == std::string::npos ? next : next - at));
  }
  return sections;
}

TEST(RunFolder, EveryRunAddsItsSectionToTheLogWrittenAsItGoes) {
  const fs::path out = testing::MakeScratchFolder("run_folder_log") / "out";
  WriteARun(Options(out));
  // A run that stops on an error, and one killed (its log is on disk
  // line by line; nothing closes it).
  // A run refused before it writes leaves the folder as it was.
  const auto before = Contents(out);
  EXPECT_THROW(
      {
        const RunFolder folder(Options(out));
        throw InputError("refused");
      },
      InputError);
  EXPECT_EQ(Contents(out), before);
  EXPECT_THROW(
      {
        const RunFolder folder(Options(out));
        folder.MarkIncomplete();
        VIOSFM_LOG(DEBUG) << "a debug line of the second run";
        throw InputError("stops");
      },
      InputError);
  {
    const RunFolder folder(Options(out));
    folder.MarkIncomplete();
    VIOSFM_LOG(INFO) << "the third run's line";
    const std::vector<std::string> sections = LogSections(out);
    ASSERT_EQ(sections.size(), 3u);
    EXPECT_NE(sections[2].find("the third run's line"), std::string::npos);
  }
  const std::vector<std::string> sections = LogSections(out);
  ASSERT_EQ(sections.size(), 3u);
  EXPECT_NE(sections[0].find("run: complete (summary.json written)"), std::string::npos)
      << sections[0];
  EXPECT_NE(sections[1].find("D "), std::string::npos);
  EXPECT_NE(sections[1].find("a debug line of the second run"), std::string::npos);
  EXPECT_NE(sections[1].find("run: stopped by an error"), std::string::npos);
  EXPECT_NE(sections[2].find("an earlier run's log above"), std::string::npos);
  // The manifest claims the log: a run killed before its end leaves it viosfm's.
  EXPECT_TRUE(ReadFolderManifest(out)->Owns(kRunLogFileName));
}

TEST(RunFolder, RemoveAtomicWriteLeftovers) {
  const fs::path out = testing::MakeScratchFolder("run_folder_leftovers");
  const PipelineOptions options = Options(out);
  for (const char* file : {"summary.json", "notes.txt", "verification/pairs.csv"}) {
    Write(out / file, "x");
  }
  // Leftovers of killed atomic writes, at the top and inside the run's folders.
  for (const char* file : {"summary.json.tmp-123", "model.old-77", "verification/pairs.csv.tmp-5",
                           "bag/mav0/cam0/data/2.png.tmp-9.png", "notes.txt.tmp-1"}) {
    Write(out / file, "x");
  }
  EXPECT_EQ(RemoveAtomicWriteLeftovers(options), 4u);
  EXPECT_FALSE(fs::exists(out / "summary.json.tmp-123"));
  EXPECT_FALSE(fs::exists(out / "verification/pairs.csv.tmp-5"));
  EXPECT_FALSE(fs::exists(out / "bag/mav0/cam0/data/2.png.tmp-9.png"));
  EXPECT_TRUE(fs::exists(out / "notes.txt.tmp-1"));  // not a file of the run
  EXPECT_TRUE(fs::exists(out / "summary.json"));
}

TEST(DatabaseFolder, ACommandWithOtherOptionsIsRefusedAndTheSameOnesRecorded) {
  const fs::path out = testing::MakeScratchFolder("database_folder") / "run";
  WriteARun(Options(out));
  const auto before = Contents(out);
  // `viosfm features --max-features 100` into the run's database: refused,
  // nothing written.
  {
    DatabaseFolder folder(out / "database.db", {});
    const InputError error = testing::ExpectInputError(
        [&] { folder.CheckAndRecord(FingerprintPart(Fingerprint("100"), {"sift."})); });
    EXPECT_EQ(error.path(), (out / "fingerprint.json").string());
    EXPECT_NE(std::string(error.what()).find("sift.max_num_features was '800', is now '100'"),
              std::string::npos)
        << error.what();
  }
  EXPECT_EQ(Contents(out), before);
  // The same options: recorded, the run's fingerprint unchanged.
  {
    DatabaseFolder folder(out / "database.db", {});
    RunFingerprint part = FingerprintPart(Fingerprint("800"), {"sift."});
    folder.CheckAndRecord(part);
    folder.Finish();
  }
  EXPECT_EQ(ReadTextFile(out / "fingerprint.json"), before.at("fingerprint.json"));
  CheckStoredRunData(out, Fingerprint("800"), true);
  // While a run holds the folder, the command is refused.
  const RunFolder run(Options(out));
  EXPECT_NE(testing::InputErrorMessage([&] {
              DatabaseFolder folder(out / "database.db", {});
            }).find("another viosfm command"),
            std::string::npos);
}

TEST(DatabaseFolder, AnotherToolsDatabaseIsWrittenIntoButNeverClaimed) {
  const fs::path folder_path = testing::MakeScratchFolder("database_foreign");
  Write(folder_path / "images" / "a.png", "the user's");
  ColmapDatabase::Open(folder_path / "colmap.db");  // made by "COLMAP"
  {
    DatabaseFolder folder(folder_path / "colmap.db", {});
    folder.CheckAndRecord(Fingerprint("800"));
    folder.Finish();
  }
  const FolderManifest manifest = *ReadFolderManifest(folder_path);
  EXPECT_EQ(manifest.files, std::set<std::string>{"fingerprint.json"});
  EXPECT_EQ(manifest.kind, "database");
  EXPECT_TRUE(ColmapDatabase::ReadViosfmRecordOf(folder_path / "colmap.db").has_value());
  // A run into that folder writes beside the user's files, never over them.
  { RunFolder run(Options(folder_path)); }
  EXPECT_EQ(ReadTextFile(folder_path / "images" / "a.png"), "the user's");
  EXPECT_TRUE(fs::exists(folder_path / "colmap.db"));
}

}  // namespace
}  // namespace viosfm

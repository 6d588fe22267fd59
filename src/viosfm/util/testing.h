// Helpers for tests: where the real datasets are, and scratch folders.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "viosfm/util/errors.h"

namespace viosfm::testing {

// The real-data folder (../shared/data by default; env VIOSFM_DATA_DIR overrides).
std::filesystem::path DataDir();
// DataDir()/name if it exists, otherwise an empty path.
std::filesystem::path FindDataset(const std::string& name);
// Test fixtures committed next to the sources: src/viosfm/<relative>.
std::filesystem::path SourcePath(const std::string& relative);
// A fresh empty folder under the system temp dir, unique per test, removed at exit.
std::filesystem::path MakeScratchFolder(const std::string& name);
// Copies the folder `source` into `target` (created): text files copied,
// .png images hard-linked one by one (copied across file systems), so that
// a test may delete or replace any of them without touching the source (a
// file is replaced by removing it first, never written through). Returns
// `target`.
std::filesystem::path CopyFolderLinkingImages(const std::filesystem::path& source,
                                              const std::filesystem::path& target);

// Writes `text` to `path` (binary, no newline translation); fails the test on error.
void WriteTextFile(const std::filesystem::path& path, const std::string& text);

// Runs `function` and returns the InputError it throws; fails the test if it
// throws none.
template <typename Function>
InputError ExpectInputError(Function function) {
  try {
    function();
  } catch (const InputError& error) {
    return error;
  }
  ADD_FAILURE() << "expected an InputError";
  return InputError("(no error)");
}

// The message of the InputError `function` throws ("" and a test failure if none).
template <typename Function>
std::string InputErrorMessage(Function function) {
  return ExpectInputError(function).what();
}

}  // namespace viosfm::testing

// Skips the current test (GoogleTest) when a dataset folder is absent.
#define VIOSFM_REQUIRE_DATASET(path_var, name)                                               \
  const std::filesystem::path path_var = ::viosfm::testing::FindDataset(name);               \
  if (path_var.empty()) {                                                                    \
    GTEST_SKIP() << "dataset '" << name << "' not found in " << ::viosfm::testing::DataDir() \
                 << " (set VIOSFM_DATA_DIR); skipping";                                      \
  }

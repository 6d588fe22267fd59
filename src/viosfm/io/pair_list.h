// Image pair lists, in the format of COLMAP's `matches_importer
// --match_type pairs`: one pair a line, "image_name1 image_name2", names
// separated by whitespace (so a name cannot contain any). Blank lines and
// lines starting with '#' are skipped.
//
// Reading throws InputError naming the file, the line and what was expected;
// writing is atomic (temporary file, then rename).
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace viosfm {

struct ImageNamePair {
  std::string name1;
  std::string name2;
  int64_t line = 0;  // 1-based line of the file it was read from (0 if not read from a file)
};

struct ImageNamePairList {
  std::filesystem::path path;  // the file read (for error messages)
  std::vector<ImageNamePair> pairs;
};

// Every line must hold exactly two different names. Repeated pairs are kept
// as they are (the pair generator removes duplicates).
ImageNamePairList ReadImagePairList(const std::filesystem::path& path);

// Writes "name1 name2\n" per pair, in the given order. A name that is empty
// or contains whitespace cannot be written in this format: InputError.
void WriteImagePairList(const std::filesystem::path& path, const std::vector<ImageNamePair>& pairs);

}  // namespace viosfm

// Reading the JSON files of run and benchmark folders.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>

namespace viosfm {

// Parses a JSON file. Throws InputError naming the file (and the line where
// parsing stopped) if it cannot be read or is not valid JSON.
nlohmann::json ReadJsonFile(const std::filesystem::path& path);

}  // namespace viosfm

// An image file's size as its header states it, read without decoding the
// pixels, so that an image whose header claims a huge size is refused
// before any memory is allocated for it (io/image_io.h, dataset_checks.h).
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>

namespace viosfm {

struct ImageHeaderSize {
  int64_t width = 0;   // pixels
  int64_t height = 0;  // pixels
};

// The most pixels an image may have (2^28: 16384 x 16384), so that decoding
// one allocates at most 768 MiB (three channels).
inline constexpr int64_t kMaxImagePixels = int64_t{1} << 28;

// The size stated by the header of a PNG, JPEG, PGM/PPM (binary or text)
// or BMP file; nullopt for any other format (or a file too short to be one
// of these). Throws InputError naming the file if it cannot be opened or if
// a header of one of these formats is malformed (a zero size, a JPEG without
// a frame header).
std::optional<ImageHeaderSize> ReadImageHeaderSize(const std::filesystem::path& path);

}  // namespace viosfm

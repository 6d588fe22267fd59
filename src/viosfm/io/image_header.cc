#include "viosfm/io/image_header.h"

#include <array>
#include <cctype>
#include <fstream>
#include <string>
#include <vector>

#include "viosfm/util/errors.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;

// The header bytes read at most (a JPEG's frame header follows its EXIF and
// colour profile segments, which are rarely longer).
constexpr size_t kMaxHeaderBytes = 1 << 20;

uint32_t BigEndian32(const unsigned char* bytes) {
  return (uint32_t{bytes[0]} << 24) | (uint32_t{bytes[1]} << 16) | (uint32_t{bytes[2]} << 8) |
         uint32_t{bytes[3]};
}
uint32_t BigEndian16(const unsigned char* bytes) {
  return (uint32_t{bytes[0]} << 8) | uint32_t{bytes[1]};
}
int64_t LittleEndianSigned32(const unsigned char* bytes) {
  const uint32_t value = uint32_t{bytes[0]} | (uint32_t{bytes[1]} << 8) |
                         (uint32_t{bytes[2]} << 16) | (uint32_t{bytes[3]} << 24);
  return static_cast<int32_t>(value);
}

class HeaderReader {
 public:
  explicit HeaderReader(const fs::path& path) : path_(path), stream_(path, std::ios::binary) {
    if (!stream_) throw InputError(path.string(), 0, "cannot open the image for reading");
  }
  // Bytes [0, size) of the file (fewer at its end).
  const std::vector<unsigned char>& Prefix(size_t size) {
    if (size > bytes_.size() && !at_end_) {
      const size_t old_size = bytes_.size();
      bytes_.resize(size);
      stream_.read(reinterpret_cast<char*>(bytes_.data() + old_size),
                   static_cast<std::streamsize>(size - old_size));
      bytes_.resize(old_size + static_cast<size_t>(stream_.gcount()));
      if (bytes_.size() < size) at_end_ = true;
      if (stream_.bad()) throw InputError(path_.string(), 0, "cannot read the image's header");
    }
    return bytes_;
  }
  [[noreturn]] void Fail(const std::string& what) const {
    throw InputError(path_.string(), 0, what);
  }

 private:
  fs::path path_;
  std::ifstream stream_;
  std::vector<unsigned char> bytes_;
  bool at_end_ = false;
};

ImageHeaderSize Checked(HeaderReader& reader, int64_t width, int64_t height, const char* format) {
  if (width <= 0 || height <= 0) {
    reader.Fail(std::string("the ") + format + " header states a size of " + std::to_string(width) +
                "x" + std::to_string(height) + " pixels");
  }
  return {width, height};
}

std::optional<ImageHeaderSize> PngSize(HeaderReader& reader) {
  const std::vector<unsigned char>& bytes = reader.Prefix(24);
  if (bytes.size() < 24 || std::string(bytes.begin() + 12, bytes.begin() + 16) != "IHDR") {
    reader.Fail("a PNG file without its IHDR header");
  }
  return Checked(reader, BigEndian32(&bytes[16]), BigEndian32(&bytes[20]), "PNG");
}

std::optional<ImageHeaderSize> JpegSize(HeaderReader& reader) {
  size_t position = 2;
  while (true) {
    const std::vector<unsigned char>& bytes =
        reader.Prefix(std::min(position + 9, kMaxHeaderBytes));
    if (position + 4 > bytes.size()) {
      reader.Fail("a JPEG file without a frame header (SOF) in its first " +
                  std::to_string(kMaxHeaderBytes) + " bytes");
    }
    if (bytes[position] != 0xFF) reader.Fail("a JPEG file with a malformed marker");
    const unsigned char marker = bytes[position + 1];
    if (marker == 0xFF) {  // fill byte
      ++position;
      continue;
    }
    // Markers without a length: TEM, RSTn, SOI.
    if (marker == 0x01 || (marker >= 0xD0 && marker <= 0xD8)) {
      position += 2;
      continue;
    }
    if (marker == 0xD9 || marker == 0xDA) reader.Fail("a JPEG file without a frame header (SOF)");
    const size_t length = BigEndian16(&bytes[position + 2]);
    if (length < 2) reader.Fail("a JPEG file with a malformed segment length");
    const bool frame =
        marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
    if (frame) {
      if (position + 9 > bytes.size()) reader.Fail("a truncated JPEG frame header");
      return Checked(reader, BigEndian16(&bytes[position + 7]), BigEndian16(&bytes[position + 5]),
                     "JPEG");
    }
    position += 2 + length;
  }
}

// The next whitespace-separated number of a PNM header (comments skipped),
// within its first kMaxPnmHeaderBytes.
constexpr size_t kMaxPnmHeaderBytes = 4096;
int64_t PnmNumber(HeaderReader& reader, size_t* position) {
  const std::vector<unsigned char>& bytes = reader.Prefix(kMaxPnmHeaderBytes);
  while (*position < bytes.size() && (std::isspace(bytes[*position]) || bytes[*position] == '#')) {
    if (bytes[*position] == '#') {
      while (*position < bytes.size() && bytes[*position] != '\n') ++*position;
    } else {
      ++*position;
    }
  }
  int64_t value = 0;
  int digits = 0;
  while (*position < bytes.size() && std::isdigit(bytes[*position])) {
    if (++digits > 12) reader.Fail("a PGM/PPM header with an oversized number");
    value = value * 10 + (bytes[*position] - '0');
    ++*position;
  }
  if (digits == 0) reader.Fail("a PGM/PPM header without its width and height");
  return value;
}

}  // namespace

std::optional<ImageHeaderSize> ReadImageHeaderSize(const fs::path& path) {
  HeaderReader reader(path);
  const std::vector<unsigned char> start = reader.Prefix(8);
  static constexpr std::array<unsigned char, 8> kPng = {0x89, 'P',  'N',  'G',
                                                        '\r', '\n', 0x1A, '\n'};
  if (start.size() >= 8 && std::equal(kPng.begin(), kPng.end(), start.begin())) {
    return PngSize(reader);
  }
  if (start.size() >= 3 && start[0] == 0xFF && start[1] == 0xD8 && start[2] == 0xFF) {
    return JpegSize(reader);
  }
  if (start.size() >= 3 && start[0] == 'P' && start[1] >= '1' && start[1] <= '6' &&
      std::isspace(start[2])) {
    size_t position = 2;
    const int64_t width = PnmNumber(reader, &position);
    const int64_t height = PnmNumber(reader, &position);
    return Checked(reader, width, height, "PGM/PPM");
  }
  if (start.size() >= 2 && start[0] == 'B' && start[1] == 'M') {
    const std::vector<unsigned char>& bytes = reader.Prefix(26);
    if (bytes.size() < 26) reader.Fail("a truncated BMP header");
    const int64_t height = LittleEndianSigned32(&bytes[22]);
    return Checked(reader, LittleEndianSigned32(&bytes[18]), height < 0 ? -height : height, "BMP");
  }
  return std::nullopt;
}

}  // namespace viosfm

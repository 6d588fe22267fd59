#include "viosfm/io/compression.h"

#include <lz4frame.h>
#include <zstd.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <memory>

#include "viosfm/util/errors.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;

// The first allocation allows a compression ratio of 16; the buffer then
// doubles, never beyond `limit`.
size_t InitialOutputSize(size_t compressed_size, uint64_t limit) {
  constexpr uint64_t kMinInitial = uint64_t{1} << 20;
  return static_cast<size_t>(
      std::min<uint64_t>(limit, std::max<uint64_t>(kMinInitial, 16 * uint64_t{compressed_size})));
}

bool GrowOutput(std::vector<uint8_t>& out, uint64_t limit) {
  if (out.size() >= limit) return false;
  out.resize(static_cast<size_t>(std::min<uint64_t>(limit, 2 * uint64_t{out.size()})));
  return true;
}

struct ZstdDContextDeleter {
  void operator()(ZSTD_DCtx* context) const { ZSTD_freeDCtx(context); }
};
struct ZstdCContextDeleter {
  void operator()(ZSTD_CCtx* context) const { ZSTD_freeCCtx(context); }
};

}  // namespace

bool StartsWithZstdFrame(std::span<const uint8_t> data) {
  return data.size() >= 4 && std::memcmp(data.data(), kZstdFrameMagic, 4) == 0;
}

std::vector<uint8_t> DecompressZstd(std::span<const uint8_t> data,
                                    std::optional<uint64_t> stated_size, uint64_t max_size,
                                    const std::string& where) {
  const uint64_t limit = stated_size ? *stated_size : max_size;
  const auto fail = [&](const std::string& what) -> void {
    throw InputError(where + ": zstd data " + what);
  };
  std::unique_ptr<ZSTD_DCtx, ZstdDContextDeleter> context(ZSTD_createDCtx());
  if (!context) fail("cannot be decompressed (no zstd context)");
  std::vector<uint8_t> out(InitialOutputSize(data.size(), limit));
  ZSTD_inBuffer in{data.data(), data.size(), 0};
  size_t produced = 0;
  while (true) {
    if (produced == out.size() && !GrowOutput(out, limit)) {
      // Full at the limit: any further byte is one too many.
      uint8_t extra = 0;
      ZSTD_outBuffer probe{&extra, 1, 0};
      const size_t status = ZSTD_decompressStream(context.get(), &probe, &in);
      if (ZSTD_isError(status)) fail(std::string("is corrupt (") + ZSTD_getErrorName(status) + ")");
      if (probe.pos > 0) {
        fail("decompresses to more than the " + std::to_string(limit) + " bytes " +
             (stated_size ? "its header states" : "allowed"));
      }
      if (status == 0 && in.pos == in.size) break;
      if (in.pos == in.size) fail("ends inside a frame (truncated)");
      continue;
    }
    ZSTD_outBuffer buffer{out.data(), out.size(), produced};
    const size_t status = ZSTD_decompressStream(context.get(), &buffer, &in);
    if (ZSTD_isError(status)) fail(std::string("is corrupt (") + ZSTD_getErrorName(status) + ")");
    produced = buffer.pos;
    if (status == 0 && in.pos == in.size) break;  // the last frame is complete
    if (in.pos == in.size && buffer.pos < buffer.size) {
      fail("ends inside a frame after " + std::to_string(data.size()) + " bytes (truncated)");
    }
  }
  out.resize(produced);
  if (stated_size && produced != *stated_size) {
    fail("decompresses to " + std::to_string(produced) + " bytes, its header states " +
         std::to_string(*stated_size));
  }
  return out;
}

std::vector<uint8_t> DecompressLz4Frame(std::span<const uint8_t> data, uint64_t stated_size,
                                        const std::string& where) {
  std::vector<uint8_t> out(InitialOutputSize(data.size(), stated_size));
  LZ4F_dctx* context = nullptr;
  if (LZ4F_isError(LZ4F_createDecompressionContext(&context, LZ4F_VERSION))) {
    throw InputError(where + ": cannot create an lz4 decompression context");
  }
  size_t in_offset = 0;
  size_t out_offset = 0;
  size_t status = 1;
  bool overflow = false;
  // With the input consumed, a call with no input flushes what the decoder
  // still holds; the loop ends at the frame's end or when nothing moves.
  while (status != 0) {
    if (out_offset == out.size() && !GrowOutput(out, stated_size)) {
      // Full at the stated size: a frame that is not finished would give more.
      uint8_t extra = 0;
      size_t extra_size = 1;
      size_t in_size = data.size() - in_offset;
      status =
          LZ4F_decompress(context, &extra, &extra_size, data.data() + in_offset, &in_size, nullptr);
      in_offset += in_size;
      if (!LZ4F_isError(status) && extra_size > 0) overflow = true;
      if (LZ4F_isError(status) || overflow || (in_size == 0 && extra_size == 0)) break;
      continue;
    }
    size_t in_size = data.size() - in_offset;
    size_t out_size = out.size() - out_offset;
    status = LZ4F_decompress(context, out.data() + out_offset, &out_size, data.data() + in_offset,
                             &in_size, nullptr);
    if (LZ4F_isError(status)) break;
    in_offset += in_size;
    out_offset += out_size;
    if (in_size == 0 && out_size == 0) break;
  }
  LZ4F_freeDecompressionContext(context);
  if (LZ4F_isError(status)) {
    throw InputError(where + ": lz4 data cannot be decompressed (" +
                     std::string(LZ4F_getErrorName(status)) + ")");
  }
  if (overflow || out_offset != stated_size || status != 0) {
    throw InputError(
        where + ": lz4 data decompresses to " +
        (overflow ? "more than " + std::to_string(stated_size) : std::to_string(out_offset)) +
        " bytes" + (status != 0 && !overflow ? " and ends inside its frame" : "") +
        ", its header states " + std::to_string(stated_size));
  }
  out.resize(out_offset);
  return out;
}

std::vector<uint8_t> CompressZstd(std::span<const uint8_t> data, int level) {
  std::vector<uint8_t> out(ZSTD_compressBound(data.size()));
  const size_t size = ZSTD_compress(out.data(), out.size(), data.data(), data.size(), level);
  VIOSFM_CHECK(!ZSTD_isError(size)) << "zstd compression failed: " << ZSTD_getErrorName(size);
  out.resize(size);
  return out;
}

std::vector<uint8_t> CompressLz4Frame(std::span<const uint8_t> data) {
  LZ4F_preferences_t preferences = LZ4F_INIT_PREFERENCES;
  preferences.frameInfo.blockMode = LZ4F_blockIndependent;
  preferences.frameInfo.contentChecksumFlag = LZ4F_contentChecksumEnabled;
  preferences.frameInfo.blockSizeID = LZ4F_max4MB;
  std::vector<uint8_t> out(LZ4F_compressFrameBound(data.size(), &preferences));
  const size_t size =
      LZ4F_compressFrame(out.data(), out.size(), data.data(), data.size(), &preferences);
  VIOSFM_CHECK(!LZ4F_isError(size)) << "lz4 compression failed: " << LZ4F_getErrorName(size);
  out.resize(size);
  return out;
}

void DecompressZstdFile(const fs::path& in, const fs::path& out) {
  std::ifstream input(in, std::ios::binary);
  if (!input) throw InputError(in.string(), 0, "cannot open the file");
  std::ofstream output(out, std::ios::binary | std::ios::trunc);
  if (!output) throw InputError(out.string(), 0, "cannot write the file (is the folder writable?)");
  const auto fail = [&](const std::string& what) {
    output.close();
    std::error_code ignored;
    fs::remove(out, ignored);
    throw InputError(in.string(), 0, what);
  };
  std::unique_ptr<ZSTD_DCtx, ZstdDContextDeleter> context(ZSTD_createDCtx());
  std::vector<uint8_t> in_buffer(ZSTD_DStreamInSize());
  std::vector<uint8_t> out_buffer(ZSTD_DStreamOutSize());
  size_t status = 1;
  uint64_t consumed = 0;
  bool any = false;
  while (true) {
    input.read(reinterpret_cast<char*>(in_buffer.data()),
               static_cast<std::streamsize>(in_buffer.size()));
    const size_t read = static_cast<size_t>(input.gcount());
    if (read == 0) break;
    if (!any && !StartsWithZstdFrame(std::span<const uint8_t>(in_buffer.data(), read))) {
      fail("not zstd data (expected the frame magic 28 b5 2f fd at byte 0)");
    }
    any = true;
    ZSTD_inBuffer buffer_in{in_buffer.data(), read, 0};
    while (buffer_in.pos < buffer_in.size) {
      ZSTD_outBuffer buffer_out{out_buffer.data(), out_buffer.size(), 0};
      status = ZSTD_decompressStream(context.get(), &buffer_out, &buffer_in);
      if (ZSTD_isError(status)) {
        fail("zstd data corrupt near byte offset " + std::to_string(consumed + buffer_in.pos) +
             " (" + ZSTD_getErrorName(status) + ")");
      }
      output.write(reinterpret_cast<const char*>(out_buffer.data()),
                   static_cast<std::streamsize>(buffer_out.pos));
    }
    consumed += read;
  }
  // Flush what the decoder still holds.
  while (any && status != 0) {
    ZSTD_inBuffer buffer_in{nullptr, 0, 0};
    ZSTD_outBuffer buffer_out{out_buffer.data(), out_buffer.size(), 0};
    status = ZSTD_decompressStream(context.get(), &buffer_out, &buffer_in);
    if (ZSTD_isError(status) || buffer_out.pos == 0) break;
    output.write(reinterpret_cast<const char*>(out_buffer.data()),
                 static_cast<std::streamsize>(buffer_out.pos));
  }
  if (!any) fail("empty file, expected zstd data");
  if (status != 0) fail("the zstd data ends inside a frame (the file is truncated)");
  output.close();
  if (!output) fail("cannot write " + out.string() + " (disk full?)");
}

void CompressZstdFile(const fs::path& in, const fs::path& out, int level) {
  std::ifstream input(in, std::ios::binary);
  if (!input) throw InputError(in.string(), 0, "cannot open the file");
  std::ofstream output(out, std::ios::binary | std::ios::trunc);
  if (!output) throw InputError(out.string(), 0, "cannot write the file (is the folder writable?)");
  std::unique_ptr<ZSTD_CCtx, ZstdCContextDeleter> context(ZSTD_createCCtx());
  ZSTD_CCtx_setParameter(context.get(), ZSTD_c_compressionLevel, level);
  std::vector<uint8_t> in_buffer(ZSTD_CStreamInSize());
  std::vector<uint8_t> out_buffer(ZSTD_CStreamOutSize());
  while (true) {
    input.read(reinterpret_cast<char*>(in_buffer.data()),
               static_cast<std::streamsize>(in_buffer.size()));
    const size_t read = static_cast<size_t>(input.gcount());
    const bool last = read < in_buffer.size();
    ZSTD_inBuffer buffer_in{in_buffer.data(), read, 0};
    bool finished = false;
    while (!finished) {
      ZSTD_outBuffer buffer_out{out_buffer.data(), out_buffer.size(), 0};
      const size_t remaining = ZSTD_compressStream2(context.get(), &buffer_out, &buffer_in,
                                                    last ? ZSTD_e_end : ZSTD_e_continue);
      VIOSFM_CHECK(!ZSTD_isError(remaining)) << "zstd compression failed";
      output.write(reinterpret_cast<const char*>(out_buffer.data()),
                   static_cast<std::streamsize>(buffer_out.pos));
      finished = last ? remaining == 0 : buffer_in.pos == buffer_in.size;
    }
    if (last) break;
  }
  output.close();
  if (!output) throw InputError(out.string(), 0, "cannot write the file (disk full?)");
}

}  // namespace viosfm

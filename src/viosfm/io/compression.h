// The zstd and LZ4 frame formats as ROS 2 bags use them: MCAP chunks (zstd
// or lz4), rosbag2's per-message and per-file compression (zstd).
//
// Decompression never trusts a stated size: the output grows with what the
// data actually gives, up to the stated size (or `max_size` when none is
// stated), so a corrupt or hostile header costs memory only in proportion to
// the data behind it. Every failure throws InputError("<where>: <what>").
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace viosfm {

// The first four bytes of every zstd frame (28 b5 2f fd).
inline constexpr uint8_t kZstdFrameMagic[4] = {0x28, 0xb5, 0x2f, 0xfd};

// Whether `data` begins with kZstdFrameMagic.
bool StartsWithZstdFrame(std::span<const uint8_t> data);

// Decompresses one or more zstd frames. With `stated_size` the output must
// have exactly that many bytes; without it, at most `max_size`.
std::vector<uint8_t> DecompressZstd(std::span<const uint8_t> data,
                                    std::optional<uint64_t> stated_size, uint64_t max_size,
                                    const std::string& where);

// Decompresses an LZ4 frame (the LZ4 frame format, not a raw block) into
// exactly `stated_size` bytes.
std::vector<uint8_t> DecompressLz4Frame(std::span<const uint8_t> data, uint64_t stated_size,
                                        const std::string& where);

// zstd frame of `data` (level 1 to 19; rosbag2 and MCAP writers use 1 to 3).
std::vector<uint8_t> CompressZstd(std::span<const uint8_t> data, int level = 3);

// LZ4 frame of `data` (independent blocks, content checksum).
std::vector<uint8_t> CompressLz4Frame(std::span<const uint8_t> data);

// Streams the zstd-compressed file `in` into `out` (created or truncated),
// as rosbag2's per-file compression needs (a .db3 must be a file for
// SQLite). Throws InputError naming `in` when it is not zstd data or is
// truncated; a partial `out` is removed.
void DecompressZstdFile(const std::filesystem::path& in, const std::filesystem::path& out);

// Streams `in` into the zstd-compressed file `out`.
void CompressZstdFile(const std::filesystem::path& in, const std::filesystem::path& out,
                      int level = 3);

}  // namespace viosfm

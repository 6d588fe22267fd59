// libFuzzer target: MCAP files (io/mcap.h) read as ROS 2 bags
// (io/rosbag2.h), and the CDR messages of known types in them. The input is
// the .mcap file.
#include "fuzz_ros2_messages.h"
#include "fuzz_util.h"
#include "viosfm/io/compression.h"
#include "viosfm/io/mcap.h"
#include "viosfm/io/rosbag2.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace viosfm;
  using namespace viosfm::fuzz;
  const std::filesystem::path path = ScratchFolder() / "fuzz.mcap";
  WriteBytes(path, AsText(data, size));
  AcceptsInput([&] {
    McapReader reader(path);
    uint64_t counted = 0;
    for (const McapChannel& channel : reader.channels()) counted += channel.num_messages;
    uint64_t read = 0;
    reader.ReadMessages([](const McapChannel&) { return true; },
                        [&](const McapMessage& message) {
                          Require(message.channel != nullptr, "a message has a channel");
                          ++read;
                          ReadCdrMessage(message.channel->schema_name, message.data,
                                         "fuzz.mcap: " + message.location);
                        });
    // Without a summary the counts come from the same scan.
    if (!reader.has_summary()) Require(read == counted, "the counted messages are read");
  });
  // A zstd file would be read as a per-file-compressed bag: decompressed to
  // a file, which a fuzzer's tiny input can make gigabytes long.
  if (StartsWithZstdFrame(std::span<const uint8_t>(data, size))) return 0;
  AcceptsInput([&] {
    Rosbag2Reader reader(path);
    reader.ReadMessages([](const BagConnection&) { return true; },
                        [&](const BagMessage& message) {
                          ReadCdrMessage(message.connection->type, message.data, message.location);
                        });
  });
  return 0;
}

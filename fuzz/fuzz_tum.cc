// libFuzzer target: the TUM trajectory reader (io/trajectory_io.h), and the
// round trip read -> write -> read on what it accepts.
#include "fuzz_trajectory_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  viosfm::fuzz::TrajectoryRoundTrip(viosfm::fuzz::AsText(data, size),
                                    viosfm::TrajectoryFormat::kTum, 0.0);
  return 0;
}

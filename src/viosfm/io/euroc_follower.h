// A EuRoC folder (euroc.h) while a recorder writes it: `viosfm run
// --follow` reads its rows as they are appended.
//
// What the recorder does: the camera's and the IMU's sensor.yaml first (the
// camera's with its rate_hz); then each image file written whole (under
// another name, renamed when complete) before its row is appended to
// cam0/data.csv, and the IMU's rows appended to imu0/data.csv, each line
// ended by its newline. Rows are parsed and checked as ReadEurocDataset
// parses them (InputError naming the file and the line). A last line without
// its newline is waited for; so is an image row whose file is not there yet,
// with the rows after it. Nothing is ever read twice, and a file that
// shrinks (rewritten, not appended to) is an InputError.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "viosfm/io/euroc.h"
#include "viosfm/scene/sequence.h"

namespace viosfm {

class EurocFollower {
 public:
  // Reads the calibration now (InputError as ReadEurocDataset throws it,
  // and for a camera sensor.yaml without rate_hz); the data.csv files may
  // not exist yet.
  explicit EurocFollower(const std::filesystem::path& root, const EurocReadOptions& options = {});

  // The recording's rig (as ReadEurocDataset reads it) and root; no images
  // and no IMU samples.
  const Sequence& header() const { return header_; }
  // The header to change: calibration files replace its rig (io/kalibr.h
  // ApplyCalibrationFiles).
  Sequence* mutable_header() { return &header_; }

  struct Rows {
    std::vector<SequenceImage> images;
    std::vector<ImuSample> imu;
    bool empty() const { return images.empty() && imu.empty(); }
  };
  // The complete rows appended since the last call.
  Rows Poll();
  // The end of the recording: a last line without its newline is read as a
  // row; an image row whose file is still missing is an InputError.
  Rows Finish();
  // The recording's ground truth, if it holds one by now (as
  // ReadEurocDataset reads it).
  std::vector<GroundTruthState> ReadGroundTruth() const;

 private:
  // One appended-to file: how far it was read, and what is left of its
  // last, unfinished line.
  struct Tail {
    std::filesystem::path path;
    std::uintmax_t offset = 0;
    int64_t line = 0;
    std::string partial;
    std::optional<timestamp_ns_t> previous;
    int64_t previous_line = 0;
  };
  // The complete lines appended to `tail` (with `ended`, the unfinished one
  // too), each with its line number; data lines only.
  std::vector<std::pair<int64_t, std::string>> NewLines(Tail* tail, bool ended);
  Rows Read(bool ended);

  Sequence header_;
  EurocReadOptions options_;
  std::filesystem::path mav0_;
  Rigid3d body_from_imu_;
  std::filesystem::path image_folder_;
  Tail images_;
  Tail imu_;
  // Image rows read, waiting for their files.
  std::vector<std::pair<int64_t, SequenceImage>> waiting_images_;
};

}  // namespace viosfm

#include "viosfm/io/euroc_replay.h"

#include <chrono>
#include <cmath>
#include <fstream>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include "viosfm/io/euroc.h"
#include "viosfm/io/text_lines.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/logging.h"
#include "viosfm/util/string_util.h"
#include "viosfm/util/timestamp.h"

namespace viosfm {

namespace fs = std::filesystem;

namespace {

// A data line of a list and its stamp (its first field).
struct Row {
  timestamp_ns_t stamp_ns = 0;
  std::string text;
};

// The header lines ('#') and the data rows of a EuRoC list.
void ReadRows(const fs::path& csv, std::string* header, std::vector<Row>* rows) {
  std::ifstream in(csv);
  if (!in) throw InputError(csv.string(), 0, "cannot be read");
  std::string line;
  int64_t number = 0;
  while (std::getline(in, line)) {
    ++number;
    const std::string_view text = Trim(line);
    if (text.empty()) continue;
    if (text.front() == '#') {
      if (rows->empty()) *header += std::string(text) + "\n";
      continue;
    }
    const std::vector<std::string_view> fields = SplitFields(text, ",");
    const std::optional<int64_t> stamp = ParseInt(fields.front());
    if (!stamp) throw InputError(csv.string(), number, "expected a timestamp in column 1");
    rows->push_back({*stamp, std::string(text)});
  }
}

void Append(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::app | std::ios::binary);
  out << text;
  out.flush();
  if (!out) throw InputError(path.string(), 0, "cannot be written");
}

}  // namespace

void ReplayEurocRecording(const fs::path& source, const fs::path& target,
                          const EurocReplayOptions& options) {
  if (!(options.speed >= 0.0) || !std::isfinite(options.speed)) {
    throw InputError("replay: speed must be >= 0");
  }
  if (!(options.skip_s >= 0.0)) throw InputError("replay: skip must be >= 0 s");
  if (!fs::is_directory(source)) throw InputError(source.string(), 0, "dataset folder not found");
  const fs::path mav0 = EurocMav0Folder(source, EurocReadOptions());
  const fs::path out = target / "mav0";
  if (fs::exists(out / "cam0" / "data.csv") || fs::exists(out / "imu0" / "data.csv")) {
    throw InputError(target.string(), 0, "holds a recording already");
  }
  std::string image_header, imu_header;
  std::vector<Row> images, imu;
  ReadRows(mav0 / "cam0" / "data.csv", &image_header, &images);
  ReadRows(mav0 / "imu0" / "data.csv", &imu_header, &imu);
  if (images.empty() || imu.empty()) {
    throw InputError(mav0.string(), 0, "replay: a recording with images and IMU is replayed");
  }
  fs::create_directories(out / "cam0" / "data");
  fs::create_directories(out / "imu0");
  fs::copy_file(mav0 / "cam0" / "sensor.yaml", out / "cam0" / "sensor.yaml",
                fs::copy_options::overwrite_existing);
  fs::copy_file(mav0 / "imu0" / "sensor.yaml", out / "imu0" / "sensor.yaml",
                fs::copy_options::overwrite_existing);
  Append(out / "cam0" / "data.csv", image_header);
  Append(out / "imu0" / "data.csv", imu_header);

  const timestamp_ns_t first_ns =
      std::min(images.front().stamp_ns, imu.front().stamp_ns) + SecondsToNs(options.skip_s);
  const auto start = std::chrono::steady_clock::now();
  const auto wait_until = [&](timestamp_ns_t stamp_ns) {
    if (options.speed <= 0.0) return;
    const double due_s = NsToSeconds(stamp_ns - first_ns) / options.speed;
    std::this_thread::sleep_until(start + std::chrono::duration<double>(due_s));
  };
  // The stamp whose time has come.
  const auto due_ns = [&]() -> timestamp_ns_t {
    if (options.speed <= 0.0) return std::numeric_limits<timestamp_ns_t>::max();
    const double elapsed_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return first_ns + SecondsToNs(elapsed_s * options.speed);
  };
  size_t next_imu = 0;
  size_t num_images = 0;
  for (const Row& image : images) {
    if (image.stamp_ns < first_ns) continue;
    // The IMU rows up to the image, each once its time has come (those
    // already due in one write).
    while (next_imu < imu.size() && imu[next_imu].stamp_ns <= image.stamp_ns) {
      if (imu[next_imu].stamp_ns < first_ns) {
        ++next_imu;
        continue;
      }
      wait_until(imu[next_imu].stamp_ns);
      const timestamp_ns_t now_ns = due_ns();
      std::string rows;
      while (next_imu < imu.size() && imu[next_imu].stamp_ns <= image.stamp_ns &&
             imu[next_imu].stamp_ns <= now_ns) {
        rows += imu[next_imu++].text + "\n";
      }
      Append(out / "imu0" / "data.csv", rows);
    }
    wait_until(image.stamp_ns);
    const std::string name = std::string(SplitFields(image.text, ",").back());
    const fs::path written = out / "cam0" / "data" / name;
    const fs::path partial = written.string() + ".part";
    fs::create_directories(written.parent_path());
    fs::copy_file(mav0 / "cam0" / "data" / name, partial, fs::copy_options::overwrite_existing);
    fs::rename(partial, written);
    Append(out / "cam0" / "data.csv", image.text + "\n");
    ++num_images;
  }
  std::string rest;
  for (; next_imu < imu.size(); ++next_imu) {
    if (imu[next_imu].stamp_ns >= first_ns) rest += imu[next_imu].text + "\n";
  }
  if (!rest.empty()) {
    wait_until(imu.back().stamp_ns);
    Append(out / "imu0" / "data.csv", rest);
  }
  const fs::path ground_truth = mav0 / "state_groundtruth_estimate0";
  if (fs::is_directory(ground_truth)) {
    fs::copy(ground_truth, out / "state_groundtruth_estimate0",
             fs::copy_options::recursive | fs::copy_options::overwrite_existing);
  }
  VIOSFM_LOG(INFO) << "replay: " << num_images << " images and " << imu.size() << " IMU rows of "
                   << source.string() << " written into " << target.string();
}

}  // namespace viosfm

// libFuzzer target: the EuRoC ASL CSV files (io/euroc.h). The input is three
// files separated by kFileSeparator: cam0/data.csv, imu0/data.csv and
// state_groundtruth_estimate0/data.csv. Each is read by its own reader, then
// the whole dataset (fixed sensor.yaml files) by ReadEurocDataset, which adds
// the frame-rate estimate and the IMU coverage check.
#include "fuzz_util.h"
#include "viosfm/io/euroc.h"

namespace {

namespace fs = std::filesystem;

const fs::path& DatasetRoot() {
  static const fs::path root = [] {
    const fs::path mav0 = viosfm::fuzz::ScratchFolder() / "dataset" / "mav0";
    fs::create_directories(mav0 / "cam0" / "data");
    fs::create_directories(mav0 / "imu0");
    fs::create_directories(mav0 / "state_groundtruth_estimate0");
    viosfm::fuzz::WriteBytes(mav0 / "cam0" / "sensor.yaml",
                             "%YAML:1.0\n"
                             "T_BS: {cols: 4, rows: 4, data: [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, "
                             "0, 0, 0, 1]}\n"
                             "resolution: [752, 480]\ncamera_model: pinhole\n"
                             "intrinsics: [458.6, 457.3, 367.2, 248.4]\n"
                             "distortion_model: radial-tangential\n"
                             "distortion_coefficients: [-0.28, 0.07, 0.0002, 1.8e-05]\n");
    viosfm::fuzz::WriteBytes(mav0 / "imu0" / "sensor.yaml",
                             "%YAML:1.0\nrate_hz: 200\ngyroscope_noise_density: 1.6968e-04\n"
                             "gyroscope_random_walk: 1.9393e-05\n"
                             "accelerometer_noise_density: 2.0e-3\n"
                             "accelerometer_random_walk: 3.0e-3\n");
    return mav0.parent_path();
  }();
  return root;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace viosfm;
  using namespace viosfm::fuzz;
  const std::vector<std::string_view> files = SplitFiles(AsText(data, size), 3);
  const fs::path mav0 = DatasetRoot() / "mav0";
  const fs::path images_csv = mav0 / "cam0" / "data.csv";
  const fs::path imu_csv = mav0 / "imu0" / "data.csv";
  const fs::path ground_truth_csv = mav0 / "state_groundtruth_estimate0" / "data.csv";
  WriteBytes(images_csv, files[0]);
  WriteBytes(imu_csv, files[1]);
  WriteBytes(ground_truth_csv, files[2]);

  AcceptsInput([&] { ReadEurocImageList(images_csv, mav0 / "cam0" / "data", false); });
  AcceptsInput([&] { ReadEurocImu(imu_csv); });
  AcceptsInput([&] { ReadEurocGroundTruth(ground_truth_csv); });
  const GroundTruthReadResult ground_truth = TryReadEurocGroundTruth(ground_truth_csv);
  Require(ground_truth.ok() != ground_truth.states.empty(),
          "TryReadEurocGroundTruth gives states or an error");

  EurocReadOptions options;
  options.check_images_exist = false;
  Sequence sequence;
  if (AcceptsInput([&] { sequence = ReadEurocDataset(DatasetRoot(), options); })) {
    Require(!sequence.images.empty() && !sequence.imu.empty(), "a read dataset has images and IMU");
    Require(sequence.rig.camera_rate_hz >= 0.0, "the frame rate is not negative");
  }
  options.strict_ground_truth = true;
  options.require_imu_coverage = true;
  AcceptsInput([&] { ReadEurocDataset(DatasetRoot(), options); });
  return 0;
}

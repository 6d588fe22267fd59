// libFuzzer target: Kalibr calibration files (io/kalibr.h). The input is a
// camchain.yaml and an IMU yaml separated by kFileSeparator (an empty second
// part: no IMU file); what is accepted is applied to a sequence.
#include "fuzz_util.h"
#include "viosfm/io/kalibr.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace viosfm;
  using namespace viosfm::fuzz;
  const std::vector<std::string_view> files = SplitFiles(AsText(data, size), 2);
  const std::filesystem::path camchain = ScratchFolder() / "camchain.yaml";
  const std::filesystem::path imu = ScratchFolder() / "imu.yaml";
  WriteBytes(camchain, files[0]);
  WriteBytes(imu, files[1]);
  AcceptsInput([&] { ReadKalibrImuYaml(imu); });
  KalibrCalibration calibration;
  if (AcceptsInput([&] {
        calibration = ReadKalibrCalibration(camchain, files[1].empty() ? "" : imu.string());
      })) {
    Sequence sequence;
    sequence.rig.camera.camera_id = 1;
    sequence.rig.camera.model_id = CameraModelId::kPinhole;
    sequence.rig.camera.width = 640;
    sequence.rig.camera.height = 480;
    sequence.rig.camera.params = {500, 500, 320, 240};
    if (AcceptsInput([&] { ApplyCalibration(calibration, &sequence); })) {
      Require(sequence.rig.Validate().empty(), "an applied calibration gives a valid rig");
      // The time offset is bounded, so moving a stamp cannot overflow.
      Require(sequence.rig.CamToImuTime(0) == calibration.cam_time_offset_ns,
              "CamToImuTime adds the offset");
    }
  }
  return 0;
}

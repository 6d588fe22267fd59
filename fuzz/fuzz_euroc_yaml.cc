// libFuzzer target: EuRoC/Kalibr sensor.yaml files (io/euroc.h): the camera
// reader, the IMU reader and the T_BS reader on the same input.
#include "fuzz_util.h"
#include "viosfm/io/euroc.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace viosfm;
  using namespace viosfm::fuzz;
  const std::filesystem::path path = ScratchFolder() / "sensor.yaml";
  WriteBytes(path, AsText(data, size));
  EurocCameraCalibration camera;
  if (AcceptsInput([&] { camera = ReadEurocCameraYaml(path); })) {
    Require(camera.camera.HasValidParams(), "an accepted camera has valid parameters");
    SensorRig rig;
    rig.camera = camera.camera;
    rig.body_from_cam = camera.body_from_cam;
    Require(rig.Validate().empty(), "an accepted camera yaml gives a valid rig");
  }
  EurocImuCalibration imu;
  if (AcceptsInput([&] { imu = ReadEurocImuYaml(path); })) {
    Require(imu.noise.Validate().empty(), "an accepted IMU yaml gives a valid noise model");
  }
  AcceptsInput([&] { ReadEurocSensorTransform(path); });
  return 0;
}

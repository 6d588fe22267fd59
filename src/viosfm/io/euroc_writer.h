// Writers for the EuRoC ASL layout (the format is described in euroc.h).
// Numbers are written with 17 significant digits, so read -> write -> read
// is lossless. Every file is written atomically.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "viosfm/scene/sequence.h"

namespace viosfm {

void WriteEurocImageList(const std::filesystem::path& csv,
                         const std::vector<SequenceImage>& images);
void WriteEurocImu(const std::filesystem::path& csv, const std::vector<ImuSample>& samples);
void WriteEurocGroundTruth(const std::filesystem::path& csv,
                           const std::vector<GroundTruthState>& states);
// Camera sensor.yaml: OPENCV -> radial-tangential, OPENCV_FISHEYE ->
// equidistant, PINHOLE -> none. Other models throw InputError.
void WriteEurocCameraYaml(const std::filesystem::path& yaml, const Camera& camera,
                          const Rigid3d& body_from_cam, double rate_hz);
void WriteEurocImuYaml(const std::filesystem::path& yaml, const ImuNoise& noise);
// The texts of those two files (InputError for a camera model without a
// EuRoC equivalent).
std::string EurocCameraYamlText(const Camera& camera, const Rigid3d& body_from_cam, double rate_hz);
std::string EurocImuYamlText(const ImuNoise& noise);

// Writes <root>/mav0/{cam0/{data.csv,sensor.yaml}, imu0/{data.csv,sensor.yaml},
// state_groundtruth_estimate0/data.csv} for what the sequence has (cam0 only
// with images, imu0 only with IMU, ground truth only when present). Image
// files themselves are not written; `images[i].path` names them relative to
// mav0/cam0/data/.
void WriteEurocDataset(const std::filesystem::path& root, const Sequence& sequence);

}  // namespace viosfm

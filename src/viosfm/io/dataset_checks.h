// What a dataset may say, checked against physics and against the dataset's
// own folder while it is read, so that impossible input stops with an
// InputError naming the file and the line instead of reaching an estimator:
//
//  - IMU samples: every axis of the accelerometer within
//    imu_max_accel_m_s2 (default 50 g) and of the gyroscope within
//    imu_max_gyro_rad_s (default 35 rad/s). MEMS IMUs measure at most
//    +-16 to +-40 g and +-2000 deg/s (34.9 rad/s) full scale, so a larger
//    value is a corrupt sample, not a motion; an IMU with a wider range
//    (impact, spin) raises the bounds (dataset_checks.* options).
//  - IMU gaps: a stretch without samples longer than kImuGapReportNs is
//    reported with the count and the longest (FindImuGaps, a plain function
//    for whatever consumes the IMU to act on); the samples are never
//    interpolated here.
//  - camera calibration: focal lengths positive and finite, the principal
//    point inside the image, and a distortion that maps the image one to
//    one onto a field of view a lens can have (CheckCameraCalibration);
//  - rig extrinsics: a body-from-sensor translation within 10 m
//    (kMaxRigTranslationM), the size of any rig that carries a camera and
//    an IMU on one body;
//  - files: every file a dataset names lies inside the dataset's folder once
//    symbolic links are followed, unless allow_links_outside;
//  - images: each image's size from its file header (io/image_io.h),
//    before any decoding, equals the calibration's resolution.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "viosfm/geometry/rigid3.h"
#include "viosfm/scene/sequence.h"
#include "viosfm/sensor/camera.h"
#include "viosfm/sensor/imu.h"
#include "viosfm/util/option_fields.h"
#include "viosfm/util/timestamp.h"

namespace viosfm {

// The unit "g" of an accelerometer's range, m/s^2 (standard gravity).
inline constexpr double kOneG = 9.80665;
// The largest body-from-sensor translation of a rig, m.
inline constexpr double kMaxRigTranslationM = 10.0;
// IMU gaps longer than this are reported (0.1 s: ten samples of a 100 Hz
// IMU; a dropped sample or two is common and not reported).
inline constexpr timestamp_ns_t kImuGapReportNs = 100'000'000;

struct DatasetChecks {
  // The largest |acceleration| on any axis an IMU sample may state, m/s^2.
  // Default 50 g.
  double imu_max_accel_m_s2 = 50.0 * kOneG;
  // The largest |angular rate| on any axis, rad/s. Default 35 (2005 deg/s).
  double imu_max_gyro_rad_s = 35.0;
  // Follow symbolic links that leave the dataset's folder (default false:
  // such a link is an InputError naming it).
  bool allow_links_outside = false;

  template <class Self, class Visitor>
  static void VisitFields(Self& self, Visitor&& visit) {
    visit(
        {"imu_max_accel_m_s2", "m/s^2, the largest acceleration an IMU sample may state", kRunOnly},
        self.imu_max_accel_m_s2);
    visit(
        {"imu_max_gyro_rad_s", "rad/s, the largest angular rate an IMU sample may state", kRunOnly},
        self.imu_max_gyro_rad_s);
    visit(
        {"allow_links_outside", "follow symbolic links that leave the dataset's folder", kRunOnly},
        self.allow_links_outside);
  }

  // Empty if valid; otherwise names the bad field.
  std::string Validate() const;
};

// InputError naming `file` and `line` if a value of `sample` is beyond the
// bounds.
void CheckImuSample(const ImuSample& sample, const DatasetChecks& checks,
                    const std::filesystem::path& file, int64_t line);

// CheckImuSample for samples read from something without lines (a bag):
// the error names `source`, the sample's number (from 1) and its stamp.
void CheckImuSamples(const std::vector<ImuSample>& samples, const DatasetChecks& checks,
                     const std::filesystem::path& source);

// A stretch without IMU samples: between samples `index` - 1 and `index`.
struct ImuGap {
  size_t index = 0;
  timestamp_ns_t from_ns = 0;  // the stamp of the sample before it
  timestamp_ns_t to_ns = 0;    // the stamp of the sample after it
  timestamp_ns_t length_ns() const { return to_ns - from_ns; }
};
// Every gap longer than `max_step_ns` between consecutive samples, in order.
std::vector<ImuGap> FindImuGaps(const std::vector<ImuSample>& samples, timestamp_ns_t max_step_ns);
// "2 gaps longer than 0.1 s in the IMU (the longest 5.000 s, 3.20 s after
// its first sample)"; empty without gaps.
std::string DescribeImuGaps(const std::vector<ImuGap>& gaps, const std::vector<ImuSample>& samples,
                            timestamp_ns_t max_step_ns);

// Logs a warning naming `source` with DescribeImuGaps of the gaps longer
// than kImuGapReportNs, if there are any; returns them.
std::vector<ImuGap> ReportImuGaps(const std::vector<ImuSample>& samples,
                                  const std::filesystem::path& source);

// Empty if the camera is physically sound (see the top of the file),
// otherwise what is wrong, naming the values.
std::string CheckCameraCalibration(const Camera& camera);
// Empty if the translation of a body-from-sensor transform is within
// kMaxRigTranslationM, otherwise what is wrong.
std::string CheckRigTranslation(const Rigid3d& body_from_sensor);

// InputError naming `file` (and `source`: the list and line that named it)
// if `file`, symbolic links followed, is not inside `dataset_folder`, unless
// checks.allow_links_outside. Returns the file's canonical path.
std::filesystem::path CheckInsideDataset(const std::filesystem::path& dataset_folder,
                                         const std::filesystem::path& file,
                                         const DatasetChecks& checks, const std::string& source);

// Every image of `sequence`: inside `dataset_folder` (CheckInsideDataset),
// no file listed twice (also through a link), and its header's size equal
// to the camera's resolution. InputError naming the image otherwise.
// `dataset_folder` empty: the folder check is skipped (extracted images).
void CheckSequenceImages(const Sequence& sequence, const std::filesystem::path& dataset_folder,
                         const DatasetChecks& checks);

}  // namespace viosfm

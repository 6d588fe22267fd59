#include "viosfm/io/dataset_checks.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

#include "viosfm/io/image_header.h"
#include "viosfm/sensor/camera_models.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/logging.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;

std::string Number(double value) {
  std::ostringstream text;
  text << value;
  return text.str();
}

// Steps along each ray from the principal point to the image's border.
constexpr int kRaySteps = 64;
// A pixel's round trip through the lens model, px.
constexpr double kMaxRoundTripPx = 0.05;
// The field of view a distortion may give the image, as the ratio of a
// border pixel's angle from the optical axis with the distortion to its
// angle without it: a lens compresses or widens the view, no lens by 4.
constexpr double kMaxFieldOfViewRatio = 4.0;

// Whether `path` lies inside `folder` (both canonical).
bool IsInside(const fs::path& path, const fs::path& folder) {
  const auto [folder_end, path_it] =
      std::mismatch(folder.begin(), folder.end(), path.begin(), path.end());
  return folder_end == folder.end();
}

}  // namespace

std::string DatasetChecks::Validate() const {
  if (!(imu_max_accel_m_s2 > 0.0) || !std::isfinite(imu_max_accel_m_s2)) {
    return "imu_max_accel_m_s2 must be a positive number";
  }
  if (!(imu_max_gyro_rad_s > 0.0) || !std::isfinite(imu_max_gyro_rad_s)) {
    return "imu_max_gyro_rad_s must be a positive number";
  }
  return "";
}

void CheckImuSample(const ImuSample& sample, const DatasetChecks& checks, const fs::path& file,
                    int64_t line) {
  static constexpr const char* kAxes[] = {"x", "y", "z"};
  for (int axis = 0; axis < 3; ++axis) {
    const double accel = sample.accel[axis];
    if (!(std::abs(accel) <= checks.imu_max_accel_m_s2)) {
      throw InputError(
          file.string(), line,
          "acceleration a_" + std::string(kAxes[axis]) + " = " + Number(accel) +
              " m/s^2 is beyond what an IMU measures (|a| <= " + Number(checks.imu_max_accel_m_s2) +
              " m/s^2, " + Number(checks.imu_max_accel_m_s2 / kOneG) +
              " g): a corrupt sample (an IMU with a wider range: raise "
              "dataset_checks.imu_max_accel_m_s2)");
    }
    const double gyro = sample.gyro[axis];
    if (!(std::abs(gyro) <= checks.imu_max_gyro_rad_s)) {
      throw InputError(
          file.string(), line,
          "angular rate w_" + std::string(kAxes[axis]) + " = " + Number(gyro) +
              " rad/s is beyond what an IMU measures (|w| <= " + Number(checks.imu_max_gyro_rad_s) +
              " rad/s): a corrupt sample (an IMU with a wider range: raise "
              "dataset_checks.imu_max_gyro_rad_s)");
    }
  }
}

void CheckImuSamples(const std::vector<ImuSample>& samples, const DatasetChecks& checks,
                     const fs::path& source) {
  for (size_t i = 0; i < samples.size(); ++i) {
    try {
      CheckImuSample(samples[i], checks, source, 0);
    } catch (const InputError& error) {
      const std::string what = error.what();
      throw InputError(source.string(), 0,
                       "IMU sample " + std::to_string(i + 1) + " (stamp " +
                           std::to_string(samples[i].timestamp_ns) +
                           " ns): " + what.substr(source.string().size() + 2));
    }
  }
}

std::vector<ImuGap> ReportImuGaps(const std::vector<ImuSample>& samples, const fs::path& source) {
  std::vector<ImuGap> gaps = FindImuGaps(samples, kImuGapReportNs);
  if (!gaps.empty()) {
    VIOSFM_LOG(WARNING) << source.string() << ": "
                        << DescribeImuGaps(gaps, samples, kImuGapReportNs);
  }
  return gaps;
}

std::vector<ImuGap> FindImuGaps(const std::vector<ImuSample>& samples, timestamp_ns_t max_step_ns) {
  std::vector<ImuGap> gaps;
  for (size_t i = 1; i < samples.size(); ++i) {
    const timestamp_ns_t from = samples[i - 1].timestamp_ns;
    const timestamp_ns_t to = samples[i].timestamp_ns;
    if (to - from > max_step_ns) gaps.push_back({i, from, to});
  }
  return gaps;
}

std::string DescribeImuGaps(const std::vector<ImuGap>& gaps, const std::vector<ImuSample>& samples,
                            timestamp_ns_t max_step_ns) {
  if (gaps.empty() || samples.empty()) return "";
  const auto longest = std::max_element(gaps.begin(), gaps.end(), [](const auto& a, const auto& b) {
    return a.length_ns() < b.length_ns();
  });
  timestamp_ns_t total_ns = 0;
  for (const ImuGap& gap : gaps) total_ns += gap.length_ns();
  return std::to_string(gaps.size()) + " gap(s) longer than " + FormatNsAsSeconds(max_step_ns, 3) +
         " s without samples (" + FormatNsAsSeconds(total_ns, 3) + " s in all; the longest " +
         FormatNsAsSeconds(longest->length_ns(), 3) + " s, from " +
         FormatNsAsSeconds(longest->from_ns - samples.front().timestamp_ns, 3) +
         " s after the first sample)";
}

std::string CheckCameraCalibration(const Camera& camera) {
  if (!IsCameraModelSupported(camera.model_id) || !camera.HasValidParams()) {
    return "camera model " + camera.ModelName() + " with " + std::to_string(camera.params.size()) +
           " parameters cannot be checked";
  }
  for (const double value : camera.params) {
    if (!std::isfinite(value)) return "its parameters must be finite numbers";
  }
  const double width = static_cast<double>(camera.width);
  const double height = static_cast<double>(camera.height);
  if (!(width >= 1.0 && height >= 1.0)) return "its resolution must be positive";
  for (const int index : FocalLengthIndices(camera)) {
    if (!(camera.params[index] > 0.0)) {
      return "focal length " + Number(camera.params[index]) + " px must be positive";
    }
  }
  const std::vector<int> principal = PrincipalPointIndices(camera);
  const double cx = camera.params[principal[0]];
  const double cy = camera.params[principal[1]];
  if (!(cx >= 0.0 && cx <= width && cy >= 0.0 && cy <= height)) {
    return "principal point (" + Number(cx) + ", " + Number(cy) + ") px is outside the " +
           std::to_string(camera.width) + "x" + std::to_string(camera.height) + " image";
  }
  if (ExtraParamIndices(camera).empty()) return "";
  // Rays from the principal point to the border's corners and midpoints:
  // along each, the angle from the optical axis must grow (one to one: the
  // lens does not fold the image onto itself), each pixel must come back
  // from its ray, and the border's angle must be one a lens can give.
  const double focal = MeanFocalLength(camera);
  const Eigen::Vector2d centre(cx, cy);
  const double right = width - 0.5;
  const double bottom = height - 0.5;
  const Eigen::Vector2d border[] = {{-0.5, -0.5},    {cx, -0.5},   {right, -0.5},  {right, cy},
                                    {right, bottom}, {cx, bottom}, {-0.5, bottom}, {-0.5, cy}};
  for (const Eigen::Vector2d& end : border) {
    if ((end - centre).norm() < 1.0) continue;
    double previous_angle = 0.0;
    for (int step = 1; step <= kRaySteps; ++step) {
      const Eigen::Vector2d pixel = centre + (end - centre) * step / kRaySteps;
      const Eigen::Vector3d ray = Unproject(camera, pixel);
      const double angle = std::atan2(ray.head<2>().norm(), ray.z());
      const std::string where = " at pixel (" + Number(std::round(pixel.x())) + ", " +
                                Number(std::round(pixel.y())) + ")";
      if (!ray.allFinite() || !std::isfinite(angle)) {
        return "its distortion " + Number(camera.params[ExtraParamIndices(camera)[0]]) +
               ", ... gives no viewing ray" + where + ": out of range";
      }
      if (ray.z() > 0.1) {
        const std::optional<Eigen::Vector2d> back = Project(camera, ray);
        if (!back || !back->allFinite() || (*back - pixel).norm() > kMaxRoundTripPx) {
          return "its distortion folds the image" + where +
                 ": no viewing ray projects there (the lens model is not one to one inside the "
                 "image)";
        }
      }
      if (!(angle > previous_angle)) {
        return "its distortion folds the image" + where +
               ": the angle from the optical axis stops growing towards the border";
      }
      previous_angle = angle;
    }
    const double pinhole_angle = std::atan((end - centre).norm() / focal);
    const double ratio = previous_angle / pinhole_angle;
    if (!(ratio <= kMaxFieldOfViewRatio && ratio >= 1.0 / kMaxFieldOfViewRatio)) {
      return "its distortion makes the image's border " + Number(previous_angle * 180.0 / M_PI) +
             " degrees from the optical axis, where its focal length alone puts it at " +
             Number(pinhole_angle * 180.0 / M_PI) + " degrees (no lens changes it " +
             Number(kMaxFieldOfViewRatio) + " times)";
    }
  }
  return "";
}

std::string CheckRigTranslation(const Rigid3d& body_from_sensor) {
  const double length = body_from_sensor.translation.stableNorm();
  if (!(length <= kMaxRigTranslationM)) {
    return "its translation is " + Number(length) + " m; a sensor on the rig lies within " +
           Number(kMaxRigTranslationM) + " m of the body frame";
  }
  return "";
}

fs::path CheckInsideDataset(const fs::path& dataset_folder, const fs::path& file,
                            const DatasetChecks& checks, const std::string& source) {
  std::error_code error;
  const fs::path canonical = fs::weakly_canonical(file, error);
  if (error) {
    throw InputError(file.string(), 0, "cannot resolve the path: " + error.message());
  }
  if (checks.allow_links_outside) return canonical;
  const fs::path folder = fs::weakly_canonical(dataset_folder, error);
  if (error) {
    throw InputError(dataset_folder.string(), 0, "cannot resolve the path: " + error.message());
  }
  if (!IsInside(canonical, folder)) {
    throw InputError(file.string(), 0,
                     (source.empty() ? std::string() : "named by " + source + ": ") +
                         "leads outside the dataset " + dataset_folder.string() + " (to " +
                         canonical.string() +
                         ", through a symbolic link): refused; give --allow-external-links (option "
                         "dataset_checks.allow_links_outside) to follow such links");
  }
  return canonical;
}

void CheckSequenceImages(const Sequence& sequence, const fs::path& dataset_folder,
                         const DatasetChecks& checks) {
  std::map<fs::path, size_t> index_of_file;
  const Camera& camera = sequence.rig.camera;
  for (size_t i = 0; i < sequence.images.size(); ++i) {
    const fs::path& path = sequence.images[i].path;
    const fs::path canonical = dataset_folder.empty()
                                   ? fs::weakly_canonical(path)
                                   : CheckInsideDataset(dataset_folder, path, checks, "");
    const auto [it, inserted] = index_of_file.emplace(canonical, i);
    if (!inserted) {
      const SequenceImage& first = sequence.images[it->second];
      throw InputError(path.string(), 0,
                       "is the same file as " + first.path.string() + " (stamp " +
                           std::to_string(first.timestamp_ns) + " ns) and is listed again at " +
                           std::to_string(sequence.images[i].timestamp_ns) +
                           " ns: one image under two stamps");
    }
    const std::optional<ImageHeaderSize> size = ReadImageHeaderSize(path);
    if (size && camera.width > 0 &&
        (static_cast<uint64_t>(size->width) != camera.width ||
         static_cast<uint64_t>(size->height) != camera.height)) {
      throw InputError(path.string(), 0,
                       "the image is " + std::to_string(size->width) + "x" +
                           std::to_string(size->height) +
                           " pixels (its header says), the camera's "
                           "calibration " +
                           std::to_string(camera.width) + "x" + std::to_string(camera.height));
    }
  }
}

}  // namespace viosfm

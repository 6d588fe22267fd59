#include "viosfm/io/image_folder.h"

#include <algorithm>
#include <fstream>
#include <map>
#include <tuple>

#include "viosfm/io/euroc.h"
#include "viosfm/io/image_io.h"
#include "viosfm/io/text_lines.h"
#include "viosfm/sensor/camera_models.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/logging.h"
#include "viosfm/util/string_util.h"

namespace viosfm {
namespace fs = std::filesystem;

namespace {

// A file name read as a timestamp is at least 1 s in nanoseconds: smaller
// numbers ("0001.jpg") number the photos.
constexpr timestamp_ns_t kMinNameStampNs = 1'000'000'000;

bool IsAllDigits(std::string_view text) {
  return !text.empty() &&
         std::all_of(text.begin(), text.end(), [](char c) { return c >= '0' && c <= '9'; });
}

// An image and where its stamp came from, for duplicate messages.
struct StampedImage {
  SequenceImage image;
  std::string source_path;  // the image file (a) or the timestamps file (b)
  int64_t source_line = 0;  // 0 (a) or the line of the timestamps file (b)

  std::string Source() const {
    return source_line > 0 ? source_path + ":" + std::to_string(source_line) : source_path;
  }
};

// The images named by their stamps; when some name is not a stamp (or a
// number below kMinNameStampNs: a frame number, not nanoseconds), the
// folder is an unordered photo collection: the images in name order, 1 s
// apart (`unordered` set).
std::vector<StampedImage> ImagesFromNames(const fs::path& folder, bool* unordered) {
  std::vector<StampedImage> images;
  std::vector<fs::path> paths;
  for (const fs::directory_entry& entry : fs::directory_iterator(folder)) {
    if (!entry.is_regular_file() || !HasImageExtension(entry.path())) continue;
    paths.push_back(entry.path());
  }
  if (paths.empty()) {
    throw InputError(folder.string(), 0, "expected image files (.png, .jpg, .jpeg), found none");
  }
  std::sort(paths.begin(), paths.end());
  *unordered = false;
  for (const fs::path& path : paths) {
    const std::string stem = path.stem().string();
    const std::optional<timestamp_ns_t> stamp =
        IsAllDigits(stem) ? ParseNs(stem) : std::optional<timestamp_ns_t>();
    if (!stamp || !IsTimestampInRange(*stamp) || *stamp < kMinNameStampNs) {
      *unordered = true;
      break;
    }
    images.push_back({{*stamp, path}, path.string(), 0});
  }
  if (*unordered) {
    images.clear();
    for (size_t i = 0; i < paths.size(); ++i) {
      images.push_back(
          {{static_cast<timestamp_ns_t>(i + 1) * 1'000'000'000, paths[i]}, paths[i].string(), 0});
    }
  }
  return images;
}

// The camera of a folder without calibration: a simple radial camera with
// the focal length COLMAP assumes without EXIF data (1.2 times the larger
// side), centred, undistorted; the bundle adjustment refines it.
Camera GuessCamera(const fs::path& first_image) {
  const GreyImage image = ReadGreyImage(first_image);
  const double width = static_cast<double>(image.width);
  const double height = static_cast<double>(image.height);
  Camera camera =
      MakeCamera(CameraModelId::kSimpleRadial, image.width, image.height,
                 {1.2 * std::max(width, height), 0.5 * (width - 1.0), 0.5 * (height - 1.0), 0.0});
  camera.camera_id = 1;
  return camera;
}

std::vector<StampedImage> ImagesFromTimestampsFile(const fs::path& folder, const fs::path& file) {
  std::vector<StampedImage> images;
  std::map<fs::path, int64_t> line_of_path;
  ForEachDataLine(file, "timestamps file", [&](int64_t line_number, std::string_view text) {
    std::vector<std::string_view> fields = SplitFields(text, " \t");
    if (fields.size() == 1) fields = SplitFields(text, ",");
    if (fields.size() != 2 || fields[0].empty() || fields[1].empty()) {
      throw InputError(file.string(), line_number,
                       "expected 'filename timestamp' (timestamp in integer ns, or seconds with a "
                       "decimal point), got " +
                           std::to_string(fields.size()) + " fields");
    }
    const std::string_view stamp_text = fields[1];
    std::optional<timestamp_ns_t> stamp;
    if (stamp_text.find('.') != std::string_view::npos) {
      stamp = ParseSecondsToNs(stamp_text);
    } else if (IsAllDigits(stamp_text) ||
               (stamp_text.front() == '-' && IsAllDigits(stamp_text.substr(1)))) {
      stamp = ParseNs(stamp_text);
    }
    if (!stamp || !IsTimestampInRange(*stamp)) {
      throw InputError(file.string(), line_number,
                       "expected a timestamp in integer ns or in seconds with a decimal point in "
                       "column 2, within +-2^62 ns (146 years) of the epoch, got '" +
                           std::string(stamp_text) + "'");
    }
    // A name resolved inside the folder: never an absolute path or one that
    // climbs out of it.
    const fs::path name{std::string(fields[0])};
    const bool inside =
        !name.has_root_path() && fields[0].find('\0') == std::string_view::npos &&
        std::none_of(name.begin(), name.end(), [](const fs::path& part) { return part == ".."; });
    if (!inside) {
      throw InputError(file.string(), line_number,
                       "image name '" + std::string(fields[0]) +
                           "' must be a relative path inside the image folder " + folder.string() +
                           " (not absolute, no '..')");
    }
    const fs::path path = folder / name;
    if (!fs::is_regular_file(path)) {
      throw InputError(
          file.string(), line_number,
          "listed image '" + std::string(fields[0]) + "' does not exist: " + path.string());
    }
    const auto [it, inserted] = line_of_path.emplace(path.lexically_normal(), line_number);
    if (!inserted) {
      throw InputError(file.string(), line_number,
                       "image '" + std::string(fields[0]) + "' is already listed on line " +
                           std::to_string(it->second));
    }
    images.push_back({{*stamp, path}, file.string(), line_number});
  });
  if (images.empty()) {
    throw InputError(file.string(), 0, "expected 'filename timestamp' lines, found none");
  }
  return images;
}

}  // namespace

bool HasImageExtension(const fs::path& path) {
  const std::string extension = ToLower(path.extension().string());
  return extension == ".png" || extension == ".jpg" || extension == ".jpeg";
}

std::string ImageFolderOptions::Validate() const {
  if (camera.has_value() && !camera_yaml.empty()) {
    return "give at most one of camera and camera_yaml";
  }
  if (camera && (!camera->HasValidParams() || camera->width == 0 || camera->height == 0)) {
    return "camera must have a known model, its number of params and a positive size";
  }
  return "";
}

Sequence ReadImageFolder(const fs::path& folder, const ImageFolderOptions& options,
                         const DatasetChecks& checks) {
  if (const std::string problem = options.Validate(); !problem.empty()) {
    throw InputError("image folder options: " + problem);
  }
  RequireFolder(folder, "image folder");

  Sequence sequence;
  sequence.root = folder;
  if (options.camera) {
    if (const std::string problem = CheckCameraCalibration(*options.camera); !problem.empty()) {
      throw InputError("the image folder's camera " + options.camera->ModelName() +
                       " is not one a camera can have: " + problem);
    }
    sequence.rig.camera = *options.camera;
    sequence.rig.camera.camera_id = 1;
    sequence.rig.camera_rate_hz = 0.0;  // estimated from the stamps below
  } else if (!options.camera_yaml.empty()) {
    const EurocCameraCalibration calibration = ReadEurocCameraYaml(options.camera_yaml);
    sequence.rig.camera = calibration.camera;
    sequence.rig.body_from_cam = calibration.body_from_cam;
    sequence.rig.camera_rate_hz = calibration.rate_hz;
  }

  std::vector<StampedImage> images =
      options.timestamps_file.empty() ? ImagesFromNames(folder, &sequence.unordered)
                                      : ImagesFromTimestampsFile(folder, options.timestamps_file);
  if (sequence.unordered) {
    VIOSFM_LOG(WARNING) << "image folder " << folder.string()
                        << ": the image names are not timestamps: taken as an unordered photo "
                           "collection, in name order (--timestamps FILE gives their stamps)";
  }
  // Sort by stamp, then by source so that the duplicate message is stable.
  std::sort(images.begin(), images.end(), [](const StampedImage& a, const StampedImage& b) {
    return a.image.timestamp_ns != b.image.timestamp_ns
               ? a.image.timestamp_ns < b.image.timestamp_ns
               : std::tie(a.source_path, a.source_line) < std::tie(b.source_path, b.source_line);
  });
  for (size_t i = 1; i < images.size(); ++i) {
    if (images[i].image.timestamp_ns == images[i - 1].image.timestamp_ns) {
      throw InputError(images[i].source_path, images[i].source_line,
                       "duplicate timestamp " + std::to_string(images[i].image.timestamp_ns) +
                           " ns, also given by " + images[i - 1].Source() +
                           "; expected one image per timestamp");
    }
  }
  sequence.images.reserve(images.size());
  for (StampedImage& image : images) sequence.images.push_back(std::move(image.image));
  if (!(sequence.rig.camera_rate_hz > 0)) {
    sequence.rig.camera_rate_hz = EstimateFrameRateHz(sequence.images);
  }
  CheckSequenceImages(sequence, folder, checks);

  if (!options.camera && options.camera_yaml.empty()) {
    sequence.rig.camera = GuessCamera(sequence.images.front().path);
    sequence.camera_guessed = true;
    VIOSFM_LOG(WARNING) << "image folder " << folder.string()
                        << ": no calibration given (--camera-yaml, --calibration): the camera is "
                           "guessed from the image size (focal length "
                        << sequence.rig.camera.params[0]
                        << " px, no distortion) and refined by the bundle adjustment";
  }
  VIOSFM_LOG(INFO) << "image folder " << folder.string() << ": " << sequence.images.size()
                   << " images (" << sequence.rig.camera.ModelName() << " "
                   << sequence.rig.camera.width << "x" << sequence.rig.camera.height << "), no IMU";
  return sequence;
}

}  // namespace viosfm

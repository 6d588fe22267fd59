// The plain image-folder layout: a folder of images and no IMU.
//
// Timestamps come from one of:
//  (a) the file names: every image file (extension .png, .jpg or .jpeg, any
//      case) is named by its timestamp in integer nanoseconds, digits only,
//      e.g. "1403715273262142976.png". Other files and sub-folders are
//      ignored. When some image's name is not such a number, or is below
//      1e9 (1 s: "0001.jpg" numbers a photo), the folder is an unordered
//      photo collection (Sequence::unordered): its images in name order,
//      stamped 1 s apart from 1 s.
//  (b) a timestamps file (options.timestamps_file), one image a line:
//          <filename> <timestamp>
//      separated by spaces, tabs or one comma; blank lines and lines starting
//      with '#' are skipped. <filename> is relative to the folder, stays
//      inside it (not absolute, no '..') and has no spaces. <timestamp> without a decimal point is
//      an integer count of nanoseconds ("1403715273262142976"); with a decimal point it is seconds
//      ("1403715273.262142976", converted digit-exactly, rounded to 1 ns). Only the listed files
//      are used, in any order.
// Images are returned sorted by timestamp; two images with the same stamp
// are an error.
//
// The camera is given (options.camera), read from a EuRoC/Kalibr camera
// sensor.yaml (options.camera_yaml, see euroc.h, which also gives
// body_from_cam and the frame rate), or, with neither, guessed from the first
// image's size as COLMAP does without EXIF data (Sequence::camera_guessed: a
// simple radial camera, focal length 1.2 times the larger side).
//
// Errors throw InputError naming the file, the line (where there is one) and
// what was expected: a missing folder, no images, duplicate stamps or file
// names, a listed file that does not exist or lies outside the folder, a
// malformed timestamps line, an invalid camera; and what `checks` refuses
// (dataset_checks.h: a link leaving the folder, an image whose header's
// size is not the camera's).
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "viosfm/io/dataset_checks.h"
#include "viosfm/scene/sequence.h"

namespace viosfm {

struct ImageFolderOptions {
  // File of "filename timestamp" lines; empty: stamps from the file names.
  std::filesystem::path timestamps_file;
  // The camera intrinsics (camera_id is set to 1). At most one of camera and
  // camera_yaml may be given; with neither the camera is guessed.
  std::optional<Camera> camera;
  // A EuRoC/Kalibr camera sensor.yaml.
  std::filesystem::path camera_yaml;

  // Empty if valid; otherwise names the bad field.
  std::string Validate() const;
  bool Check() const { return Validate().empty(); }
};

// Whether a file name has one of the image extensions above.
bool HasImageExtension(const std::filesystem::path& path);

Sequence ReadImageFolder(const std::filesystem::path& folder, const ImageFolderOptions& options,
                         const DatasetChecks& checks = {});

}  // namespace viosfm

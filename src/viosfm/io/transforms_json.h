// transforms.json, the camera file of nerfstudio and instant-ngp (and the
// Gaussian-splatting trainers that read it), following nerfstudio's "Data
// conventions" page (docs.nerf.studio/quickstart/data_conventions.html):
//
//   {
//     "camera_model": "OPENCV",          PINHOLE, OPENCV or OPENCV_FISHEYE
//     "fl_x", "fl_y", "cx", "cy",        pixels
//     "w", "h",                          image size, pixels
//     "k1", "k2", "p1", "p2"             OPENCV (radial-tangential)
//     "k1", "k2", "k3", "k4"             OPENCV_FISHEYE (equidistant)
//     "ply_file_path": "sparse_pc.ply",  optional: initial points (splatfacto)
//     "frames": [ {"file_path": "images/<name>",
//                  "transform_matrix": 4x4 rows, camera-to-world} ... ]
//   }
//
// Conventions, and what viosfm converts:
//  - camera axes are OpenGL's: +x right, +y up, +z back (the camera looks
//    along -z); viosfm's (OpenCV's, COLMAP's) are +x right, +y down, +z
//    forward, so transform_matrix = world_from_cam * diag(1, -1, -1, 1);
//  - the world frame is the model's: viosfm's is gravity-aligned with +z up,
//    which is also nerfstudio's world convention, in metres;
//  - pixel coordinates: nerfstudio shoots the ray of pixel (0, 0) through
//    that pixel's centre at (0.5, 0.5), i.e. the top-left image corner is
//    the origin (COLMAP's convention; its colmap2nerf conversion copies
//    COLMAP's cx, cy unchanged). viosfm's cameras have the centre of the
//    top-left pixel at (0, 0) (OpenCV's), so cx, cy gain 0.5 on the way out
//    and lose it on the way in;
//  - file_path is relative to the folder of transforms.json.
// Numbers are written with 17 significant digits, so poses round-trip.
//
// SIMPLE_PINHOLE and PINHOLE are written as PINHOLE; SIMPLE_RADIAL and
// RADIAL as OPENCV (k1, k2; p1 = p2 = 0); other camera models throw
// InputError. Reading accepts what writing produces (the top-level
// intrinsics; per-frame intrinsics are not read) and throws InputError naming
// the file and the frame for a missing key, a wrong type or a
// transform_matrix that is not a rigid transform.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "viosfm/geometry/rigid3.h"
#include "viosfm/sensor/camera.h"

namespace viosfm {

struct TransformsFrame {
  std::string file_path;
  Rigid3d cam_from_world;  // viosfm's (OpenCV) camera axes
};

struct TransformsJson {
  Camera camera;  // viosfm's convention (see above)
  std::vector<TransformsFrame> frames;
  std::string ply_file_path;  // empty: none
};

void WriteTransformsJson(const std::filesystem::path& path, const TransformsJson& transforms);
TransformsJson ReadTransformsJson(const std::filesystem::path& path);

}  // namespace viosfm

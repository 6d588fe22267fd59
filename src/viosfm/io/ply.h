// PLY point clouds (vertices with position and colour).
//
// Written files have one element "vertex" with
//   property double x, y, z      (double, not float: coordinates far from the
//                                 origin keep full precision; MeshLab,
//                                 CloudCompare and Open3D read double)
//   property uchar red, green, blue
// in "binary_little_endian 1.0" (default) or "ascii 1.0" (numbers as %.17g,
// so they read back exactly). The header is exactly:
//   ply
//   format binary_little_endian 1.0      (or: format ascii 1.0)
//   element vertex N
//   property double x
//   property double y
//   property double z
//   property uchar red
//   property uchar green
//   property uchar blue
//   end_header
//
// ReadPly reads this layout and the common variants around it: ascii,
// binary_little_endian or binary_big_endian; x y z of any scalar type; red
// green blue optional (uchar); other scalar vertex properties (e.g. COLMAP
// fused.ply's float nx ny nz) skipped; "comment"/"obj_info" lines skipped;
// elements after "vertex" ignored. Malformed files throw InputError naming the
// file and the header line or vertex.
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <vector>

#include "viosfm/scene/reconstruction.h"

namespace viosfm {

struct PlyPoints {
  std::vector<Eigen::Vector3d> xyz;
  // Empty if the file has no colour; otherwise one per point.
  std::vector<Vector3ub> rgb;
};

// `rgb` has one colour per point, or is empty to write no colour properties
// (the header then ends after "property double z"); other sizes CHECK-fail.
void WritePlyPoints(const std::filesystem::path& path, const std::vector<Eigen::Vector3d>& xyz,
                    const std::vector<Vector3ub>& rgb, bool binary = true);
// The 3D points of a reconstruction with their colours, in point order.
void WritePly(const std::filesystem::path& path, const Reconstruction& reconstruction,
              bool binary = true);

PlyPoints ReadPly(const std::filesystem::path& path);

}  // namespace viosfm

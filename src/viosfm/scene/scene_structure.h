// Ground truth of a synthetic scene's 3D structure: its textured planar
// rectangles in the world frame, with the named region (floor, stairwell,
// corridor segment) each belongs to, so that one can compute which surfaces
// (and so which floor) a camera sees.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace viosfm {

// The rectangle origin + a * axis_u + b * axis_v, a, b in [0, 1] (metres,
// world frame).
struct SceneStructureQuad {
  int id = -1;          // index of the quad in its scene
  std::string region;   // name of the region containing the quad's centre ("none": none)
  int floor = -1;       // storey of that region (0 = ground; -1 stairwell or none)
  int texture_id = -1;  // quads sharing a texture id look identical
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  // m
  Eigen::Vector3d axis_u = Eigen::Vector3d::Zero();  // m
  Eigen::Vector3d axis_v = Eigen::Vector3d::Zero();  // m
};

using SceneStructure = std::vector<SceneStructureQuad>;

}  // namespace viosfm

// The 3D view of the run report: the point cloud (decimated) and the camera
// path, coloured by its position error when a ground truth exists, in a
// WebGL canvas with orbit controls (drag: rotate, wheel: zoom, right-drag or
// shift-drag: pan).
//
// The page stays one self-contained file: three.js (Debian's libjs-three,
// r111, its non-module build three.min.js) and its OrbitControls
// (examples/js/controls/OrbitControls.js of the same package) are copied into
// the page, and the scene is embedded as base64 little-endian arrays
// (float32 positions relative to the scene's centre, so models far from the
// origin keep their precision; uint8 RGB colours). Nothing is loaded from the
// network or from other files.
//
// Self-test: opened as report.html#viewer-selftest, the page writes the
// canvas as a PNG data URL into <pre id="viewer3d-selftest"> after its first
// frame (the drawing buffer is preserved for this), so a headless browser's
// --dump-dom shows what WebGL drew.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace viosfm {

struct Viewer3dScene {
  std::vector<Eigen::Vector3d> points;  // world, metres
  // One RGB per point, or empty (grey).
  std::vector<Eigen::Matrix<uint8_t, 3, 1>> colors;
  // The estimated positions along the trajectory, in the points' frame.
  std::vector<Eigen::Vector3d> path;
  // Position error (m) of each path vertex, or empty without ground truth.
  std::vector<double> path_errors_m;
  // The ground truth in the points' frame (drawn grey), or empty.
  std::vector<Eigen::Vector3d> ground_truth_path;
};

struct Viewer3dOptions {
  // Points kept in the page (every k-th point, k = ceil(N / max_points)):
  // a browser draws 200 000 points fluently and the page grows by about
  // 20 bytes a point. Default 200 000.
  size_t max_points = 200'000;
  // Where libjs-three installs three.js. Default /usr/share/javascript/three.
  std::filesystem::path three_js_dir = "/usr/share/javascript/three";
  // Canvas size (px). Defaults 1100 x 600.
  int width = 1100;
  int height = 600;

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }
};

// The indices every k-th point keeps (k = ceil(n / max_points)), in order.
std::vector<size_t> DecimationIndices(size_t n, size_t max_points);

// Whether three.min.js and OrbitControls.js are in options.three_js_dir.
bool HasThreeJs(const Viewer3dOptions& options);

// The HTML of the view (canvas, legend, data and scripts). Throws
// InputError if three.js is missing (check HasThreeJs first) or the options
// are invalid.
std::string RenderViewer3d(const Viewer3dScene& scene, const Viewer3dOptions& options);

}  // namespace viosfm

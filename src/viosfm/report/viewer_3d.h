// The 3D view of the run report, in a WebGL canvas with orbit controls
// (drag: rotate, wheel: zoom, right-drag or shift-drag: pan):
//  - the point cloud (decimated), coloured by height (a colour bar in
//    metres) or by the images' colour, as the user chooses;
//  - camera frustums of the posed frames, spread so that they do not
//    overlap (a frame 1.5 frustum depths from the last one drawn or turned
//    30 degrees from it; at most max_cameras), drawn as the camera saw: its
//    image's corners and a tick on the image's top edge; a click on one
//    shows the frame's image and name beside the view and marks it;
//  - the camera path, coloured by its position error when a ground truth
//    exists (drawn grey);
//  - a metric grid on the floor (cells of a round number of metres, said in
//    the legend) and the world's axes at its origin (x red, y green, z blue),
//    with z up against gravity when the model is gravity-aligned;
//  - check boxes that show or hide each of these.
//
// The page stays one self-contained file: three.js (Debian's libjs-three,
// r111, its non-module build three.min.js) and its OrbitControls
// (examples/js/controls/OrbitControls.js of the same package) are copied into
// the page; the scene is embedded as base64 little-endian arrays (float32
// positions relative to the scene's centre, so models far from the origin
// keep their precision; uint8 RGB colours) and the frames' images as small
// JPEG thumbnails. Nothing is loaded from the network or from other files.
//
// Self-test: opened as report.html#viewer-selftest, the page writes the
// canvas as a PNG data URL into <pre id="viewer3d-selftest"> after its first
// frame (the drawing buffer is preserved for this), so a headless browser's
// --dump-dom shows what WebGL drew; opened as #viewer-selftest-click, it
// first clicks the frustum nearest the canvas's centre (the frame panel then
// shows that frame). window.viosfmViewer lets a script hide layers, switch
// colours and find where a frustum is on the screen.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "viosfm/geometry/rigid3.h"
#include "viosfm/sensor/camera.h"

namespace viosfm {

// A posed frame drawn as a frustum.
struct Viewer3dFrame {
  Rigid3d cam_from_world;        // in the points' frame
  std::string name;              // the image's name, shown when clicked
  std::optional<double> time_s;  // seconds since the recording's first frame
  // The image file; its thumbnail is embedded (empty or unreadable: none, and
  // the click says so).
  std::filesystem::path image_path;
};

struct Viewer3dScene {
  std::vector<Eigen::Vector3d> points;  // world, metres
  // One RGB per point, or empty (then only the height colours).
  std::vector<Eigen::Matrix<uint8_t, 3, 1>> colors;
  // The estimated positions along the trajectory, in the points' frame.
  std::vector<Eigen::Vector3d> path;
  // Position error (m) of each path vertex, or empty without ground truth.
  std::vector<double> path_errors_m;
  // The ground truth in the points' frame (drawn grey), or empty.
  std::vector<Eigen::Vector3d> ground_truth_path;
  // The frames as frustums, and their (one) camera's intrinsics.
  std::vector<Viewer3dFrame> frames;
  Camera camera;
  // The world's z axis points against gravity (the model was levelled by the
  // IMU or the VIO); false: z is only the model's.
  bool gravity_up = true;
};

struct Viewer3dOptions {
  // Points kept in the page (every k-th point, k = ceil(N / max_points)):
  // a browser draws 200 000 points fluently and the page grows by about
  // 20 bytes a point. Default 200 000.
  size_t max_points = 200'000;
  // Frustums drawn (every k-th frame beyond it), each with a thumbnail of
  // about 10 KB. Default 300.
  size_t max_cameras = 300;
  // Width of the embedded thumbnails (px); 0: no thumbnails. Default 256.
  int thumbnail_width = 256;
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

// The frames drawn as frustums, in order: the first, then each one at least
// `min_distance` (m) from the last one kept or turned from it by at least
// `min_turn_deg`; every k-th of those when more than max_frames remain.
std::vector<size_t> SpreadFrames(const std::vector<Viewer3dFrame>& frames, double min_distance,
                                 double min_turn_deg, size_t max_frames);

// Whether three.min.js and OrbitControls.js are in options.three_js_dir.
bool HasThreeJs(const Viewer3dOptions& options);

// The spacing of the floor grid for a scene of this radius (m): 1, 2 or 5
// times a power of ten, about a fifth of the radius.
double GridSpacing(double radius_m);

// A JPEG thumbnail `width` px wide of the image at `path` (smaller images
// keep their size); empty if the file cannot be read as an image.
std::vector<uint8_t> MakeThumbnailJpeg(const std::filesystem::path& path, int width);

// The HTML of the view (controls, canvas, frame panel, legend, data and
// scripts). Throws InputError if three.js is missing (check HasThreeJs
// first) or the options are invalid.
std::string RenderViewer3d(const Viewer3dScene& scene, const Viewer3dOptions& options);

}  // namespace viosfm

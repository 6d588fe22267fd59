#include "viosfm/report/viewer_3d.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "viosfm/report/svg_plot.h"
#include "viosfm/sensor/camera_models.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;

const char* kThreeFile = "three.min.js";
// A frame turned this much from the last frustum drawn gets its own.
constexpr double kMinFrustumTurnDeg = 30.0;
const char* kOrbitControlsFile = "examples/js/controls/OrbitControls.js";

std::string Base64(const std::vector<uint8_t>& bytes) {
  static const char* kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (size_t i = 0; i < bytes.size(); i += 3) {
    const uint32_t b0 = bytes[i];
    const uint32_t b1 = i + 1 < bytes.size() ? bytes[i + 1] : 0;
    const uint32_t b2 = i + 2 < bytes.size() ? bytes[i + 2] : 0;
    const uint32_t triple = (b0 << 16) | (b1 << 8) | b2;
    out.push_back(kAlphabet[(triple >> 18) & 63]);
    out.push_back(kAlphabet[(triple >> 12) & 63]);
    out.push_back(i + 1 < bytes.size() ? kAlphabet[(triple >> 6) & 63] : '=');
    out.push_back(i + 2 < bytes.size() ? kAlphabet[triple & 63] : '=');
  }
  return out;
}

// Positions relative to `center` as little-endian float32.
std::string Float32Base64(const std::vector<Eigen::Vector3d>& xyz, const Eigen::Vector3d& center) {
  std::vector<uint8_t> bytes;
  bytes.reserve(xyz.size() * 12);
  for (const Eigen::Vector3d& p : xyz) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t bits = std::bit_cast<uint32_t>(static_cast<float>(p[k] - center[k]));
      for (int b = 0; b < 4; ++b) bytes.push_back(static_cast<uint8_t>(bits >> (8 * b)));
    }
  }
  return Base64(bytes);
}

std::string Number(double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.6g", value);
  return buffer;
}

// Keeps a script's text from closing its <script> element early: "</script"
// (any case) becomes "<\/script", which means the same inside a JavaScript
// string or regular expression, the only places it can occur.
std::string ScriptSafe(const std::string& text) {
  std::string lower = text;
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  std::string out;
  out.reserve(text.size());
  size_t from = 0;
  for (size_t at = lower.find("</script"); at != std::string::npos;
       at = lower.find("</script", at + 1)) {
    out.append(text, from, at + 1 - from);  // up to and with '<'
    out.push_back('\\');
    from = at + 1;
  }
  out.append(text, from, std::string::npos);
  return out;
}

// The viewer; VIOSFM_SCENE holds the data (RenderViewer3d).
const char* kViewerScript = R"JS(
(function () {
  var d = VIOSFM_SCENE;
  var $ = function (id) { return document.getElementById(id); };
  var canvas = $('viewer3d-canvas');
  var status = $('viewer3d-status');
  function decode(text, Type) {
    var s = atob(text), bytes = new Uint8Array(s.length);
    for (var i = 0; i < s.length; ++i) bytes[i] = s.charCodeAt(i);
    return new Type(bytes.buffer);
  }
  function geometry(positions, colors) {
    var g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.BufferAttribute(positions, 3));
    if (colors) g.setAttribute('color', new THREE.BufferAttribute(colors, 3, true));
    return g;
  }
  // matplotlib's viridis at 0, 1/8, ..., 1 (as report/svg_plot.h's ColorMap).
  var stops = [[68,1,84],[72,40,120],[62,73,137],[49,104,142],[38,130,142],[31,158,137],
               [53,183,121],[110,206,88],[253,231,37]];
  function colorMap(t, out, k) {
    t = Math.min(1, Math.max(0, t || 0)) * (stops.length - 1);
    var i = Math.min(Math.floor(t), stops.length - 2), f = t - i;
    for (var c = 0; c < 3; ++c) out[k + c] = Math.round((1 - f) * stops[i][c] + f * stops[i + 1][c]);
  }
  var renderer;
  try {
    renderer = new THREE.WebGLRenderer({canvas: canvas, antialias: true,
                                        preserveDrawingBuffer: true});
  } catch (e) {
    status.textContent = 'No 3D view: this browser has no WebGL (' + e.message + ').';
    return;
  }
  renderer.setPixelRatio(1);
  renderer.setSize(d.width, d.height, false);
  renderer.setClearColor(0x1e1e1e, 1);
  var scene = new THREE.Scene();
  var layers = {points: new THREE.Group(), cameras: new THREE.Group(), path: new THREE.Group(),
                grid: new THREE.Group()};
  for (var name in layers) scene.add(layers[name]);

  // Points, coloured by height or by the images' colour.
  var pointPositions = decode(d.points, Float32Array);
  var imageColors = d.has_point_colors ? decode(d.point_colors, Uint8Array) : null;
  var heightColors = new Uint8Array(d.num_points * 3);
  for (var i = 0; i < d.num_points; ++i) {
    colorMap((pointPositions[3 * i + 2] - d.height_min) / (d.height_max - d.height_min),
             heightColors, 3 * i);
  }
  var pointGeometry = geometry(pointPositions, heightColors);
  if (d.num_points > 0) {
    layers.points.add(new THREE.Points(pointGeometry,
        new THREE.PointsMaterial({size: 2, sizeAttenuation: false,
                                  vertexColors: THREE.VertexColors})));
  }
  function setColorMode(mode) {
    var colors = mode === 'image' && imageColors ? imageColors : heightColors;
    pointGeometry.setAttribute('color', new THREE.BufferAttribute(colors, 3, true));
    $('viewer3d-height-legend').style.visibility = colors === heightColors ? 'visible' : 'hidden';
    render();
  }

  // Camera path (coloured by its error) and the ground truth.
  if (d.num_ground_truth > 1) {
    layers.path.add(new THREE.Line(geometry(decode(d.ground_truth, Float32Array), null),
                                   new THREE.LineBasicMaterial({color: 0xb0b0b0})));
  }
  if (d.num_path > 1) {
    var pathGeometry = geometry(decode(d.path, Float32Array), decode(d.path_colors, Uint8Array));
    layers.path.add(new THREE.Line(pathGeometry,
        new THREE.LineBasicMaterial({vertexColors: THREE.VertexColors})));
  }

  // Frustums: per frame its centre, the image's corners (top-left, top-right,
  // bottom-right, bottom-left) at depth d.frustum_depth and the tip of a tick
  // on the top edge.
  var frustum = decode(d.frustums, Float32Array);
  var edges = [[0,1],[0,2],[0,3],[0,4],[1,2],[2,3],[3,4],[4,1],[1,5],[5,2]];
  // The clicked frustum is drawn over the others (no depth test): it lies
  // exactly on its orange lines.
  function frustumLines(indices, color, onTop) {
    var positions = new Float32Array(indices.length * edges.length * 6), k = 0;
    indices.forEach(function (f) {
      edges.forEach(function (e) {
        for (var end = 0; end < 2; ++end) {
          for (var c = 0; c < 3; ++c) positions[k++] = frustum[(6 * f + e[end]) * 3 + c];
        }
      });
    });
    var lines = new THREE.LineSegments(geometry(positions, null),
        new THREE.LineBasicMaterial({color: color, depthTest: !onTop}));
    if (onTop) lines.renderOrder = 1;
    return lines;
  }
  var all = [];
  for (var f = 0; f < d.frames.length; ++f) all.push(f);
  if (all.length > 0) layers.cameras.add(frustumLines(all, 0xff8c1a));
  var selectedLines = null;

  // Grid on the floor and the world's axes at its origin.
  var grid = new THREE.GridHelper(d.grid.size, Math.round(d.grid.size / d.grid.spacing),
                                  0x8a8a8a, 0x4a4a4a);
  grid.rotation.x = Math.PI / 2;  // GridHelper lies in x-z; the floor is x-y
  grid.position.set(d.grid.center[0], d.grid.center[1], d.grid.z);
  layers.grid.add(grid);
  var axisColors = [0xe53935, 0x43a047, 0x1e88e5];
  var axisNames = ['x', 'y', d.gravity_up ? 'z (up)' : 'z'];
  var origin = new THREE.Vector3(d.origin[0], d.origin[1], d.origin[2]);
  for (var a = 0; a < 3; ++a) {
    var direction = new THREE.Vector3(a === 0 ? 1 : 0, a === 1 ? 1 : 0, a === 2 ? 1 : 0);
    var length = d.grid.spacing;
    layers.grid.add(new THREE.ArrowHelper(direction, origin, length, axisColors[a],
                                          0.25 * length, 0.12 * length));
    layers.grid.add(label(axisNames[a], axisColors[a],
        origin.clone().add(direction.clone().multiplyScalar(1.25 * length)), 0.3 * length));
  }
  function label(text, color, position, height) {
    var c = document.createElement('canvas');
    c.width = 256; c.height = 64;
    var g = c.getContext('2d');
    g.font = 'bold 44px sans-serif';
    g.fillStyle = '#' + ('000000' + color.toString(16)).slice(-6);
    g.textBaseline = 'middle';
    g.fillText(text, 4, 32);
    var sprite = new THREE.Sprite(new THREE.SpriteMaterial({map: new THREE.CanvasTexture(c),
                                                            depthTest: false}));
    sprite.scale.set(4 * height, height, 1);
    sprite.position.copy(position);
    sprite.center.set(0, 0.5);
    return sprite;
  }

  var r = d.radius;
  var camera = new THREE.PerspectiveCamera(50, d.width / d.height, r / 1000, r * 100);
  camera.up.set(0, 0, 1);
  camera.position.set(1.0 * r, -1.35 * r, 0.95 * r);
  var controls = new THREE.OrbitControls(camera, canvas);
  controls.target.set(0, 0, 0);
  controls.screenSpacePanning = true;
  function render() { renderer.render(scene, camera); }
  controls.addEventListener('change', render);
  controls.update();

  // Where a frame's frustum is on the canvas (CSS px from its top-left): the
  // centre of its image rectangle.
  function screenPosition(f) {
    var p = new THREE.Vector3();
    for (var corner = 1; corner <= 4; ++corner) {
      p.x += frustum[(6 * f + corner) * 3] / 4;
      p.y += frustum[(6 * f + corner) * 3 + 1] / 4;
      p.z += frustum[(6 * f + corner) * 3 + 2] / 4;
    }
    var rect = canvas.getBoundingClientRect();
    var inFront = p.clone().applyMatrix4(camera.matrixWorldInverse).z < 0;
    p.project(camera);
    return {x: (p.x + 1) / 2 * rect.width, y: (1 - p.y) / 2 * rect.height, visible: inFront &&
            Math.abs(p.x) <= 1 && Math.abs(p.y) <= 1};
  }
  function select(f) {
    if (selectedLines) layers.cameras.remove(selectedLines);
    selectedLines = frustumLines([f], 0xffff00, true);
    layers.cameras.add(selectedLines);
    var frame = d.frames[f];
    var panel = $('viewer3d-frame');
    var image = $('viewer3d-frame-image');
    if (frame.thumbnail) {
      image.src = 'data:image/jpeg;base64,' + frame.thumbnail;
      image.hidden = false;
    } else {
      image.removeAttribute('src');
      image.hidden = true;
    }
    $('viewer3d-frame-caption').textContent = frame.name +
        (frame.time_s !== null ? ' (' + frame.time_s.toFixed(2) + ' s)' : '') +
        (frame.thumbnail ? '' : ': its image was not found at ' + frame.image_path);
    panel.hidden = false;
    panel.setAttribute('data-frame', String(f));
    render();
  }
  // A click (a press and release within 5 px) picks the nearest frustum
  // within 14 px of it.
  var down = null;
  canvas.addEventListener('pointerdown', function (e) { down = [e.clientX, e.clientY]; });
  canvas.addEventListener('pointerup', function (e) {
    if (!down || Math.hypot(e.clientX - down[0], e.clientY - down[1]) > 5) return;
    if (!layers.cameras.visible) return;
    var rect = canvas.getBoundingClientRect();
    var x = e.clientX - rect.left, y = e.clientY - rect.top, best = -1, bestDistance = 14;
    for (var f = 0; f < d.frames.length; ++f) {
      var s = screenPosition(f);
      var distance = Math.hypot(s.x - x, s.y - y);
      if (s.visible && distance < bestDistance) { best = f; bestDistance = distance; }
    }
    if (best >= 0) select(best);
  });
  $('viewer3d-frame-close').addEventListener('click', function () {
    $('viewer3d-frame').hidden = true;
    if (selectedLines) layers.cameras.remove(selectedLines);
    selectedLines = null;
    render();
  });
  ['points', 'cameras', 'path', 'grid'].forEach(function (name) {
    $('viewer3d-show-' + name).addEventListener('change', function (e) {
      layers[name].visible = e.target.checked;
      render();
    });
  });
  document.querySelectorAll('input[name="viewer3d-color"]').forEach(function (input) {
    input.addEventListener('change', function (e) { setColorMode(e.target.value); });
  });
  setColorMode(d.has_point_colors ? 'image' : 'height');

  window.viosfmViewer = {
    numFrames: d.frames.length,
    render: render,
    setColorMode: function (mode) {
      var input = document.querySelector('input[name="viewer3d-color"][value="' + mode + '"]');
      if (input) input.checked = true;
      setColorMode(mode);
    },
    setVisible: function (name, visible) {
      $('viewer3d-show-' + name).checked = visible;
      layers[name].visible = visible;
      render();
    },
    screenPosition: screenPosition,
    selected: function () {
      var panel = $('viewer3d-frame');
      return panel.hidden ? -1 : Number(panel.getAttribute('data-frame'));
    }
  };
  status.textContent = d.num_points + ' of ' + d.total_points + ' points, ' + d.num_path +
      ' poses, ' + d.frames.length + ' cameras. Drag to rotate, scroll to zoom, right-drag or ' +
      'shift-drag to pan; click a camera to see its image.';
  canvas.setAttribute('data-rendered', 'true');
  // #viewer-selftest-click first clicks (as a user's press and release) the
  // visible frustum nearest the canvas's centre.
  if (window.location.hash === '#viewer-selftest-click') {
    var rect = canvas.getBoundingClientRect(), target = -1, nearest = Infinity;
    for (var f = 0; f < d.frames.length; ++f) {
      var s = screenPosition(f);
      var distance = Math.hypot(s.x - rect.width / 2, s.y - rect.height / 2);
      if (s.visible && distance < nearest) { target = f; nearest = distance; }
    }
    if (target >= 0) {
      var at = screenPosition(target);
      ['pointerdown', 'pointerup'].forEach(function (type) {
        canvas.dispatchEvent(new PointerEvent(type, {clientX: rect.left + at.x,
            clientY: rect.top + at.y, bubbles: true}));
      });
    }
    $('viewer3d-selftest').setAttribute('data-clicked', String(target));
  }
  if (window.location.hash.indexOf('#viewer-selftest') === 0) {
    $('viewer3d-selftest').textContent = canvas.toDataURL('image/png');
  }
})();
)JS";

const char* kViewerStyle = R"CSS(
#viewer3d .controls { font-size: 13px; margin: 6px 0; }
#viewer3d .controls label { margin-right: 10px; }
#viewer3d .stage { position: relative; display: inline-block; max-width: 100%; }
#viewer3d-frame { position: absolute; top: 8px; right: 8px; width: 330px; margin: 0;
  background: rgba(255, 255, 255, 0.95); border: 1px solid #888; padding: 6px; font-size: 12px; }
#viewer3d-frame img { width: 100%; display: block; }
#viewer3d-frame button { float: right; }
#viewer3d-height-legend span { display: inline-block; width: 160px; height: 10px; vertical-align: middle; }
)CSS";

struct Extent {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  double radius = 1.0;
};

// The centre (median per axis of the points, else of the path) and a radius
// holding 90 % of the points and the path.
Extent SceneExtent(const std::vector<Eigen::Vector3d>& points,
                   const std::vector<Eigen::Vector3d>& path) {
  Extent extent;
  const std::vector<Eigen::Vector3d>& reference = points.empty() ? path : points;
  if (reference.empty()) return extent;
  for (int k = 0; k < 3; ++k) {
    std::vector<double> values;
    for (const Eigen::Vector3d& p : reference) values.push_back(p[k]);
    std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
    extent.center[k] = values[values.size() / 2];
  }
  std::vector<double> distances;
  for (const Eigen::Vector3d& p : reference) distances.push_back((p - extent.center).norm());
  for (const Eigen::Vector3d& p : path) distances.push_back((p - extent.center).norm());
  std::sort(distances.begin(), distances.end());
  extent.radius = std::max(1e-3, distances[distances.size() * 9 / 10]);
  return extent;
}
}  // namespace

std::string Viewer3dOptions::Validate() const {
  if (max_points < 1) return "max_points must be >= 1";
  if (max_cameras < 1) return "max_cameras must be >= 1";
  if (thumbnail_width < 0) return "thumbnail_width must be >= 0";
  if (width < 100 || height < 100) return "width and height must be >= 100 px";
  return "";
}

std::vector<size_t> DecimationIndices(size_t n, size_t max_points) {
  VIOSFM_CHECK_GE(max_points, 1u);
  const size_t step = std::max<size_t>(1, (n + max_points - 1) / max_points);
  std::vector<size_t> indices;
  for (size_t i = 0; i < n; i += step) indices.push_back(i);
  return indices;
}

std::vector<size_t> SpreadFrames(const std::vector<Viewer3dFrame>& frames, double min_distance,
                                 double min_turn_deg, size_t max_frames) {
  std::vector<size_t> spread;
  Rigid3d last_world_from_cam;
  for (size_t i = 0; i < frames.size(); ++i) {
    const Rigid3d world_from_cam = frames[i].cam_from_world.Inverse();
    if (!spread.empty()) {
      const double distance = (world_from_cam.translation - last_world_from_cam.translation).norm();
      const double turn_deg =
          world_from_cam.rotation.angularDistance(last_world_from_cam.rotation) * 180.0 / M_PI;
      if (distance < min_distance && turn_deg < min_turn_deg) continue;
    }
    spread.push_back(i);
    last_world_from_cam = world_from_cam;
  }
  std::vector<size_t> kept;
  for (const size_t k : DecimationIndices(spread.size(), max_frames)) kept.push_back(spread[k]);
  return kept;
}

bool HasThreeJs(const Viewer3dOptions& options) {
  std::error_code error;
  return fs::is_regular_file(options.three_js_dir / kThreeFile, error) &&
         fs::is_regular_file(options.three_js_dir / kOrbitControlsFile, error);
}

double GridSpacing(double radius_m) {
  const double target = std::max(radius_m, 1e-6) / 5.0;
  const double magnitude = std::pow(10.0, std::floor(std::log10(target)));
  for (const double factor : {1.0, 2.0, 5.0}) {
    if (factor * magnitude >= target * (1.0 - 1e-9)) return factor * magnitude;
  }
  return 10.0 * magnitude;
}

std::vector<uint8_t> MakeThumbnailJpeg(const fs::path& path, int width) {
  std::error_code error;
  if (width <= 0 || path.empty() || !fs::is_regular_file(path, error)) return {};
  const cv::Mat image = cv::imread(path.string(), cv::IMREAD_COLOR);
  if (image.empty()) return {};
  cv::Mat small = image;
  if (image.cols > width) {
    const int height = std::max(
        1, static_cast<int>(std::lround(static_cast<double>(image.rows) * width / image.cols)));
    cv::resize(image, small, cv::Size(width, height), 0, 0, cv::INTER_AREA);
  }
  std::vector<uint8_t> bytes;
  cv::imencode(".jpg", small, bytes, {cv::IMWRITE_JPEG_QUALITY, 70});
  return bytes;
}

namespace {

// The 3D view's HTML in named steps: the points decimated, the path
// coloured, the heights and the floor grid, the camera frustums with their
// thumbnails, then the scene's JSON and the page's controls and legends.
class Viewer3dRenderer {
 public:
  Viewer3dRenderer(const Viewer3dScene& scene, const Viewer3dOptions& options)
      : scene_(scene), options_(options) {}

  std::string Render() {
    const std::string three = ReadTextFile(options_.three_js_dir / kThreeFile);
    const std::string orbit = ReadTextFile(options_.three_js_dir / kOrbitControlsFile);
    DecimatePoints();
    const Extent extent = SceneExtent(points_, scene_.path);
    center_ = extent.center;
    radius_ = extent.radius;
    ColorPath();
    PlaceHeightsAndGrid();
    AddFrustums();
    std::ostringstream out;
    WriteControls(out);
    WriteLegends(out);
    out << "<pre id=\"viewer3d-selftest\" hidden></pre>\n</div>\n";
    out << "<script>\n" << ScriptSafe(three) << "\n</script>\n";
    out << "<script>\n" << ScriptSafe(orbit) << "\n</script>\n";
    out << "<script>\nvar VIOSFM_SCENE = " << ScriptSafe(SceneJson().dump()) << ";\n"
        << kViewerScript << "</script>\n";
    return out.str();
  }

 private:
  // Decimated points and their colours.
  void DecimatePoints() {
    const std::vector<size_t> kept = DecimationIndices(scene_.points.size(), options_.max_points);
    has_colors_ = !scene_.colors.empty() && scene_.colors.size() == scene_.points.size();
    for (const size_t i : kept) {
      points_.push_back(scene_.points[i]);
      if (has_colors_) {
        colors_.insert(colors_.end(), scene_.colors[i].data(), scene_.colors[i].data() + 3);
      }
    }
  }

  // Path colours: the error on the report's colour map, else one colour.
  void ColorPath() {
    for (const double e : scene_.path_errors_m) max_error_ = std::max(max_error_, e);
    by_error_ = scene_.path_errors_m.size() == scene_.path.size() && !scene_.path.empty();
    for (size_t i = 0; i < scene_.path.size(); ++i) {
      const Color c = by_error_
                          ? ColorMap(max_error_ > 0 ? scene_.path_errors_m[i] / max_error_ : 0.0)
                          : Color{255, 255, 255};
      path_colors_.insert(path_colors_.end(), {c.r, c.g, c.b});
    }
  }

  // Heights: the colour bar spans the 2nd to 98th percentile; the floor grid
  // lies at the 2nd (below the cameras when there are no points).
  void PlaceHeightsAndGrid() {
    std::vector<double> heights;
    for (const Eigen::Vector3d& p : points_) heights.push_back(p.z());
    if (heights.empty()) {
      for (const Eigen::Vector3d& p : scene_.path) heights.push_back(p.z() - 1.0);
    }
    std::sort(heights.begin(), heights.end());
    height_min_ = heights.empty() ? center_.z() : heights[heights.size() * 2 / 100];
    height_max_ = heights.empty() ? center_.z() + 1.0 : heights[heights.size() * 98 / 100];
    if (!(height_max_ > height_min_)) height_max_ = height_min_ + 1.0;
    spacing_ = GridSpacing(radius_);
    grid_half_ = std::ceil(1.6 * radius_ / spacing_) * spacing_;
    // Grid lines on multiples of the spacing in world coordinates.
    grid_center_ = Eigen::Vector2d(std::round(center_.x() / spacing_) * spacing_,
                                   std::round(center_.y() / spacing_) * spacing_);
  }

  // Frustums in the camera's own shape, a fifth of a grid cell deep, spread
  // so that they do not overlap; each frame with its thumbnail.
  void AddFrustums() {
    const double depth = 0.2 * spacing_;
    const std::vector<size_t> frame_indices =
        SpreadFrames(scene_.frames, 1.5 * depth, kMinFrustumTurnDeg, options_.max_cameras);
    const std::array<Eigen::Vector3d, 6> corners = FrustumCorners();
    frames_ = nlohmann::json::array();
    for (const size_t i : frame_indices) {
      const Viewer3dFrame& frame = scene_.frames[i];
      const Rigid3d world_from_cam = frame.cam_from_world.Inverse();
      for (const Eigen::Vector3d& corner : corners) {
        frustum_points_.push_back(world_from_cam * (depth * corner));
      }
      const std::vector<uint8_t> thumbnail =
          MakeThumbnailJpeg(frame.image_path, options_.thumbnail_width);
      frames_.push_back(
          {{"name", frame.name},
           {"time_s", frame.time_s ? nlohmann::json(*frame.time_s) : nlohmann::json()},
           {"image_path", frame.image_path.string()},
           {"thumbnail", Base64(thumbnail)}});
    }
  }

  // The frustum's apex, the image's corners at unit depth and the tick
  // above its top edge (a 4:3 image without intrinsics).
  std::array<Eigen::Vector3d, 6> FrustumCorners() const {
    const Camera& cam = scene_.camera;
    const bool has_intrinsics = cam.width > 0 && cam.height > 0 && cam.HasValidParams();
    const double w = has_intrinsics ? static_cast<double>(cam.width) : 4.0;
    const double h = has_intrinsics ? static_cast<double>(cam.height) : 3.0;
    const auto ray = [&](double u, double v) -> Eigen::Vector3d {
      if (!has_intrinsics) return Eigen::Vector3d((u - 0.5 * w) / w, (v - 0.5 * h) / w, 1.0);
      const Eigen::Vector2d xy = ImageToCam(cam, Eigen::Vector2d(u, v));
      return Eigen::Vector3d(xy.x(), xy.y(), 1.0);
    };
    return {Eigen::Vector3d::Zero(), ray(0, 0), ray(w, 0), ray(w, h), ray(0, h),
            ray(0.5 * w, -0.25 * h)};
  }

  nlohmann::json SceneJson() const {
    const Eigen::Vector3d& c = center_;
    return {{"width", options_.width},
            {"height", options_.height},
            {"radius", radius_},
            {"center", {c.x(), c.y(), c.z()}},
            {"origin", {-c.x(), -c.y(), -c.z()}},
            {"total_points", scene_.points.size()},
            {"num_points", points_.size()},
            {"has_point_colors", has_colors_},
            {"height_min", height_min_ - c.z()},
            {"height_max", height_max_ - c.z()},
            {"num_path", scene_.path.size()},
            {"num_ground_truth", scene_.ground_truth_path.size()},
            {"gravity_up", scene_.gravity_up},
            {"grid",
             {{"spacing", spacing_},
              {"size", 2.0 * grid_half_},
              {"center", {grid_center_.x() - c.x(), grid_center_.y() - c.y()}},
              {"z", height_min_ - c.z()}}},
            {"points", Float32Base64(points_, c)},
            {"point_colors", Base64(colors_)},
            {"path", Float32Base64(scene_.path, c)},
            {"path_colors", Base64(path_colors_)},
            {"ground_truth", Float32Base64(scene_.ground_truth_path, c)},
            {"frustums", Float32Base64(frustum_points_, c)},
            {"frames", frames_}};
  }

  // The colouring and show/hide controls, the canvas and the frame's figure.
  void WriteControls(std::ostringstream& out) const {
    out << "<style>" << kViewerStyle << "</style>\n<div id=\"viewer3d\">\n";
    out << "<div class=\"controls\">Colour the points by <label><input type=\"radio\" "
           "name=\"viewer3d-color\" value=\"height\""
        << (has_colors_ ? "" : " checked") << "> height</label><label><input type=\"radio\" "
        << "name=\"viewer3d-color\" value=\"image\"" << (has_colors_ ? " checked" : " disabled")
        << "> the images' colour</label> &middot; Show ";
    for (const auto& [id, text] :
         {std::pair{"points", "points"}, std::pair{"cameras", "cameras"},
          std::pair{"path", "camera path"}, std::pair{"grid", "grid and axes"}}) {
      out << "<label><input type=\"checkbox\" id=\"viewer3d-show-" << id << "\" checked> " << text
          << "</label>";
    }
    out << "</div>\n<div class=\"stage\">\n<canvas id=\"viewer3d-canvas\" width=\""
        << options_.width << "\" height=\"" << options_.height
        << "\" style=\"width:" << options_.width << "px;height:" << options_.height
        << "px;max-width:100%;border:1px solid #ccc;touch-action:none;display:block\"></canvas>\n";
    out << "<figure id=\"viewer3d-frame\" hidden><button type=\"button\" "
           "id=\"viewer3d-frame-close\">"
           "close</button><figcaption id=\"viewer3d-frame-caption\"></figcaption>"
           "<img id=\"viewer3d-frame-image\" alt=\"the frame's image\"></figure>\n</div>\n";
    out << "<p id=\"viewer3d-status\" class=\"meta\">The 3D view needs JavaScript and WebGL.</p>\n";
  }

  // The grid's, the heights' and the path's legends.
  void WriteLegends(std::ostringstream& out) const {
    out << "<p id=\"viewer3d-legend\" class=\"meta\">Grid: " << Number(spacing_)
        << " m cells at z = " << Number(height_min_)
        << " m (the floor: 2 % of the points lie lower); axes at the "
        << "world's origin, " << Number(spacing_) << " m long: x red, y green, z blue"
        << (scene_.gravity_up ? " (up, against gravity)"
                              : " (the model's; no gravity: images only)")
        << ". Cameras orange, the clicked one yellow; the tick marks the image's top edge.</p>\n";
    out << "<p id=\"viewer3d-height-legend\" class=\"meta\">Points by height: "
        << Number(height_min_) << " m <span style=\"background:linear-gradient(to right";
    for (int i = 0; i <= 8; ++i) out << ", " << ColorMap(i / 8.0).Hex();
    out << ")\"></span> " << Number(height_max_) << " m</p>\n";
    if (by_error_) {
      out << "<p class=\"meta\">Camera path coloured by position error: <span "
             "style=\"display:inline-block;width:160px;height:10px;vertical-align:middle;"
             "background:linear-gradient(to right";
      for (int i = 0; i <= 4; ++i) out << ", " << ColorMap(i / 4.0).Hex();
      out << ")\"></span> 0 to " << Number(max_error_)
          << " m (Sim(3)-aligned); ground truth in grey.</p>\n";
    } else {
      out << "<p class=\"meta\">Camera path in white.</p>\n";
    }
  }

  const Viewer3dScene& scene_;
  const Viewer3dOptions& options_;

  std::vector<Eigen::Vector3d> points_;
  std::vector<uint8_t> colors_;
  bool has_colors_ = false;
  Eigen::Vector3d center_ = Eigen::Vector3d::Zero();
  double radius_ = 0.0;

  double max_error_ = 0.0;
  bool by_error_ = false;
  std::vector<uint8_t> path_colors_;

  double height_min_ = 0.0;
  double height_max_ = 0.0;
  double spacing_ = 0.0;
  double grid_half_ = 0.0;
  Eigen::Vector2d grid_center_ = Eigen::Vector2d::Zero();

  std::vector<Eigen::Vector3d> frustum_points_;
  nlohmann::json frames_;
};

}  // namespace

std::string RenderViewer3d(const Viewer3dScene& scene, const Viewer3dOptions& options) {
  if (const std::string error = options.Validate(); !error.empty()) {
    throw InputError("invalid 3D view options: " + error);
  }
  return Viewer3dRenderer(scene, options).Render();
}

}  // namespace viosfm

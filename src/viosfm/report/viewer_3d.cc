#include "viosfm/report/viewer_3d.h"

#include <algorithm>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "viosfm/report/svg_plot.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;

const char* kThreeFile = "three.min.js";
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

// The viewer; VIOSFM_SCENE holds the data.
const char* kViewerScript = R"JS(
(function () {
  var d = VIOSFM_SCENE;
  var canvas = document.getElementById('viewer3d-canvas');
  var status = document.getElementById('viewer3d-status');
  function decode(text, Type) {
    var s = atob(text), bytes = new Uint8Array(s.length);
    for (var i = 0; i < s.length; ++i) bytes[i] = s.charCodeAt(i);
    return new Type(bytes.buffer);
  }
  function geometry(positions, colors) {
    var g = new THREE.BufferGeometry();
    var set = (g.setAttribute || g.addAttribute).bind(g);
    set('position', new THREE.BufferAttribute(decode(positions, Float32Array), 3));
    if (colors) set('color', new THREE.BufferAttribute(decode(colors, Uint8Array), 3, true));
    return g;
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
  if (d.num_points > 0) {
    scene.add(new THREE.Points(geometry(d.points, d.point_colors),
        new THREE.PointsMaterial({size: 2, sizeAttenuation: false,
                                  vertexColors: THREE.VertexColors})));
  }
  if (d.num_ground_truth > 1) {
    scene.add(new THREE.Line(geometry(d.ground_truth, null),
                             new THREE.LineBasicMaterial({color: 0xb0b0b0})));
  }
  if (d.num_path > 1) {
    scene.add(new THREE.Line(geometry(d.path, d.path_colors),
                             new THREE.LineBasicMaterial({vertexColors: THREE.VertexColors})));
    scene.add(new THREE.Points(geometry(d.path, d.path_colors),
        new THREE.PointsMaterial({size: 4, sizeAttenuation: false,
                                  vertexColors: THREE.VertexColors})));
  }
  var r = d.radius;
  var camera = new THREE.PerspectiveCamera(50, d.width / d.height, r / 1000, r * 100);
  camera.up.set(0, 0, 1);  // the world is gravity-aligned, z up
  camera.position.set(1.0 * r, -1.35 * r, 0.95 * r);
  var controls = new THREE.OrbitControls(camera, canvas);
  controls.target.set(0, 0, 0);
  controls.screenSpacePanning = true;
  function render() { renderer.render(scene, camera); }
  controls.addEventListener('change', render);
  controls.update();
  render();
  status.textContent = d.num_points + ' of ' + d.total_points + ' points, ' + d.num_path +
      ' poses. Drag to rotate, scroll to zoom, right-drag or shift-drag to pan.';
  canvas.setAttribute('data-rendered', 'true');
  if (window.location.hash === '#viewer-selftest') {
    document.getElementById('viewer3d-selftest').textContent = canvas.toDataURL('image/png');
  }
})();
)JS";

}  // namespace

std::string Viewer3dOptions::Validate() const {
  if (max_points < 1) return "max_points must be >= 1";
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

bool HasThreeJs(const Viewer3dOptions& options) {
  std::error_code error;
  return fs::is_regular_file(options.three_js_dir / kThreeFile, error) &&
         fs::is_regular_file(options.three_js_dir / kOrbitControlsFile, error);
}

std::string RenderViewer3d(const Viewer3dScene& scene, const Viewer3dOptions& options) {
  if (const std::string error = options.Validate(); !error.empty()) {
    throw InputError("invalid 3D view options: " + error);
  }
  const std::string three = ReadTextFile(options.three_js_dir / kThreeFile);
  const std::string orbit = ReadTextFile(options.three_js_dir / kOrbitControlsFile);

  // Decimated points and their colours.
  const std::vector<size_t> kept = DecimationIndices(scene.points.size(), options.max_points);
  std::vector<Eigen::Vector3d> points;
  std::vector<uint8_t> colors;
  for (const size_t i : kept) {
    points.push_back(scene.points[i]);
    for (int k = 0; k < 3; ++k) {
      colors.push_back(scene.colors.size() == scene.points.size() ? scene.colors[i][k] : 160);
    }
  }
  // The centre (median per axis of the points, else of the path) and a
  // radius holding 90 % of them.
  const std::vector<Eigen::Vector3d>& reference = points.empty() ? scene.path : points;
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  double radius = 1.0;
  if (!reference.empty()) {
    for (int k = 0; k < 3; ++k) {
      std::vector<double> values;
      for (const Eigen::Vector3d& p : reference) values.push_back(p[k]);
      std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
      center[k] = values[values.size() / 2];
    }
    std::vector<double> distances;
    for (const Eigen::Vector3d& p : reference) distances.push_back((p - center).norm());
    for (const Eigen::Vector3d& p : scene.path) distances.push_back((p - center).norm());
    std::sort(distances.begin(), distances.end());
    radius = std::max(1e-3, distances[distances.size() * 9 / 10]);
  }
  // Path colours: the error on the report's colour map, else one colour.
  double max_error = 0.0;
  for (const double e : scene.path_errors_m) max_error = std::max(max_error, e);
  const bool by_error = scene.path_errors_m.size() == scene.path.size() && !scene.path.empty();
  std::vector<uint8_t> path_colors;
  for (size_t i = 0; i < scene.path.size(); ++i) {
    const Color c = by_error ? ColorMap(max_error > 0 ? scene.path_errors_m[i] / max_error : 0.0)
                             : Color{255, 120, 30};
    path_colors.insert(path_colors.end(), {c.r, c.g, c.b});
  }

  std::ostringstream out;
  out << "<div id=\"viewer3d\">\n<canvas id=\"viewer3d-canvas\" width=\"" << options.width
      << "\" height=\"" << options.height << "\" style=\"width:" << options.width
      << "px;height:" << options.height
      << "px;max-width:100%;border:1px solid #ccc;touch-action:none\"></canvas>\n";
  out << "<p id=\"viewer3d-status\" class=\"meta\">The 3D view needs JavaScript and WebGL.</p>\n";
  if (by_error) {
    out << "<p class=\"meta\">Camera path coloured by position error: <span "
           "style=\"display:inline-block;width:160px;height:10px;vertical-align:middle;"
           "background:linear-gradient(to right";
    for (int i = 0; i <= 4; ++i) out << ", " << ColorMap(i / 4.0).Hex();
    out << ")\"></span> 0 to " << Number(max_error)
        << " m (Sim(3)-aligned); ground truth in grey.</p>\n";
  }
  out << "<pre id=\"viewer3d-selftest\" hidden></pre>\n</div>\n";
  out << "<script>\n" << ScriptSafe(three) << "\n</script>\n";
  out << "<script>\n" << ScriptSafe(orbit) << "\n</script>\n";
  out << "<script>\nvar VIOSFM_SCENE = {"
      << "width: " << options.width << ", height: " << options.height
      << ", radius: " << Number(radius) << ", center: [" << Number(center.x()) << ", "
      << Number(center.y()) << ", " << Number(center.z()) << "]"
      << ", total_points: " << scene.points.size() << ", num_points: " << points.size()
      << ", num_path: " << scene.path.size()
      << ", num_ground_truth: " << scene.ground_truth_path.size() << ",\n  points: \""
      << Float32Base64(points, center) << "\",\n  point_colors: \"" << Base64(colors)
      << "\",\n  path: \"" << Float32Base64(scene.path, center) << "\",\n  path_colors: \""
      << Base64(path_colors) << "\",\n  ground_truth: \""
      << Float32Base64(scene.ground_truth_path, center) << "\"};\n"
      << kViewerScript << "</script>\n";
  return out.str();
}

}  // namespace viosfm

#include "viosfm/sim/scene_model.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "viosfm/io/image_io.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/string_util.h"

namespace viosfm {

uint64_t MixSeed(uint64_t seed, uint64_t index) {
  uint64_t z = seed + 0x9e3779b97f4a7c15ULL * (index + 1);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

Texture MakeSurfaceTexture(double size_u, double size_v, double texels_per_metre, uint64_t seed,
                           const ProceduralTextureOptions& style) {
  ProceduralTextureOptions options = style;
  options.width =
      std::max(8, NextPowerOfTwo(static_cast<int>(std::ceil(size_u * texels_per_metre))));
  options.height =
      std::max(8, NextPowerOfTwo(static_cast<int>(std::ceil(size_v * texels_per_metre))));
  options.seed = seed;
  return MakeProceduralTexture(options);
}

std::vector<Texture> LoadPhotoTextures(const std::filesystem::path& folder, int size) {
  std::error_code error;
  if (!std::filesystem::is_directory(folder, error)) {
    throw InputError(folder.string(), 0, "texture folder not found (expected a folder of images)");
  }
  const std::vector<std::string> extensions = {".png", ".jpg",  ".jpeg", ".bmp",
                                               ".tif", ".tiff", ".pgm",  ".ppm"};
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(folder)) {
    if (!entry.is_regular_file()) continue;
    const std::string extension = ToLower(entry.path().extension().string());
    if (std::find(extensions.begin(), extensions.end(), extension) != extensions.end()) {
      files.push_back(entry.path());
    }
  }
  if (files.empty()) {
    throw InputError(folder.string(), 0,
                     "texture folder holds no image (expected .png, .jpg, .jpeg, .bmp, .tif, "
                     ".tiff, .pgm or .ppm files)");
  }
  std::sort(files.begin(), files.end(), [](const auto& a, const auto& b) {
    return a.filename().string() < b.filename().string();
  });
  std::vector<Texture> textures;
  for (const std::filesystem::path& file : files) {
    textures.push_back(TextureFromImage(ReadGreyImage(file), size));
  }
  return textures;
}

Texture MakeSurfaceTextureFrom(const PhotoTextures& photos, int surface_index, double size_u,
                               double size_v, double texels_per_metre, uint64_t seed,
                               const ProceduralTextureOptions& style) {
  if (photos == nullptr || photos->empty()) {
    return MakeSurfaceTexture(size_u, size_v, texels_per_metre, seed, style);
  }
  VIOSFM_CHECK_GE(surface_index, 0);
  const Texture& photo = (*photos)[static_cast<size_t>(surface_index) % photos->size()];
  const int width =
      std::min(photo.width(),
               NextPowerOfTwo(std::max(1, static_cast<int>(std::ceil(size_u * texels_per_metre)))));
  const int height =
      std::min(photo.height(),
               NextPowerOfTwo(std::max(1, static_cast<int>(std::ceil(size_v * texels_per_metre)))));
  const uint64_t offset = MixSeed(seed, 0x70686f746fULL);
  const int i0 = static_cast<int>(offset % static_cast<uint64_t>(photo.width()));
  const int j0 = static_cast<int>((offset >> 32) % static_cast<uint64_t>(photo.height()));
  return CropTexture(photo, i0, j0, width, height);
}

namespace {

// Adds a quad with its own texture (surface number surface_index of the scene).
void AddTexturedQuad(Scene& scene, const Eigen::Vector3d& origin, const Eigen::Vector3d& axis_u,
                     const Eigen::Vector3d& axis_v, double texels_per_metre, uint64_t seed,
                     const PhotoTextures& photos = nullptr, int surface_index = 0) {
  TexturedQuad quad;
  quad.origin = origin;
  quad.axis_u = axis_u;
  quad.axis_v = axis_v;
  quad.texels_per_metre = texels_per_metre;
  quad.texture_id = scene.AddTexture(MakeSurfaceTextureFrom(photos, surface_index, axis_u.norm(),
                                                            axis_v.norm(), texels_per_metre, seed));
  scene.AddQuad(quad);
}

}  // namespace

int Scene::AddTexture(Texture texture) {
  VIOSFM_CHECK_GT(texture.width(), 0);
  textures_.push_back(std::move(texture));
  return static_cast<int>(textures_.size()) - 1;
}

int Scene::AddQuad(const TexturedQuad& quad) {
  VIOSFM_CHECK(quad.texture_id >= 0 && quad.texture_id < static_cast<int>(textures_.size()))
      << "quad texture id " << quad.texture_id << " does not exist";
  VIOSFM_CHECK_GT(quad.texels_per_metre, 0.0);
  QuadFrame frame;
  frame.length_u = quad.axis_u.norm();
  frame.length_v = quad.axis_v.norm();
  VIOSFM_CHECK(frame.length_u > 0.0 && frame.length_v > 0.0) << "degenerate quad";
  frame.unit_u = quad.axis_u / frame.length_u;
  frame.unit_v = quad.axis_v / frame.length_v;
  VIOSFM_CHECK_LT(std::abs(frame.unit_u.dot(frame.unit_v)), 1e-9) << "quad axes not orthogonal";
  frame.normal = frame.unit_u.cross(frame.unit_v).normalized();
  frame.offset = frame.normal.dot(quad.origin);
  quads_.push_back(quad);
  frames_.push_back(frame);
  return static_cast<int>(quads_.size()) - 1;
}

void Scene::AddBox(const Eigen::Vector3d& min, const Eigen::Vector3d& max, double texels_per_metre,
                   uint64_t seed, const PhotoTextures& photos, int first_surface) {
  const Eigen::Vector3d size = max - min;
  VIOSFM_CHECK((size.array() > 0.0).all()) << "box with an empty extent";
  const Eigen::Vector3d dx(size.x(), 0, 0);
  const Eigen::Vector3d dy(0, size.y(), 0);
  const Eigen::Vector3d dz(0, 0, size.z());
  // Sides: u horizontal, v vertical; then the top.
  AddTexturedQuad(*this, min, dx, dz, texels_per_metre, MixSeed(seed, 0), photos,
                  first_surface + 0);
  AddTexturedQuad(*this, min + dy, dx, dz, texels_per_metre, MixSeed(seed, 1), photos,
                  first_surface + 1);
  AddTexturedQuad(*this, min, dy, dz, texels_per_metre, MixSeed(seed, 2), photos,
                  first_surface + 2);
  AddTexturedQuad(*this, min + dx, dy, dz, texels_per_metre, MixSeed(seed, 3), photos,
                  first_surface + 3);
  AddTexturedQuad(*this, min + dz, dx, dy, texels_per_metre, MixSeed(seed, 4), photos,
                  first_surface + 4);
}

int Scene::AddSurfaceWithOpenings(const Eigen::Vector3d& origin, const Eigen::Vector3d& axis_u,
                                  const Eigen::Vector3d& axis_v, int texture_id,
                                  double texels_per_metre,
                                  const std::vector<SurfaceRect>& openings) {
  const double length_u = axis_u.norm();
  const double length_v = axis_v.norm();
  VIOSFM_CHECK(length_u > 0.0 && length_v > 0.0) << "degenerate surface";
  const Eigen::Vector3d unit_u = axis_u / length_u;
  const Eigen::Vector3d unit_v = axis_v / length_v;
  // Columns between consecutive opening edges; in each column, the v
  // intervals that no opening covers.
  std::vector<double> cuts = {0.0, length_u};
  for (const SurfaceRect& opening : openings) {
    VIOSFM_CHECK(opening.u0 < opening.u1 && opening.v0 < opening.v1) << "empty opening";
    cuts.push_back(std::clamp(opening.u0, 0.0, length_u));
    cuts.push_back(std::clamp(opening.u1, 0.0, length_u));
  }
  std::sort(cuts.begin(), cuts.end());
  cuts.erase(std::unique(cuts.begin(), cuts.end()), cuts.end());
  int added = 0;
  for (size_t c = 0; c + 1 < cuts.size(); ++c) {
    const double u0 = cuts[c];
    const double u1 = cuts[c + 1];
    if (u1 - u0 < 1e-9) continue;
    const double middle = 0.5 * (u0 + u1);
    std::vector<std::pair<double, double>> holes;
    for (const SurfaceRect& opening : openings) {
      if (opening.u0 < middle && middle < opening.u1) {
        holes.emplace_back(std::max(opening.v0, 0.0), std::min(opening.v1, length_v));
      }
    }
    std::sort(holes.begin(), holes.end());
    double v = 0.0;
    holes.emplace_back(length_v, length_v);
    for (const auto& [hole_begin, hole_end] : holes) {
      if (hole_begin - v > 1e-9) {
        TexturedQuad quad;
        quad.origin = origin + u0 * unit_u + v * unit_v;
        quad.axis_u = (u1 - u0) * unit_u;
        quad.axis_v = (hole_begin - v) * unit_v;
        quad.texture_id = texture_id;
        quad.texels_per_metre = texels_per_metre;
        quad.texture_offset = Eigen::Vector2d(u0, v);
        AddQuad(quad);
        ++added;
      }
      v = std::max(v, hole_end);
    }
  }
  return added;
}

void Scene::IntersectQuad(size_t k, const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                          double t_min, RayHit* best) const {
  const QuadFrame& frame = frames_[k];
  const double denominator = frame.normal.dot(direction);
  if (std::abs(denominator) < 1e-12) return;
  const double t = (frame.offset - frame.normal.dot(origin)) / denominator;
  if (!(t > t_min) || t >= best->t) return;
  const Eigen::Vector3d relative = origin + t * direction - quads_[k].origin;
  const double u = relative.dot(frame.unit_u);
  if (u < 0.0 || u > frame.length_u) return;
  const double v = relative.dot(frame.unit_v);
  if (v < 0.0 || v > frame.length_v) return;
  best->t = t;
  best->quad_id = static_cast<int>(k);
  best->u = u;
  best->v = v;
  best->cos_incidence = std::abs(denominator);
}

std::optional<RayHit> Scene::Intersect(const Eigen::Vector3d& origin,
                                       const Eigen::Vector3d& direction, double t_min) const {
  RayHit best;
  best.t = std::numeric_limits<double>::infinity();
  for (size_t k = 0; k < frames_.size(); ++k) IntersectQuad(k, origin, direction, t_min, &best);
  if (best.quad_id < 0) return std::nullopt;
  return best;
}

std::optional<RayHit> Scene::Intersect(const Eigen::Vector3d& origin,
                                       const Eigen::Vector3d& direction, double t_min,
                                       const std::vector<int>& candidates) const {
  RayHit best;
  best.t = std::numeric_limits<double>::infinity();
  for (const int k : candidates) IntersectQuad(k, origin, direction, t_min, &best);
  if (best.quad_id < 0) return std::nullopt;
  return best;
}

Eigen::Vector3d Scene::PointOnQuad(int quad_id, double u, double v) const {
  VIOSFM_CHECK(quad_id >= 0 && quad_id < static_cast<int>(quads_.size()));
  const QuadFrame& frame = frames_[quad_id];
  return quads_[quad_id].origin + u * frame.unit_u + v * frame.unit_v;
}

std::string RoomSceneOptions::Validate() const {
  const Eigen::Vector3d size = room_max - room_min;
  if (!(size.x() >= 3.0 && size.y() >= 3.0))
    return "room_min/room_max: the room must be >= 3 m wide";
  if (!(size.z() >= 2.5)) return "room_min/room_max: the room must be >= 2.5 m high";
  if (!(texels_per_metre > 0.0 && texels_per_metre <= 2048.0)) {
    return "texels_per_metre must be in (0, 2048]";
  }
  return "";
}

Scene MakeRoomScene(const RoomSceneOptions& options) {
  VIOSFM_CHECK(options.Check()) << options.Validate();
  Scene scene;
  const Eigen::Vector3d& lo = options.room_min;
  const Eigen::Vector3d& hi = options.room_max;
  const Eigen::Vector3d size = hi - lo;
  const double tpm = options.texels_per_metre;
  const Eigen::Vector3d dx(size.x(), 0, 0);
  const Eigen::Vector3d dy(0, size.y(), 0);
  const Eigen::Vector3d dz(0, 0, size.z());
  uint64_t surface = 0;
  const auto next_seed = [&]() { return MixSeed(options.seed, surface++); };
  int photo_surface = 0;  // surfaces textured so far

  AddTexturedQuad(scene, lo, dx, dy, tpm, next_seed(), options.photos, photo_surface++);  // floor
  AddTexturedQuad(scene, lo + dz, dx, dy, tpm, next_seed(), options.photos,
                  photo_surface++);  // ceiling
  AddTexturedQuad(scene, lo, dx, dz, tpm, next_seed(), options.photos,
                  photo_surface++);  // wall y = min
  AddTexturedQuad(scene, lo + dy, dx, dz, tpm, next_seed(), options.photos,
                  photo_surface++);  // wall y = max
  AddTexturedQuad(scene, lo, dy, dz, tpm, next_seed(), options.photos,
                  photo_surface++);  // wall x = min
  AddTexturedQuad(scene, lo + dx, dy, dz, tpm, next_seed(), options.photos,
                  photo_surface++);  // wall x = max

  if (options.furniture) {
    // Boxes in a strip at most 0.7 m deep along the walls: (wall, depth,
    // start and end as fractions of the wall, height). Walls: 0 = +x, 1 = +y,
    // 2 = -x, 3 = -y.
    struct Furniture {
      int wall;
      double depth, from, to, height;
    };
    const Furniture furniture[] = {
        {0, 0.60, 0.30, 0.55, 0.90},                               // cabinet facing the start pose
        {0, 0.55, 0.70, 0.88, 1.60},                               // shelf
        {1, 0.55, 0.15, 0.40, 1.10},                               // desk-like block
        {1, 0.65, 0.60, 0.75, 2.20},                               // wardrobe
        {2, 0.60, 0.55, 0.80, 0.70},                               // low chest
        {2, 0.50, 0.10, 0.30, 1.40}, {3, 0.45, 0.30, 0.55, 1.80},  // bookcase
        {3, 0.60, 0.75, 0.92, 1.00},
    };
    for (const Furniture& item : furniture) {
      Eigen::Vector3d min = lo;
      Eigen::Vector3d max = lo;
      max.z() = lo.z() + item.height;
      switch (item.wall) {
        case 0:  // +x
          min.x() = hi.x() - item.depth;
          max.x() = hi.x() - 0.02;
          min.y() = lo.y() + item.from * size.y();
          max.y() = lo.y() + item.to * size.y();
          break;
        case 1:  // +y
          min.y() = hi.y() - item.depth;
          max.y() = hi.y() - 0.02;
          min.x() = lo.x() + item.from * size.x();
          max.x() = lo.x() + item.to * size.x();
          break;
        case 2:  // -x
          min.x() = lo.x() + 0.02;
          max.x() = lo.x() + item.depth;
          min.y() = lo.y() + item.from * size.y();
          max.y() = lo.y() + item.to * size.y();
          break;
        default:  // -y
          min.y() = lo.y() + 0.02;
          max.y() = lo.y() + item.depth;
          min.x() = lo.x() + item.from * size.x();
          max.x() = lo.x() + item.to * size.x();
          break;
      }
      scene.AddBox(min, max, tpm, next_seed(), options.photos, photo_surface);
      photo_surface += 5;
    }
  }
  return scene;
}

}  // namespace viosfm

// Synthetic scenes for the renderer: textured planar rectangles, ray casting
// against them, and the "room" preset.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "viosfm/sim/texture.h"

namespace viosfm {

// Textures made from photos (TextureFromImage), shared read-only by the
// scenes built from them; null or empty: procedural textures.
using PhotoTextures = std::shared_ptr<const std::vector<Texture>>;

// A rectangle origin + a * axis_u + b * axis_v, a, b in [0, 1]. axis_u and
// axis_v are its edges (metres) and must be orthogonal. Surface coordinates
// (u, v) are metres from the origin along the two edges; the texture is laid
// out with texel = (u, v) * texels_per_metre (so it tiles if the rectangle is
// larger than the texture).
struct TexturedQuad {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d axis_u = Eigen::Vector3d::UnitX();
  Eigen::Vector3d axis_v = Eigen::Vector3d::UnitY();
  int texture_id = 0;
  double texels_per_metre = 100.0;
  // Metres added to (u, v) before the texture lookup, so that pieces of one
  // surface (a wall cut around a doorway) continue one texture seamlessly.
  Eigen::Vector2d texture_offset = Eigen::Vector2d::Zero();
};

struct RayHit {
  double t = 0.0;              // distance along the (unit) ray direction, metres
  int quad_id = -1;            // index into Scene::quads()
  double u = 0.0;              // metres along axis_u from the quad's origin
  double v = 0.0;              // metres along axis_v
  double cos_incidence = 1.0;  // |cos| of the angle between the ray and the quad normal
};

// An axis-aligned rectangle [u0, u1] x [v0, v1] in a quad's surface
// coordinates (metres), e.g. a doorway cut out of a wall.
struct SurfaceRect {
  double u0 = 0.0;
  double u1 = 0.0;
  double v0 = 0.0;
  double v1 = 0.0;
};

class Scene {
 public:
  // Returns the id of the added texture / quad. A quad's axes must be
  // orthogonal and non-degenerate and its texture must exist (checked).
  int AddTexture(Texture texture);
  int AddQuad(const TexturedQuad& quad);
  // Adds the five faces (no bottom) of the axis-aligned box [min, max], each
  // with its own procedural texture of the given seed base and resolution.
  // With photos, face k shows MakeSurfaceTextureFrom(photos, first_surface + k, ...).
  void AddBox(const Eigen::Vector3d& min, const Eigen::Vector3d& max, double texels_per_metre,
              uint64_t seed, const PhotoTextures& photos = nullptr, int first_surface = 0);
  // Adds the rectangle origin + [0, 1] axis_u + [0, 1] axis_v with the
  // `openings` (surface coordinates, metres; they must not overlap) left
  // out: it is cut into pieces that share texture_id with continuous texture
  // coordinates. Returns the number of quads added.
  int AddSurfaceWithOpenings(const Eigen::Vector3d& origin, const Eigen::Vector3d& axis_u,
                             const Eigen::Vector3d& axis_v, int texture_id, double texels_per_metre,
                             const std::vector<SurfaceRect>& openings);

  const std::vector<TexturedQuad>& quads() const { return quads_; }
  const std::vector<Texture>& textures() const { return textures_; }
  const Texture& texture(int texture_id) const { return textures_[texture_id]; }

  // Nearest hit with t > t_min of the ray origin + t * direction (direction
  // must have unit norm); nullopt if the ray misses every quad. Quads are
  // two-sided.
  std::optional<RayHit> Intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                                  double t_min = 1e-6) const;
  // The same, testing only the quads in `candidates` (e.g. those in a view
  // frustum).
  std::optional<RayHit> Intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                                  double t_min, const std::vector<int>& candidates) const;

  // Point in the world of surface coordinates (u, v) of a quad.
  Eigen::Vector3d PointOnQuad(int quad_id, double u, double v) const;

 private:
  // Updates `best` if quad k is hit nearer than best->t.
  void IntersectQuad(size_t k, const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                     double t_min, RayHit* best) const;
  // Per-quad data precomputed for intersection.
  struct QuadFrame {
    Eigen::Vector3d normal;  // unit
    double offset = 0.0;     // normal . origin
    Eigen::Vector3d unit_u;
    Eigen::Vector3d unit_v;
    double length_u = 0.0;
    double length_v = 0.0;
  };
  std::vector<Texture> textures_;
  std::vector<TexturedQuad> quads_;
  std::vector<QuadFrame> frames_;
};

// Independent seeds derived from one (SplitMix64 finaliser of seed and index).
uint64_t MixSeed(uint64_t seed, uint64_t index);

// A procedural texture (style: every option but width, height and seed) that
// covers size_u x size_v metres at texels_per_metre without repeating.
Texture MakeSurfaceTexture(double size_u, double size_v, double texels_per_metre, uint64_t seed,
                           const ProceduralTextureOptions& style = {});

// Every image (.png, .jpg, .jpeg, .bmp, .tif, .tiff, .pgm, .ppm, any case) of
// `folder`, sorted by file name, as size x size textures (size a power of
// two). Throws InputError naming the folder if it is not a folder or holds
// no image, and naming the file if one cannot be read.
std::vector<Texture> LoadPhotoTextures(const std::filesystem::path& folder, int size);

// The texture of surface number `surface_index` of a scene, covering
// size_u x size_v metres at texels_per_metre. With photos: a window of photo
// (surface_index mod count), as large as the surface needs (powers of two,
// at most the photo; larger surfaces tile the photo), starting at a texel
// offset drawn from `seed`, so surfaces sharing a photo show different parts
// of it. Without: MakeSurfaceTexture(size_u, size_v, texels_per_metre, seed,
// style).
Texture MakeSurfaceTextureFrom(const PhotoTextures& photos, int surface_index, double size_u,
                               double size_v, double texels_per_metre, uint64_t seed,
                               const ProceduralTextureOptions& style = {});

struct RoomSceneOptions {
  Eigen::Vector3d room_min{-4.0, -4.0, 0.0};  // m, inside of the walls (floor at z = 0)
  Eigen::Vector3d room_max{4.0, 4.0, 3.0};    // m
  double texels_per_metre = 128.0;            // texture resolution on every surface
  bool furniture = true;                      // boxes along the walls (outside [-3.2, 3.2]^2)
  uint64_t seed = 0;                          // textures are derived from it
  PhotoTextures photos;  // non-empty: surface k shows photo k mod count (default: procedural)

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }
};

// A room (floor, ceiling, four walls, z up) with furniture-like boxes placed
// along the walls, leaving the default walk box [-3, 3] x [-3, 3] x [0.8, 2]
// free. Every surface has its own procedural texture, large enough that it
// does not repeat across the surface.
Scene MakeRoomScene(const RoomSceneOptions& options);

}  // namespace viosfm

#include "viosfm/sim/scenarios.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>

#include "viosfm/util/errors.h"

namespace viosfm {
namespace {

using Eigen::Vector3d;

constexpr double kEyeHeight = 1.4;     // m, body height above the floor while walking
constexpr double kStoreyHeight = 3.5;  // m, two_floors: floor 2 is this much above floor 1
constexpr double kRoomHeight = 3.0;    // m, two_floors: floor to ceiling

// Texture styles.
ProceduralTextureOptions RichStyle() {
  return ProceduralTextureOptions{};
}

// Smooth, low-contrast, low-detail (painted plaster, concrete): value noise
// only, sampled at a coarse resolution, contrast `contrast` about `mean`.
Texture WeakTexture(double size_u, double size_v, double texels_per_metre, uint64_t seed,
                    float mean, float contrast) {
  ProceduralTextureOptions style;
  style.blobs_per_megatexel = 0;
  style.posters_per_megatexel = 0;
  style.text_blocks_per_megatexel = 0;
  return WithContrast(MakeSurfaceTexture(size_u, size_v, texels_per_metre, seed, style), mean,
                      contrast);
}

// Adds quads sharing textures; keeps a running seed counter.
class SceneBuilder {
 public:
  SceneBuilder(Scene* scene, uint64_t seed, PhotoTextures photos)
      : scene_(scene), seed_(seed), photos_(std::move(photos)) {}

  uint64_t NextSeed() { return MixSeed(seed_, counter_++); }

  // A richly textured surface's texture (a photo if the scenario has them).
  Texture SurfaceTexture(double size_u, double size_v, double tpm,
                         const ProceduralTextureOptions& style) {
    return MakeSurfaceTextureFrom(photos_, photo_surface_++, size_u, size_v, tpm, NextSeed(),
                                  style);
  }
  int RichTexture(double size_u, double size_v, double tpm) {
    return scene_->AddTexture(SurfaceTexture(size_u, size_v, tpm, RichStyle()));
  }
  int WeakTextureId(double size_u, double size_v, double tpm, float mean, float contrast) {
    return scene_->AddTexture(WeakTexture(size_u, size_v, tpm, NextSeed(), mean, contrast));
  }

  void Quad(const Vector3d& origin, const Vector3d& axis_u, const Vector3d& axis_v, int texture_id,
            double tpm) {
    TexturedQuad quad;
    quad.origin = origin;
    quad.axis_u = axis_u;
    quad.axis_v = axis_v;
    quad.texture_id = texture_id;
    quad.texels_per_metre = tpm;
    scene_->AddQuad(quad);
  }

  // Five textures for the sides (x-facing, y-facing) and top of a box of
  // the given size.
  std::array<int, 5> BoxTextures(const Vector3d& size, double tpm) {
    return {RichTexture(size.x(), size.z(), tpm), RichTexture(size.x(), size.z(), tpm),
            RichTexture(size.y(), size.z(), tpm), RichTexture(size.y(), size.z(), tpm),
            RichTexture(size.x(), size.y(), tpm)};
  }
  // The box [min, max] (no bottom; no top if with_top is false).
  void Box(const Vector3d& min, const Vector3d& max, const std::array<int, 5>& textures, double tpm,
           bool with_top = true) {
    const Vector3d size = max - min;
    const Vector3d dx(size.x(), 0, 0);
    const Vector3d dy(0, size.y(), 0);
    const Vector3d dz(0, 0, size.z());
    Quad(min, dx, dz, textures[0], tpm);
    Quad(min + dy, dx, dz, textures[1], tpm);
    Quad(min, dy, dz, textures[2], tpm);
    Quad(min + dx, dy, dz, textures[3], tpm);
    if (with_top) Quad(min + dz, dx, dy, textures[4], tpm);
  }

  Scene& scene() { return *scene_; }

 private:
  Scene* scene_;
  uint64_t seed_;
  PhotoTextures photos_;
  uint64_t counter_ = 0;
  int photo_surface_ = 0;  // richly textured surfaces so far
};

Eigen::AlignedBox3d Box(const Vector3d& min, const Vector3d& max) {
  return Eigen::AlignedBox3d(min, max);
}

// ---------------------------------------------------------------- room

Scenario MakeRoom(const ScenarioOptions& options) {
  Scenario scenario;
  RoomSceneOptions room;
  room.texels_per_metre = options.texels_per_metre;
  room.seed = options.seed;
  room.photos = options.photos;
  scenario.scene = MakeRoomScene(room);
  scenario.regions.push_back({"room", 0, Box(room.room_min, room.room_max)});
  return scenario;
}

// ----------------------------------------------------------------- mav

// The room, flown: a faster, more rotating random walk than a hand's, and
// the accelerometer vibrating.
Scenario MakeMav(const ScenarioOptions& options) {
  Scenario scenario = MakeRoom(options);
  WalkOptions flight;
  flight.speed_mps = 0.5;
  flight.knot_spacing_s = 0.5;
  flight.turn_stddev_rad = 0.2;
  flight.height_stddev_m = 0.15;
  flight.look_around_rad = 0.5;
  flight.pitch_roll_stddev_rad = 0.12;
  scenario.walk_style = flight;
  scenario.vibration.accel_rms_mps2 = 1.2;
  return scenario;
}

// ---------------------------------------------------------- two_floors
//
// Plan (both floors): room [-4, 4]^2 x [z0, z0 + 3] with a pillar in the
// middle and furniture along the walls; its wall x = 4 has two doorways,
// y in [-3.5, -2.1] and [2.1, 3.5], 2.2 m high, into the stairwell
// x in [4.05, 6], y in [-4, 4], z in [0, 6.5]. The stairs climb along +y
// from y = -2 (z = 0) to y = 1.9 (z = 3.5), 14 steps of 0.3 x 0.25 m, onto a
// landing at z = 3.5. Floor 1 is entered from the lower doorway, floor 2
// from the upper one.

constexpr double kDoorLowY0 = -3.5, kDoorLowY1 = -2.1;
constexpr double kDoorHighY0 = 2.1, kDoorHighY1 = 3.5;
constexpr double kDoorwayHeight = 2.2;
constexpr double kShaftX0 = 4.05, kShaftX1 = 6.0;
constexpr double kShaftTop = 6.5;
constexpr double kStairStartY = -2.0, kStairRun = 0.3, kStairRise = 0.25;
constexpr int kNumSteps = 14;

// The stairs' landing starts where the last step's tread would end (y = 1.9).
constexpr double kLandingY = kStairStartY + (kNumSteps - 1) * kStairRun;

// Both floors' rooms: one set of textures, used by both.
void AddTwoFloorsRooms(SceneBuilder& builder, double tpm) {
  const int floor_texture = builder.RichTexture(8, 8, tpm);
  const int ceiling_texture = builder.RichTexture(8, 8, tpm);
  const int wall_south = builder.RichTexture(8, kRoomHeight, tpm);
  const int wall_north = builder.RichTexture(8, kRoomHeight, tpm);
  const int wall_west = builder.RichTexture(8, kRoomHeight, tpm);
  const int wall_east = builder.RichTexture(8, kRoomHeight, tpm);
  struct Furniture {
    Vector3d min, max;
  };
  const Furniture furniture[] = {
      {{-3.0, 3.40, 0}, {-1.6, 3.98, 1.8}},    // bookcase, north wall
      {{0.4, 3.45, 0}, {2.0, 3.98, 0.9}},      // cabinet, north wall
      {{-1.0, -3.98, 0}, {1.2, -3.40, 1.1}},   // desk, south wall
      {{-3.98, -2.0, 0}, {-3.40, -0.2, 2.0}},  // wardrobe, west wall
      {{-3.98, 1.0, 0}, {-3.45, 2.2, 0.8}},    // chest, west wall
      {{3.40, -1.2, 0}, {3.98, 0.8, 1.3}},     // shelf between the doorways, east wall
  };
  std::vector<std::array<int, 5>> furniture_textures;
  for (const Furniture& item : furniture) {
    furniture_textures.push_back(builder.BoxTextures(item.max - item.min, tpm));
  }
  const std::array<int, 5> pillar_textures = builder.BoxTextures({0.6, 0.6, kRoomHeight}, tpm);

  for (int floor = 0; floor < 2; ++floor) {
    const Vector3d z0(0, 0, floor * kStoreyHeight);
    builder.Quad(Vector3d(-4, -4, 0) + z0, {8, 0, 0}, {0, 8, 0}, floor_texture, tpm);
    builder.Quad(Vector3d(-4, -4, kRoomHeight) + z0, {8, 0, 0}, {0, 8, 0}, ceiling_texture, tpm);
    builder.Quad(Vector3d(-4, -4, 0) + z0, {8, 0, 0}, {0, 0, kRoomHeight}, wall_south, tpm);
    builder.Quad(Vector3d(-4, 4, 0) + z0, {8, 0, 0}, {0, 0, kRoomHeight}, wall_north, tpm);
    builder.Quad(Vector3d(-4, -4, 0) + z0, {0, 8, 0}, {0, 0, kRoomHeight}, wall_west, tpm);
    builder.scene().AddSurfaceWithOpenings(Vector3d(4, -4, 0) + z0, {0, 8, 0}, {0, 0, kRoomHeight},
                                           wall_east, tpm,
                                           {{kDoorLowY0 + 4, kDoorLowY1 + 4, 0, kDoorwayHeight},
                                            {kDoorHighY0 + 4, kDoorHighY1 + 4, 0, kDoorwayHeight}});
    for (size_t k = 0; k < std::size(furniture); ++k) {
      builder.Box(furniture[k].min + z0, furniture[k].max + z0, furniture_textures[k], tpm);
    }
    builder.Box(Vector3d(-0.3, -0.3, 0) + z0, Vector3d(0.3, 0.3, kRoomHeight) + z0, pillar_textures,
                tpm, /*with_top=*/false);
  }
}

// The stairwell, its stairs and landing: weak textures everywhere.
void AddStairwell(SceneBuilder& builder, double weak_tpm) {
  const double shaft_width = kShaftX1 - kShaftX0;
  const int shaft_wall = builder.WeakTextureId(8, kShaftTop, weak_tpm, 0.62f, 0.08f);
  const int shaft_floor = builder.WeakTextureId(2, 8, weak_tpm, 0.45f, 0.08f);
  const int tread_texture = builder.WeakTextureId(2, 8, weak_tpm, 0.50f, 0.06f);
  const int riser_texture = builder.WeakTextureId(2, 4, weak_tpm, 0.58f, 0.06f);
  builder.Quad({4.0, -4, 0}, {2.0, 0, 0}, {0, 8, 0}, shaft_floor, weak_tpm);
  builder.Quad({4.0, -4, kShaftTop}, {2.0, 0, 0}, {0, 8, 0}, shaft_wall, weak_tpm);
  builder.Quad({kShaftX1, -4, 0}, {0, 8, 0}, {0, 0, kShaftTop}, shaft_wall, weak_tpm);
  builder.Quad({kShaftX0, -4, 0}, {shaft_width, 0, 0}, {0, 0, kShaftTop}, shaft_wall, weak_tpm);
  builder.Quad({kShaftX0, 4, 0}, {shaft_width, 0, 0}, {0, 0, kShaftTop}, shaft_wall, weak_tpm);
  std::vector<SurfaceRect> doorways;
  for (int floor = 0; floor < 2; ++floor) {
    const double v0 = floor * kStoreyHeight;
    doorways.push_back({kDoorLowY0 + 4, kDoorLowY1 + 4, v0, v0 + kDoorwayHeight});
    doorways.push_back({kDoorHighY0 + 4, kDoorHighY1 + 4, v0, v0 + kDoorwayHeight});
  }
  builder.scene().AddSurfaceWithOpenings({kShaftX0, -4, 0}, {0, 8, 0}, {0, 0, kShaftTop},
                                         shaft_wall, weak_tpm, doorways);
  for (int k = 0; k < kNumSteps; ++k) {
    const double y = kStairStartY + k * kStairRun;
    builder.Quad({kShaftX0, y, k * kStairRise}, {shaft_width, 0, 0}, {0, 0, kStairRise},
                 riser_texture, weak_tpm);
    if (k + 1 < kNumSteps) {
      builder.Quad({kShaftX0, y, (k + 1) * kStairRise}, {shaft_width, 0, 0}, {0, kStairRun, 0},
                   tread_texture, weak_tpm);
    }
  }
  const double landing_y = kLandingY;
  builder.Quad({kShaftX0, landing_y, kStoreyHeight}, {shaft_width, 0, 0}, {0, 4 - landing_y, 0},
               tread_texture, weak_tpm);
  // Underside of the flight, 0.25 m below the step nosings, and the fascia
  // below the landing.
  const double soffit_y0 = kStairStartY + kStairRun;
  const Vector3d soffit_axis(0, landing_y - soffit_y0,
                             (landing_y - soffit_y0) * kStairRise / kStairRun);
  builder.Quad({kShaftX0, soffit_y0, 0}, {shaft_width, 0, 0}, soffit_axis, riser_texture, weak_tpm);
  builder.Quad({kShaftX0, landing_y, soffit_axis.z()}, {shaft_width, 0, 0},
               {0, 0, kStoreyHeight - kStairRise - soffit_axis.z()}, riser_texture, weak_tpm);
}

Scenario MakeTwoFloors(const ScenarioOptions& options) {
  Scenario scenario;
  scenario.storey_height_m = kStoreyHeight;
  SceneBuilder builder(&scenario.scene, options.seed, options.photos);
  AddTwoFloorsRooms(builder, options.texels_per_metre);
  AddStairwell(builder, std::min(24.0, options.texels_per_metre));

  // Route: one loop of floor 1 (A B C D A), on past B out through the
  // lower doorway, up the stairs, in through the upper doorway to C, and one
  // loop of floor 2 (C D A B C) over the same plan in the same direction.
  const double e = kEyeHeight;
  const double door_low = 0.5 * (kDoorLowY0 + kDoorLowY1);     // -2.8
  const double door_high = 0.5 * (kDoorHighY0 + kDoorHighY1);  // 2.8
  const double shaft_x = 0.5 * (kShaftX0 + kShaftX1);
  const double s = kStoreyHeight;
  const Vector3d a(-2.5, door_low, e), b(2.5, door_low, e), c(2.5, door_high, e),
      d(-2.5, door_high, e);
  const Vector3d up(0, 0, s);
  scenario.route = {a,
                    b,
                    c,
                    d,
                    a,
                    {shaft_x, door_low, e},
                    {shaft_x, kStairStartY - 0.3, e},
                    {shaft_x, kLandingY - 0.1, s + e},
                    {shaft_x, door_high, s + e},
                    c + up,
                    d + up,
                    a + up,
                    b + up,
                    c + up};
  scenario.regions = {
      {"floor1", 0, Box({-4, -4, 0}, {4, 4, kRoomHeight})},
      {"floor2", 1, Box({-4, -4, s}, {4, 4, s + kRoomHeight})},
      {"stairwell", -1, Box({4, -4, 0}, {kShaftX1, 4, kShaftTop})},
  };
  return scenario;
}

// ------------------------------------------------------------ corridor
//
// Ring corridor between the outer rectangle [-12, 12] x [-8, 8] and the
// inner block [-10, 10] x [-6, 6], 2.8 m high; identical doors every 4 m on
// both walls.

constexpr double kOuterX = 12, kOuterY = 8, kInnerX = 10, kInnerY = 6, kCorridorHeight = 2.8;

Scenario MakeCorridor(const ScenarioOptions& options) {
  Scenario scenario;
  SceneBuilder builder(&scenario.scene, options.seed, options.photos);
  const double tpm = options.texels_per_metre;
  const double floor_tpm = 0.5 * tpm;
  // Walls: a plain painted look (mild texture); floor and ceiling textured.
  ProceduralTextureOptions wall_style;
  wall_style.blobs_per_megatexel = 400;
  wall_style.posters_per_megatexel = 15;
  wall_style.text_blocks_per_megatexel = 15;
  const auto wall = [&](const Vector3d& origin, const Vector3d& axis_u) {
    const int texture = builder.scene().AddTexture(WithContrast(
        builder.SurfaceTexture(axis_u.norm(), kCorridorHeight, tpm, wall_style), 0.6f, 0.6f));
    builder.Quad(origin, axis_u, {0, 0, kCorridorHeight}, texture, tpm);
  };
  wall({-kOuterX, -kOuterY, 0}, {2 * kOuterX, 0, 0});
  wall({-kOuterX, kOuterY, 0}, {2 * kOuterX, 0, 0});
  wall({-kOuterX, -kOuterY, 0}, {0, 2 * kOuterY, 0});
  wall({kOuterX, -kOuterY, 0}, {0, 2 * kOuterY, 0});
  wall({-kInnerX, -kInnerY, 0}, {2 * kInnerX, 0, 0});
  wall({-kInnerX, kInnerY, 0}, {2 * kInnerX, 0, 0});
  wall({-kInnerX, -kInnerY, 0}, {0, 2 * kInnerY, 0});
  wall({kInnerX, -kInnerY, 0}, {0, 2 * kInnerY, 0});
  const double width = kOuterY - kInnerY;
  for (const double z : {0.0, kCorridorHeight}) {
    const double strip_tpm = z == 0.0 ? floor_tpm : 0.5 * floor_tpm;
    const auto strip = [&](const Vector3d& origin, const Vector3d& axis_u, const Vector3d& axis_v) {
      builder.Quad(origin, axis_u, axis_v,
                   builder.RichTexture(axis_u.norm(), axis_v.norm(), strip_tpm), strip_tpm);
    };
    strip({-kOuterX, -kOuterY, z}, {2 * kOuterX, 0, 0}, {0, width, 0});
    strip({-kOuterX, kInnerY, z}, {2 * kOuterX, 0, 0}, {0, width, 0});
    strip({-kOuterX, -kInnerY, z}, {width, 0, 0}, {0, 2 * kInnerY, 0});
    strip({kInnerX, -kInnerY, z}, {width, 0, 0}, {0, 2 * kInnerY, 0});
  }
  // Doors: 1 x 2 m, 1 cm in front of the wall, texture u to the right of a
  // viewer facing the door.
  const int door_texture = builder.scene().AddTexture(MakeDoorTexture(MixSeed(options.seed, 9001)));
  const auto door = [&](const Vector3d& center_on_wall, const Vector3d& normal) {
    const Vector3d right = (-normal).cross(Vector3d::UnitZ());
    builder.Quad(center_on_wall + 0.01 * normal - 0.5 * right, right, {0, 0, 2.0}, door_texture,
                 256.0);
  };
  for (const double x : {-8.0, -4.0, 0.0, 4.0, 8.0}) {
    door({x, -kOuterY, 0}, Vector3d::UnitY());
    door({x, kOuterY, 0}, -Vector3d::UnitY());
  }
  for (const double x : {-6.0, -2.0, 2.0, 6.0}) {
    door({x, -kInnerY, 0}, -Vector3d::UnitY());
    door({x, kInnerY, 0}, Vector3d::UnitY());
  }
  for (const double y : {-4.0, 0.0, 4.0}) {
    door({-kOuterX, y, 0}, Vector3d::UnitX());
    door({kOuterX, y, 0}, -Vector3d::UnitX());
  }
  for (const double y : {-2.0, 2.0}) {
    door({-kInnerX, y, 0}, -Vector3d::UnitX());
    door({kInnerX, y, 0}, Vector3d::UnitX());
  }
  // Route: once round (south, east, north, west) and on along the south
  // side past the start, closing the loop.
  const double x = 0.5 * (kOuterX + kInnerX);
  const double y = 0.5 * (kOuterY + kInnerY);
  const double e = kEyeHeight;
  scenario.route = {{-8, -y, e}, {x, -y, e}, {x, y, e}, {-x, y, e}, {-x, -y, e}, {-2, -y, e}};
  scenario.regions = {
      {"south", 0, Box({-kOuterX, -kOuterY, 0}, {kOuterX, -kInnerY, kCorridorHeight})},
      {"east", 0, Box({kInnerX, -kInnerY, 0}, {kOuterX, kInnerY, kCorridorHeight})},
      {"north", 0, Box({-kOuterX, kInnerY, 0}, {kOuterX, kOuterY, kCorridorHeight})},
      {"west", 0, Box({-kOuterX, -kInnerY, 0}, {-kInnerX, kInnerY, kCorridorHeight})},
  };
  return scenario;
}

// ---------------------------------------------------------------- dark
//
// Tunnel [-12, 12] x [-1.5, 1.5] x [0, 3]; x in [-3, 3] almost textureless.

constexpr double kTunnelX = 12, kTunnelY = 1.5, kTunnelHeight = 3, kBlankX = 3;

Scenario MakeDark(const ScenarioOptions& options) {
  Scenario scenario;
  SceneBuilder builder(&scenario.scene, options.seed, options.photos);
  const double tpm = options.texels_per_metre;
  const double blank_tpm = std::min(16.0, tpm);
  const double width = 2 * kTunnelY;
  const double section = kTunnelX - kBlankX;  // length of each textured section
  // Long surfaces as (origin at x = 0 offset, axis_v): floor, ceiling, two walls.
  struct Surface {
    Vector3d origin;  // at x = -kTunnelX
    Vector3d axis_v;
  };
  const Surface surfaces[] = {
      {{-kTunnelX, -kTunnelY, 0}, {0, width, 0}},
      {{-kTunnelX, -kTunnelY, kTunnelHeight}, {0, width, 0}},
      {{-kTunnelX, -kTunnelY, 0}, {0, 0, kTunnelHeight}},
      {{-kTunnelX, kTunnelY, 0}, {0, 0, kTunnelHeight}},
  };
  for (const Surface& surface : surfaces) {
    const double size_v = surface.axis_v.norm();
    builder.Quad(surface.origin, {section, 0, 0}, surface.axis_v,
                 builder.RichTexture(section, size_v, tpm), tpm);
    builder.Quad(surface.origin + Vector3d(section, 0, 0), {2 * kBlankX, 0, 0}, surface.axis_v,
                 builder.WeakTextureId(2 * kBlankX, size_v, blank_tpm, 0.55f, 0.02f), blank_tpm);
    builder.Quad(surface.origin + Vector3d(section + 2 * kBlankX, 0, 0), {section, 0, 0},
                 surface.axis_v, builder.RichTexture(section, size_v, tpm), tpm);
  }
  builder.Quad({-kTunnelX, -kTunnelY, 0}, {0, width, 0}, {0, 0, kTunnelHeight},
               builder.RichTexture(width, kTunnelHeight, tpm), tpm);
  builder.Quad({kTunnelX, -kTunnelY, 0}, {0, width, 0}, {0, 0, kTunnelHeight},
               builder.RichTexture(width, kTunnelHeight, tpm), tpm);

  scenario.render.exposure_gain = 0.3;
  scenario.render.noise_sigma = 5.0;
  scenario.render.vignetting = 0.5;
  scenario.render.distance_falloff = 0.15;  // a head lamp: far surfaces are darker
  scenario.render.motion_blur_samples = 5;
  scenario.exposure_time_s = 0.02;
  const double e = 1.3;
  scenario.route = {
      {-10.5, -0.5, e}, {10.5, -0.5, e}, {11.2, 0, e}, {10.5, 0.5, e}, {-10.5, 0.5, e}};
  scenario.regions = {
      {"blank", 0, Box({-kBlankX, -kTunnelY, 0}, {kBlankX, kTunnelY, kTunnelHeight})},
      {"west", 0, Box({-kTunnelX, -kTunnelY, 0}, {-kBlankX, kTunnelY, kTunnelHeight})},
      {"east", 0, Box({kBlankX, -kTunnelY, 0}, {kTunnelX, kTunnelY, kTunnelHeight})},
  };
  return scenario;
}

}  // namespace

int Scenario::RegionIndex(const Eigen::Vector3d& point) const {
  for (size_t k = 0; k < regions.size(); ++k) {
    if (regions[k].box.contains(point)) return static_cast<int>(k);
  }
  return -1;
}

std::vector<std::string> AvailableScenarios() {
  return {"room", "two_floors", "corridor", "dark", "mav"};
}

std::string ScenarioOptions::Validate() const {
  const auto names = AvailableScenarios();
  if (std::find(names.begin(), names.end(), name) == names.end()) {
    std::string list;
    for (const auto& known : names) list += (list.empty() ? "" : ", ") + known;
    return "scenario '" + name + "' is unknown (available: " + list + ")";
  }
  if (!(texels_per_metre >= 8.0 && texels_per_metre <= 1024.0)) {
    return "texels_per_metre must be in [8, 1024]";
  }
  return "";
}

Scenario MakeScenario(const ScenarioOptions& options) {
  if (const std::string error = options.Validate(); !error.empty()) {
    throw InputError("scenario options: " + error);
  }
  Scenario scenario;
  if (options.name == "room") {
    scenario = MakeRoom(options);
  } else if (options.name == "two_floors") {
    scenario = MakeTwoFloors(options);
  } else if (options.name == "corridor") {
    scenario = MakeCorridor(options);
  } else if (options.name == "mav") {
    scenario = MakeMav(options);
  } else {
    scenario = MakeDark(options);
  }
  scenario.name = options.name;
  return scenario;
}

SceneStructure ScenarioStructure(const Scenario& scenario) {
  SceneStructure structure;
  const std::vector<TexturedQuad>& quads = scenario.scene.quads();
  for (size_t k = 0; k < quads.size(); ++k) {
    const TexturedQuad& quad = quads[k];
    SceneStructureQuad out;
    out.id = static_cast<int>(k);
    const int region = scenario.RegionIndex(quad.origin + 0.5 * (quad.axis_u + quad.axis_v));
    out.region = region >= 0 ? scenario.regions[region].name : "none";
    out.floor = region >= 0 ? scenario.regions[region].floor : -1;
    out.texture_id = quad.texture_id;
    out.origin = quad.origin;
    out.axis_u = quad.axis_u;
    out.axis_v = quad.axis_v;
    structure.push_back(std::move(out));
  }
  return structure;
}

BodyTrajectory GenerateScenarioMotion(const Scenario& scenario,
                                      const ScenarioMotionOptions& options) {
  if (scenario.route.empty()) {
    WalkOptions walk = scenario.walk_style ? *scenario.walk_style : options.walk;
    walk.duration_s = options.duration_s;
    walk.static_start_s = options.static_start_s;
    walk.box_min = scenario.walk_box_min;
    walk.box_max = scenario.walk_box_max;
    walk.start_ns = options.start_ns;
    walk.seed = options.seed;
    return GenerateWalk(walk);
  }
  RouteWalkOptions walk;
  walk.waypoints = scenario.route;
  walk.duration_s = options.duration_s;
  walk.static_start_s = options.static_start_s;
  walk.speed_mps = options.speed_mps;
  walk.start_ns = options.start_ns;
  walk.seed = options.seed;
  return GenerateRouteWalk(walk);
}

double SurfaceClearance(const Scene& scene, const Eigen::Vector3d& point) {
  double clearance = std::numeric_limits<double>::infinity();
  bool escaped = false;
  for (int dx = -1; dx <= 1; ++dx) {
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dz = -1; dz <= 1; ++dz) {
        if (dx == 0 && dy == 0 && dz == 0) continue;
        const Vector3d direction = Vector3d(dx, dy, dz).normalized();
        const std::optional<RayHit> hit = scene.Intersect(point, direction, 0.0);
        if (!hit) {
          escaped = true;
        } else {
          clearance = std::min(clearance, hit->t);
        }
      }
    }
  }
  return escaped ? std::numeric_limits<double>::infinity() : clearance;
}

Texture MakeDoorTexture(uint64_t seed) {
  constexpr int kWidth = 256;   // texels over 1 m
  constexpr int kHeight = 512;  // texels over 2 m
  constexpr double kTpm = 256.0;
  ProceduralTextureOptions grain;
  grain.width = kWidth;
  grain.height = kHeight;
  grain.seed = seed;
  grain.posters_per_megatexel = 0;
  grain.text_blocks_per_megatexel = 0;
  grain.blobs_per_megatexel = 300;
  const Texture base = MakeProceduralTexture(grain);
  std::vector<float> texels(static_cast<size_t>(kWidth) * kHeight);
  // Rectangles in metres (u right, v up from the floor).
  const auto inside = [](double u, double v, double u0, double u1, double v0, double v1) {
    return u >= u0 && u < u1 && v >= v0 && v < v1;
  };
  for (int j = 0; j < kHeight; ++j) {
    for (int i = 0; i < kWidth; ++i) {
      const double u = (i + 0.5) / kTpm;
      const double v = (j + 0.5) / kTpm;
      float value = 0.35f + 0.3f * base.Texel(0, i, j);         // wood-like leaf
      if (!inside(u, v, 0.06, 0.94, 0.0, 1.94)) value = 0.12f;  // dark frame
      // Two raised panels: bright top-left bevel, dark bottom-right bevel.
      for (const auto& [v0, v1] : {std::pair{0.15, 0.90}, std::pair{1.10, 1.80}}) {
        if (inside(u, v, 0.18, 0.82, v0, v1) && !inside(u, v, 0.20, 0.80, v0 + 0.02, v1 - 0.02)) {
          value = (u < 0.20 || v > v1 - 0.02) ? 0.85f : 0.2f;
        }
      }
      // Handle and its rose, and a small sign.
      const double handle = std::hypot(u - 0.86, v - 1.0);
      if (handle < 0.045) value = handle < 0.03 ? 0.92f : 0.1f;
      if (inside(u, v, 0.38, 0.62, 1.86, 1.92)) value = 0.9f;
      if (inside(u, v, 0.40, 0.60, 1.88, 1.90) && (i / 4) % 2 == 0) value = 0.15f;
      texels[static_cast<size_t>(j) * kWidth + i] = value;
    }
  }
  return Texture(kWidth, kHeight, std::move(texels));
}

}  // namespace viosfm

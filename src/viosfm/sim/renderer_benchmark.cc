// Rendering speed: frames per second of the `room` scenario at the EuRoC
// camera's 752x480, with the rows of each frame split over 1 or 2 threads.
// The scene, the ray table and the camera poses are built once, outside the
// timed loop; each iteration renders one frame (noise, vignetting and the
// scenario's exposure included) from the next of 21 poses one second apart
// on the default walk in the room (each run lasts >= 2 s, so it cycles
// through all of them).
#include <benchmark/benchmark.h>

#include <vector>

#include "viosfm/sim/renderer.h"
#include "viosfm/sim/scenarios.h"
#include "viosfm/sim/sequence_simulator.h"

namespace viosfm {
namespace {

struct RoomFixture {
  Scenario scenario;
  RayTable rays;
  std::vector<Rigid3d> cam_from_world;  // one pose a second of a 20 s walk
};

RoomFixture MakeRoomFixture() {
  RoomFixture room;
  room.scenario = MakeScenario(ScenarioOptions{});
  const SimulationOptions options;  // camera and extrinsics of the simulator
  room.rays = RayTable(options.camera);
  ScenarioMotionOptions motion;
  motion.duration_s = 20.0;
  motion.static_start_s = 0.0;
  const BodyTrajectory walk = GenerateScenarioMotion(room.scenario, motion);
  for (timestamp_ns_t t = walk.start_ns(); t <= walk.end_ns(); t += 1'000'000'000) {
    room.cam_from_world.push_back((walk.WorldFromBody(t) * options.body_from_cam).Inverse());
  }
  return room;
}

const RoomFixture& Room() {
  static const RoomFixture fixture = MakeRoomFixture();
  return fixture;
}

void BM_RenderRoom752x480(benchmark::State& state) {
  const RoomFixture& room = Room();
  RenderOptions options = room.scenario.render;
  options.num_threads = static_cast<int>(state.range(0));
  size_t frame = 0;
  for (auto _ : state) {
    options.seed = frame;
    GreyImage image = Render(room.scenario.scene, room.rays,
                             room.cam_from_world[frame % room.cam_from_world.size()], options);
    benchmark::DoNotOptimize(image.pixels.data());
    ++frame;
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_RenderRoom752x480)
    ->Arg(1)
    ->Arg(2)
    ->ArgName("threads")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(2.0);

}  // namespace
}  // namespace viosfm

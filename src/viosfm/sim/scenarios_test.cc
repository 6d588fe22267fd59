#include "viosfm/sim/scenarios.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <set>

#include "viosfm/io/euroc.h"
#include "viosfm/io/image_io.h"
#include "viosfm/sim/sequence_simulator.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {
namespace fs = std::filesystem;

// The default camera at a quarter of the resolution (fast renders).
Camera SmallCamera() {
  Camera camera = SimulationOptions::DefaultCamera();
  camera.width = 188;
  camera.height = 120;
  for (int k = 0; k < 4; ++k) camera.params[k] *= 0.25;
  camera.params[2] = (SimulationOptions::DefaultCamera().params[2] + 0.5) * 0.25 - 0.5;
  camera.params[3] = (SimulationOptions::DefaultCamera().params[3] + 0.5) * 0.25 - 0.5;
  return camera;
}

// A short, coarse sequence: 3 s (1 s static) at 2 Hz, small images.
SimulationOptions ShortOptions(const std::string& scenario) {
  SimulationOptions options;
  options.scenario = scenario;
  options.duration_s = 3.0;
  options.static_start_s = 1.0;
  options.camera_rate_hz = 2.0;
  options.texels_per_metre = 32.0;
  options.camera = SmallCamera();
  options.seed = 11;
  return options;
}

// Camera at `center` looking along `forward` (horizontal), image y down.
Rigid3d LookingAlong(const Eigen::Vector3d& center, const Eigen::Vector3d& forward) {
  const Eigen::Vector3d z = forward.normalized();
  const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();  // right
  const Eigen::Vector3d y = z.cross(x);                                      // down
  Eigen::Matrix3d world_from_cam;
  world_from_cam << x, y, z;
  return Rigid3d(Eigen::Quaterniond(world_from_cam), center).Inverse();
}

// Normalised cross-correlation of the pixels of a and b inside the central
// `fraction` of the image (1: whole image).
double Ncc(const GreyImage& a, const GreyImage& b, double fraction = 1.0) {
  const int x0 = static_cast<int>(a.width * (1 - fraction) / 2);
  const int y0 = static_cast<int>(a.height * (1 - fraction) / 2);
  double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0, n = 0;
  for (int y = y0; y < a.height - y0; ++y) {
    for (int x = x0; x < a.width - x0; ++x) {
      const double va = a.at(x, y);
      const double vb = b.at(x, y);
      sa += va;
      sb += vb;
      saa += va * va;
      sbb += vb * vb;
      sab += va * vb;
      n += 1;
    }
  }
  const double cov = sab / n - (sa / n) * (sb / n);
  const double var_a = saa / n - (sa / n) * (sa / n);
  const double var_b = sbb / n - (sb / n) * (sb / n);
  return cov / std::sqrt(var_a * var_b);
}

std::string FileBytes(const fs::path& path) {
  std::ifstream stream(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(stream), std::istreambuf_iterator<char>());
}

class EveryScenario : public ::testing::TestWithParam<std::string> {};

// Over a full 60 s walk (two seeds) the camera stays in the plan's regions,
// at least 0.2 m from every surface, and never crosses a surface between
// frames.
TEST_P(EveryScenario, CameraStaysInFreeSpace) {
  ScenarioOptions scenario_options;
  scenario_options.name = GetParam();
  scenario_options.texels_per_metre = 8.0;  // geometry only
  const Scenario scenario = MakeScenario(scenario_options);
  for (const uint64_t seed : {0, 1}) {
    ScenarioMotionOptions motion_options;
    motion_options.seed = seed;
    const BodyTrajectory motion = GenerateScenarioMotion(scenario, motion_options);
    const Rigid3d body_from_cam = SimulationOptions::DefaultBodyFromCam();
    std::set<int> regions;
    double min_clearance = 1e9;
    Eigen::Vector3d previous = Eigen::Vector3d::Constant(std::nan(""));
    for (timestamp_ns_t t = motion.start_ns(); t <= motion.end_ns(); t += 50'000'000) {
      const Eigen::Vector3d center = (motion.WorldFromBody(t) * body_from_cam).translation;
      const int region = scenario.RegionIndex(center);
      ASSERT_GE(region, 0) << GetParam() << " seed " << seed << ": camera outside the plan at "
                           << center.transpose();
      regions.insert(region);
      const double clearance = SurfaceClearance(scenario.scene, center);
      min_clearance = std::min(min_clearance, clearance);
      ASSERT_GE(clearance, 0.2) << GetParam() << " seed " << seed << " at " << center.transpose();
      if (previous.allFinite() && (center - previous).norm() > 1e-9) {
        const Eigen::Vector3d step = center - previous;
        const auto hit = scenario.scene.Intersect(previous, step.normalized(), 0.0);
        ASSERT_TRUE(hit.has_value());
        EXPECT_GT(hit->t, step.norm() + 0.2)
            << GetParam() << ": a surface ahead of the motion at " << center.transpose();
      }
      previous = center;
    }
    // Every region of the plan is visited.
    EXPECT_EQ(regions.size(), scenario.regions.size()) << GetParam();
    std::cout << GetParam() << " (" << scenario.scene.quads().size() << " quads) seed " << seed
              << ": min clearance " << min_clearance << " m\n";
  }
}

// A short sequence renders, is written in the EuRoC layout and reads back
// with its images; every PNG is the frame's render; frames.csv lists the
// regions.
TEST_P(EveryScenario, WritesAReadableSequenceWithImages) {
  const SimulationOptions options = ShortOptions(GetParam());
  const SimulatedSequence simulated = SimulateSequence(options);
  ASSERT_EQ(simulated.sequence.images.size(), 7u);  // 3 s at 2 Hz, both ends
  const fs::path out = testing::MakeScratchFolder("scenario_" + GetParam());
  WriteSimulatedSequence(out, simulated, options);
  const Sequence read = ReadEurocDataset(out);
  ASSERT_EQ(read.images.size(), simulated.sequence.images.size());
  EXPECT_EQ(read.images[3].timestamp_ns, simulated.sequence.images[3].timestamp_ns);
  EXPECT_EQ(read.ground_truth.size(), read.images.size());
  EXPECT_EQ(read.rig.camera.width, 188u);
  const RayTable rays(options.camera);
  for (const size_t k : {size_t{0}, size_t{6}}) {
    const GreyImage image = ReadGreyImage(read.images[k].path);
    EXPECT_EQ(image.pixels, RenderSimulatedFrame(simulated, rays, k, options).pixels);
  }
  // A rendered image is not blank.
  const GreyImage last = ReadGreyImage(read.images.back().path);
  const auto [lo, hi] = std::minmax_element(last.pixels.begin(), last.pixels.end());
  EXPECT_GT(*hi - *lo, 30);
  std::ifstream frames(out / "frames.csv");
  std::string line;
  int rows = 0;
  std::getline(frames, line);
  EXPECT_EQ(line.rfind("#timestamp [ns],region,floor", 0), 0u);
  while (std::getline(frames, line)) {
    ++rows;
    EXPECT_EQ(line.find(",none,"), std::string::npos) << line;
  }
  EXPECT_EQ(rows, 7);
}

// Same options, same PNG bytes (also when rows instead of frames are split
// over the threads).
TEST_P(EveryScenario, SameSeedSameImageBytes) {
  SimulationOptions options = ShortOptions(GetParam());
  options.duration_s = 1.5;
  const fs::path a = testing::MakeScratchFolder("determinism_a_" + GetParam());
  const fs::path b = testing::MakeScratchFolder("determinism_b_" + GetParam());
  WriteSimulatedSequence(a, SimulateSequence(options), options);
  options.threads_over_frames = false;
  WriteSimulatedSequence(b, SimulateSequence(options), options);
  int compared = 0;
  for (const auto& entry : fs::directory_iterator(a / "mav0/cam0/data")) {
    const std::string bytes = FileBytes(entry.path());
    ASSERT_FALSE(bytes.empty());
    EXPECT_EQ(bytes, FileBytes(b / "mav0/cam0/data" / entry.path().filename()))
        << entry.path().filename();
    ++compared;
  }
  EXPECT_EQ(compared, 4);
}

INSTANTIATE_TEST_SUITE_P(Scenarios, EveryScenario,
                         ::testing::Values("room", "two_floors", "corridor", "dark", "mav"));

// mav: the room flown at 0.5 m/s, more pitch than the handheld walk, and its
// accelerometer vibrating once the motion starts; the room's scene.
TEST(Mav, FliesTheRoomAndVibrates) {
  ScenarioOptions scenario_options;
  scenario_options.name = "mav";
  scenario_options.texels_per_metre = 8.0;
  const Scenario mav = MakeScenario(scenario_options);
  scenario_options.name = "room";
  const Scenario room = MakeScenario(scenario_options);
  EXPECT_EQ(mav.scene.quads().size(), room.scene.quads().size());
  ASSERT_TRUE(mav.walk_style.has_value());
  EXPECT_GT(mav.vibration.accel_rms_mps2, 1.0);
  ScenarioMotionOptions motion_options;
  motion_options.duration_s = 30.0;
  const BodyTrajectory motion = GenerateScenarioMotion(mav, motion_options);
  const timestamp_ns_t from = motion.start_ns() + SecondsToNs(motion_options.static_start_s);
  const double path = motion.PathLength(from, motion.end_ns());
  const double speed = path / NsToSeconds(motion.end_ns() - from);
  EXPECT_NEAR(speed, 0.5, 0.1);  // EuRoC's Vicon-room flights: 0.3 to 0.9 m/s

  SimulationOptions options = ShortOptions("mav");
  options.render_images = false;
  const SimulatedSequence vibrating = SimulateSequence(options);
  options.scenario = "room";
  options.walk = *mav.walk_style;
  // The same walk without vibration: the room's scene and the mav's walk
  // differ only in the accelerometer's readings once the motion starts.
  const SimulatedSequence still = SimulateSequence(options);
  ASSERT_EQ(still.sequence.imu.size(), vibrating.sequence.imu.size());
  double before_sq = 0.0;
  double after_sq = 0.0;
  for (size_t k = 0; k < still.sequence.imu.size(); ++k) {
    const double difference =
        (vibrating.sequence.imu[k].accel - still.sequence.imu[k].accel).squaredNorm();
    const bool moving = still.sequence.imu[k].timestamp_ns >=
                        still.motion.start_ns() + SecondsToNs(options.static_start_s);
    (moving ? after_sq : before_sq) += difference;
    EXPECT_EQ(still.sequence.imu[k].gyro, vibrating.sequence.imu[k].gyro);
  }
  EXPECT_EQ(before_sq, 0.0);
  EXPECT_GT(after_sq, 0.0);
}

// two_floors, the repeated-structure trap: a floor-1 view and the same view
// 3.5 m higher on floor 2 look the same; a view 1 m aside does not.
void ExpectFloorTwoRepeatsFloorOne(const PhotoTextures& photos) {
  ScenarioOptions scenario_options;
  scenario_options.name = "two_floors";
  scenario_options.texels_per_metre = 64.0;
  scenario_options.photos = photos;
  const Scenario scenario = MakeScenario(scenario_options);
  const RayTable rays(SmallCamera());
  RenderOptions render = scenario.render;
  // A floor-1 pose of the walk, looking along -x (away from the doorways).
  ScenarioMotionOptions motion_options;
  const BodyTrajectory motion = GenerateScenarioMotion(scenario, motion_options);
  const Rigid3d body_from_cam = SimulationOptions::DefaultBodyFromCam();
  Rigid3d world_from_cam;
  bool found = false;
  for (timestamp_ns_t t = motion.start_ns(); t <= motion.end_ns() && !found; t += 100'000'000) {
    world_from_cam = motion.WorldFromBody(t) * body_from_cam;
    const Eigen::Vector3d forward = world_from_cam.rotation * Eigen::Vector3d::UnitZ();
    found = scenario.regions[scenario.RegionIndex(world_from_cam.translation)].name == "floor1" &&
            forward.x() < -0.9;
  }
  ASSERT_TRUE(found);
  const Rigid3d floor1 = world_from_cam.Inverse();
  Rigid3d up = world_from_cam;
  up.translation.z() += scenario.storey_height_m;
  Rigid3d aside = world_from_cam;
  aside.translation.y() += 1.0;
  render.seed = 1;
  const GreyImage image1 = Render(scenario.scene, rays, floor1, render);
  render.seed = 2;  // other sensor noise
  const GreyImage image2 = Render(scenario.scene, rays, up.Inverse(), render);
  const GreyImage image_aside = Render(scenario.scene, rays, aside.Inverse(), render);
  const double ncc_floors = Ncc(image1, image2);
  const double ncc_aside = Ncc(image1, image_aside);
  std::cout << "NCC floor 1 vs floor 2: " << ncc_floors << ", vs 1 m aside: " << ncc_aside << "\n";
  EXPECT_GT(ncc_floors, 0.9);
  EXPECT_LT(ncc_aside, 0.5);
}

TEST(TwoFloors, FloorTwoRepeatsFloorOne) {
  ExpectFloorTwoRepeatsFloorOne(nullptr);
}

// With photo textures (three 256 x 256 stand-ins) the floors still share
// every texture.
TEST(TwoFloors, FloorTwoRepeatsFloorOneWithPhotoTextures) {
  auto photos = std::make_shared<std::vector<Texture>>();
  for (uint64_t seed = 0; seed < 3; ++seed) {
    ProceduralTextureOptions options;
    options.width = options.height = 256;
    options.seed = 100 + seed;
    photos->push_back(MakeProceduralTexture(options));
  }
  ExpectFloorTwoRepeatsFloorOne(photos);
}

// corridor: two different doors seen from the same relative pose look the
// same; the wall between doors does not.
TEST(Corridor, DoorsLookAlike) {
  ScenarioOptions scenario_options;
  scenario_options.name = "corridor";
  scenario_options.texels_per_metre = 32.0;
  const Scenario scenario = MakeScenario(scenario_options);
  const RayTable rays(SmallCamera());
  RenderOptions render = scenario.render;
  const Eigen::Vector3d forward = -Eigen::Vector3d::UnitY();  // facing the outer south wall
  render.seed = 1;
  const GreyImage door_a =
      Render(scenario.scene, rays, LookingAlong({-4, -7, 1.3}, forward), render);
  render.seed = 2;
  const GreyImage door_b =
      Render(scenario.scene, rays, LookingAlong({4, -7, 1.3}, forward), render);
  const GreyImage wall = Render(scenario.scene, rays, LookingAlong({-6, -7, 1.3}, forward), render);
  // The central 40 % of the image sees only the door (1 m wide, at 1 m).
  const double ncc_doors = Ncc(door_a, door_b, 0.4);
  const double ncc_wall = Ncc(door_a, wall, 0.4);
  std::cout << "NCC door vs door: " << ncc_doors << ", door vs wall: " << ncc_wall << "\n";
  EXPECT_GT(ncc_doors, 0.9);
  EXPECT_LT(ncc_wall, 0.5);
}

// dark: dimmer and noisier than room at a comparable view. Noise is measured
// from two renders that differ only in the noise seed.
TEST(Dark, DimmerAndNoisierThanRoom) {
  const auto mean_and_snr = [](const std::string& name) {
    ScenarioOptions scenario_options;
    scenario_options.name = name;
    scenario_options.texels_per_metre = 32.0;
    const Scenario scenario = MakeScenario(scenario_options);
    const RayTable rays(SmallCamera());
    RenderOptions render = scenario.render;
    // 3 m from an end wall (dark) or a side wall (room), looking at it.
    const Rigid3d pose = name == "dark" ? LookingAlong({9, 0, 1.3}, Eigen::Vector3d::UnitX())
                                        : LookingAlong({1, 0, 1.3}, Eigen::Vector3d::UnitX());
    render.seed = 1;
    const GreyImage a = Render(scenario.scene, rays, pose, render);
    render.seed = 2;
    const GreyImage b = Render(scenario.scene, rays, pose, render);
    double sum = 0, sum_sq_diff = 0;
    for (size_t k = 0; k < a.pixels.size(); ++k) {
      sum += a.pixels[k];
      const double d = static_cast<double>(a.pixels[k]) - b.pixels[k];
      sum_sq_diff += d * d;
    }
    const double mean = sum / a.pixels.size();
    const double noise = std::sqrt(sum_sq_diff / a.pixels.size() / 2.0);
    return std::pair{mean, mean / noise};
  };
  const auto [room_mean, room_snr] = mean_and_snr("room");
  const auto [dark_mean, dark_snr] = mean_and_snr("dark");
  std::cout << "mean intensity room " << room_mean << ", dark " << dark_mean << "; SNR room "
            << room_snr << ", dark " << dark_snr << "\n";
  EXPECT_LT(dark_mean, 0.5 * room_mean);
  EXPECT_LT(dark_snr, 0.3 * room_snr);
}

// The dark walk blurs: at full resolution, a frame rendered with the
// scenario's shutter time has less gradient energy than the sharp frame at
// the same stamp (noise switched off to compare the signal only).
TEST(Dark, FramesAreMotionBlurred) {
  SimulationOptions options = ShortOptions("dark");
  options.camera = SimulationOptions::DefaultCamera();
  const SimulatedSequence simulated = SimulateSequence(options);
  const RayTable rays(options.camera);
  Scenario scenario = *simulated.scenario;
  scenario.render.noise_sigma = 0.0;
  const auto gradient_energy = [](const GreyImage& image) {
    double sum = 0.0;
    for (int y = 0; y < image.height; ++y) {
      for (int x = 1; x < image.width; ++x) sum += std::abs(image.at(x, y) - image.at(x - 1, y));
    }
    return sum;
  };
  const timestamp_ns_t t = simulated.sequence.images[5].timestamp_ns;
  const timestamp_ns_t half = SecondsToNs(0.5 * scenario.exposure_time_s);
  ASSERT_GT(half, 0);
  const double sharp = gradient_energy(
      Render(scenario.scene, rays, SimulatedCamFromWorld(simulated, t), scenario.render));
  const double blurred = gradient_energy(
      RenderWithMotionBlur(scenario.scene, rays, SimulatedCamFromWorld(simulated, t - half),
                           SimulatedCamFromWorld(simulated, t + half), scenario.render));
  std::cout << "gradient energy blurred / sharp: " << blurred / sharp << "\n";
  EXPECT_LT(blurred, 0.95 * sharp);  // measured 0.91 (1: no blur)
}

// ---------------------------------------------------------------------
// Measurements for docs/simulator.md, run by hand:
//   test_sim_scenarios_test --gtest_also_run_disabled_tests --gtest_filter='*DISABLED_*'

// OpenCV SIFT (default settings) keypoints per frame on 50 frames of the
// default `room` walk (752 x 480, seed 0, one frame per second after the
// static start).
TEST(Measurement, DISABLED_SiftFeaturesOnRoomFrames) {
  SimulationOptions options;
  options.scenario = "room";
  options.duration_s = 51.0;
  options.camera_rate_hz = 1.0;
  const SimulatedSequence simulated = SimulateSequence(options);
  const RayTable rays(options.camera);
  const auto sift = cv::SIFT::create();
  std::vector<size_t> counts;
  for (size_t k = 2; k < simulated.sequence.images.size(); ++k) {
    GreyImage image = RenderSimulatedFrame(simulated, rays, k, options, 2);
    const cv::Mat mat(image.height, image.width, CV_8UC1, image.pixels.data());
    std::vector<cv::KeyPoint> keypoints;
    sift->detect(mat, keypoints);
    counts.push_back(keypoints.size());
  }
  ASSERT_EQ(counts.size(), 50u);
  double sum = 0;
  for (const size_t count : counts) sum += count;
  std::sort(counts.begin(), counts.end());
  std::cout << "SIFT keypoints over " << counts.size() << " room frames: mean "
            << sum / counts.size() << ", min " << counts.front() << ", median "
            << counts[counts.size() / 2] << ", max " << counts.back() << "\n";
  EXPECT_GE(counts.front(), 500u);
}

// Writes the pictures of docs/simulator.md (frames at half resolution).
TEST(Measurement, DISABLED_WriteDocPictures) {
  const fs::path folder = testing::SourcePath("../../docs/images");
  fs::create_directories(folder);
  const auto half = [](const GreyImage& image) {
    GreyImage out(image.width / 2, image.height / 2);
    for (int y = 0; y < out.height; ++y) {
      for (int x = 0; x < out.width; ++x) {
        const int sum = image.at(2 * x, 2 * y) + image.at(2 * x + 1, 2 * y) +
                        image.at(2 * x, 2 * y + 1) + image.at(2 * x + 1, 2 * y + 1);
        out.at(x, y) = static_cast<uint8_t>((sum + 2) / 4);
      }
    }
    return out;
  };
  const auto side_by_side = [](const GreyImage& a, const GreyImage& b) {
    GreyImage out(a.width + b.width + 4, a.height, 255);
    for (int y = 0; y < a.height; ++y) {
      for (int x = 0; x < a.width; ++x) out.at(x, y) = a.at(x, y);
      for (int x = 0; x < b.width; ++x) out.at(a.width + 4 + x, y) = b.at(x, y);
    }
    return out;
  };
  // One frame of each scenario's default walk (seed 0) at the given second.
  const auto frame = [&](const std::string& scenario, double seconds) {
    SimulationOptions options;
    options.scenario = scenario;
    options.camera_rate_hz = 1.0;
    const SimulatedSequence simulated = SimulateSequence(options);
    return RenderSimulatedFrame(simulated, RayTable(options.camera), static_cast<size_t>(seconds),
                                options, 2);
  };
  WriteGreyPng(folder / "sim_room.png", half(frame("room", 20)));
  WriteGreyPng(folder / "sim_corridor.png", half(frame("corridor", 10)));
  WriteGreyPng(folder / "sim_dark.png",
               side_by_side(half(frame("dark", 8)), half(frame("dark", 17))));
  WriteGreyPng(folder / "sim_two_floors_stairs.png", half(frame("two_floors", 32)));
  // The trap: a floor-1 frame and the same pose 3.5 m higher.
  SimulationOptions options;
  options.scenario = "two_floors";
  options.camera_rate_hz = 1.0;
  const SimulatedSequence simulated = SimulateSequence(options);
  const RayTable rays(options.camera);
  const Rigid3d world_from_cam =
      SimulatedCamFromWorld(simulated, simulated.sequence.images[12].timestamp_ns).Inverse();
  Rigid3d up = world_from_cam;
  up.translation.z() += simulated.scenario->storey_height_m;
  RenderOptions render = simulated.scenario->render;
  const GreyImage floor1 =
      Render(simulated.scenario->scene, rays, world_from_cam.Inverse(), render);
  render.seed = 1;
  const GreyImage floor2 = Render(simulated.scenario->scene, rays, up.Inverse(), render);
  WriteGreyPng(folder / "sim_two_floors.png", side_by_side(half(floor1), half(floor2)));
}

}  // namespace
}  // namespace viosfm

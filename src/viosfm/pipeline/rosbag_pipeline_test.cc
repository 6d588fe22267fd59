// `viosfm run` on a ROS 1 bag gives exactly what it gives on the EuRoC
// folder the bag was written from: same trajectories and model, byte for
// byte (the images, IMU values, stamps and calibration survive the bag
// exactly, and the extracted images have the folder's names;
// io/rosbag_dataset_test checks the sequences field by field).
//
// With one thread and an external VIO file: today two runs of viosfm's own
// VIO on the same folder already differ in the last digits when only the
// heap layout changes (e.g. GLIBC_TUNABLES=glibc.malloc.tcache_count=0), and
// multi-threaded stages can differ between runs, so a byte comparison of
// those would test the process, not the bag.
#include <gtest/gtest.h>

#include <filesystem>

#include "viosfm/io/euroc.h"
#include "viosfm/io/rosbag_dataset.h"
#include "viosfm/pipeline/pipeline.h"
#include "viosfm/pipeline/pipeline_test_fixture.h"
#include "viosfm/sensor/camera_models.h"
#include "viosfm/sim/sequence_simulator.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;

PipelineOptions SmallOptions(const fs::path& dataset, const fs::path& vio, const fs::path& out) {
  PipelineOptions options = pipeline_testing::SmallRunOptions(dataset, vio, out, 400);
  options.num_threads = 1;
  options.seed = 7;
  return options;
}

TEST(RosbagPipeline, BagGivesTheFolderResultByteForByte) {
  const fs::path folder = testing::MakeScratchFolder("rosbag_pipeline");
  const SimulationOptions sim = pipeline_testing::HalfResolutionRoom(11);
  const fs::path dataset = folder / "dataset";
  WriteSimulatedSequence(dataset, SimulateSequence(sim), sim);

  const fs::path bag = folder / "dataset.bag";
  WriteRosbagDataset(ReadEurocDataset(dataset), bag);

  const fs::path vio = dataset / "vio_emulated.tum";
  const PipelineSummary from_folder =
      RunPipeline(SmallOptions(dataset, vio, folder / "out_folder"));
  const PipelineSummary from_bag = RunPipeline(SmallOptions(bag, vio, folder / "out_bag"));
  ASSERT_GT(from_folder.num_frames_registered, 10u);
  EXPECT_EQ(from_bag.num_frames_in, from_folder.num_frames_in);
  EXPECT_EQ(from_bag.num_frames_registered, from_folder.num_frames_registered);
  EXPECT_EQ(from_bag.num_points, from_folder.num_points);
  ASSERT_TRUE(from_folder.evaluation.has_value());
  ASSERT_TRUE(from_bag.evaluation.has_value());
  EXPECT_EQ(from_bag.evaluation->ate_rmse_m, from_folder.evaluation->ate_rmse_m);
  for (const std::string file : {"trajectory_body.tum", "trajectory_cam.tum", "vio_body.tum",
                                 "groundtruth_body.tum", "model/cameras.bin", "model/images.bin",
                                 "model/points3D.bin", "points.ply", "verification/pairs.csv"}) {
    SCOPED_TRACE(file);
    const std::string a = ReadTextFile(folder / "out_folder" / file);
    ASSERT_FALSE(a.empty());
    EXPECT_TRUE(a == ReadTextFile(folder / "out_bag" / file));
  }
  // The bag's images were extracted as a EuRoC folder beside the outputs.
  EXPECT_TRUE(fs::is_regular_file(folder / "out_bag" / "bag" / "mav0" / "cam0" / "data.csv"));
}

}  // namespace
}  // namespace viosfm

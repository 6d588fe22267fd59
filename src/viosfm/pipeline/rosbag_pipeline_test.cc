// `viosfm run` on a bag (ROS 1 .bag, ROS 2 .db3 or .mcap) gives exactly what
// it gives on the EuRoC folder the bag was written from: same trajectories
// and model, byte for byte (the images, IMU values, stamps and calibration
// survive the bag exactly, and the extracted images have the folder's names;
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

// The simulated sequence, its run from the folder, and the folder written
// as bags: computed once for the three containers.
class RosbagPipeline : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    folder_ = new fs::path(testing::MakeScratchFolder("rosbag_pipeline"));
    const SimulationOptions sim = pipeline_testing::HalfResolutionRoom(11);
    WriteSimulatedSequence(*folder_ / "dataset", SimulateSequence(sim), sim);
    from_folder_ = new PipelineSummary(RunPipeline(SmallOptions(
        *folder_ / "dataset", *folder_ / "dataset" / "vio_emulated.tum", *folder_ / "out_folder")));
  }
  static void TearDownTestSuite() {
    delete from_folder_;
    delete folder_;
  }

  // Writes the folder as `bag_name`, runs it and compares with the folder's run.
  static void ExpectSameRun(const std::string& bag_name) {
    const fs::path& folder = *folder_;
    const fs::path bag = folder / bag_name;
    const fs::path out = folder / ("out_" + bag_name);
    WriteRosbagDataset(ReadEurocDataset(folder / "dataset"), bag);
    const PipelineSummary from_bag =
        RunPipeline(SmallOptions(bag, folder / "dataset" / "vio_emulated.tum", out));
    ASSERT_GT(from_folder_->num_frames_registered, 10u);
    EXPECT_EQ(from_bag.num_frames_in, from_folder_->num_frames_in);
    EXPECT_EQ(from_bag.num_frames_registered, from_folder_->num_frames_registered);
    EXPECT_EQ(from_bag.num_points, from_folder_->num_points);
    ASSERT_TRUE(from_folder_->evaluation.has_value());
    ASSERT_TRUE(from_bag.evaluation.has_value());
    EXPECT_EQ(from_bag.evaluation->ate_rmse_m, from_folder_->evaluation->ate_rmse_m);
    for (const std::string file : {"trajectory_body.tum", "trajectory_cam.tum", "vio_body.tum",
                                   "groundtruth_body.tum", "model/cameras.bin", "model/images.bin",
                                   "model/points3D.bin", "points.ply", "verification/pairs.csv"}) {
      SCOPED_TRACE(file);
      const std::string a = ReadTextFile(folder / "out_folder" / file);
      ASSERT_FALSE(a.empty());
      EXPECT_TRUE(a == ReadTextFile(out / file));
    }
    // The bag's images were extracted as a EuRoC folder beside the outputs.
    EXPECT_TRUE(fs::is_regular_file(out / "bag" / "mav0" / "cam0" / "data.csv"));
  }

  static fs::path* folder_;
  static PipelineSummary* from_folder_;
};
fs::path* RosbagPipeline::folder_ = nullptr;
PipelineSummary* RosbagPipeline::from_folder_ = nullptr;

TEST_F(RosbagPipeline, Ros1BagGivesTheFolderResultByteForByte) {
  ExpectSameRun("dataset.bag");
}

TEST_F(RosbagPipeline, Ros2SqliteBagGivesTheFolderResultByteForByte) {
  ExpectSameRun("dataset.db3");
}

TEST_F(RosbagPipeline, McapBagGivesTheFolderResultByteForByte) {
  ExpectSameRun("dataset.mcap");
}

}  // namespace
}  // namespace viosfm

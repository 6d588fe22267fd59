#include "viosfm/report/bench_report.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>

#include "viosfm/io/trajectory_io.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::Not;

std::string EvalJson(double rmse, double median, int pairs) {
  return "{\"num_pairs\": " + std::to_string(pairs) +
         ", \"ate\": {\"translation_m\": {\"rmse\": " + std::to_string(rmse) +
         ", \"median\": " + std::to_string(median) + "}}}";
}

void Write(const fs::path& path, const std::string& text) {
  fs::create_directories(path.parent_path());
  testing::WriteTextFile(path, text);
}

// A results folder as bench/run.sh writes it: one sequence of 4 frames, two
// methods and a batch-size sweep of two runs.
fs::path MakeFixture() {
  const fs::path root = testing::MakeScratchFolder("bench_report");
  Write(root / "meta.txt", "date: 2026-01-01\nmode: quick\nviosfm: abc1234\n");
  Write(root / "room/sequence/simulation.yaml", "scenario: room\n");
  Write(root / "room/sequence/mav0/cam0/data.csv",
        "#timestamp [ns],filename\n1,1.png\n2,2.png\n3,3.png\n4,4.png\n");
  const fs::path runs = root / "room/runs";
  Write(runs / "viosfm/time.txt", "12.5 204800 10.25 1.5\n");
  Write(runs / "viosfm/eval.json",
        "{\"num_pairs\": 4, \"alignment\": {\"scale\": 0.98}, \"ate\": {\"translation_m\": "
        "{\"rmse\": 0.0123, \"median\": 0.0101}}}");
  Write(runs / "viosfm/eval_se3.json", EvalJson(0.0456, 0.04, 4));
  Write(runs / "viosfm/run/summary.json",
        "{\"frames\": {\"in\": 4, \"selected\": 4, \"registered\": 4},"
        " \"stages\": [{\"name\": \"mapper\", \"seconds\": 3.25}]}");
  Write(runs / "colmap_sequential/time.txt", "30.0 102400\n");
  Write(runs / "colmap_sequential/eval.json", EvalJson(0.5, 0.25, 3));
  Write(runs / "colmap_sequential/num_models.txt", "2\n");
  Write(runs / "vio/eval.json", EvalJson(0.2, 0.15, 4));
  Write(runs / "viosfm_no_rpc/time.txt", "4.0 204800\n");
  Write(runs / "viosfm_no_rpc/eval.json", EvalJson(0.04, 0.03, 4));
  Write(runs / "viosfm_no_rpc/reused.txt", "features and verified matches of viosfm\n");
  Write(root / "batch_size/10/time.txt", "8.0 1024\n");
  Write(root / "batch_size/10/eval.json", EvalJson(0.02, 0.01, 4));
  Write(root / "batch_size/5/time.txt", "9.0 1024\n");
  Write(root / "batch_size/5/eval.json", EvalJson(0.03, 0.01, 4));
  Write(root / "batch_size/5/failed", "");
  Write(root / "batch_size/5/version.txt", "0ld0001\n");
  return root;
}

TEST(BenchReport, ReadsRunsInMethodOrder) {
  const BenchResults results = ReadBenchResults(MakeFixture());
  ASSERT_EQ(results.runs.size(), 4u);
  EXPECT_EQ(results.runs[0].method, "vio");
  EXPECT_EQ(results.runs[1].method, "viosfm");
  EXPECT_EQ(results.runs[2].method, "viosfm_no_rpc");
  EXPECT_EQ(results.runs[3].method, "colmap_sequential");
  const BenchRun& viosfm = results.runs[1];
  EXPECT_EQ(viosfm.frames_in, 4);
  EXPECT_EQ(viosfm.frames_registered, 4);
  EXPECT_NEAR(*viosfm.ate_rmse_m, 0.0123, 1e-9);
  EXPECT_NEAR(*viosfm.ate_se3_rmse_m, 0.0456, 1e-9);
  EXPECT_NEAR(*viosfm.scale, 1.0 / 0.98, 1e-9);
  EXPECT_NEAR(*viosfm.seconds, 12.5, 1e-9);
  EXPECT_NEAR(*viosfm.peak_memory_mb, 200.0, 1e-9);
  EXPECT_NEAR(*viosfm.mapping_seconds, 3.25, 1e-9);
  EXPECT_NEAR(*viosfm.cpu_seconds, 11.75, 1e-9);
  EXPECT_TRUE(viosfm.reused.empty());
  EXPECT_FALSE(results.runs[2].cpu_seconds.has_value());
  EXPECT_EQ(results.runs[2].reused, "features and verified matches of viosfm");
  // Without batch_size_sequence.txt the sweep belongs to the first sequence.
  EXPECT_EQ(results.batch_size_sequence, "room");
  const BenchRun& colmap = results.runs[3];
  EXPECT_EQ(colmap.frames_registered, 3);
  EXPECT_EQ(colmap.num_models, 2);
  // Sweeps are sorted by number, not by name.
  ASSERT_EQ(results.batch_size.size(), 2u);
  EXPECT_EQ(results.batch_size[0].method, "5");
  EXPECT_TRUE(results.batch_size[0].failed);
  EXPECT_EQ(results.batch_size[1].method, "10");
}

TEST(BenchReport, MarkdownHasTheNumbers) {
  const std::string md = FormatBenchMarkdown(ReadBenchResults(MakeFixture()), "images");
  EXPECT_THAT(md, HasSubstr("- mode: quick"));
  EXPECT_THAT(md,
              HasSubstr("| viosfm | 4 / 4 | 12.30 | 10.10 | 45.60 | 1.0204 | 12.5 | 11.8 | 200 |"));
  EXPECT_THAT(md, HasSubstr("| viosfm w/o relative-pose term [1] | 4 / 4 | 40.00 | 30.00 | n/a "
                            "| n/a | 4.0 | n/a | 200 |"));
  EXPECT_THAT(md, HasSubstr("[1] viosfm w/o relative-pose term: started from the features and "
                            "verified matches of viosfm;"));
  EXPECT_THAT(md,
              HasSubstr("| COLMAP 3.8, sequential matcher | 3 / 4 (2 models) | 500.00 | 250.00 |"));
  EXPECT_THAT(md,
              HasSubstr("| input VIO (emulated) | - | 200.00 | 150.00 | n/a | n/a | - | - | - |"));
  EXPECT_THAT(md, HasSubstr("| 10 | 4 | 20.00 | 8.0 |"));
  // The version of each sweep run: its version.txt, else meta.txt's.
  EXPECT_THAT(md, HasSubstr("| 10 | 4 | 20.00 | 8.0 | n/a | n/a | abc1234 |"));
  EXPECT_THAT(md, HasSubstr("| 0ld0001 |"));
}

TEST(BenchReport, RunsOfAnotherVersionGetANote) {
  const fs::path root = MakeFixture();
  Write(root / "room/runs/viosfm/version.txt", "abc1234\n");
  EXPECT_THAT(FormatBenchMarkdown(ReadBenchResults(root), "images"),
              Not(HasSubstr("run with viosfm")));
  Write(root / "room/runs/viosfm/version.txt", "0ld0001\n");
  const std::string md = FormatBenchMarkdown(ReadBenchResults(root), "images");
  EXPECT_THAT(md, HasSubstr("| viosfm [1] | 4 / 4 |"));
  EXPECT_THAT(md, HasSubstr("[1] viosfm: run with viosfm 0ld0001."));
}

TEST(BenchReport, LengthRunsStartedFromStoredMatchesGetANote) {
  const fs::path root = MakeFixture();
  Write(root / "length/300/time.txt", "30.0 2048 29.0 1.0\n");
  Write(root / "length/300/eval.json", EvalJson(0.001, 0.001, 4));
  Write(root / "length/2400/time.txt", "90.0 4096 88.0 2.0\n");
  Write(root / "length/2400/eval.json", EvalJson(0.002, 0.001, 4));
  Write(root / "length/2400/reused.txt", "features and verified matches of an earlier run\n");
  Write(root / "length/2400_stopped/time.txt", "");
  const BenchResults results = ReadBenchResults(root);
  ASSERT_EQ(results.length.size(), 2u);
  const std::string md = FormatBenchMarkdown(results, "images");
  EXPECT_THAT(md, HasSubstr("| 2400 | 4 | 2.00 | 90.0 | 90.0 |"));
  EXPECT_THAT(md, HasSubstr("2400 frames: started from the features and verified matches of an "
                            "earlier run; its time is that of the remaining stages."));
  EXPECT_THAT(md, Not(HasSubstr("300 frames: started")));
}

TEST(BenchReport, WritesPageAndBatchSizeFigures) {
  const fs::path root = MakeFixture();
  const BenchResults results = ReadBenchResults(root);
  WriteBenchReport(results, root / "docs/bench.md", root / "docs/images");
  EXPECT_THAT(ReadTextFile(root / "docs/bench.md"),
              HasSubstr("](images/bench_batch_size_ate.svg)"));
  EXPECT_THAT(ReadTextFile(root / "docs/images/bench_batch_size_ate.svg"), HasSubstr("<svg"));
}

// A dataset's runs whose sequence folder is not there (a moved dataset, or a
// results folder copied elsewhere): the page still has its numbers, without
// trajectory figures.
TEST(BenchReport, DatasetWithoutItsSequenceFolderStillGetsItsRows) {
  const fs::path root = MakeFixture();
  const fs::path run = root / "MyData/runs/colmap_same_pairs";
  fs::create_directories(run / "sparse/0");
  for (const auto& entry :
       fs::directory_iterator(testing::SourcePath("io/testdata/colmap_fountain_bin"))) {
    fs::copy_file(entry.path(), run / "sparse/0" / entry.path().filename());
  }
  Write(run / "time.txt", "40.0 1024\n");
  Write(run / "eval.json", EvalJson(0.0777, 0.05, 11));
  Write(root / "MyData/runs/vio/eval.json", EvalJson(0.0888, 0.06, 11));
  const BenchResults results = ReadBenchResults(root);
  WriteBenchReport(results, root / "docs/bench.md", root / "docs/images");
  const std::string page = ReadTextFile(root / "docs/bench.md");
  EXPECT_THAT(page, HasSubstr("MyData"));
  EXPECT_THAT(page, HasSubstr("77.7"));
  EXPECT_THAT(page, HasSubstr("| input VIO (--vio-trajectory) | - | 88.80 |"));
  EXPECT_FALSE(fs::exists(root / "docs/images/bench_MyData_colmap_same_pairs_top.svg"));
}

// Trajectory figures: drawn and linked for a run with a trajectory on a
// sequence with ground truth; not linked for a run without one (still going).
TEST(BenchReport, LinksOnlyTheTrajectoriesItDraws) {
  const fs::path root = MakeFixture();
  std::string truth =
      "#timestamp,p_x,p_y,p_z,q_w,q_x,q_y,q_z,v_x,v_y,v_z,bw_x,bw_y,bw_z,ba_x,ba_y,ba_z\n";
  std::string tum;
  for (int i = 1; i <= 4; ++i) {
    const std::string x = std::to_string(0.5 * i);
    const std::string y = std::to_string(0.1 * i * i);
    truth += std::to_string(i) + "000000000," + x + "," + y + ",1,1,0,0,0,0,0,0,0,0,0,0,0,0\n";
    tum += std::to_string(i) + ".0 " + x + " " + y + " 1 0 0 0 1\n";
  }
  Write(root / "room/sequence/mav0/state_groundtruth_estimate0/data.csv", truth);
  Write(root / "room/runs/viosfm/run/trajectory_body.tum", tum);
  const BenchResults results = ReadBenchResults(root);
  WriteBenchReport(results, root / "docs/bench.md", root / "docs/images");
  const std::string page = ReadTextFile(root / "docs/bench.md");
  EXPECT_THAT(page, HasSubstr("](images/bench_room_viosfm_top.svg)"));
  EXPECT_THAT(ReadTextFile(root / "docs/images/bench_room_viosfm_top.svg"),
              HasSubstr("viosfm (sim3-aligned)"));
  // colmap_sequential has numbers but no model.
  EXPECT_THAT(page, Not(HasSubstr("bench_room_colmap_sequential_top.svg")));
  EXPECT_FALSE(fs::exists(root / "docs/images/bench_room_colmap_sequential_top.svg"));
}

TEST(BenchReport, BatchSizeSweepNamesItsSequence) {
  const fs::path root = MakeFixture();
  Write(root / "batch_size_sequence.txt", "room_30s\n");
  Write(root / "room_30s/runs/colmap_same_pairs/time.txt", "50.0 1024\n");
  Write(root / "room_30s/runs/colmap_same_pairs/eval.json", EvalJson(0.07, 0.05, 4));
  const BenchResults results = ReadBenchResults(root);
  EXPECT_EQ(results.batch_size_sequence, "room_30s");
  EXPECT_THAT(FormatBenchMarkdown(results, "images"), HasSubstr("On room_30s;"));
  WriteBenchReport(results, root / "docs/bench.md", root / "docs/images");
  // COLMAP's ATE of the sweep's sequence is a reference line of the figure.
  EXPECT_THAT(ReadTextFile(root / "docs/images/bench_batch_size_ate.svg"),
              HasSubstr("COLMAP 3.8, viosfm&#39;s pairs"));
}

// Two floors 3 m apart, 4 frames each, plus one stairwell frame (-1).
struct TwoFloors {
  Trajectory ground_truth;
  std::string frames_csv = "#timestamp [ns],region,floor\n";
};

TwoFloors MakeTwoFloors() {
  TwoFloors scene;
  const double xy[4][2] = {{0, 0}, {4, 0}, {4, 3}, {0, 3}};
  for (int i = 0; i < 9; ++i) {
    const int floor = i < 4 ? 0 : (i == 4 ? -1 : 1);
    StampedPose pose;
    pose.timestamp_ns = 1000 + i;
    const double* p = xy[i < 4 ? i : (i == 4 ? 0 : i - 5)];
    pose.world_from_frame.translation =
        Eigen::Vector3d(p[0], p[1], floor < 0 ? 1.5 : 3.0 * floor) + Eigen::Vector3d(0, 0, 1.2);
    scene.ground_truth.poses.push_back(pose);
    scene.frames_csv += std::to_string(pose.timestamp_ns) + ",r," + std::to_string(floor) + "\n";
  }
  return scene;
}

TEST(BenchReport, FloorPlacementOfExactAndMergedFloors) {
  const TwoFloors scene = MakeTwoFloors();
  const fs::path folder = testing::MakeScratchFolder("bench_report_floors");
  Write(folder / "frames.csv", scene.frames_csv);
  // An exact estimate in another frame (scaled, shifted): the true heights.
  Trajectory moved = scene.ground_truth;
  for (StampedPose& pose : moved.poses) {
    pose.world_from_frame.translation =
        0.5 * pose.world_from_frame.translation + Eigen::Vector3d(10, -2, 7);
  }
  FloorPlacement exact = ComputeFloorPlacement(moved, scene.ground_truth, folder / "frames.csv");
  ASSERT_EQ(exact.floors, (std::vector<int>{0, 1}));
  EXPECT_EQ(exact.num_frames, (std::vector<int>{4, 4}));
  EXPECT_NEAR(exact.mean_height_m[0], 1.2, 1e-9);
  EXPECT_NEAR(exact.mean_height_m[1], 4.2, 1e-9);
  EXPECT_NEAR(exact.true_mean_height_m[1], 4.2, 1e-9);
  EXPECT_NEAR(exact.floor_ate_rmse_m[0], 0.0, 1e-9);
  EXPECT_NEAR(exact.floor_ate_rmse_m[1], 0.0, 1e-9);
  // Floors merged into one (the failure of purely visual SfM): the
  // estimated gap shrinks far below the true 3 m.
  Trajectory merged = scene.ground_truth;
  for (StampedPose& pose : merged.poses) pose.world_from_frame.translation.z() = 1.2;
  const FloorPlacement wrong =
      ComputeFloorPlacement(merged, scene.ground_truth, folder / "frames.csv");
  ASSERT_EQ(wrong.floors.size(), 2u);
  EXPECT_LT(std::abs(wrong.mean_height_m[1] - wrong.mean_height_m[0]), 0.5);
  // Each floor on its own is still exact (a translation of the other).
  EXPECT_NEAR(wrong.floor_ate_rmse_m[1], 0.0, 1e-9);
  // One floor only: nothing to report. A broken row names the file.
  Write(folder / "one_floor.csv", "1000,r,0\n1001,r,0\n");
  EXPECT_TRUE(
      ComputeFloorPlacement(moved, scene.ground_truth, folder / "one_floor.csv").floors.empty());
  // Three collinear positions cannot be aligned: no placement, no error.
  Trajectory line;
  for (int i = 0; i < 3; ++i) line.poses.push_back(moved.poses[i]);
  for (int i = 0; i < 3; ++i) line.poses[i].world_from_frame.translation = Eigen::Vector3d(i, 0, 0);
  EXPECT_TRUE(
      ComputeFloorPlacement(line, scene.ground_truth, folder / "frames.csv").floors.empty());
  Write(folder / "bad.csv", "1000,r,zero\n");
  EXPECT_THAT(testing::InputErrorMessage(
                  [&] { ComputeFloorPlacement(moved, scene.ground_truth, folder / "bad.csv"); }),
              HasSubstr("bad.csv:1"));
}

TEST(BenchReport, MarkdownHasTheFloorTable) {
  const fs::path root = MakeFixture();
  const TwoFloors scene = MakeTwoFloors();
  Write(root / "room/sequence/frames.csv", scene.frames_csv);
  WriteEurocTrajectory(root / "room/sequence/mav0/state_groundtruth_estimate0/data.csv",
                       scene.ground_truth);
  WriteTumTrajectory(root / "room/runs/viosfm/run/trajectory_body.tum", scene.ground_truth);
  const BenchResults results = ReadBenchResults(root);
  ASSERT_EQ(results.floors.size(), 1u);
  EXPECT_EQ(results.floors[0].first, "room");
  const std::string md = FormatBenchMarkdown(results, "images");
  EXPECT_THAT(md, HasSubstr("| viosfm | 1 | 4 | 4.20 | 4.20 | 0.00 |"));
}

TEST(BenchReport, BadInputNamesTheFile) {
  const fs::path root = MakeFixture();
  Write(root / "room/runs/viosfm/eval.json", "{\"ate\": ");
  EXPECT_THAT(testing::InputErrorMessage([&] { ReadBenchResults(root); }),
              HasSubstr("room/runs/viosfm/eval.json"));
  Write(root / "room/runs/viosfm/eval.json", "{}");
  // An empty time.txt is a run still going: no time, no error.
  Write(root / "room/runs/viosfm/time.txt", "");
  EXPECT_FALSE(ReadBenchResults(root).runs[1].seconds.has_value());
  // A killed run: GNU time's status line, then the figures.
  Write(root / "room/runs/viosfm/time.txt", "Command terminated by signal 15\n7.5 2048 6.0 0.5\n");
  Write(root / "room/runs/viosfm/failed", "");
  {
    const BenchResults results = ReadBenchResults(root);
    ASSERT_TRUE(results.runs[1].seconds.has_value());
    EXPECT_DOUBLE_EQ(*results.runs[1].seconds, 7.5);
    EXPECT_TRUE(results.runs[1].failed);
  }
  Write(root / "room/runs/viosfm/time.txt", "twelve\n");
  EXPECT_THAT(testing::InputErrorMessage([&] { ReadBenchResults(root); }), HasSubstr("time.txt"));
  EXPECT_THROW(ReadBenchResults(root / "missing"), InputError);
}

}  // namespace
}  // namespace viosfm

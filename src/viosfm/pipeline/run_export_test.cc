#include "viosfm/pipeline/run_export.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <string>

#include "viosfm/io/colmap_database.h"
#include "viosfm/io/colmap_model.h"
#include "viosfm/io/colmap_pose_priors.h"
#include "viosfm/io/ply.h"
#include "viosfm/io/transforms_json.h"
#include "viosfm/pipeline/pipeline.h"
#include "viosfm/pipeline/pipeline_test_fixture.h"
#include "viosfm/sensor/camera_models.h"
#include "viosfm/sim/sequence_simulator.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/folder_manifest.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;

// A 3 s simulated walk (10 Hz, half EuRoC's resolution) run with small
// settings and the emulated VIO, then exported.
struct Fixture {
  fs::path folder;
  fs::path dataset;
  fs::path run;
  RunExportSummary summary;
  double summary_json_ate_m = 0.0;  // the run's Sim(3) ATE against the simulator's truth
};

const Fixture& SharedFixture() {
  static const Fixture fixture = [] {
    Fixture f;
    f.folder = testing::MakeScratchFolder("run_export");
    const SimulationOptions sim = pipeline_testing::HalfResolutionRoom(4);
    f.dataset = f.folder / "dataset";
    WriteSimulatedSequence(f.dataset, SimulateSequence(sim), sim);
    f.run = f.folder / "run";
    const PipelineOptions options =
        pipeline_testing::SmallRunOptions(f.dataset, f.dataset / "vio_emulated.tum", f.run, 400);
    RunPipeline(options);
    RunExportOptions export_options;
    export_options.run_folder = f.run;
    f.summary = ExportRun(export_options);
    const nlohmann::json summary = nlohmann::json::parse(ReadTextFile(f.run / "summary.json"));
    f.summary_json_ate_m = summary["eval"]["metric"]["ate_sim3_rmse_m"].get<double>();
    return f;
  }();
  return fixture;
}

TEST(RunExport, WritesEveryFileWithTheModelsPoses) {
  const Fixture& f = SharedFixture();
  const fs::path e = f.run / "export";
  EXPECT_EQ(f.summary.output_folder, e);
  const Reconstruction model = ReadColmapModel(f.run / "model");
  ASSERT_GT(model.NumRegImages(), 10u);
  EXPECT_EQ(f.summary.num_images, model.NumRegImages());
  EXPECT_EQ(f.summary.num_points, model.NumPoints3D());
  EXPECT_EQ(f.summary.image_folder, fs::absolute(f.dataset / "mav0" / "cam0" / "data"));
  EXPECT_TRUE(fs::is_symlink(e / "images"));
  for (const char* file : {"cameras.bin", "images.bin", "points3D.bin"}) {
    EXPECT_EQ(ReadTextFile(e / "sparse" / "0" / file), ReadTextFile(f.run / "model" / file));
  }
  EXPECT_EQ(ReadPly(e / "sparse_pc.ply").xyz.size(), model.NumPoints3D());

  // Pose priors: the camera centres with the model's covariances: each
  // image's own (symmetric, positive definite), the scale's part growing
  // with the distance from the first image, within the simulator's truth:
  // the model's camera centres are off by about a millimetre (its ATE), a
  // few standard deviations of its priors, not hundreds.
  const std::vector<ColmapPosePrior> priors = ReadColmapPosePriors(e / "database.db");
  ASSERT_EQ(priors.size(), model.NumRegImages());
  EXPECT_EQ(f.summary.num_priors_from_model + f.summary.num_priors_isotropic, priors.size());
  EXPECT_GE(f.summary.num_priors_from_model, priors.size() - 1);
  EXPECT_GT(f.summary.keypoint_sigma_px, 0.05);
  EXPECT_LT(f.summary.keypoint_sigma_px, 2.0);
  EXPECT_GT(f.summary.scale_sigma, 0.0);
  const double ate_m = f.summary_json_ate_m;
  ASSERT_GT(ate_m, 0.0);
  EXPECT_GT(f.summary.median_position_stddev_m, ate_m / 30.0);
  EXPECT_LT(f.summary.median_position_stddev_m, ate_m * 30.0);
  std::set<double> traces;
  for (const ColmapPosePrior& prior : priors) {
    const Image& image = model.GetImage(prior.image_id);
    EXPECT_EQ(prior.position, image.ProjectionCenter());
    EXPECT_LT((prior.position_covariance - prior.position_covariance.transpose()).norm(), 1e-18);
    EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(prior.position_covariance)
                  .eigenvalues()
                  .minCoeff(),
              0.0);
    EXPECT_EQ(prior.coordinate_system, ColmapCoordinateSystem::kCartesian);
    traces.insert(prior.position_covariance.trace());
  }
  EXPECT_EQ(traces.size(), priors.size());  // per image, not one for all
  // The rest of the database is the run's.
  ColmapDatabase exported = ColmapDatabase::Open(e / "database.db");
  ColmapDatabase original = ColmapDatabase::Open(f.run / "database.db");
  EXPECT_EQ(exported.NumKeypoints(), original.NumKeypoints());
  EXPECT_EQ(exported.NumVerifiedImagePairs(), original.NumVerifiedImagePairs());

  // transforms.json round-trips the model's poses to 1e-9, and every file exists.
  const TransformsJson transforms = ReadTransformsJson(e / "transforms.json");
  ASSERT_EQ(transforms.frames.size(), model.NumRegImages());
  EXPECT_EQ(transforms.camera.params, model.Cameras().begin()->second.params);
  for (const TransformsFrame& frame : transforms.frames) {
    EXPECT_TRUE(fs::is_regular_file(e / frame.file_path)) << frame.file_path;
    const Image* image = model.ImageByName(fs::path(frame.file_path).filename().string());
    ASSERT_NE(image, nullptr);
    EXPECT_LT(frame.cam_from_world.rotation.angularDistance(image->cam_from_world.rotation), 1e-9);
    EXPECT_LT((frame.cam_from_world.Inverse().translation - image->ProjectionCenter()).norm(),
              1e-9);
  }
}

TEST(RunExport, TakesPerImageCovariances) {
  const Fixture& f = SharedFixture();
  const Reconstruction model = ReadColmapModel(f.run / "model");
  const Image& image = model.GetImage(model.RegImageIds().front());
  RunExportOptions options;
  options.run_folder = f.run;
  options.output_folder = f.folder / "export_covariance";
  Eigen::Matrix3d covariance;
  covariance << 4e-4, 1e-5, 0, 1e-5, 9e-4, 0, 0, 0, 2.5e-3;
  options.prior_position_covariances[image.name] = covariance;
  options.prior_position_stddev_m = 0.5;
  const RunExportSummary summary = ExportRun(options);
  EXPECT_EQ(summary.num_priors_from_covariances, 1u);
  for (const ColmapPosePrior& prior : ReadColmapPosePriors(options.output_folder / "database.db")) {
    EXPECT_EQ(prior.position_covariance, prior.image_id == image.image_id
                                             ? covariance
                                             : Eigen::Matrix3d(0.25 * Eigen::Matrix3d::Identity()));
  }
}

TEST(RunExport, MissingRunIsAnInputError) {
  const Fixture& f = SharedFixture();
  RunExportOptions options;
  options.run_folder = f.folder / "absent";
  EXPECT_NE(testing::InputErrorMessage([&] { ExportRun(options); }).find("run folder"),
            std::string::npos);
  options.run_folder = f.run;
  options.prior_position_stddev_m = -1;
  EXPECT_NE(testing::InputErrorMessage([&] { ExportRun(options); }).find("prior_position_stddev_m"),
            std::string::npos);
}

// The documented convention checked by an independent loader (Python's
// standard library): scripts/check_transforms_json.py.
TEST(RunExport, TransformsJsonPassesTheLoaderScript) {
  const Fixture& f = SharedFixture();
  if (std::system("python3 --version > /dev/null 2>&1") != 0) {
    GTEST_SKIP() << "python3 not installed (apt-get install python3); skipping";
  }
  const std::string command =
      "python3 " + std::string(VIOSFM_SOURCE_DIR) + "/scripts/check_transforms_json.py" + " " +
      (f.run / "export" / "transforms.json").string() + " --colmap-model " +
      (f.run / "model_txt").string() + " > " + (f.folder / "check.log").string() + " 2>&1";
  EXPECT_EQ(std::system(command.c_str()), 0) << ReadTextFile(f.folder / "check.log");
}

// Runs `colmap ARGS` (COLMAP 3.8, Debian's, headless) and returns its output.
std::string RunColmap(const Fixture& f, const std::string& args, const std::string& log) {
  const std::string command =
      "QT_QPA_PLATFORM=offscreen colmap " + args + " > " + (f.folder / log).string() + " 2>&1";
  EXPECT_EQ(std::system(command.c_str()), 0) << ReadTextFile(f.folder / log);
  return ReadTextFile(f.folder / log);
}

size_t PointsOf(const std::string& analyzer_output) {
  std::smatch match;
  EXPECT_TRUE(std::regex_search(analyzer_output, match, std::regex("Points: ([0-9]+)")))
      << analyzer_output;
  return match.empty() ? 0 : std::stoul(match[1]);
}

// COLMAP 3.8 opens the exported model and database (the 3.10+ pose_priors
// table is an addition it ignores) and, triangulating from our poses held
// fixed and our verified matches, reproduces our point count within 10 %.
TEST(RunExport, Colmap38OpensTheExportAndReproducesThePoints) {
  const Fixture& f = SharedFixture();
  if (std::system("colmap help > /dev/null 2>&1") != 0) {
    GTEST_SKIP() << "colmap not installed (apt-get install colmap); skipping";
  }
  const fs::path e = f.run / "export";
  const size_t ours = PointsOf(
      RunColmap(f, "model_analyzer --path " + e.string() + "/sparse/0", "analyzer_ours.log"));
  EXPECT_EQ(ours, f.summary.num_points);
  // A copy of the database, since COLMAP writes to the one it opens.
  fs::copy_file(e / "database.db", f.folder / "colmap.db", fs::copy_options::overwrite_existing);
  fs::create_directories(f.folder / "triangulated");
  RunColmap(f,
            "point_triangulator --database_path " + (f.folder / "colmap.db").string() +
                " --image_path " + (e / "images").string() + " --input_path " + e.string() +
                "/sparse/0 --output_path " + (f.folder / "triangulated").string(),
            "triangulator.log");
  const size_t theirs = PointsOf(RunColmap(
      f, "model_analyzer --path " + (f.folder / "triangulated").string(), "analyzer_colmap.log"));
  std::cerr << "points: viosfm " << ours << ", COLMAP 3.8 point_triangulator " << theirs << "\n";
  EXPECT_NEAR(static_cast<double>(theirs), static_cast<double>(ours), 0.1 * ours);
  // COLMAP 3.8 left the priors alone.
  EXPECT_EQ(ReadColmapPosePriors(f.folder / "colmap.db").size(), f.summary.num_images);
}

// Every file below `folder` with its content.
std::map<std::string, std::string> Contents(const fs::path& folder) {
  std::map<std::string, std::string> contents;
  for (const auto& entry : fs::recursive_directory_iterator(folder)) {
    if (entry.is_regular_file() && !entry.is_symlink()) {
      contents[entry.path().lexically_relative(folder).generic_string()] =
          ReadTextFile(entry.path());
    }
  }
  return contents;
}

TEST(RunExport, NeverIntoAFolderOfTheUsersTheRunOrAFolderHoldingIt) {
  const Fixture& f = SharedFixture();
  const fs::path users = f.folder / "users_folder";
  fs::create_directories(users / "model");
  testing::WriteTextFile(users / "model" / "cameras.bin", "the user's");
  const auto run_before = Contents(f.run);
  RunExportOptions options;
  options.run_folder = f.run;
  for (const fs::path& out : {users, f.run, f.folder, f.run / "model" / "sub"}) {
    options.output_folder = out;
    const InputError error = testing::ExpectInputError([&] { ExportRun(options); });
    EXPECT_EQ(error.path(), out.string());
  }
  EXPECT_EQ(ReadTextFile(users / "model" / "cameras.bin"), "the user's");
  EXPECT_EQ(Contents(f.run), run_before);
  EXPECT_FALSE(fs::exists(f.run / "model" / "sub"));
}

TEST(RunExport, AnExportAgainKeepsWhatTheUserAddedAndTheRunRecordsIt) {
  const Fixture& f = SharedFixture();
  // The default export is the run's, with a manifest of its own.
  EXPECT_EQ(ReadFolderManifest(f.run)->subfolders, std::set<std::string>{"export"});
  const FolderManifest exported = *ReadFolderManifest(f.run / "export");
  EXPECT_EQ(exported.kind, "export");
  EXPECT_TRUE(exported.complete);
  EXPECT_EQ(exported.files.count("transforms.json"), 1u);
  EXPECT_EQ(exported.files.count("images"), 1u);  // the link, not what it points to

  const fs::path out = f.folder / "exported";
  RunExportOptions options;
  options.run_folder = f.run;
  options.output_folder = out;
  ExportRun(options);
  const auto first = Contents(out);
  testing::WriteTextFile(out / "notes.txt", "the user's");
  fs::create_directories(out / "colmap_sparse" / "0");
  testing::WriteTextFile(out / "colmap_sparse" / "0" / "images.bin", "COLMAP's, the user's");
  ExportRun(options);
  std::map<std::string, std::string> second = Contents(out);
  EXPECT_EQ(second.at("notes.txt"), "the user's");
  EXPECT_EQ(second.at("colmap_sparse/0/images.bin"), "COLMAP's, the user's");
  second.erase("notes.txt");
  second.erase("colmap_sparse/0/images.bin");
  EXPECT_EQ(second, first);  // the export's own files, written again the same
}

}  // namespace
}  // namespace viosfm

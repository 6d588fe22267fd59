#include "viosfm/report/html_report.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "viosfm/eval/report.h"
#include "viosfm/eval/traj_eval.h"
#include "viosfm/io/colmap_model.h"
#include "viosfm/io/image_io.h"
#include "viosfm/io/ply.h"
#include "viosfm/io/trajectory_io.h"
#include "viosfm/io/verification_report.h"
#include "viosfm/sensor/camera_models.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;

// Numbers written into the fixture's summary.json.
constexpr int kFramesIn = 412;
constexpr int kFramesSelected = 206;
constexpr int kFramesRegistered = 197;
constexpr int kPoints = 12345;
constexpr double kVioAteRmse = 0.2345;
constexpr double kVioAteMedian = 0.1987;
constexpr int kNumPairs = 60;

// A loop with a height change at 20 Hz.
Trajectory MakeGroundTruth(int n) {
  Trajectory trajectory;
  for (int i = 0; i < n; ++i) {
    const double a = 2.0 * M_PI * i / n;
    StampedPose pose;
    pose.timestamp_ns = 1'403'636'580'000'000'000LL + i * 50'000'000LL;
    pose.world_from_frame.translation = Eigen::Vector3d(
        4.0 * std::cos(a), 2.5 * std::sin(a) + 0.4 * std::sin(3 * a), 1.0 + 0.6 * std::sin(2 * a));
    pose.world_from_frame.rotation =
        Eigen::Quaterniond(Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()));
    trajectory.poses.push_back(pose);
  }
  return trajectory;
}

// The estimate's frame: a similarity away from the ground truth's.
const Sim3d kEstFromRef(0.5, Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ())),
                        Eigen::Vector3d(1.0, 2.0, 0.0));

// Every second ground-truth pose in another similarity frame, with a
// deterministic wobble (m, in the ground truth's scale) that grows along the loop.
Trajectory MakeEstimate(const Trajectory& truth) {
  const Sim3d& est_from_ref = kEstFromRef;
  Trajectory estimate;
  for (size_t i = 0; i < truth.size(); i += 2) {
    StampedPose pose = truth.poses[i];
    const double t = static_cast<double>(i) / truth.size();
    pose.world_from_frame.translation +=
        0.08 * t * Eigen::Vector3d(std::sin(0.3 * i), std::cos(0.2 * i), std::sin(0.5 * i));
    pose.world_from_frame = est_from_ref.TransformPose(pose.world_from_frame);
    estimate.poses.push_back(pose);
  }
  return estimate;
}

// The input VIO: the ground truth with a drift.
Trajectory MakeVio(const Trajectory& truth) {
  Trajectory vio = truth;
  for (size_t i = 0; i < vio.size(); ++i) {
    vio.poses[i].world_from_frame.translation += Eigen::Vector3d(0.002 * i, -0.001 * i, 0.0005 * i);
  }
  return vio;
}

std::vector<PairDecision> MakeDecisions() {
  std::vector<PairDecision> decisions;
  for (int i = 0; i < kNumPairs; ++i) {
    PairDecision d;
    d.image_id1 = i + 1;
    d.image_id2 = i + 2;
    d.name1 = "cam0/" + std::to_string(i + 1) + ".png";
    d.name2 = "cam0/" + std::to_string(i + 2) + ".png";
    d.source = i % 3 == 0 ? "retrieval" : "temporal";
    d.num_matches = 100 + i;
    d.has_vio_prior = i % 10 != 9;  // every tenth pair without a prior (ratio NaN)
    if (d.has_vio_prior) {
      // Deterministic spread over [0, 1), skewed to small ratios.
      const double u = std::fmod(i * 0.6180339887, 1.0);
      d.vio_outlier_ratio = u * u;
      d.vio_rejected = d.vio_outlier_ratio > 0.5;
    }
    d.accepted = !d.vio_rejected;
    d.num_inliers = d.accepted ? 80 : 0;
    d.reason = d.accepted ? kPairAccepted : kPairVioOutlierRatio;
    decisions.push_back(d);
  }
  return decisions;
}

size_t CountAbove(const std::vector<PairDecision>& decisions, double threshold) {
  size_t n = 0;
  for (const PairDecision& d : decisions) n += d.has_vio_prior && d.vio_outlier_ratio > threshold;
  return n;
}

nlohmann::ordered_json MakeSummary(bool with_eval) {
  nlohmann::ordered_json s;
  s["viosfm_version"] = "0.1.0-test";
  s["dataset"] = "synthetic_loop";
  s["started_utc"] = "2026-11-21T07:00:00Z";
  s["frames"] = {
      {"in", kFramesIn}, {"selected", kFramesSelected}, {"registered", kFramesRegistered}};
  s["pairs"] = {{"candidates", kNumPairs}, {"accepted", 48},  {"vio_rejected", 12},
                {"ransac_rejected", 3},    {"no_matches", 1}, {"depth_rejected", 2}};
  s["texture_probe"] = {{"probed", true},
                        {"textured", true},
                        {"message", "textured: 2500 of 2500 keypoints; 4 Hz, 2500 features"}};
  s["points"] = kPoints;
  s["observations"] = 98765;
  s["mean_track_length"] = 8.0004;
  s["mean_reprojection_error_px"] = 0.81234;
  s["batches"] = nlohmann::ordered_json::array();
  for (int b = 0; b < 5; ++b) {
    s["batches"].push_back({{"index", b},
                            {"images", 40},
                            {"registered_total", 40 * (b + 1) - b},
                            {"points_total", 2500 * (b + 1)},
                            {"mean_reprojection_error_px", 0.7 + 0.02 * b},
                            {"seconds_ba", 1.5 + 0.75 * b}});
  }
  s["stages"] = {{{"name", "vio"}, {"seconds", 12.5}},
                 {{"name", "features"}, {"seconds", 30.25}},
                 {{"name", "matching"}, {"seconds", 41.0}},
                 {{"name", "mapping"}, {"seconds", 17.75}}};
  s["total_seconds"] = 101.5;
  s["peak_memory_mb"] = 812.4;
  if (with_eval) {
    s["eval"] = {{"alignment", "sim3"},
                 {"ate_rmse_m", 0.0421},
                 {"ate_median_m", 0.0377},
                 {"ate_mean_m", 0.0399},
                 {"ate_max_m", 0.0912},
                 {"vio_ate_rmse_m", kVioAteRmse},
                 {"vio_ate_median_m", kVioAteMedian},
                 {"num_poses", kFramesRegistered}};
  }
  if (with_eval) {
    s["gyro_check"] = {{"intervals", 28},
                       {"rmse_deg", 0.2741},
                       {"median_deg", 0.222},
                       {"max_deg", 0.6072},
                       {"worst_from_s", 1.0904},
                       {"worst_to_s", 2.1102},
                       {"time_offset_ns", -47332495}};
  } else {
    s["gyro_check"] = {{"message", "no IMU"}};
  }
  s["options_file"] = "options.json";
  return s;
}

struct Fixture {
  fs::path run_dir;
  EvaluationResult estimate_eval;  // what eval.json holds
};

// A complete run folder (every optional file present but eval_vio.json).
Fixture BuildFixture(const fs::path& run_dir) {
  Fixture fixture;
  fixture.run_dir = run_dir;
  fs::create_directories(run_dir / "verification");
  const Trajectory truth = MakeGroundTruth(400);
  const Trajectory estimate = MakeEstimate(truth);
  WriteTumTrajectory(run_dir / "groundtruth_body.tum", truth);
  WriteTumTrajectory(run_dir / "trajectory_body.tum", estimate);
  WriteTumTrajectory(run_dir / "vio_body.tum", MakeVio(truth));
  // The points of a room around the loop (walls of an ellipse, 0 to 2.5 m
  // high, striped), in the estimate's frame.
  std::vector<Eigen::Vector3d> points;
  std::vector<Vector3ub> colors;
  for (int i = 0; i < 20000; ++i) {
    const double a = 2.0 * M_PI * (i % 400) / 400.0;
    const double z = 2.5 * (i / 400) / 50.0;
    points.push_back(kEstFromRef * Eigen::Vector3d(6.0 * std::cos(a), 4.0 * std::sin(a), z));
    const uint8_t v = static_cast<uint8_t>((i / 400) % 2 == 0 ? 230 : 120);
    colors.push_back(Vector3ub(v, v, v));
  }
  WritePlyPoints(run_dir / "points.ply", points, colors);
  EvaluationOptions options;
  options.alignment = AlignmentMode::kSim3;
  fixture.estimate_eval = EvaluateTrajectories(estimate, truth, options);
  WriteEvaluationJson(run_dir / "eval.json", fixture.estimate_eval, options,
                      {"trajectory_body.tum", "tum", "groundtruth_body.tum", "tum"});
  testing::WriteTextFile(run_dir / "summary.json", MakeSummary(true).dump(2));
  nlohmann::ordered_json run_options;
  run_options["mapper"] = {{"batch_size", 40}, {"relative_pose_weight", 1000.0}};
  run_options["verification"] = {{"max_vio_outlier_ratio", 0.5}, {"epipolar_threshold_px", 20}};
  run_options["dataset_path"] = "/data/<loop>&co";
  testing::WriteTextFile(run_dir / "options.json", run_options.dump(2));
  const std::vector<PairDecision> decisions = MakeDecisions();
  VerificationSummary summary;
  summary.num_pairs = kNumPairs;
  summary.num_pairs_without_prior = 6;
  summary.seconds_total = 41.0;
  summary.options = {{"max_vio_outlier_ratio", "0.5"}};
  WriteVerificationJson(run_dir / "verification" / "verification.json", summary, decisions);
  WritePairDecisionsCsv(run_dir / "verification" / "pairs.csv", decisions);
  return fixture;
}

// Every 10th pose of the estimate as a frame of model/ (a 640 x 480 pinhole
// camera looking along the loop, its image's top up), and the frames'
// images, each a flat colour, in a EuRoC-like dataset folder that
// options.json names. Returns the number of frames.
size_t AddModelAndImages(const Fixture& fixture) {
  const fs::path dataset = fixture.run_dir.parent_path() / "dataset";
  const fs::path images = dataset / "mav0" / "cam0" / "data";
  fs::create_directories(images);
  Reconstruction model;
  Camera camera = MakeCamera(CameraModelId::kPinhole, 640, 480, {500, 500, 320, 240});
  camera.camera_id = 1;
  model.AddCamera(camera);
  Eigen::Matrix3d body_from_cam;
  body_from_cam.col(0) = Eigen::Vector3d::UnitX();   // image right
  body_from_cam.col(1) = -Eigen::Vector3d::UnitZ();  // image down
  body_from_cam.col(2) = Eigen::Vector3d::UnitY();   // forward along the loop
  const Trajectory estimate = MakeEstimate(MakeGroundTruth(400));
  size_t n = 0;
  for (size_t i = 0; i < estimate.size(); i += 10, ++n) {
    Image image;
    image.image_id = static_cast<image_t>(n + 1);
    image.camera_id = 1;
    image.name = std::to_string(estimate.poses[i].timestamp_ns) + ".png";
    const Rigid3d world_from_cam =
        estimate.poses[i].world_from_frame * Rigid3d(body_from_cam, Eigen::Vector3d::Zero());
    image.cam_from_world = world_from_cam.Inverse();
    image.registered = true;
    model.AddImage(image);
    const cv::Mat pixels(480, 640, CV_8UC3, cv::Scalar(40, 160, 40));
    EXPECT_TRUE(cv::imwrite((images / image.name).string(), pixels));
  }
  WriteColmapModel(fixture.run_dir / "model", model, ColmapModelFormat::kBinary);
  nlohmann::json options = nlohmann::json::parse(ReadTextFile(fixture.run_dir / "options.json"));
  options["dataset"] = dataset.string();
  testing::WriteTextFile(fixture.run_dir / "options.json", options.dump(2));
  return n;
}

std::string Fixed(double value, int decimals) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.*f", decimals, value);
  return buffer;
}

size_t Count(const std::string& text, const std::string& needle) {
  size_t n = 0;
  for (size_t pos = text.find(needle); pos != std::string::npos;
       pos = text.find(needle, pos + needle.size())) {
    ++n;
  }
  return n;
}

bool Contains(const std::string& text, const std::string& needle) {
  return text.find(needle) != std::string::npos;
}

TEST(RenderRunReport, ShowsTheRunsNumbersAndFigures) {
  const Fixture fixture = BuildFixture(testing::MakeScratchFolder("report_full") / "run");
  const std::string html = RenderRunReport(fixture.run_dir);
  // Summary numbers.
  EXPECT_TRUE(Contains(html, "<th>frames in</th><td class=\"num\">412</td>"));
  EXPECT_TRUE(Contains(html, "<td class=\"num\">197 (47.8 %)</td>"));
  EXPECT_TRUE(Contains(html, "<td class=\"num\">12345</td>"));
  EXPECT_TRUE(Contains(html, "<td class=\"num\">0.812</td>"));
  EXPECT_TRUE(Contains(html,
                       "<th>frame rate and features, from the texture</th><td "
                       "class=\"num\">textured: 2500 of 2500 keypoints; 4 Hz, 2500 "
                       "features</td>"));
  // ATE of the estimate from eval.json, of the VIO from summary.json.
  const double rmse = fixture.estimate_eval.ate_translation_m.rmse;
  EXPECT_GT(rmse, 0.005);
  EXPECT_TRUE(Contains(html, "<th>ATE RMSE, viosfm (m)</th><td class=\"num\">" + Fixed(rmse, 4)));
  EXPECT_TRUE(Contains(html, "<th>ATE median, viosfm (m)</th><td class=\"num\">" +
                                 Fixed(fixture.estimate_eval.ate_translation_m.median, 4)));
  EXPECT_TRUE(Contains(html, "<th>ATE RMSE, input VIO (m)</th><td class=\"num\">0.2345</td>"));
  EXPECT_TRUE(Contains(html, "<th>ATE median, input VIO (m)</th><td class=\"num\">0.1987</td>"));
  // Figures: two trajectory views, the histogram, the stage chart, the BA chart.
  EXPECT_EQ(Count(html, "<svg "), 5u);
  EXPECT_EQ(Count(html, "</svg>"), 5u);
  EXPECT_TRUE(Contains(html, ">position error (m)</text>"));
  EXPECT_TRUE(Contains(html, ">threshold 0.50</text>"));
  EXPECT_TRUE(Contains(html, ">matching</text>"));
  EXPECT_TRUE(Contains(html, ">41.00</text>"));
  const std::vector<PairDecision> decisions = MakeDecisions();
  EXPECT_TRUE(Contains(html, "54 pairs with a VIO check (from verification/pairs.csv); " +
                                 std::to_string(CountAbove(decisions, 0.5)) + " above"));
  EXPECT_TRUE(Contains(html, "<th>rejected by the VIO prior</th><td class=\"num\">12</td>"));
  EXPECT_TRUE(Contains(html, "<th>depth_rejected</th><td class=\"num\">2</td>"));
  // Options, escaped.
  EXPECT_TRUE(Contains(html, "<th>mapper.batch_size</th><td class=\"num\">40</td>"));
  EXPECT_TRUE(Contains(html, "/data/&lt;loop&gt;&amp;co"));
  // Nothing is fetched: outside the embedded scripts of the 3D view (three.js
  // and its data, see HtmlReport.ThreeDViewIsSelfContained) no element loads
  // anything, and no URLs but the SVG namespace.
  std::string outside = html;
  for (size_t start = outside.find("<script>"); start != std::string::npos;
       start = outside.find("<script>", start + 1)) {
    const size_t end = outside.find("</script>", start);
    ASSERT_NE(end, std::string::npos);
    outside.erase(start + 8, end - start - 8);
  }
  EXPECT_FALSE(Contains(outside, "<script src"));
  EXPECT_FALSE(Contains(outside, "src="));
  EXPECT_FALSE(Contains(outside, "href="));
  EXPECT_EQ(Count(outside, "http"), Count(outside, "xmlns=\"http://www.w3.org/2000/svg\""));
  EXPECT_FALSE(Contains(html, "no ground truth"));
  EXPECT_TRUE(Contains(html,
                       "<th>rotations against the gyro over 1 s (deg; the model uses the gyro)</th>"
                       "<td class=\"num\">RMSE 0.274, max 0.607 (1.09 to 2.11 s), 28 intervals"));
  // Deterministic.
  EXPECT_EQ(html, RenderRunReport(fixture.run_dir));
}

TEST(RenderRunReport, MissingOptionalFilesAreNamedInTheirSections) {
  const fs::path run_dir = testing::MakeScratchFolder("report_minimal");
  nlohmann::ordered_json summary = MakeSummary(false);
  summary.erase("stages");
  testing::WriteTextFile(run_dir / "summary.json", summary.dump());
  WriteTumTrajectory(run_dir / "trajectory_body.tum", MakeGroundTruth(50));
  const std::string html = RenderRunReport(run_dir);
  EXPECT_TRUE(Contains(html, "<th>ATE, viosfm</th><td class=\"num\">no ground truth</td>"));
  EXPECT_TRUE(Contains(html, "<th>ATE, input VIO</th><td class=\"num\">no ground truth</td>"));
  EXPECT_TRUE(Contains(html, "<th>rotations against the gyro</th><td class=\"num\">no IMU</td>"));
  EXPECT_TRUE(Contains(html, "no ground truth: no absolute trajectory error"));
  EXPECT_TRUE(Contains(html, "no ground truth: the estimate and the input VIO are drawn"));
  EXPECT_TRUE(Contains(html, "no pair records"));
  EXPECT_TRUE(Contains(html, "no stage timings"));
  EXPECT_TRUE(Contains(html, "no options.json"));
  // The trajectory views and the BA chart are still drawn.
  EXPECT_EQ(Count(html, "<svg "), 3u);
  EXPECT_FALSE(Contains(html, "position error (m)"));
}

// summary.json's `warnings` are listed at the top, before the summary, one
// item each; a run without them has no list.
TEST(RenderRunReport, DecisionsAreListedAtTheTop) {
  const fs::path run_dir = testing::MakeScratchFolder("report_decisions");
  nlohmann::ordered_json summary = MakeSummary(false);
  summary["warnings"] = {
      "time offset: camera-IMU 0.0 -> -47.3 ms (the VIO's estimate replaced "
      "the calibration's)",
      "metric scale: the VIO's (IMU fit not usable: x < y), +-2.00 %"};
  testing::WriteTextFile(run_dir / "summary.json", summary.dump());
  const std::string html = RenderRunReport(run_dir);
  const size_t list = html.find("<ul id=\"decisions\"");
  ASSERT_NE(list, std::string::npos);
  EXPECT_LT(list, html.find("<h2 id=\"summary\">"));
  EXPECT_EQ(Count(html, "<li>"), 2u);
  EXPECT_TRUE(Contains(html,
                       "<li>time offset: camera-IMU 0.0 -&gt; -47.3 ms (the VIO&#39;s "
                       "estimate replaced the calibration&#39;s)</li>"));
  EXPECT_TRUE(Contains(html, "(IMU fit not usable: x &lt; y), +-2.00 %</li>"));

  testing::WriteTextFile(run_dir / "summary.json", MakeSummary(false).dump());
  EXPECT_FALSE(Contains(RenderRunReport(run_dir), "id=\"decisions\""));
}

TEST(RenderRunReport, AteFromSummaryWhenNoEvalFiles) {
  const fs::path run_dir = testing::MakeScratchFolder("report_summary_eval");
  testing::WriteTextFile(run_dir / "summary.json", MakeSummary(true).dump());
  const std::string html = RenderRunReport(run_dir);
  EXPECT_TRUE(Contains(html, "<th>ATE RMSE, viosfm (m)</th><td class=\"num\">0.0421</td>"));
  EXPECT_TRUE(Contains(html, "<th>ATE median, viosfm (m)</th><td class=\"num\">0.0377</td>"));
  EXPECT_TRUE(Contains(html, "<td class=\"num\">0.0912</td>"));
  EXPECT_TRUE(Contains(html, "no trajectory: trajectory_body.tum is missing"));
}

TEST(RenderRunReport, MissingSummaryIsAnInputErrorNamingIt) {
  const fs::path run_dir = testing::MakeScratchFolder("report_no_summary");
  const InputError error = testing::ExpectInputError([&] { RenderRunReport(run_dir); });
  EXPECT_EQ(error.path(), (run_dir / "summary.json").string());
  EXPECT_TRUE(Contains(error.what(), "summary.json"));
}

TEST(RenderRunReport, MalformedFilesAreInputErrorsWithLines) {
  const fs::path run_dir = testing::MakeScratchFolder("report_bad");
  testing::WriteTextFile(run_dir / "summary.json", "{\n  \"frames\": {\"in\": 3},\n  oops\n}\n");
  const InputError error = testing::ExpectInputError([&] { RenderRunReport(run_dir); });
  EXPECT_EQ(error.line(), 3);
  EXPECT_TRUE(Contains(error.what(), "summary.json"));

  testing::WriteTextFile(run_dir / "summary.json", MakeSummary(false).dump());
  fs::create_directories(run_dir / "verification");
  testing::WriteTextFile(run_dir / "verification" / "pairs.csv",
                         "image_id1,image_id2,vio_outlier_ratio\n1,2,0.25\n1,3,nan\n2,3,abc\n");
  const InputError csv_error = testing::ExpectInputError([&] { RenderRunReport(run_dir); });
  EXPECT_EQ(csv_error.line(), 4);
  EXPECT_TRUE(Contains(csv_error.what(), "vio_outlier_ratio"));
}

TEST(WriteRunReport, WritesTheRenderedPageAtomically) {
  const Fixture fixture = BuildFixture(testing::MakeScratchFolder("report_write") / "run");
  const fs::path path = DefaultReportPath(fixture.run_dir);
  EXPECT_EQ(path, fixture.run_dir / "report.html");
  WriteRunReport(fixture.run_dir, path);
  EXPECT_EQ(ReadTextFile(path), RenderRunReport(fixture.run_dir));
  for (const auto& entry : fs::directory_iterator(fixture.run_dir)) {
    EXPECT_EQ(entry.path().string().find(".tmp"), std::string::npos) << entry.path();
  }
}

// Headless Chromium renders the page: the DOM holds the numbers and the SVG
// elements, and a screenshot is a non-trivial image.
constexpr const char* kChromium = "/usr/bin/chromium";

// Runs Chromium with `arguments` on `html`, its stdout to `stdout_path`
// (stderr, which carries its log noise, to a file beside it). Returns the exit status.
// WebGL runs on SwiftShader, Chromium's software renderer (--disable-gpu;
// --enable-unsafe-swiftshader lets versions that ask for it use it).
int RunChromium(const fs::path& scratch, const std::string& arguments, const fs::path& html,
                const fs::path& stdout_path, const std::string& fragment = "") {
  const std::string command = "timeout 60 " + std::string(kChromium) +
                              " --headless --no-sandbox --disable-gpu --enable-unsafe-swiftshader"
                              " --no-first-run --user-data-dir='" +
                              (scratch / "chromium_profile").string() + "' " + arguments +
                              " 'file://" + fs::absolute(html).string() + fragment + "' > '" +
                              stdout_path.string() + "' 2> '" +
                              (scratch / "chromium_stderr.txt").string() + "'";
  return std::system(command.c_str());
}

TEST(ChromiumRendering, DomHoldsNumbersAndScreenshotIsNonTrivial) {
  if (!fs::exists(kChromium)) {
    GTEST_SKIP() << kChromium << " not found (apt-get install chromium); skipping the browser test";
  }
  const char* keep = std::getenv("VIOSFM_REPORT_FIXTURE_DIR");
  const fs::path scratch = testing::MakeScratchFolder("report_chromium");
  // VIOSFM_REPORT_FIXTURE_DIR keeps the fixture run folder (for the docs' screenshot).
  const Fixture fixture = BuildFixture(keep != nullptr ? fs::path(keep) : scratch / "run");
  const fs::path html = fixture.run_dir / "report.html";
  WriteRunReport(fixture.run_dir, html);

  const fs::path dom_path = scratch / "dom.html";
  ASSERT_EQ(RunChromium(scratch, "--dump-dom", html, dom_path), 0)
      << ReadTextFile(scratch / "chromium_stderr.txt");
  const std::string dom = ReadTextFile(dom_path);
  EXPECT_TRUE(Contains(dom, "<h1>viosfm run report</h1>"));
  EXPECT_TRUE(Contains(dom, ">412</td>"));
  EXPECT_TRUE(Contains(dom, ">197 (47.8 %)</td>"));
  EXPECT_TRUE(
      Contains(dom, ">" + Fixed(fixture.estimate_eval.ate_translation_m.rmse, 4) + "</td>"));
  EXPECT_TRUE(Contains(dom, ">0.2345</td>"));
  // The parsed DOM has the SVG elements (Chromium writes <svg> in the HTML
  // namespace and expands self-closing tags).
  EXPECT_EQ(Count(dom, "<svg "), 5u);
  EXPECT_GE(Count(dom, "<polyline "), 10u);
  EXPECT_GE(Count(dom, "</rect>"), 60u);
  EXPECT_TRUE(Contains(dom, "class=\"plot-area\""));
  EXPECT_FALSE(Contains(dom, "<parsererror"));

  const fs::path png = scratch / "report.png";
  ASSERT_EQ(RunChromium(scratch, "--screenshot='" + png.string() + "' --window-size=1200,2000",
                        html, scratch / "screenshot_stdout.txt"),
            0)
      << ReadTextFile(scratch / "chromium_stderr.txt");
  ASSERT_TRUE(fs::is_regular_file(png));
  EXPECT_GT(fs::file_size(png), 20'000u);
  const GreyImage image = ReadGreyImage(png);
  EXPECT_EQ(image.width, 1200);
  EXPECT_EQ(image.height, 2000);
  // Mostly white page with dark text and coloured plots.
  size_t dark = 0, white = 0;
  for (uint8_t v : image.pixels) {
    dark += v < 100;
    white += v > 245;
  }
  EXPECT_GT(white, image.pixels.size() / 2);
  EXPECT_GT(dark, image.pixels.size() / 200);
  if (keep != nullptr)
    fs::copy_file(png, fs::path(keep) / "report.png", fs::copy_options::overwrite_existing);
}

std::vector<uint8_t> DecodeBase64(const std::string& text) {
  static const std::string kAlphabet =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::vector<uint8_t> out;
  uint32_t buffer = 0;
  int bits = 0;
  for (const char c : text) {
    const size_t value = kAlphabet.find(c);
    if (value == std::string::npos) continue;  // '=' padding, line breaks
    buffer = (buffer << 6) | static_cast<uint32_t>(value);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(static_cast<uint8_t>((buffer >> bits) & 0xff));
    }
  }
  return out;
}

// The page is still one file: the 3D view carries three.js and its data.
TEST(HtmlReport, ThreeDViewIsSelfContained) {
  const Fixture fixture = BuildFixture(testing::MakeScratchFolder("report_3d") / "run");
  const std::string html = RenderRunReport(fixture.run_dir);
  if (!Contains(html, "id=\"viewer3d-canvas\"")) {
    ASSERT_TRUE(Contains(html, "no 3D view: three.js was not found"));
    GTEST_SKIP() << "libjs-three not installed (apt-get install libjs-three); skipping";
  }
  EXPECT_TRUE(Contains(html, "REVISION=\"111\""));  // Debian's three.js
  EXPECT_TRUE(Contains(html, "OrbitControls"));
  EXPECT_TRUE(Contains(html, "\"num_points\":20000"));
  EXPECT_TRUE(Contains(html, "Camera path coloured by position error"));
  EXPECT_FALSE(Contains(html, "<script src"));
  EXPECT_FALSE(Contains(html, "<link "));
  EXPECT_EQ(Count(html, "<script>"), 3u);
}

// Headless Chromium draws the 3D view with WebGL: the canvas the page hands
// back (report.html#viewer-selftest) is a PNG with the points and the path
// on the dark background.
TEST(ChromiumRendering, ThreeDViewDrawsWithWebGl) {
  if (!fs::exists(kChromium)) {
    GTEST_SKIP() << kChromium << " not found (apt-get install chromium); skipping the browser test";
  }
  const char* keep = std::getenv("VIOSFM_REPORT_FIXTURE_DIR");
  const fs::path scratch = testing::MakeScratchFolder("report_chromium_3d");
  const Fixture fixture = BuildFixture(keep != nullptr ? fs::path(keep) : scratch / "run");
  const fs::path html = fixture.run_dir / "report.html";
  WriteRunReport(fixture.run_dir, html);
  if (!Contains(ReadTextFile(html), "id=\"viewer3d-canvas\"")) {
    GTEST_SKIP() << "libjs-three not installed (apt-get install libjs-three); skipping";
  }
  const fs::path dom_path = scratch / "dom_3d.html";
  ASSERT_EQ(RunChromium(scratch, "--dump-dom", html, dom_path, "#viewer-selftest"), 0)
      << ReadTextFile(scratch / "chromium_stderr.txt");
  const std::string dom = ReadTextFile(dom_path);
  EXPECT_TRUE(Contains(dom, "20000 of 20000 points, 200 poses")) << "status line missing";
  const std::string prefix = "data:image/png;base64,";
  const size_t start = dom.find(prefix);
  ASSERT_NE(start, std::string::npos) << "no canvas data in the DOM (WebGL unavailable?)";
  const size_t end = dom.find('<', start);
  const std::vector<uint8_t> png =
      DecodeBase64(dom.substr(start + prefix.size(), end - start - prefix.size()));
  const fs::path png_path = scratch / "view3d.png";
  {
    std::ofstream out(png_path, std::ios::binary);
    out.write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size()));
  }
  const GreyImage canvas = ReadGreyImage(png_path);
  EXPECT_EQ(canvas.width, 1100);
  EXPECT_EQ(canvas.height, 600);
  // The background is grey 30; points are 120 and 230, the path is coloured.
  size_t drawn = 0, bright = 0;
  for (const uint8_t v : canvas.pixels) {
    drawn += std::abs(static_cast<int>(v) - 30) > 10;
    bright += v > 180;
  }
  const size_t total = canvas.pixels.size();
  EXPECT_GT(drawn, total / 100) << drawn << " of " << total << " pixels drawn";
  EXPECT_LT(drawn, total * 9 / 10);
  EXPECT_GT(bright, total / 1000);
  if (keep != nullptr) {
    fs::copy_file(png_path, fs::path(keep) / "view3d.png", fs::copy_options::overwrite_existing);
  }
}

// The 3D view with the frames of model/: headless Chromium draws the
// frustums (orange), the grid and the x, y, z axes (red, green, blue), and a
// click on a frustum (#viewer-selftest-click) marks it (yellow) and shows its
// frame's image and name.
TEST(ChromiumRendering, ThreeDViewShowsFrustumsGridAxesAndTheClickedFrame) {
  if (!fs::exists(kChromium)) {
    GTEST_SKIP() << kChromium << " not found (apt-get install chromium); skipping the browser test";
  }
  const char* keep = std::getenv("VIOSFM_REPORT_FIXTURE_DIR");
  const fs::path scratch = testing::MakeScratchFolder("report_chromium_frustums");
  const Fixture fixture = BuildFixture(keep != nullptr ? fs::path(keep) : scratch / "run");
  const size_t num_frames = AddModelAndImages(fixture);
  const fs::path html = fixture.run_dir / "report.html";
  WriteRunReport(fixture.run_dir, html);
  const std::string page = ReadTextFile(html);
  if (!Contains(page, "id=\"viewer3d-canvas\"")) {
    GTEST_SKIP() << "libjs-three not installed (apt-get install libjs-three); skipping";
  }
  EXPECT_TRUE(Contains(page, "z blue (up, against gravity)"));
  const fs::path dom_path = scratch / "dom_click.html";
  ASSERT_EQ(RunChromium(scratch, "--dump-dom", html, dom_path, "#viewer-selftest-click"), 0)
      << ReadTextFile(scratch / "chromium_stderr.txt");
  const std::string dom = ReadTextFile(dom_path);
  EXPECT_TRUE(Contains(dom, "200 poses, " + std::to_string(num_frames) + " cameras"));
  // The click picked a frame, and the panel shows it: no longer hidden, its
  // caption the image's name, its image a JPEG thumbnail.
  const size_t clicked_at = dom.find("data-clicked=\"");
  ASSERT_NE(clicked_at, std::string::npos);
  const int clicked = std::stoi(dom.substr(clicked_at + 14));
  ASSERT_GE(clicked, 0) << "no frustum visible to click";
  ASSERT_LT(clicked, static_cast<int>(num_frames));
  EXPECT_TRUE(Contains(
      dom, "<figure id=\"viewer3d-frame\" data-frame=\"" + std::to_string(clicked) + "\">"))
      << dom.substr(dom.find("<figure id=\"viewer3d-frame\""), 200);
  const Trajectory estimate = MakeEstimate(MakeGroundTruth(400));
  const std::string name =
      std::to_string(estimate.poses[10 * static_cast<size_t>(clicked)].timestamp_ns) + ".png";
  EXPECT_TRUE(Contains(dom, "<figcaption id=\"viewer3d-frame-caption\">" + name + " ("));
  EXPECT_TRUE(Contains(dom,
                       "id=\"viewer3d-frame-image\" alt=\"the frame's image\" "
                       "src=\"data:image/jpeg;base64,"));

  const std::string prefix = "data:image/png;base64,";
  const size_t start = dom.find(prefix);
  ASSERT_NE(start, std::string::npos) << "no canvas data in the DOM (WebGL unavailable?)";
  const size_t end = dom.find('<', start);
  const std::vector<uint8_t> png =
      DecodeBase64(dom.substr(start + prefix.size(), end - start - prefix.size()));
  const cv::Mat canvas = cv::imdecode(png, cv::IMREAD_COLOR);
  ASSERT_FALSE(canvas.empty());
  if (keep != nullptr) {
    cv::imwrite((fs::path(keep) / "view3d_frames.png").string(), canvas);
  }
  // Pixels near each element's colour (BGR): frustums 0xff8c1a, the clicked
  // one 0xffff00, axes 0xe53935, 0x43a047, 0x1e88e5, the grid's lines 0x8a8a8a
  // and 0x4a4a4a.
  const auto count = [&canvas](int r, int g, int b, int tolerance) {
    size_t n = 0;
    for (int y = 0; y < canvas.rows; ++y) {
      for (int x = 0; x < canvas.cols; ++x) {
        const cv::Vec3b p = canvas.at<cv::Vec3b>(y, x);
        n += std::abs(p[2] - r) <= tolerance && std::abs(p[1] - g) <= tolerance &&
             std::abs(p[0] - b) <= tolerance;
      }
    }
    return n;
  };
  EXPECT_GT(count(0xff, 0x8c, 0x1a, 30), 200u) << "frustums";
  EXPECT_GT(count(0xff, 0xff, 0x00, 30), 20u) << "the clicked frustum";
  EXPECT_GT(count(0xe5, 0x39, 0x35, 30), 20u) << "x axis";
  EXPECT_GT(count(0x43, 0xa0, 0x47, 30), 20u) << "y axis";
  EXPECT_GT(count(0x1e, 0x88, 0xe5, 30), 20u) << "z axis";
  EXPECT_GT(count(0x8a, 0x8a, 0x8a, 12) + count(0x4a, 0x4a, 0x4a, 12), 1000u) << "grid";
}

}  // namespace
}  // namespace viosfm

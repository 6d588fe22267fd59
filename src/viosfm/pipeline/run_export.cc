#include "viosfm/pipeline/run_export.h"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <vector>

#include "viosfm/io/bag_container.h"
#include "viosfm/io/colmap_model.h"
#include "viosfm/io/colmap_pose_priors.h"
#include "viosfm/io/ply.h"
#include "viosfm/io/transforms_json.h"
#include "viosfm/sfm/camera_position_covariance.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/logging.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;

// The folder the run read its images from, from RUN/options.json; empty if
// it cannot be told or does not exist.
fs::path ImageFolderOfRun(const fs::path& run_folder) {
  const fs::path options_file = run_folder / "options.json";
  std::error_code error;
  if (!fs::is_regular_file(options_file, error)) return {};
  nlohmann::json options;
  try {
    options = nlohmann::json::parse(ReadTextFile(options_file));
  } catch (const nlohmann::json::exception& e) {
    throw InputError(options_file.string(), 0, std::string("not valid JSON: ") + e.what());
  }
  const auto text = [&options](const char* key) -> std::string {
    return options.contains(key) && options[key].is_string() ? options[key].get<std::string>()
                                                             : std::string();
  };
  const fs::path dataset = text("dataset");
  if (dataset.empty()) return {};
  std::vector<fs::path> candidates;
  if (IsBagPath(dataset)) {
    const fs::path extract = text("rosbag.extract_folder");
    candidates = {extract / "mav0" / "cam0" / "data",
                  run_folder / "bag" / "mav0" / "cam0" / "data"};
  } else {
    candidates = {dataset / "mav0" / "cam0" / "data", dataset / "cam0" / "data", dataset};
  }
  for (const fs::path& candidate : candidates) {
    if (!candidate.empty() && fs::is_directory(candidate, error)) return fs::absolute(candidate);
  }
  return {};
}

// imu_scale.applied_scale_sigma of RUN/summary.json (relative); 0 when the
// run predates it or has none (the priors then leave the scale out).
double ScaleSigmaOfRun(const fs::path& summary_file) {
  nlohmann::json summary;
  try {
    summary = nlohmann::json::parse(ReadTextFile(summary_file));
  } catch (const nlohmann::json::exception& e) {
    throw InputError(summary_file.string(), 0, std::string("not valid JSON: ") + e.what());
  }
  const nlohmann::json* scale = summary.contains("imu_scale") ? &summary["imu_scale"] : nullptr;
  if (scale == nullptr || !scale->is_object() || !scale->contains("applied_scale_sigma") ||
      !(*scale)["applied_scale_sigma"].is_number()) {
    VIOSFM_LOG(WARNING) << "export: " << summary_file.string()
                        << " has no imu_scale.applied_scale_sigma (a run of an older viosfm): "
                           "the priors' covariances leave the scale's uncertainty out";
    return 0.0;
  }
  const double sigma = (*scale)["applied_scale_sigma"].get<double>();
  if (!(sigma >= 0.0) || !std::isfinite(sigma)) {
    throw InputError(summary_file.string(), 0,
                     "imu_scale.applied_scale_sigma must be a non-negative number");
  }
  return sigma;
}

}  // namespace

std::string RunExportOptions::Validate() const {
  if (run_folder.empty()) return "run_folder: a run folder is required";
  if (!(prior_position_stddev_m >= 0) || !std::isfinite(prior_position_stddev_m)) {
    return "prior_position_stddev_m must be 0 (the model's covariances) or positive";
  }
  return "";
}

RunExportSummary ExportRun(const RunExportOptions& options) {
  if (const std::string error = options.Validate(); !error.empty()) {
    throw InputError("invalid export options: " + error);
  }
  const fs::path run = options.run_folder;
  RequireFolder(run, "run folder");
  // summary.json is written last: without it the run was interrupted (or is
  // still running) and its other files may be stale or missing.
  RequireFile(run / "summary.json",
              "summary.json of a finished run (an interrupted run has none: run it again)");
  RequireFile(run / "database.db", "COLMAP database of the run");
  RequireFolder(run / "model", "COLMAP model of the run");
  const Reconstruction model = ReadColmapModel(run / "model");

  RunExportSummary summary;
  summary.output_folder = options.output_folder.empty() ? run / "export" : options.output_folder;
  summary.image_folder =
      options.image_folder.empty() ? ImageFolderOfRun(run) : fs::absolute(options.image_folder);
  if (!options.image_folder.empty()) RequireFolder(options.image_folder, "image folder");
  if (summary.image_folder.empty()) {
    VIOSFM_LOG(WARNING) << "export: the run's image folder was not found (from " << run.string()
                        << "/options.json); no images link (give --images)";
  }

  // Pose priors of the registered images: the camera centre, the given,
  // the model's or the isotropic covariance, and (for COLMAP 3.8) the rotation.
  const bool from_model = options.prior_position_stddev_m == 0.0;
  const double stddev = from_model ? kFallbackPositionStddevM : options.prior_position_stddev_m;
  const double variance = stddev * stddev;
  CameraPositionCovariances model_covariances;
  if (from_model) {
    CameraPositionCovarianceOptions covariance_options;
    covariance_options.scale_sigma = ScaleSigmaOfRun(run / "summary.json");
    model_covariances = ComputeCameraPositionCovariances(model, covariance_options);
    summary.keypoint_sigma_px = model_covariances.keypoint_sigma_px;
    summary.scale_sigma = covariance_options.scale_sigma;
  }
  std::vector<double> position_stddevs;
  std::vector<ColmapPosePrior> priors;
  TransformsJson transforms;
  std::vector<image_t> ids = model.RegImageIds();
  std::sort(ids.begin(), ids.end());
  for (const image_t image_id : ids) {
    const Image& image = model.GetImage(image_id);
    ColmapPosePrior prior;
    prior.image_id = image_id;
    prior.position = image.ProjectionCenter();
    prior.cam_from_world_rotation = image.cam_from_world.rotation;
    const auto covariance = options.prior_position_covariances.find(image.name);
    const auto from_model_entry = model_covariances.by_image.find(image_id);
    if (covariance != options.prior_position_covariances.end()) {
      prior.position_covariance = covariance->second;
      ++summary.num_priors_from_covariances;
    } else if (from_model_entry != model_covariances.by_image.end()) {
      prior.position_covariance = from_model_entry->second;
      ++summary.num_priors_from_model;
    } else {
      prior.position_covariance = variance * Eigen::Matrix3d::Identity();
      ++summary.num_priors_isotropic;
    }
    position_stddevs.push_back(std::sqrt(prior.position_covariance.trace() / 3.0));
    priors.push_back(prior);
    transforms.frames.push_back({"images/" + image.name, image.cam_from_world});
  }
  if (model.NumCameras() != 1) {
    throw InputError(
        (run / "model").string(), 0,
        "transforms.json holds one camera; the model has " + std::to_string(model.NumCameras()));
  }
  if (!position_stddevs.empty()) {
    auto middle =
        position_stddevs.begin() + static_cast<std::ptrdiff_t>(position_stddevs.size() / 2);
    std::nth_element(position_stddevs.begin(), middle, position_stddevs.end());
    summary.median_position_stddev_m = *middle;
  }
  transforms.camera = model.Cameras().begin()->second;
  transforms.ply_file_path = "sparse_pc.ply";
  summary.num_images = ids.size();
  summary.num_points = model.NumPoints3D();

  WriteFolderAtomically(summary.output_folder, [&](const fs::path& folder) {
    CopyColmapDatabase(run / "database.db", folder / "database.db");
    WriteColmapPosePriors(folder / "database.db", priors);
    fs::create_directories(folder / "sparse" / "0");
    for (const char* file : {"cameras.bin", "images.bin", "points3D.bin"}) {
      fs::copy_file(run / "model" / file, folder / "sparse" / "0" / file);
    }
    WriteTransformsJson(folder / "transforms.json", transforms);
    WritePly(folder / "sparse_pc.ply", model);
    if (!summary.image_folder.empty()) {
      fs::create_directory_symlink(summary.image_folder, folder / "images");
    }
  });
  VIOSFM_LOG(INFO) << "export: " << summary.num_images << " images, " << summary.num_points
                   << " points -> " << summary.output_folder.string()
                   << " (database.db with pose priors, sparse/0, transforms.json, sparse_pc.ply"
                   << (summary.image_folder.empty()
                           ? ""
                           : ", images -> " + summary.image_folder.string())
                   << ")";
  VIOSFM_LOG(INFO) << "export: pose priors: " << summary.num_priors_from_model
                   << " with the model's covariance (keypoint sigma " << summary.keypoint_sigma_px
                   << " px, scale sigma " << summary.scale_sigma << "), "
                   << summary.num_priors_from_covariances << " given, "
                   << summary.num_priors_isotropic << " isotropic (" << stddev
                   << " m); median position stddev " << summary.median_position_stddev_m << " m";
  return summary;
}

}  // namespace viosfm

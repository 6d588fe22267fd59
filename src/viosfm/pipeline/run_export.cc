#include "viosfm/pipeline/run_export.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <optional>
#include <vector>

#include "viosfm/io/bag_container.h"
#include "viosfm/io/colmap_model.h"
#include "viosfm/io/colmap_pose_priors.h"
#include "viosfm/io/ply.h"
#include "viosfm/io/transforms_json.h"
#include "viosfm/pipeline/run_folder.h"
#include "viosfm/sfm/camera_position_covariance.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/folder_manifest.h"
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

bool IsInsideOrSame(const fs::path& path, const fs::path& folder) {
  const auto [folder_end, path_it] =
      std::mismatch(folder.begin(), folder.end(), path.begin(), path.end());
  return folder_end == folder.end();
}

// InputError naming `output` when an export there would replace the run or
// a folder holding it.
void CheckExportFolderPlace(const fs::path& run, const fs::path& output) {
  const fs::path run_path = fs::weakly_canonical(fs::absolute(run));
  const fs::path output_path = fs::weakly_canonical(fs::absolute(output));
  if (output_path == run_path) {
    throw InputError(output.string(), 0,
                     "--out is the run folder itself: an export goes into a folder of its own "
                     "(default RUN/export); nothing was changed");
  }
  if (IsInsideOrSame(run_path, output_path)) {
    throw InputError(output.string(), 0,
                     "--out holds the run folder " + run.string() +
                         ": an export goes into a folder of its own (default RUN/export); "
                         "nothing was changed");
  }
}

// The name of `output` in `run`, if it lies inside it; InputError naming
// it if it lies deeper than directly inside (in one of the run's folders).
std::optional<std::string> NameInsideRun(const fs::path& run, const fs::path& output) {
  const fs::path run_path = fs::weakly_canonical(fs::absolute(run));
  const fs::path output_path = fs::weakly_canonical(fs::absolute(output));
  if (!IsInsideOrSame(output_path, run_path) || output_path == run_path) return std::nullopt;
  if (output_path.parent_path() != run_path) {
    throw InputError(output.string(), 0,
                     "--out lies inside a folder of the run: an export inside the run folder goes "
                     "directly into it (default RUN/export); nothing was changed");
  }
  return output_path.filename().string();
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
  const fs::path output = options.output_folder.empty() ? run / "export" : options.output_folder;
  CheckExportFolderPlace(run, output);
  const std::optional<std::string> inside_run = NameInsideRun(run, output);
  // The run's folder is locked while it is read (and its manifest records
  // an export written inside it); the export's folder by its manifest.
  std::optional<ManagedFolder> run_manifest;
  std::optional<FolderLock> run_lock;
  if (ReadFolderManifest(run)) {
    run_manifest.emplace(run, RunFolderManifestOptions());
  } else {
    run_lock.emplace(run, "another viosfm command");
  }
  // summary.json is written last: without it the run was interrupted (or is
  // still running) and its other files may be stale or missing.
  RequireFile(run / "summary.json",
              "summary.json of a finished run (an interrupted run has none: run it again)");
  RequireFile(run / "database.db", "COLMAP database of the run");
  RequireFolder(run / "model", "COLMAP model of the run");
  const Reconstruction model = ReadColmapModel(run / "model");

  RunExportSummary summary;
  summary.output_folder = output;
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

  // An export folder inside the run is the run's, with a manifest of its
  // own (what the user adds there stays through the run's --overwrite).
  if (inside_run && run_manifest) {
    if (run_manifest->IsForeign(*inside_run) &&
        run_manifest->manifest().subfolders.count(*inside_run) == 0) {
      throw InputError((run / *inside_run).string(), 0,
                       "--out: exists in the run folder and viosfm did not write it; choose "
                       "another --out");
    }
  }
  ManagedFolder::Options export_options;
  export_options.kind = "export";
  export_options.flag = "--out";
  ManagedFolder folder(output, export_options);
  const std::string temporary = ".viosfm-export.tmp-" + std::to_string(::getpid());
  folder.Claim({"database.db", "sparse", "transforms.json", "sparse_pc.ply", "images", temporary});
  if (inside_run && run_manifest) {
    run_manifest->AddSubfolder(*inside_run);
    run_manifest->Save();
  }
  // The earlier export's files go (the user's stay); the new ones are
  // written aside, then moved in.
  folder.RemoveWritten();
  const fs::path staging = output / temporary;
  fs::create_directories(staging / "sparse" / "0");
  CopyColmapDatabase(run / "database.db", staging / "database.db");
  WriteColmapPosePriors(staging / "database.db", priors);
  for (const char* file : {"cameras.bin", "images.bin", "points3D.bin"}) {
    fs::copy_file(run / "model" / file, staging / "sparse" / "0" / file);
  }
  WriteTransformsJson(staging / "transforms.json", transforms);
  WritePly(staging / "sparse_pc.ply", model);
  if (!summary.image_folder.empty()) {
    fs::create_directory_symlink(summary.image_folder, staging / "images");
  }
  for (const char* name : {"database.db", "sparse", "transforms.json", "sparse_pc.ply", "images"}) {
    if (fs::symlink_status(staging / name).type() != fs::file_type::not_found) {
      fs::rename(staging / name, output / name);
    }
  }
  fs::remove_all(staging);
  SyncToDisk(output);
  folder.Finish();
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

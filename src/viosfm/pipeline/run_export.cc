#include "viosfm/pipeline/run_export.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <vector>

#include "viosfm/io/bag_container.h"
#include "viosfm/io/colmap_database.h"
#include "viosfm/io/colmap_model.h"
#include "viosfm/io/colmap_pose_priors.h"
#include "viosfm/io/ply.h"
#include "viosfm/io/transforms_json.h"
#include "viosfm/pipeline/run_folder.h"
#include "viosfm/scene/reprojection.h"
#include "viosfm/sfm/camera_position_covariance.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/folder_manifest.h"
#include "viosfm/util/logging.h"
#include "viosfm/util/progress.h"

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

// The pose priors of the registered images and their transforms.json frames.
struct PosePriors {
  std::vector<ColmapPosePrior> priors;
  TransformsJson transforms;
};

// The camera centre of each registered image with the given, the model's or
// the isotropic covariance, and (for COLMAP 3.8) the rotation.
PosePriors MakePosePriors(const RunExportOptions& options, const fs::path& run,
                          const Reconstruction& model, RunExportSummary* summary) {
  const bool from_model = options.prior_position_stddev_m == 0.0;
  const double stddev = from_model ? kFallbackPositionStddevM : options.prior_position_stddev_m;
  CameraPositionCovariances model_covariances;
  if (from_model) {
    CameraPositionCovarianceOptions covariance_options;
    covariance_options.scale_sigma = ScaleSigmaOfRun(run / "summary.json");
    model_covariances = ComputeCameraPositionCovariances(model, covariance_options);
    summary->keypoint_sigma_px = model_covariances.keypoint_sigma_px;
    summary->scale_sigma = covariance_options.scale_sigma;
  }
  PosePriors result;
  std::vector<double> position_stddevs;
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
      ++summary->num_priors_from_covariances;
    } else if (from_model_entry != model_covariances.by_image.end()) {
      prior.position_covariance = from_model_entry->second;
      ++summary->num_priors_from_model;
    } else {
      prior.position_covariance = stddev * stddev * Eigen::Matrix3d::Identity();
      ++summary->num_priors_isotropic;
    }
    position_stddevs.push_back(std::sqrt(prior.position_covariance.trace() / 3.0));
    result.priors.push_back(prior);
    result.transforms.frames.push_back({"images/" + image.name, image.cam_from_world});
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
    summary->median_position_stddev_m = *middle;
  }
  result.transforms.camera = model.Cameras().begin()->second;
  result.transforms.ply_file_path = "sparse_pc.ply";
  summary->num_images = ids.size();
  return result;
}

// The image names of the run's database (paths relative to its image
// folder); InputError naming the database for a name that would lead out
// of the export's images/ folder.
std::vector<std::string> DatabaseImageNames(const fs::path& database_path) {
  std::vector<std::string> names;
  for (const DatabaseImage& image : ColmapDatabase::Open(database_path).ReadAllImages()) {
    const fs::path name = fs::path(image.name).lexically_normal();
    if (image.name.empty() || name.is_absolute() || *name.begin() == "..") {
      throw InputError(database_path.string(), 0,
                       "image " + std::to_string(image.image_id) + " is named '" + image.name +
                           "': expected a path inside the image folder");
    }
    names.push_back(image.name);
  }
  return names;
}

// Puts each image `names` of `image_folder` into `images` (a new folder):
// a hard link to the image's file (its target, if it is a symbolic link)
// where the filesystem allows, else a copy. InputError naming the image
// file for one that is missing.
void PlaceImages(const fs::path& image_folder, const std::vector<std::string>& names,
                 const fs::path& images, RunExportSummary* summary) {
  ProgressBar progress("export: images", static_cast<int64_t>(names.size()));
  bool links_refused = false;  // after the first refusal, copy without trying
  for (const std::string& name : names) {
    const fs::path source = image_folder / name;
    std::error_code error;
    if (!fs::is_regular_file(source, error)) {
      throw InputError(source.string(), 0,
                       "image of the run's database not found in its image folder (give the "
                       "folder that holds the run's images with --images)");
    }
    const fs::path target = images / name;
    fs::create_directories(target.parent_path());
    const fs::path file = fs::canonical(source);
    if (!links_refused) {
      fs::create_hard_link(file, target, error);
      if (!error) {
        ++summary->num_images_linked;
        progress.Update();
        continue;
      }
      links_refused = true;
      VIOSFM_LOG(INFO) << "export: images copied (a hard link from " << file.string()
                       << " was refused: " << error.message() << ")";
    }
    fs::copy_file(file, target);
    ++summary->num_images_copied;
    summary->bytes_copied += fs::file_size(target);
    progress.Update();
  }
  summary->num_image_files = names.size();
}

// Writes the export's files into `staging` (a new folder in the export's).
void WriteStaging(const fs::path& run, const Reconstruction& model, const PosePriors& priors,
                  const fs::path& staging, RunExportSummary* summary) {
  fs::create_directories(staging / "sparse" / "0");
  CopyColmapDatabase(run / "database.db", staging / "database.db");
  WriteColmapPosePriors(staging / "database.db", priors.priors);
  for (const char* file : {"cameras.bin", "images.bin", "points3D.bin"}) {
    fs::copy_file(run / "model" / file, staging / "sparse" / "0" / file);
  }
  WriteTransformsJson(staging / "transforms.json", priors.transforms);
  WritePly(staging / "sparse_pc.ply", model);
  if (!summary->image_folder.empty()) {
    PlaceImages(summary->image_folder, DatabaseImageNames(staging / "database.db"),
                staging / "images", summary);
  }
  WriteFileAtomically(staging / "README.txt", [summary](std::ostream& out) {
    out << (summary->num_image_files > 0
                ? "viosfm export: self-contained (paths relative to this folder). images/ holds "
                  "hard links to the run's images where the filesystem allows (the same files: "
                  "edit copies of them), else copies."
                : "viosfm export WITHOUT the images: the run's image folder was not found (viosfm "
                  "export --images DIR adds them); paths are relative to this folder.")
        << " From a shell in this folder:\n\n"
        << ExportGuide(*summary, fs::path());
  });
}

// The names an export writes into its folder (the manifest claims them).
const std::vector<std::string> kExportNames = {"images",          "database.db",   "sparse",
                                               "transforms.json", "sparse_pc.ply", "README.txt"};

std::string Fixed(double value, int decimals) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(decimals) << value;
  return out.str();
}

}  // namespace

ModelReprojectionErrors ComputeModelReprojectionErrors(const Reconstruction& model) {
  ModelReprojectionErrors errors;
  errors.num_observations = model.ComputeNumObservations();
  errors.mean_over_observations_px = MeanReprojectionError(model);
  double sum = 0.0;
  for (const point3D_t id : model.Point3DIds()) {
    const Point3D& point3D = model.GetPoint3D(id);
    if (point3D.error == -1.0) continue;  // COLMAP's "no error"
    sum += point3D.error;
    ++errors.num_points;
  }
  errors.mean_over_points_px =
      errors.num_points == 0 ? 0.0 : sum / static_cast<double>(errors.num_points);
  return errors;
}

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
                        << "/options.json); the export holds no images (give --images)";
  }
  const PosePriors priors = MakePosePriors(options, run, model, &summary);
  summary.num_points = model.NumPoints3D();
  summary.reprojection = ComputeModelReprojectionErrors(model);

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
  std::vector<std::string> claimed = kExportNames;
  claimed.push_back(temporary);
  folder.Claim(claimed);
  if (inside_run && run_manifest) {
    run_manifest->AddSubfolder(*inside_run);
    run_manifest->Save();
  }
  // The earlier export's files go (the user's stay); the new ones are
  // written aside, then moved in.
  folder.RemoveWritten();
  const fs::path staging = output / temporary;
  try {
    WriteStaging(run, model, priors, staging, &summary);
  } catch (...) {
    std::error_code ignored;
    fs::remove_all(staging, ignored);  // ours: nothing half-written stays
    throw;
  }
  for (const std::string& name : kExportNames) {
    if (fs::symlink_status(staging / name).type() != fs::file_type::not_found) {
      fs::rename(staging / name, output / name);
    }
  }
  fs::remove_all(staging);
  SyncToDisk(output);
  folder.Finish();
  VIOSFM_LOG(INFO) << "export: " << summary.num_images << " images, " << summary.num_points
                   << " points -> " << summary.output_folder.string()
                   << " (database.db with pose priors, sparse/0, transforms.json, sparse_pc.ply, "
                   << summary.num_image_files << " images: " << summary.num_images_linked
                   << " hard links, " << summary.num_images_copied << " copies of "
                   << Fixed(static_cast<double>(summary.bytes_copied) / 1e6, 1) << " MB)";
  VIOSFM_LOG(INFO) << "export: pose priors: " << summary.num_priors_from_model
                   << " with the model's covariance (keypoint sigma " << summary.keypoint_sigma_px
                   << " px, scale sigma " << summary.scale_sigma << "), "
                   << summary.num_priors_from_covariances << " given, "
                   << summary.num_priors_isotropic << " isotropic; median position stddev "
                   << summary.median_position_stddev_m << " m";
  return summary;
}

std::string ExportGuide(const RunExportSummary& summary, const fs::path& folder) {
  const auto at = [&folder](const std::string& name) {
    return folder.empty() ? name : (folder / name).string();
  };
  const std::string database = " --database_path " + at("database.db");
  const std::string images = " --image_path " + at("images");
  std::ostringstream out;
  out << "COLMAP 3.8 (Debian 12's; headless: QT_QPA_PLATFORM=offscreen):\n"
      << "  colmap model_analyzer --path " << at("sparse/0") << "\n"
      << "  # COLMAP's points from viosfm's poses (held) and verified matches:\n"
      << "  mkdir -p " << at("colmap_triangulated") << "\n"
      << "  colmap point_triangulator" << database << images << " --input_path " << at("sparse/0")
      << " --output_path " << at("colmap_triangulated") << "\n"
      << "  # COLMAP's own model from the same matches, moved onto viosfm's camera positions\n"
      << "  # (the pose priors in database.db, in the frame and scale of viosfm's model):\n"
      << "  mkdir -p " << at("colmap_sparse") << "\n"
      << "  colmap mapper" << database << images << " --output_path " << at("colmap_sparse") << "\n"
      << "  colmap model_aligner --input_path " << at("colmap_sparse/0") << " --output_path "
      << at("colmap_sparse/0") << database
      << " --ref_is_gps 0 --alignment_type custom --robust_alignment_max_error 0.1\n"
      << "  # Undistorted images and a PINHOLE model (for dense stereo, 3D Gaussian splatting):\n"
      << "  colmap image_undistorter" << images << " --input_path " << at("sparse/0")
      << " --output_path " << at("undistorted") << "\n"
      << "COLMAP 3.10 and later: the pose_priors table (each position with its covariance):\n"
      << "  colmap pose_prior_mapper" << database << images << " --output_path "
      << at("colmap_sparse") << "\n"
      << "nerfstudio (transforms.json, initial points sparse_pc.ply):\n"
      << "  ns-train splatfacto --data " << (folder.empty() ? "." : folder.string()) << "\n"
      << "gsplat (its COLMAP example reads sparse/0 and images/):\n"
      << "  python examples/simple_trainer.py default --data_dir "
      << (folder.empty() ? "." : folder.string()) << " --data_factor 1 --result_dir "
      << at("gsplat") << "\n"
      << "Mean reprojection error of sparse/0, two averages of the same residuals:\n"
      << "  " << Fixed(summary.reprojection.mean_over_observations_px, 4) << " px over its "
      << summary.reprojection.num_observations
      << " observations (viosfm's: summary.json, the run's log)\n"
      << "  " << Fixed(summary.reprojection.mean_over_points_px, 4) << " px over its "
      << summary.reprojection.num_points
      << " points, each point's own mean counted once (COLMAP's model_analyzer)\n";
  return out.str();
}

}  // namespace viosfm

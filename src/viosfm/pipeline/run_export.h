// `viosfm export RUN`: a finished run folder (pipeline.h) turned into the
// inputs of the next tools, in one folder (default RUN/export; a new or
// empty folder, or an earlier export: never the run itself, a folder that
// holds it, or a folder of the user's), whose viosfm_manifest.json lists
// what the export wrote (util/folder_manifest.h: an export again replaces
// those files only, so what the user added, e.g. COLMAP's output, stays):
//
//   images -> ...        a symbolic link to the run's image folder (EuRoC
//                        mav0/cam0/data, the image folder, or RUN/bag/... for
//                        a bag), so the paths below resolve
//   database.db          the run's COLMAP database (features, matches, verified
//                        pairs) with viosfm's poses as pose priors: COLMAP
//                        3.10+'s pose_priors table (position, Cartesian
//                        coordinate system, 3x3 position covariance) and
//                        COLMAP 3.8's images.prior_* columns
//                        (io/colmap_pose_priors.h)
//   sparse/0/            the run's COLMAP model (cameras, images, points3D .bin)
//   transforms.json      nerfstudio / instant-ngp cameras (io/transforms_json.h)
//                        of the registered images, file paths "images/<name>"
//   sparse_pc.ply        the model's points (ply_file_path of transforms.json)
//
// so that, e.g.:
//   colmap pose_prior_mapper --database_path E/database.db --image_path E/images
//                            --output_path E/colmap_sparse          (COLMAP 3.10+)
//   colmap point_triangulator --database_path E/database.db --image_path E/images
//                            --input_path E/sparse/0 --output_path OUT   (3.8+)
//   ns-train splatfacto --data E                                     (nerfstudio)
//
// Why a separate step and not part of `viosfm run`: it needs only the run
// folder, so any finished run can be exported (again, with other priors)
// without recomputing; the database copy doubles the disk use, which a user
// should ask for; and the pose-prior covariances can come from a model of
// the VIO's uncertainty without `viosfm run` knowing about the export.
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <map>
#include <string>

namespace viosfm {

// The isotropic standard deviation (m) of a prior the model does not fix
// (fewer than three observations, or a degenerate view of them).
inline constexpr double kFallbackPositionStddevM = 0.1;

struct RunExportOptions {
  // The run folder (with summary.json, model/, database.db). Required.
  std::filesystem::path run_folder;
  // Where the export is written. Default RUN/export.
  std::filesystem::path output_folder;
  // The images the run read; default: from RUN/options.json (the dataset,
  // or the bag's extract folder).
  std::filesystem::path image_folder;
  // The covariance of each camera position prior (images without an entry
  // in prior_position_covariances). 0 (default): the model's own, per image
  // (sfm/camera_position_covariance.h): from the image's 2D-3D observations
  // at the model's keypoint sigma, plus the metric scale's uncertainty
  // (summary.json imu_scale.applied_scale_sigma) along the camera's offset
  // from the first image; kFallbackPositionStddevM for an image the model
  // does not fix. > 0: this standard deviation (m), isotropic, for every
  // image (e.g. 0.1 m to let COLMAP's images decide locally while the priors
  // only hold the metric, gravity-aligned frame).
  double prior_position_stddev_m = 0.0;
  // Per-image 3x3 covariance of the camera position (m^2), by image name,
  // taken before either of the above. Default empty.
  std::map<std::string, Eigen::Matrix3d> prior_position_covariances;

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }
};

struct RunExportSummary {
  std::filesystem::path output_folder;
  std::filesystem::path image_folder;  // empty if it could not be found (no link)
  size_t num_images = 0;               // registered images exported
  size_t num_points = 0;
  size_t num_priors_from_covariances = 0;  // priors whose covariance was given
  size_t num_priors_from_model = 0;        // priors with the model's covariance
  size_t num_priors_isotropic = 0;         // the given or the fallback stddev
  double keypoint_sigma_px = 0.0;          // the model's, when used
  double scale_sigma = 0.0;                // the model's scale's (relative), when used
  double median_position_stddev_m = 0.0;   // sqrt(trace / 3) of the priors' covariances
};

// Throws InputError naming the file for a missing or malformed run folder.
RunExportSummary ExportRun(const RunExportOptions& options);

}  // namespace viosfm

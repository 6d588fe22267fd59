// `viosfm export RUN`: a finished run folder (pipeline.h) turned into the
// inputs of the next tools, in one folder (default RUN/export):
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

struct RunExportOptions {
  // The run folder (with summary.json, model/, database.db). Required.
  std::filesystem::path run_folder;
  // Where the export is written (replaced atomically). Default RUN/export.
  std::filesystem::path output_folder;
  // The images the run read; default: from RUN/options.json (the dataset,
  // or the bag's extract folder).
  std::filesystem::path image_folder;
  // Standard deviation of each camera position prior, isotropic (m), used
  // for images without an entry in prior_position_covariances. Default
  // 0.1 m: loose against viosfm's measured accuracy (docs/benchmarks.md:
  // Sim(3) ATE 1 mm to 2 cm on the simulated suite), so that COLMAP's images
  // decide locally while the priors hold the metric, gravity-aligned frame.
  double prior_position_stddev_m = 0.1;
  // Per-image 3x3 covariance of the camera position (m^2), by image name:
  // the input for a VIO uncertainty model. Default empty.
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
};

// Throws InputError naming the file for a missing or malformed run folder.
RunExportSummary ExportRun(const RunExportOptions& options);

}  // namespace viosfm

#include "viosfm/sfm/frame_registration.h"

#include <cmath>

#include "viosfm/geometry/epipolar.h"
#include "viosfm/geometry/lie.h"
#include "viosfm/sensor/camera_models.h"

namespace viosfm {

std::string FrameRegistrationOptions::Validate() const {
  if (const std::string error = pnp.Validate(); !error.empty()) return "pnp." + error;
  if (min_num_correspondences < 3) return "min_num_correspondences must be >= 3";
  if (!(min_predicted_inlier_ratio >= 0.0 && min_predicted_inlier_ratio <= 1.0)) {
    return "min_predicted_inlier_ratio must be in [0, 1]";
  }
  if (min_reposing_inliers < 0) return "min_reposing_inliers must be >= 0";
  if (!(break_sigmas > 0.0)) return "break_sigmas must be > 0";
  if (!(break_min_translation_m >= 0.0)) return "break_min_translation_m must be >= 0";
  if (!(break_min_rotation_rad >= 0.0)) return "break_min_rotation_rad must be >= 0";
  if (min_supporting_observations < 0) return "min_supporting_observations must be >= 0";
  if (!(support_max_error_px > 0.0)) return "support_max_error_px must be > 0";
  return "";
}

const char* FramePoseSourceName(FramePoseSource source) {
  switch (source) {
    case FramePoseSource::kVio: return "vio";
    case FramePoseSource::kVioVerified: return "vio_verified";
    case FramePoseSource::kImagesReposed: return "images_reposed";
    case FramePoseSource::kImagesWithoutVio: return "images_without_vio";
    default: break;
  }
  return "none";
}

FrameCorrespondences CollectFrameCorrespondences(const Reconstruction& reconstruction,
                                                 const std::vector<Track>& all_tracks,
                                                 const std::vector<size_t>& tracks,
                                                 image_t image_id) {
  FrameCorrespondences result;
  const Image& image = reconstruction.GetImage(image_id);
  const Camera& camera = reconstruction.GetCamera(image.camera_id);
  for (const size_t t : tracks) {
    const Track& track = all_tracks[t];
    point2D_t own = kInvalidPoint2DIdx;
    point3D_t point = kInvalidPoint3DId;
    for (const TrackElement& element : track.elements) {
      if (element.image_id == image_id) {
        own = element.point2D_idx;
        continue;
      }
      if (point != kInvalidPoint3DId) continue;
      const Image& other = reconstruction.GetImage(element.image_id);
      if (!other.registered) continue;
      const point3D_t candidate = other.points2D[element.point2D_idx].point3D_id;
      if (candidate != kInvalidPoint3DId) point = candidate;
    }
    if (own == kInvalidPoint2DIdx || point == kInvalidPoint3DId) continue;
    result.points_normalized.push_back(ImageToCam(camera, image.points2D[own].xy));
    result.points_in_world.push_back(reconstruction.GetPoint3D(point).xyz);
  }
  return result;
}

int CountExplainedPairMatches(const Reconstruction& reconstruction, image_t image_id,
                              const Rigid3d& cam_from_world,
                              const std::vector<ImagePairMatches>& pairs, double max_error_px) {
  const Image& image = reconstruction.GetImage(image_id);
  const Camera& camera = reconstruction.GetCamera(image.camera_id);
  const double focal = MeanFocalLength(camera);
  int count = 0;
  for (const ImagePairMatches& pair : pairs) {
    const bool first = pair.image_id1 == image_id;
    if (!first && pair.image_id2 != image_id) continue;
    const Image& other = reconstruction.GetImage(first ? pair.image_id2 : pair.image_id1);
    if (!other.registered) continue;
    const Camera& other_camera = reconstruction.GetCamera(other.camera_id);
    // E maps the other image's normalised points to lines of this image's.
    const Rigid3d cam_from_other = cam_from_world * other.cam_from_world.Inverse();
    const Eigen::Vector3d& t = cam_from_other.translation;
    if (!(t.norm() > 0.0)) continue;
    const Eigen::Matrix3d essential =
        Hat(t.normalized()) * cam_from_other.rotation.toRotationMatrix();
    for (const FeatureMatch& match : pair.matches) {
      const point2D_t own = first ? match.point2D_idx1 : match.point2D_idx2;
      const point2D_t theirs = first ? match.point2D_idx2 : match.point2D_idx1;
      const double squared =
          SampsonError(essential, ImageToCam(other_camera, other.points2D[theirs].xy),
                       ImageToCam(camera, image.points2D[own].xy));
      if (std::sqrt(squared) * focal <= max_error_px) ++count;
    }
  }
  return count;
}

int CountSupportingObservations(const Reconstruction& reconstruction, image_t image_id,
                                double max_error_px) {
  const Image& image = reconstruction.GetImage(image_id);
  const Camera& camera = reconstruction.GetCamera(image.camera_id);
  int count = 0;
  for (const Point2D& point2D : image.points2D) {
    if (!point2D.HasPoint3D()) continue;
    const Point3D& point3D = reconstruction.GetPoint3D(point2D.point3D_id);
    int others = 0;
    for (const TrackElement& element : point3D.track) {
      if (element.image_id != image_id && reconstruction.GetImage(element.image_id).registered) {
        ++others;
      }
    }
    if (others < 2) continue;
    const std::optional<Eigen::Vector2d> pixel =
        Project(camera, image.cam_from_world * point3D.xyz);
    if (pixel && (*pixel - point2D.xy).norm() <= max_error_px) ++count;
  }
  return count;
}

}  // namespace viosfm

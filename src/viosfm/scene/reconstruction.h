// The data model of a sparse reconstruction: cameras (intrinsics), images
// (pose, keypoints), 3D points (position, colour, track), as in COLMAP.
//
// Entries are keyed by id and also remember the order in which they were
// added. COLMAP 3.8 writes its model files in the iteration order of its
// std::unordered_map tables (not sorted by id, see io/colmap_model.h), so the
// io layer relies on this insertion order to write a model it has read back
// byte for byte. CameraIds()/ImageIds()/Point3DIds() return that order.
//
// Invariant kept by the mutating methods: Image::points2D[i].point3D_id == p
// if and only if the track of point p contains {image_id, i}.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "viosfm/geometry/rigid3.h"
#include "viosfm/sensor/camera.h"
#include "viosfm/util/timestamp.h"
#include "viosfm/util/types.h"

namespace viosfm {

using Vector3ub = Eigen::Matrix<uint8_t, 3, 1>;

// A keypoint of an image, in pixels (viosfm's convention: the centre of the
// top-left pixel is (0, 0); io/ converts COLMAP's (0.5, 0.5) on reading and
// writing), and the 3D point it observes, if any.
struct Point2D {
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();
  point3D_t point3D_id = kInvalidPoint3DId;

  bool HasPoint3D() const { return point3D_id != kInvalidPoint3DId; }
};

struct Image {
  image_t image_id = kInvalidImageId;
  camera_t camera_id = kInvalidCameraId;
  // Path relative to the image folder, e.g. "cam0/1403715273262142976.png".
  std::string name;
  Rigid3d cam_from_world;
  std::vector<Point2D> points2D;
  // Whether the pose is estimated. Only registered images are written to
  // COLMAP model files; every image read from one is registered.
  bool registered = false;
  // Capture time; see TimestampFromImageName.
  std::optional<timestamp_ns_t> timestamp_ns;

  // Camera centre in world coordinates.
  Eigen::Vector3d ProjectionCenter() const { return viosfm::ProjectionCenter(cam_from_world); }
  // Number of keypoints that observe a 3D point.
  size_t NumPoints3D() const;
};

// The capture time encoded in an image file name, as EuRoC names its images
// "1403715273262142976.png" (integer nanoseconds): the stem of the last path
// component, if it is all decimal digits without a leading zero (so "0004.jpg",
// a frame index, is not a time stamp) and fits int64. Otherwise nullopt.
std::optional<timestamp_ns_t> TimestampFromImageName(std::string_view name);

struct TrackElement {
  image_t image_id = kInvalidImageId;
  point2D_t point2D_idx = kInvalidPoint2DIdx;

  bool operator==(const TrackElement& other) const = default;
};

struct Point3D {
  Eigen::Vector3d xyz = Eigen::Vector3d::Zero();
  Vector3ub color = Vector3ub::Zero();
  // Mean reprojection error in pixels; -1 if unknown.
  double error = -1.0;
  std::vector<TrackElement> track;
};

class Reconstruction {
 public:
  // ---- Cameras ----
  // The id must be new and the parameters valid for the model (CHECK).
  void AddCamera(Camera camera);
  bool ExistsCamera(camera_t camera_id) const { return cameras_.count(camera_id) > 0; }
  const Camera& GetCamera(camera_t camera_id) const;
  Camera& GetCamera(camera_t camera_id);
  size_t NumCameras() const { return cameras_.size(); }
  const std::unordered_map<camera_t, Camera>& Cameras() const { return cameras_; }
  // Ids in the order they were added (or set by ReorderCameras).
  std::vector<camera_t> CameraIds() const;

  // ---- Images ----
  // The id and name must be new, the camera must exist, and no keypoint may
  // reference a 3D point yet (observations are added with the points), CHECK.
  void AddImage(Image image);
  bool ExistsImage(image_t image_id) const { return images_.count(image_id) > 0; }
  const Image& GetImage(image_t image_id) const;
  Image& GetImage(image_t image_id);
  // nullptr if no image has this name.
  const Image* ImageByName(const std::string& name) const;
  size_t NumImages() const { return images_.size(); }
  size_t NumRegImages() const;
  const std::unordered_map<image_t, Image>& Images() const { return images_; }
  std::vector<image_t> ImageIds() const;
  // Registered image ids, in image order.
  std::vector<image_t> RegImageIds() const;

  // ---- 3D points ----
  // Adds a point with a new id (one more than the largest id ever added) and
  // links its track's keypoints to it (they must be free, CHECK).
  point3D_t AddPoint3D(Point3D point3D);
  // The same with a given id, which must be new (used by readers).
  void AddPoint3DWithId(point3D_t point3D_id, Point3D point3D);
  bool ExistsPoint3D(point3D_t point3D_id) const { return points3D_.count(point3D_id) > 0; }
  const Point3D& GetPoint3D(point3D_t point3D_id) const;
  // Position, colour and error may be changed freely; change tracks only
  // through AddObservation / DeleteObservation.
  Point3D& GetPoint3D(point3D_t point3D_id);
  size_t NumPoints3D() const { return points3D_.size(); }
  const std::unordered_map<point3D_t, Point3D>& Points3D() const { return points3D_; }
  std::vector<point3D_t> Point3DIds() const;

  // Adds {image_id, point2D_idx} to the track of a point; the keypoint must
  // not observe a point yet (CHECK).
  void AddObservation(point3D_t point3D_id, const TrackElement& element);
  // Removes the observation of a keypoint from its point's track; a point
  // left with fewer than two observations is deleted.
  void DeleteObservation(image_t image_id, point2D_t point2D_idx);
  // Deletes a point and unlinks all keypoints that observed it.
  void DeletePoint3D(point3D_t point3D_id);

  // ---- Order ----
  // Sets the order of all entries of a table; `ids` must be a permutation of
  // the table's ids (CHECK).
  void ReorderCameras(const std::vector<camera_t>& ids);
  void ReorderImages(const std::vector<image_t>& ids);
  void ReorderPoints3D(const std::vector<point3D_t>& ids);

  // ---- Statistics (as COLMAP defines them) ----
  // Keypoints of registered images that observe a 3D point.
  size_t ComputeNumObservations() const;
  // ComputeNumObservations() / NumPoints3D(); 0 without points.
  double ComputeMeanTrackLength() const;
  // ComputeNumObservations() / NumRegImages(); 0 without registered images.
  double ComputeMeanObservationsPerRegImage() const;

 private:
  // Insertion sequence numbers: the order of a table is its ids sorted by them.
  template <typename Id>
  struct Order {
    std::unordered_map<Id, uint64_t> sequence;
    uint64_t next = 0;
    void Add(Id id) { sequence[id] = next++; }
    void Remove(Id id) { sequence.erase(id); }
    std::vector<Id> Ids() const;
    void Set(const std::vector<Id>& ids);
  };

  std::unordered_map<camera_t, Camera> cameras_;
  std::unordered_map<image_t, Image> images_;
  std::unordered_map<point3D_t, Point3D> points3D_;
  std::unordered_map<std::string, image_t> image_id_by_name_;
  Order<camera_t> camera_order_;
  Order<image_t> image_order_;
  Order<point3D_t> point3D_order_;
  point3D_t max_point3D_id_ = 0;
};

}  // namespace viosfm

#include "viosfm/scene/reconstruction.h"

#include <algorithm>
#include <limits>
#include <utility>

#include "viosfm/util/errors.h"

namespace viosfm {

size_t Image::NumPoints3D() const {
  return static_cast<size_t>(std::count_if(points2D.begin(), points2D.end(),
                                           [](const Point2D& p) { return p.HasPoint3D(); }));
}

std::optional<timestamp_ns_t> TimestampFromImageName(std::string_view name) {
  const size_t slash = name.find_last_of("/\\");
  if (slash != std::string_view::npos) name.remove_prefix(slash + 1);
  const size_t dot = name.find_last_of('.');
  const std::string_view stem = dot == std::string_view::npos ? name : name.substr(0, dot);
  if (stem.empty() || stem.size() > 19) return std::nullopt;
  if (stem.size() > 1 && stem.front() == '0') return std::nullopt;
  uint64_t value = 0;
  for (const char c : stem) {
    if (c < '0' || c > '9') return std::nullopt;
    value = value * 10 + static_cast<uint64_t>(c - '0');
  }
  if (value > static_cast<uint64_t>(std::numeric_limits<timestamp_ns_t>::max())) {
    return std::nullopt;
  }
  return static_cast<timestamp_ns_t>(value);
}

template <typename Id>
std::vector<Id> Reconstruction::Order<Id>::Ids() const {
  std::vector<std::pair<uint64_t, Id>> entries;
  entries.reserve(sequence.size());
  for (const auto& [id, seq] : sequence) entries.emplace_back(seq, id);
  std::sort(entries.begin(), entries.end());
  std::vector<Id> ids;
  ids.reserve(entries.size());
  for (const auto& entry : entries) ids.push_back(entry.second);
  return ids;
}

template <typename Id>
void Reconstruction::Order<Id>::Set(const std::vector<Id>& ids) {
  VIOSFM_CHECK_EQ(ids.size(), sequence.size()) << "not a permutation of the ids";
  std::unordered_map<Id, uint64_t> new_sequence;
  for (const Id id : ids) {
    VIOSFM_CHECK(sequence.count(id) > 0) << "unknown id " << id;
    VIOSFM_CHECK(new_sequence.emplace(id, new_sequence.size()).second) << "duplicate id " << id;
  }
  sequence = std::move(new_sequence);
  next = sequence.size();
}

// ---- Cameras ----

void Reconstruction::AddCamera(Camera camera) {
  VIOSFM_CHECK(camera.HasValidParams()) << "camera " << camera.camera_id;
  const camera_t camera_id = camera.camera_id;
  VIOSFM_CHECK(cameras_.emplace(camera_id, std::move(camera)).second)
      << "duplicate camera " << camera_id;
  camera_order_.Add(camera_id);
}

const Camera& Reconstruction::GetCamera(camera_t camera_id) const {
  const auto it = cameras_.find(camera_id);
  VIOSFM_CHECK(it != cameras_.end()) << "no camera " << camera_id;
  return it->second;
}

Camera& Reconstruction::GetCamera(camera_t camera_id) {
  const auto it = cameras_.find(camera_id);
  VIOSFM_CHECK(it != cameras_.end()) << "no camera " << camera_id;
  return it->second;
}

std::vector<camera_t> Reconstruction::CameraIds() const {
  return camera_order_.Ids();
}

// ---- Images ----

void Reconstruction::AddImage(Image image) {
  VIOSFM_CHECK(ExistsCamera(image.camera_id))
      << "image " << image.image_id << " refers to missing camera " << image.camera_id;
  for (const Point2D& point2D : image.points2D) {
    VIOSFM_CHECK(!point2D.HasPoint3D())
        << "image " << image.image_id << ": observations are added with the 3D points";
  }
  const image_t image_id = image.image_id;
  VIOSFM_CHECK(!ExistsImage(image_id)) << "duplicate image " << image_id;
  VIOSFM_CHECK(image_id_by_name_.emplace(image.name, image_id).second)
      << "duplicate image name " << image.name;
  images_.emplace(image_id, std::move(image));
  image_order_.Add(image_id);
}

const Image& Reconstruction::GetImage(image_t image_id) const {
  const auto it = images_.find(image_id);
  VIOSFM_CHECK(it != images_.end()) << "no image " << image_id;
  return it->second;
}

Image& Reconstruction::GetImage(image_t image_id) {
  const auto it = images_.find(image_id);
  VIOSFM_CHECK(it != images_.end()) << "no image " << image_id;
  return it->second;
}

const Image* Reconstruction::ImageByName(const std::string& name) const {
  const auto it = image_id_by_name_.find(name);
  return it == image_id_by_name_.end() ? nullptr : &images_.at(it->second);
}

size_t Reconstruction::NumRegImages() const {
  return static_cast<size_t>(std::count_if(
      images_.begin(), images_.end(), [](const auto& entry) { return entry.second.registered; }));
}

std::vector<image_t> Reconstruction::ImageIds() const {
  return image_order_.Ids();
}

std::vector<image_t> Reconstruction::RegImageIds() const {
  std::vector<image_t> ids = ImageIds();
  ids.erase(std::remove_if(ids.begin(), ids.end(),
                           [this](image_t id) { return !images_.at(id).registered; }),
            ids.end());
  return ids;
}

// ---- 3D points ----

point3D_t Reconstruction::AddPoint3D(Point3D point3D) {
  VIOSFM_CHECK_LT(max_point3D_id_, kInvalidPoint3DId - 1);
  const point3D_t point3D_id = max_point3D_id_ + 1;
  AddPoint3DWithId(point3D_id, std::move(point3D));
  return point3D_id;
}

void Reconstruction::AddPoint3DWithId(point3D_t point3D_id, Point3D point3D) {
  VIOSFM_CHECK_NE(point3D_id, kInvalidPoint3DId);
  VIOSFM_CHECK(!ExistsPoint3D(point3D_id)) << "duplicate 3D point " << point3D_id;
  // Check all elements before linking any, so a failure changes nothing.
  for (size_t i = 0; i < point3D.track.size(); ++i) {
    const TrackElement& element = point3D.track[i];
    const Image& image = GetImage(element.image_id);
    VIOSFM_CHECK_LT(element.point2D_idx, image.points2D.size());
    VIOSFM_CHECK(!image.points2D[element.point2D_idx].HasPoint3D())
        << "keypoint " << element.point2D_idx << " of image " << element.image_id
        << " already observes a 3D point";
    for (size_t j = 0; j < i; ++j) {
      VIOSFM_CHECK(!(point3D.track[j] == element)) << "duplicate track element";
    }
  }
  for (const TrackElement& element : point3D.track) {
    GetImage(element.image_id).points2D[element.point2D_idx].point3D_id = point3D_id;
  }
  points3D_.emplace(point3D_id, std::move(point3D));
  point3D_order_.Add(point3D_id);
  max_point3D_id_ = std::max(max_point3D_id_, point3D_id);
}

const Point3D& Reconstruction::GetPoint3D(point3D_t point3D_id) const {
  const auto it = points3D_.find(point3D_id);
  VIOSFM_CHECK(it != points3D_.end()) << "no 3D point " << point3D_id;
  return it->second;
}

Point3D& Reconstruction::GetPoint3D(point3D_t point3D_id) {
  const auto it = points3D_.find(point3D_id);
  VIOSFM_CHECK(it != points3D_.end()) << "no 3D point " << point3D_id;
  return it->second;
}

std::vector<point3D_t> Reconstruction::Point3DIds() const {
  return point3D_order_.Ids();
}

void Reconstruction::AddObservation(point3D_t point3D_id, const TrackElement& element) {
  Point3D& point3D = GetPoint3D(point3D_id);
  Image& image = GetImage(element.image_id);
  VIOSFM_CHECK_LT(element.point2D_idx, image.points2D.size());
  Point2D& point2D = image.points2D[element.point2D_idx];
  VIOSFM_CHECK(!point2D.HasPoint3D()) << "keypoint " << element.point2D_idx << " of image "
                                      << element.image_id << " already observes a 3D point";
  point2D.point3D_id = point3D_id;
  point3D.track.push_back(element);
}

void Reconstruction::DeleteObservation(image_t image_id, point2D_t point2D_idx) {
  Image& image = GetImage(image_id);
  VIOSFM_CHECK_LT(point2D_idx, image.points2D.size());
  Point2D& point2D = image.points2D[point2D_idx];
  VIOSFM_CHECK(point2D.HasPoint3D())
      << "keypoint " << point2D_idx << " of image " << image_id << " observes no 3D point";
  const point3D_t point3D_id = point2D.point3D_id;
  Point3D& point3D = GetPoint3D(point3D_id);
  const TrackElement element{image_id, point2D_idx};
  const auto it = std::find(point3D.track.begin(), point3D.track.end(), element);
  VIOSFM_CHECK(it != point3D.track.end())
      << "track of 3D point " << point3D_id << " lacks an observation";
  point3D.track.erase(it);
  point2D.point3D_id = kInvalidPoint3DId;
  if (point3D.track.size() < 2) DeletePoint3D(point3D_id);
}

void Reconstruction::DeletePoint3D(point3D_t point3D_id) {
  const auto it = points3D_.find(point3D_id);
  VIOSFM_CHECK(it != points3D_.end()) << "no 3D point " << point3D_id;
  for (const TrackElement& element : it->second.track) {
    Point2D& point2D = GetImage(element.image_id).points2D.at(element.point2D_idx);
    VIOSFM_CHECK_EQ(point2D.point3D_id, point3D_id);
    point2D.point3D_id = kInvalidPoint3DId;
  }
  points3D_.erase(it);
  point3D_order_.Remove(point3D_id);
}

// ---- Order ----

void Reconstruction::ReorderCameras(const std::vector<camera_t>& ids) {
  camera_order_.Set(ids);
}
void Reconstruction::ReorderImages(const std::vector<image_t>& ids) {
  image_order_.Set(ids);
}
void Reconstruction::ReorderPoints3D(const std::vector<point3D_t>& ids) {
  point3D_order_.Set(ids);
}

// ---- Statistics ----

size_t Reconstruction::ComputeNumObservations() const {
  size_t num_observations = 0;
  for (const auto& [image_id, image] : images_) {
    if (image.registered) num_observations += image.NumPoints3D();
  }
  return num_observations;
}

double Reconstruction::ComputeMeanTrackLength() const {
  if (points3D_.empty()) return 0.0;
  return static_cast<double>(ComputeNumObservations()) / static_cast<double>(points3D_.size());
}

double Reconstruction::ComputeMeanObservationsPerRegImage() const {
  const size_t num_reg_images = NumRegImages();
  if (num_reg_images == 0) return 0.0;
  return static_cast<double>(ComputeNumObservations()) / static_cast<double>(num_reg_images);
}

}  // namespace viosfm

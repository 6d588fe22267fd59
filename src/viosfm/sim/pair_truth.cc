#include "viosfm/sim/pair_truth.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <map>
#include <set>
#include <sstream>
#include <utility>

#include "viosfm/io/colmap_database.h"
#include "viosfm/io/euroc.h"
#include "viosfm/io/scene_structure_io.h"
#include "viosfm/sensor/camera_models.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/parallel.h"

namespace viosfm {
namespace {

constexpr double kMinHitDistance = 1e-6;  // m

// Largest stamp gap between an image and its ground-truth state.
constexpr timestamp_ns_t kMaxGroundTruthGapNs = 1'000'000;

}  // namespace

std::string PairTruthOptions::Validate() const {
  if (grid_step_px < 1) return "grid_step_px must be >= 1";
  if (!(occlusion_tolerance_m >= 0.0) || !std::isfinite(occlusion_tolerance_m)) {
    return "occlusion_tolerance_m must be >= 0 and finite";
  }
  if (!(occlusion_tolerance_relative >= 0.0 && occlusion_tolerance_relative < 1.0)) {
    return "occlusion_tolerance_relative must be in [0, 1)";
  }
  if (!(max_match_error_px > 0.0) || !std::isfinite(max_match_error_px)) {
    return "max_match_error_px must be > 0 and finite";
  }
  if (!(min_covisibility >= 0.0 && min_covisibility <= 1.0)) {
    return "min_covisibility must be in [0, 1]";
  }
  if (!(min_inlier_agreement >= 0.0 && min_inlier_agreement <= 1.0)) {
    return "min_inlier_agreement must be in [0, 1]";
  }
  return "";
}

SceneRayCaster::SceneRayCaster(const SceneStructure& structure) {
  quads_.reserve(structure.size());
  for (const SceneStructureQuad& quad : structure) {
    const Eigen::Vector3d normal = quad.axis_u.cross(quad.axis_v);
    if (!(normal.norm() > 1e-12)) continue;  // degenerate: no area
    Eigen::Matrix<double, 3, 2> axes;
    axes << quad.axis_u, quad.axis_v;
    Quad entry;
    entry.origin = quad.origin;
    entry.normal = normal.normalized();
    entry.to_uv = (axes.transpose() * axes).inverse() * axes.transpose();
    quads_.push_back(entry);
  }
}

std::optional<double> SceneRayCaster::Cast(const Eigen::Vector3d& origin,
                                           const Eigen::Vector3d& direction) const {
  std::optional<double> nearest;
  for (const Quad& quad : quads_) {
    const double denominator = direction.dot(quad.normal);
    if (std::abs(denominator) < 1e-12) continue;
    const double distance = (quad.origin - origin).dot(quad.normal) / denominator;
    if (!(distance > kMinHitDistance) || (nearest && distance >= *nearest)) continue;
    const Eigen::Vector2d uv = quad.to_uv * (origin + distance * direction - quad.origin);
    if (uv.x() < 0.0 || uv.x() > 1.0 || uv.y() < 0.0 || uv.y() > 1.0) continue;
    nearest = distance;
  }
  return nearest;
}

bool SceneRayCaster::Unoccluded(const Eigen::Vector3d& centre, const Eigen::Vector3d& point,
                                const PairTruthOptions& options) const {
  const Eigen::Vector3d offset = point - centre;
  const double distance = offset.norm();
  if (!(distance > kMinHitDistance)) return true;
  const std::optional<double> hit = Cast(centre, offset / distance);
  return !hit || *hit >= distance - (options.occlusion_tolerance_m +
                                     options.occlusion_tolerance_relative * distance);
}

PairTruthLabeller::PairTruthLabeller(const SceneStructure& structure, const Camera& camera,
                                     std::vector<PairTruthFrame> frames,
                                     const PairTruthOptions& options)
    : options_(options), camera_(camera), frames_(std::move(frames)), caster_(structure) {
  if (const std::string error = options.Validate(); !error.empty()) {
    throw InputError("invalid pair truth options: " + error);
  }
  for (size_t k = 0; k < frames_.size(); ++k) index_by_name_[frames_[k].name] = k;
  std::vector<Eigen::Vector2d> grid;
  const int step = options_.grid_step_px;
  for (int y = step / 2; y < static_cast<int>(camera_.height); y += step) {
    for (int x = step / 2; x < static_cast<int>(camera_.width); x += step) grid.emplace_back(x, y);
  }
  grid_points_.resize(frames_.size());
  grid_size_.assign(frames_.size(), grid.size());
  ParallelFor(static_cast<int64_t>(frames_.size()), options_.num_threads, [&](int64_t k, int) {
    for (const Eigen::Vector2d& pixel : grid) {
      if (const auto point = SurfacePoint(k, pixel)) grid_points_[k].push_back(*point);
    }
  });
}

PairTruthLabeller PairTruthLabeller::FromSimulation(const std::filesystem::path& folder,
                                                    const PairTruthOptions& options) {
  const std::filesystem::path scene_path = folder / "scene.csv";
  if (!std::filesystem::is_regular_file(scene_path)) {
    throw InputError(scene_path.string(), 0,
                     "scene structure not found (a `viosfm simulate` output folder is expected)");
  }
  const SceneStructure structure = ReadSceneStructure(scene_path);
  EurocReadOptions read_options;
  read_options.require_imu = false;
  read_options.check_images_exist = false;
  const Sequence sequence = ReadEurocDataset(folder, read_options);
  if (!sequence.has_ground_truth()) {
    throw InputError(folder.string(), 0,
                     "no ground truth (mav0/state_groundtruth_estimate0/data.csv)");
  }
  std::vector<PairTruthFrame> frames;
  frames.reserve(sequence.images.size());
  for (const SequenceImage& image : sequence.images) {
    const std::optional<size_t> nearest =
        NearestStampIndex(sequence.ground_truth, image.timestamp_ns, kMaxGroundTruthGapNs,
                          [](const GroundTruthState& state) { return state.timestamp_ns; });
    if (!nearest) {
      throw InputError(
          folder.string(), 0,
          "image " + image.path.filename().string() + " has no ground-truth state within 1 ms");
    }
    const GroundTruthState* best = &sequence.ground_truth[*nearest];
    PairTruthFrame frame;
    frame.name = DatabaseImageName(image);
    frame.timestamp_ns = image.timestamp_ns;
    frame.cam_from_world = (best->world_from_body * sequence.rig.body_from_cam).Inverse();
    frames.push_back(std::move(frame));
  }
  return PairTruthLabeller(structure, sequence.rig.camera, std::move(frames), options);
}

std::optional<size_t> PairTruthLabeller::FindFrame(const std::string& name) const {
  const auto it = index_by_name_.find(name);
  if (it == index_by_name_.end()) return std::nullopt;
  return it->second;
}

std::optional<Eigen::Vector3d> PairTruthLabeller::SurfacePoint(size_t index,
                                                               const Eigen::Vector2d& pixel) const {
  const Rigid3d world_from_cam = frames_[index].cam_from_world.Inverse();
  const Eigen::Vector3d ray = Unproject(camera_, pixel);
  if (!ray.allFinite()) return std::nullopt;
  const Eigen::Vector3d direction = (world_from_cam.rotation * ray).normalized();
  const std::optional<double> hit = caster_.Cast(world_from_cam.translation, direction);
  if (!hit) return std::nullopt;
  return world_from_cam.translation + *hit * direction;
}

std::optional<Eigen::Vector2d> PairTruthLabeller::VisiblePixel(size_t index,
                                                               const Eigen::Vector3d& point) const {
  const Rigid3d& cam_from_world = frames_[index].cam_from_world;
  const Eigen::Vector3d point_in_cam = cam_from_world * point;
  if (!(point_in_cam.z() > kMinHitDistance)) return std::nullopt;
  // Far outside the field of view a distortion polynomial can fold back into
  // the image: only points whose pinhole projection is near the image count.
  const Eigen::Vector2d pinhole = (CalibrationMatrix(camera_) * point_in_cam).hnormalized();
  const double width = static_cast<double>(camera_.width);
  const double height = static_cast<double>(camera_.height);
  if (pinhole.x() < -0.5 * width || pinhole.x() > 1.5 * width || pinhole.y() < -0.5 * height ||
      pinhole.y() > 1.5 * height) {
    return std::nullopt;
  }
  const std::optional<Eigen::Vector2d> pixel = Project(camera_, point_in_cam);
  if (!pixel || !(pixel->x() >= -0.5 && pixel->x() < width - 0.5 && pixel->y() >= -0.5 &&
                  pixel->y() < height - 0.5)) {
    return std::nullopt;
  }
  const Eigen::Vector3d centre = cam_from_world.Inverse().translation;
  if (!caster_.Unoccluded(centre, point, options_)) return std::nullopt;
  return pixel;
}

double PairTruthLabeller::DirectedCovisibility(size_t frame1, size_t frame2) const {
  VIOSFM_CHECK_LT(frame1, frames_.size());
  VIOSFM_CHECK_LT(frame2, frames_.size());
  if (grid_size_[frame1] == 0) return 0.0;
  size_t visible = 0;
  for (const Eigen::Vector3d& point : grid_points_[frame1]) {
    if (VisiblePixel(frame2, point)) ++visible;
  }
  return static_cast<double>(visible) / static_cast<double>(grid_size_[frame1]);
}

double PairTruthLabeller::Covisibility(size_t frame1, size_t frame2) const {
  return std::max(DirectedCovisibility(frame1, frame2), DirectedCovisibility(frame2, frame1));
}

double PairTruthLabeller::MatchAgreement(size_t frame1, size_t frame2,
                                         const FeatureKeypoints& keypoints1,
                                         const FeatureKeypoints& keypoints2,
                                         const FeatureMatches& matches) const {
  VIOSFM_CHECK_LT(frame1, frames_.size());
  VIOSFM_CHECK_LT(frame2, frames_.size());
  if (matches.empty()) return std::numeric_limits<double>::quiet_NaN();
  size_t agree = 0;
  for (const FeatureMatch& match : matches) {
    VIOSFM_CHECK_LT(match.point2D_idx1, keypoints1.size());
    VIOSFM_CHECK_LT(match.point2D_idx2, keypoints2.size());
    const FeatureKeypoint& key1 = keypoints1[match.point2D_idx1];
    const FeatureKeypoint& key2 = keypoints2[match.point2D_idx2];
    const auto point = SurfacePoint(frame1, Eigen::Vector2d(key1.x, key1.y));
    if (!point) continue;
    const auto pixel = VisiblePixel(frame2, *point);
    if (pixel && (*pixel - Eigen::Vector2d(key2.x, key2.y)).norm() <= options_.max_match_error_px) {
      ++agree;
    }
  }
  return static_cast<double>(agree) / static_cast<double>(matches.size());
}

std::vector<VerificationTruthSummary> EvaluateVerificationRuns(
    const PairTruthLabeller& labeller, const std::vector<VerificationRunInput>& runs) {
  const PairTruthOptions& options = labeller.options();
  using NamePair = std::pair<std::string, std::string>;
  const auto frame_of = [&](const VerificationRunInput& run, const std::string& name) {
    const std::optional<size_t> frame = labeller.FindFrame(name);
    if (!frame) {
      throw InputError(run.name, 0,
                       "image '" + name + "' is not a frame of the simulated sequence");
    }
    return *frame;
  };

  // Covisibility of every candidate pair of every run, once.
  std::map<NamePair, double> covisibility;
  for (const VerificationRunInput& run : runs) {
    for (const PairDecision& d : run.decisions) {
      frame_of(run, d.name1);
      frame_of(run, d.name2);
      covisibility.emplace(NamePair(d.name1, d.name2), 0.0);
    }
  }
  {
    std::vector<std::map<NamePair, double>::iterator> entries;
    for (auto it = covisibility.begin(); it != covisibility.end(); ++it) entries.push_back(it);
    ParallelFor(static_cast<int64_t>(entries.size()), options.num_threads, [&](int64_t k, int) {
      const NamePair& names = entries[k]->first;
      entries[k]->second = labeller.Covisibility(*labeller.FindFrame(names.first),
                                                 *labeller.FindFrame(names.second));
    });
  }

  std::vector<VerificationTruthSummary> summaries;
  std::set<NamePair> baseline_correct;
  for (size_t r = 0; r < runs.size(); ++r) {
    const VerificationRunInput& run = runs[r];
    VerificationTruthSummary summary;
    summary.name = run.name;
    summary.num_candidates = run.decisions.size();

    // Inliers and keypoints of the accepted pairs.
    std::vector<const PairDecision*> accepted;
    for (const PairDecision& d : run.decisions) {
      if (covisibility.at(NamePair(d.name1, d.name2)) >= options.min_covisibility) {
        ++summary.num_correct_candidates;
      }
      if (d.accepted) accepted.push_back(&d);
    }
    summary.num_accepted = accepted.size();
    std::vector<FeatureMatches> inliers(accepted.size());
    std::map<image_t, FeatureKeypoints> keypoints;
    if (!accepted.empty()) {
      if (!std::filesystem::is_regular_file(run.database)) {
        throw InputError(run.database.string(), 0, "database of run '" + run.name + "' not found");
      }
      const ColmapDatabase database = ColmapDatabase::Open(run.database);
      for (size_t k = 0; k < accepted.size(); ++k) {
        const PairDecision& d = *accepted[k];
        if (database.ExistsTwoViewGeometry(d.image_id1, d.image_id2)) {
          inliers[k] = database.ReadTwoViewGeometry(d.image_id1, d.image_id2).inlier_matches;
        }
        for (const image_t id : {d.image_id1, d.image_id2}) {
          if (!keypoints.count(id)) keypoints.emplace(id, database.ReadKeypoints(id));
        }
      }
    }
    std::vector<double> agreement(accepted.size());
    ParallelFor(static_cast<int64_t>(accepted.size()), options.num_threads, [&](int64_t k, int) {
      const PairDecision& d = *accepted[k];
      agreement[k] =
          labeller.MatchAgreement(*labeller.FindFrame(d.name1), *labeller.FindFrame(d.name2),
                                  keypoints.at(d.image_id1), keypoints.at(d.image_id2), inliers[k]);
    });

    std::set<NamePair> accepted_names;
    for (size_t k = 0; k < accepted.size(); ++k) {
      const PairDecision& d = *accepted[k];
      const NamePair names(d.name1, d.name2);
      accepted_names.insert(names);
      // No stored inliers count as disagreeing.
      if (!(agreement[k] >= options.min_inlier_agreement)) {
        ++summary.num_accepted_wrong;
        summary.wrong_pairs.push_back(names);
      } else if (covisibility.at(names) >= options.min_covisibility) {
        ++summary.num_accepted_correct;
        if (r == 0) baseline_correct.insert(names);
      } else {
        ++summary.num_accepted_other;
      }
    }
    summary.num_baseline_correct = baseline_correct.size();
    for (const NamePair& names : baseline_correct) {
      if (accepted_names.count(names)) ++summary.num_baseline_correct_kept;
    }
    if (summary.num_baseline_correct > 0) {
      summary.recall_vs_baseline = static_cast<double>(summary.num_baseline_correct_kept) /
                                   static_cast<double>(summary.num_baseline_correct);
    }
    summaries.push_back(std::move(summary));
  }
  return summaries;
}

std::string FormatVerificationTruthTable(const std::vector<VerificationTruthSummary>& summaries) {
  std::ostringstream out;
  out << "| run | candidates | correct candidates | accepted | accepted correct | accepted wrong "
         "| accepted, overlap < threshold | correct kept vs first run |\n"
      << "|---|---|---|---|---|---|---|---|\n";
  for (const VerificationTruthSummary& s : summaries) {
    out << "| " << s.name << " | " << s.num_candidates << " | " << s.num_correct_candidates << " | "
        << s.num_accepted << " | " << s.num_accepted_correct << " | " << s.num_accepted_wrong
        << " | " << s.num_accepted_other << " | " << s.num_baseline_correct_kept << "/"
        << s.num_baseline_correct;
    if (!std::isnan(s.recall_vs_baseline)) {
      out << " (" << std::fixed << std::setprecision(1) << 100.0 * s.recall_vs_baseline << " %)";
      out.unsetf(std::ios::fixed);
    }
    out << " |\n";
  }
  return out.str();
}

}  // namespace viosfm

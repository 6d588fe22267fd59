#include "viosfm/pipeline/stream_pipeline.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <filesystem>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

#include "viosfm/features/sift.h"
#include "viosfm/io/colmap_database.h"
#include "viosfm/io/dataset.h"
#include "viosfm/io/euroc.h"
#include "viosfm/io/euroc_follower.h"
#include "viosfm/io/image_io.h"
#include "viosfm/io/kalibr.h"
#include "viosfm/io/ply.h"
#include "viosfm/io/trajectory_io.h"
#include "viosfm/matching/pair_generator.h"
#include "viosfm/matching/pair_verification.h"
#include "viosfm/pipeline/feature_prefetch.h"
#include "viosfm/pipeline/frame_selection.h"
#include "viosfm/pipeline/run_common.h"
#include "viosfm/pipeline/run_fingerprint.h"
#include "viosfm/pipeline/run_folder.h"
#include "viosfm/pipeline/stage_colors.h"
#include "viosfm/pipeline/stage_dataset.h"
#include "viosfm/pipeline/stage_evaluation.h"
#include "viosfm/pipeline/stage_frames.h"
#include "viosfm/pipeline/stage_mapping.h"
#include "viosfm/pipeline/stage_outputs.h"
#include "viosfm/pipeline/stage_vio.h"
#include "viosfm/retrieval/incremental_retrieval.h"
#include "viosfm/scene/rolling_shutter.h"
#include "viosfm/sfm/batched_mapper.h"
#include "viosfm/sfm/verified_pair_stream.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/logging.h"
#include "viosfm/util/parallel.h"
#include "viosfm/util/progress.h"
#include "viosfm/util/timer.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;

// The stage names, in order (summary.json "stages").
const std::vector<std::string> kStreamStageNames = {"read_dataset", "stream", "colors",
                                                    "evaluation", "write_outputs"};

// What the structure-from-motion side takes from the VIO before its first
// frame: the rig it ran with (its camera-IMU time offset and IMU noise) and
// the rolling-shutter readout.
struct VioSetup {
  SensorRig rig;
  double readout_s = 0.0;
  std::string readout_source;
};

// The VIO's poses as they settle, for the frames the stream reaches: from
// the own VIO's thread (Report), or all at once (SetAll). The poses, their
// segments and odometers are those LoadVioPoses gives at the end, pose for
// pose (the segments numbered as RunOwnVio numbers them).
class SettledVio {
 public:
  SettledVio(const SensorRig& rig, const std::filesystem::path& root,
             const PipelineOptions& options)
      : rig_(rig), root_(root), options_(options) {}

  // The own VIO's progress (called on its thread).
  void Report(const VioProgress& progress) {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      if (!setup_) {
        VioSetup setup;
        setup.rig = rig_;
        setup.rig.cam_time_offset_ns = progress.time_offset->offset_ns;
        setup.rig.imu_noise = progress.imu_noise->used;
        const OwnVioReadout readout =
            OwnVioRollingShutter(options_, *progress.time_offset, /*log=*/false);
        setup.readout_s = readout.readout_s;
        setup.readout_source = readout.source;
        setup_ = setup;
      }
      const std::vector<VioFrameResult>& frames = *progress.frames;
      for (; consumed_ < progress.num_settled; ++consumed_) {
        const VioFrameResult& frame = frames[consumed_];
        settled_until_ns_ = frame.timestamp_ns;
        if (!frame.has_pose) continue;
        if (segments_.empty() || frame.segment != last_raw_segment_) ++segment_;
        last_raw_segment_ = frame.segment;
        AddPose(frame.timestamp_ns, frame.state.world_from_body, segment_);
      }
      finished_ = progress.finished;
    }
    changed_.notify_all();
  }

  // An external VIO's poses, all of them.
  void SetAll(const VioPoses& poses) {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      VioSetup setup;
      setup.rig = poses.own_vio_rig.value_or(rig_);
      setup.readout_s = poses.rolling_shutter_readout_s;
      setup.readout_source = poses.rolling_shutter_source;
      setup_ = setup;
      posed_ = poses.world_from_body;
      segments_ = poses.segments;
      odometers_ = poses.odometers;
      finished_ = true;
    }
    changed_.notify_all();
  }

  void Fail(const std::string& message) {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      failure_ = message;
    }
    changed_.notify_all();
  }

  // Blocks until the rig and the readout are known.
  VioSetup WaitForSetup() {
    std::unique_lock<std::mutex> lock(mutex_);
    changed_.wait(lock, [&] { return setup_.has_value() || finished_ || !failure_.empty(); });
    if (!failure_.empty()) throw std::runtime_error(failure_);
    if (!setup_) throw InputError(root_.string(), 0, "the VIO processed no frame");
    return *setup_;
  }

  // The VIO pose nearest to `stamp_ns` within max_gap_ns, as
  // SelectFramesStage associates it: blocks until the VIO has settled a
  // frame after stamp_ns + max_gap_ns (or finished).
  std::optional<FrameVioPose> PoseAt(timestamp_ns_t stamp_ns, timestamp_ns_t max_gap_ns) {
    std::unique_lock<std::mutex> lock(mutex_);
    changed_.wait(lock, [&] {
      return finished_ || !failure_.empty() || settled_until_ns_ > stamp_ns + max_gap_ns;
    });
    if (!failure_.empty()) throw std::runtime_error(failure_);
    const std::optional<size_t> index = NearestPoseIndex(posed_, stamp_ns, max_gap_ns);
    if (!index) return std::nullopt;
    return FrameVioPose{posed_.poses[*index].world_from_frame, odometers_[*index]};
  }

  size_t num_poses() {
    const std::lock_guard<std::mutex> lock(mutex_);
    return posed_.size();
  }

 private:
  void AddPose(timestamp_ns_t stamp_ns, const Rigid3d& world_from_body, int segment) {
    VioOdometer odometer;
    odometer.segment = segment;
    if (!posed_.empty() && segments_.back() == segment) {
      const Rigid3d& before = posed_.poses.back().world_from_frame;
      odometer.distance_m =
          odometers_.back().distance_m + (world_from_body.translation - before.translation).norm();
      odometer.rotation_rad = odometers_.back().rotation_rad +
                              before.rotation.angularDistance(world_from_body.rotation);
    }
    posed_.poses.push_back({stamp_ns, world_from_body});
    segments_.push_back(segment);
    odometers_.push_back(odometer);
  }

  const SensorRig rig_;
  const std::filesystem::path root_;
  const PipelineOptions& options_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::optional<VioSetup> setup_;
  Trajectory posed_;
  std::vector<int> segments_;
  std::vector<VioOdometer> odometers_;
  int segment_ = -1;
  int last_raw_segment_ = -1;
  size_t consumed_ = 0;
  timestamp_ns_t settled_until_ns_ = std::numeric_limits<timestamp_ns_t>::min();
  bool finished_ = false;
  std::string failure_;
};

// A thread whose exception is kept for the one that joins it.
class Worker {
 public:
  Worker() = default;
  Worker(const Worker&) = delete;
  Worker& operator=(const Worker&) = delete;
  ~Worker() { Join(); }

  template <class Body>
  void Start(Body body) {
    thread_ = std::thread([this, body = std::move(body)]() mutable {
      try {
        body();
      } catch (...) {
        error_ = std::current_exception();
        failed_ = true;
      }
    });
  }
  void Join() {
    if (thread_.joinable()) thread_.join();
  }
  // Joins, then rethrows the thread's exception.
  void JoinAndRethrow() {
    Join();
    if (error_) std::rethrow_exception(error_);
  }
  // The thread has ended with an exception (any thread may ask).
  bool failed() const { return failed_; }

 private:
  std::thread thread_;
  std::exception_ptr error_;
  std::atomic<bool> failed_{false};
};

// The frames the stream takes, in time order: all known up front (a
// recorded dataset) or added as a followed recording's frame selection
// takes them.
class FrameQueue {
 public:
  void Add(const SequenceImage& image) {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      images_.push_back(image);
    }
    changed_.notify_all();
  }
  void Close() {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      closed_ = true;
    }
    changed_.notify_all();
  }
  void Fail(const std::string& message) {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      failure_ = message;
    }
    changed_.notify_all();
  }
  // Blocks until frame k is known (true) or every frame is (false).
  // Throws std::runtime_error if the source failed.
  bool Get(size_t k, SequenceImage* image) {
    std::unique_lock<std::mutex> lock(mutex_);
    changed_.wait(lock, [&] { return k < images_.size() || closed_ || !failure_.empty(); });
    if (!failure_.empty()) throw std::runtime_error(failure_);
    if (k >= images_.size()) return false;
    *image = images_[k];
    return true;
  }

 private:
  std::mutex mutex_;
  std::condition_variable changed_;
  std::vector<SequenceImage> images_;
  bool closed_ = false;
  std::string failure_;
};

// The IMU as far as it has come (a followed recording's grows).
class SharedImu {
 public:
  void Add(const std::vector<ImuSample>& samples) {
    const std::lock_guard<std::mutex> lock(mutex_);
    samples_.insert(samples_.end(), samples.begin(), samples.end());
  }
  bool empty() const {
    const std::lock_guard<std::mutex> lock(mutex_);
    return samples_.empty();
  }
  // scene/rolling_shutter.h CamAngularRate on the samples so far.
  Eigen::Vector3d CamAngularRateAt(const SensorRig& rig, timestamp_ns_t stamp_ns) const {
    const std::lock_guard<std::mutex> lock(mutex_);
    return CamAngularRate(rig, samples_, stamp_ns);
  }
  std::vector<ImuSample> All() const {
    const std::lock_guard<std::mutex> lock(mutex_);
    return samples_;
  }

 private:
  mutable std::mutex mutex_;
  std::vector<ImuSample> samples_;
};

// Everything the stream builds, for the stages after it.
struct StreamOutput {
  VioPoses vio;
  // The selected frames as mapped, in order, without their keypoints (the
  // mapper holds those; the points' colours come from the grey values
  // sampled when each frame's features were extracted).
  std::vector<MapperImage> images;
  BatchedMapperInput input;  // cameras, IMU, rig, readout (the frames: `images`)
  Reconstruction reconstruction;
  VerificationResult verification;
  BatchedMapperSummary stream_mapper_summary;
  FeatureExtractionSummary features;
  PipelineStreamSummary stream;
  // A followed recording: the recording as it came, and its frame selection;
  // its texture probe (on its first frames) and the rate and feature count
  // it settled.
  Sequence followed;
  FrameSelection followed_selection;
  PipelineSummary probe;
  double frame_rate_hz = 0.0;
  int max_num_features = 0;
};

// s of a followed recording's first images its texture probe looks at (the
// frames it probes spread over them): the recording's start stands for the
// whole, which does not exist yet. The selection waits for them.
constexpr double kFollowProbeWindowS = 10.0;

// The stream over the selected frames (see stream_pipeline.h).
class Stream {
 public:
  // A recorded dataset: `sequence` and its selected frames.
  Stream(const Sequence& sequence, const std::vector<size_t>& selected,
         const PipelineOptions& options, const RunFolder& folder, FrameCache* frame_cache,
         KeypointGreyValues* keypoint_values)
      : sequence_(&sequence),
        rig_(sequence.rig),
        root_(sequence.root),
        options_(options),
        verification_options_(options.EffectiveVerificationOptions()),
        folder_(folder),
        frame_cache_(frame_cache),
        keypoint_values_(keypoint_values),
        settled_(sequence.rig, sequence.root, options) {
    for (const size_t index : selected) {
      frame_queue_.Add(sequence.images[index]);
      paths_.push_back(sequence.images[index].path);
    }
    frame_queue_.Close();
    imu_.Add(sequence.imu);
  }
  // A recording being made, followed through `follower`.
  Stream(EurocFollower* follower, const PipelineOptions& options, const RunFolder& folder,
         FrameCache* frame_cache, KeypointGreyValues* keypoint_values)
      : follower_(follower),
        rig_(follower->header().rig),
        root_(follower->header().root),
        options_(options),
        verification_options_(options.EffectiveVerificationOptions()),
        folder_(folder),
        frame_cache_(frame_cache),
        keypoint_values_(keypoint_values),
        settled_(follower->header().rig, follower->header().root, options) {}

  StreamOutput Run(const Timer& stream_timer);

 private:
  // One selected frame as the verification holds it.
  struct Frame {
    PairImage image;  // its VIO pose and, while in memory, its features
    bool in_memory = false;
  };

  // The VIO's thread: the own VIO over the recorded dataset, a reader of
  // its selected frames for an external VIO, or the followed recording.
  void RunRecordedVio(const Timer& stream_timer, double* vio_seconds);
  void FollowRecording(const Timer& stream_timer, double* vio_seconds);
  void Ingest(const SequenceImage& image);
  bool Decidable(size_t d, bool all_ingested) const;
  void Decide(size_t d);
  // frames_[k].image with its features (read back from the database when
  // no longer in memory), normalised descriptors too when `normalised`.
  const PairImage& WithFeatures(size_t k, bool normalised);
  void ForgetFeaturesBefore(size_t k);
  // The model so far, in OUT/live/ (the mapper's thread, after each batch).
  void WriteLiveModel(const Reconstruction& model, const MapperBatchStatistics& batch) const;

  const Sequence* sequence_ = nullptr;  // a recorded dataset
  EurocFollower* follower_ = nullptr;   // a recording being made
  const SensorRig rig_;
  const std::filesystem::path root_;
  // The run's options; a followed recording's texture probe settles their
  // frame rate and feature count before the first frame is queued.
  PipelineOptions options_;
  const VerificationOptions verification_options_;
  const RunFolder& folder_;
  FrameCache* frame_cache_;
  KeypointGreyValues* keypoint_values_;
  SettledVio settled_;
  FrameQueue frame_queue_;
  SharedImu imu_;
  std::vector<fs::path> paths_;  // the selected frames known up front

  std::optional<ColmapDatabase> database_;
  Camera camera_;
  VioSetup setup_;
  bool rolling_shutter_ = false;
  std::optional<FeaturePrefetch> prefetch_;
  std::optional<PairVerifier> verifier_;
  std::optional<IncrementalRetrieval> retrieval_;
  VerifiedPairStream pair_stream_;
  std::vector<Frame> frames_;
  std::vector<PairGeneratorImage> generator_images_;
  std::unordered_map<image_t, size_t> frame_of_image_;
  // Per frame: its temporal neighbours (indices, once fixed) and its
  // retrieved earlier frames (ids, best first, once known).
  std::vector<std::optional<std::vector<size_t>>> neighbours_;
  std::vector<std::optional<std::vector<image_t>>> retrieved_;
  size_t next_to_decide_ = 0;
  std::vector<PairStepSeconds> step_seconds_;
  StreamOutput out_;
  double busy_seconds_ = 0.0;
  double recording_end_seconds_ = 0.0;  // a followed recording's last row
};

void Stream::Ingest(const SequenceImage& image) {
  const std::optional<FrameVioPose> pose =
      settled_.PoseAt(image.timestamp_ns, options_.max_vio_time_difference_ns);
  ImageFeatures features;
  std::vector<uint8_t> grey_values;
  if (prefetch_ && prefetch_->WaitAndTake(image.path, &features, &grey_values)) {
    ++out_.stream.num_features_beside;
  } else {
    const std::shared_ptr<const GreyImage> pixels = frame_cache_->Take(image.path);
    if (static_cast<uint64_t>(pixels->width) != camera_.width ||
        static_cast<uint64_t>(pixels->height) != camera_.height) {
      throw InputError(image.path.string(), 0,
                       "image of " + std::to_string(pixels->width) + " x " +
                           std::to_string(pixels->height) + " pixels, expected the camera's " +
                           std::to_string(camera_.width) + " x " + std::to_string(camera_.height));
    }
    features = ExtractSift(*pixels, options_.EffectiveSiftOptions());
    grey_values = SampleKeypointGreyValues(*pixels, features.keypoints);
  }
  const Timer busy;
  const std::string name = DatabaseImageName(image);
  image_t image_id = kInvalidImageId;
  {
    ColmapDatabase::Transaction transaction(*database_);
    image_id = database_->WriteImage(name, camera_.camera_id);
    database_->WriteFeatures(image_id, features.keypoints, features.descriptors);
    transaction.Commit();
  }
  keypoint_values_->Set(image_id, std::move(grey_values));
  out_.features.num_features += features.keypoints.size();
  ++out_.features.num_extracted;

  Frame frame;
  PairImage& pair_image = frame.image;
  pair_image.image_id = image_id;
  pair_image.name = name;
  pair_image.camera_id = camera_.camera_id;
  pair_image.timestamp_ns = image.timestamp_ns;
  if (pose && verification_options_.use_vio_prior) {
    pair_image.world_from_body = pose->world_from_body;
    pair_image.odometer = pose->odometer;
  }
  if (rolling_shutter_) {
    pair_image.cam_angular_rate = imu_.CamAngularRateAt(setup_.rig, image.timestamp_ns);
  }
  const double readout_s = rolling_shutter_ ? setup_.readout_s : 0.0;
  SetPairImageKeypoints(camera_, features.keypoints, readout_s,
                        verification_options_.guided_matching, &pair_image);
  pair_image.stored_descriptors = std::make_shared<const FeatureDescriptors>(features.descriptors);
  frame.in_memory = true;

  MapperImage mapper_image;
  mapper_image.image_id = image_id;
  mapper_image.camera_id = camera_.camera_id;
  mapper_image.name = name;
  mapper_image.timestamp_ns = image.timestamp_ns;
  mapper_image.keypoints = features.keypoints;
  CompensateRollingShutterRotation(camera_, readout_s, pair_image.cam_angular_rate,
                                   &mapper_image.keypoints);
  if (pose) {
    mapper_image.vio_cam_from_world = (pose->world_from_body * setup_.rig.body_from_cam).Inverse();
    mapper_image.vio_odometer = pose->odometer;
  }
  FeatureKeypoints mapper_keypoints = std::move(mapper_image.keypoints);
  out_.images.push_back(mapper_image);
  mapper_image.keypoints = std::move(mapper_keypoints);
  pair_stream_.AddFrame(std::move(mapper_image));

  frame_of_image_[image_id] = frames_.size();
  frames_.push_back(std::move(frame));
  generator_images_.push_back({image_id, image.timestamp_ns});
  neighbours_.emplace_back();
  retrieved_.emplace_back();
  if (retrieval_) {
    for (RetrievedFrame& result : retrieval_->Add(image_id, features.descriptors)) {
      std::vector<image_t> ids;
      for (const ImageScore& score : result.similar) ids.push_back(score.image_id);
      retrieved_[frame_of_image_.at(result.image_id)] = std::move(ids);
    }
  }
  busy_seconds_ += busy.ElapsedSeconds();
}

bool Stream::Decidable(size_t d, bool all_ingested) const {
  if (d >= frames_.size()) return false;
  // Its temporal neighbours are among the N1 frames on either side.
  const size_t n1 = static_cast<size_t>(verification_options_.pairs.num_temporal_neighbors);
  if (!all_ingested && frames_.size() <= d + n1) return false;
  return !retrieval_ || retrieved_[d].has_value();
}

const PairImage& Stream::WithFeatures(size_t k, bool normalised) {
  Frame& frame = frames_[k];
  PairImage& image = frame.image;
  if (!frame.in_memory) {
    SetPairImageKeypoints(camera_, database_->ReadKeypoints(image.image_id),
                          rolling_shutter_ ? setup_.readout_s : 0.0,
                          verification_options_.guided_matching, &image);
    image.stored_descriptors =
        std::make_shared<const FeatureDescriptors>(database_->ReadDescriptors(image.image_id));
    frame.in_memory = true;
  }
  if (normalised && !image.descriptors) {
    image.descriptors =
        std::make_shared<const FloatDescriptors>(NormalizeDescriptors(*image.stored_descriptors));
  }
  return image;
}

void Stream::ForgetFeaturesBefore(size_t k) {
  for (size_t i = 0; i < std::min(k, frames_.size()); ++i) {
    Frame& frame = frames_[i];
    if (!frame.in_memory) continue;
    frame.in_memory = false;
    // Moved from, so their memory goes (`= {}` would keep the capacity).
    frame.image.points_normalized = std::vector<Eigen::Vector2d>();
    frame.image.points_px = std::vector<Eigen::Vector2d>();
    frame.image.stored_descriptors.reset();
    frame.image.descriptors.reset();
  }
}

void Stream::Decide(size_t d) {
  const Timer busy;
  const PairGeneratorOptions& pairs = verification_options_.pairs;
  const int n1 = pairs.num_temporal_neighbors;
  neighbours_[d] = TemporalNeighbors(generator_images_, d, n1);
  // The earlier frames it pairs with, and how each pair was proposed.
  std::vector<std::pair<size_t, const char*>> partners;
  std::set<size_t> taken;
  if (pairs.mode == PairMode::kTemporalRetrieval) {
    for (const size_t i : *neighbours_[d]) {
      if (i < d && taken.insert(i).second) partners.emplace_back(i, "temporal");
    }
    // Frames before it whose temporal neighbours include it.
    for (size_t i = d > static_cast<size_t>(n1) ? d - n1 : 0; i < d; ++i) {
      const std::vector<size_t>& of_i = *neighbours_[i];
      if (std::find(of_i.begin(), of_i.end(), d) != of_i.end() && taken.insert(i).second) {
        partners.emplace_back(i, "temporal");
      }
    }
    if (retrieval_) {
      std::unordered_set<image_t> excluded;
      for (const size_t i : *neighbours_[d]) excluded.insert(frames_[i].image.image_id);
      int added = 0;
      for (const image_t candidate : *retrieved_[d]) {
        if (added >= pairs.num_retrieval_neighbors) break;
        if (excluded.count(candidate) > 0) continue;
        const size_t i = frame_of_image_.at(candidate);
        excluded.insert(candidate);
        if (taken.insert(i).second) partners.emplace_back(i, "retrieval");
        ++added;
      }
    }
  } else if (pairs.mode == PairMode::kSequential) {
    for (size_t i = d > static_cast<size_t>(n1) ? d - n1 : 0; i < d; ++i) {
      partners.emplace_back(i, "sequential");
    }
  } else {  // kExhaustive
    for (size_t i = 0; i < d; ++i) partners.emplace_back(i, "exhaustive");
  }
  std::sort(partners.begin(), partners.end());

  // The pairs' work, their features loaded.
  std::vector<PairWork> work(partners.size());
  std::vector<std::pair<const PairImage*, const PairImage*>> images(partners.size());
  for (size_t p = 0; p < partners.size(); ++p) {
    const size_t i = partners[p].first;
    const bool prior = HasVioPrior(frames_[i].image, frames_[d].image);
    const bool normalised = !verification_options_.guided_matching || !prior;
    images[p] = {&WithFeatures(i, normalised), &WithFeatures(d, normalised)};
    PairDecision& decision = work[p].decision;
    decision.image_id1 = images[p].first->image_id;
    decision.image_id2 = images[p].second->image_id;
    decision.name1 = images[p].first->name;
    decision.name2 = images[p].second->name;
    decision.source = partners[p].second;
    decision.has_vio_prior = prior;
  }
  ParallelFor(static_cast<int64_t>(work.size()), options_.num_threads, [&](int64_t p, int thread) {
    verifier_->Verify(*images[p].first, *images[p].second, camera_, camera_, &work[p],
                      &step_seconds_[thread]);
  });
  std::vector<ImagePairMatches> accepted;
  VerificationSummary& summary = out_.verification.summary;
  for (PairWork& pair_work : work) {
    StorePairWork(pair_work, &*database_, &summary);
    if (pair_work.geometry) {
      accepted.push_back({pair_work.decision.image_id1, pair_work.decision.image_id2,
                          pair_work.geometry->inlier_matches});
    }
    CountDecision(pair_work.decision, &summary);
    out_.verification.decisions.push_back(std::move(pair_work.decision));
  }
  summary.num_pairs += work.size();
  // Every pair still to come has a later frame than d.
  pair_stream_.Add(std::move(accepted), frames_[d].image.timestamp_ns + 1);
  next_to_decide_ = d + 1;
  // The features of frames no temporal pair needs any more (a retrieved
  // frame's are read back).
  if (pairs.mode != PairMode::kExhaustive) {
    ForgetFeaturesBefore(next_to_decide_ > static_cast<size_t>(n1) + 1 ? next_to_decide_ - n1 - 1
                                                                       : 0);
  }
  busy_seconds_ += busy.ElapsedSeconds();
}

void Stream::WriteLiveModel(const Reconstruction& model, const MapperBatchStatistics& batch) const {
  const fs::path live = folder_.path() / "live";
  fs::create_directories(live);
  Trajectory world_from_body;
  std::vector<std::pair<timestamp_ns_t, image_t>> registered;
  for (const image_t image_id : model.RegImageIds()) {
    const std::optional<timestamp_ns_t>& stamp = model.GetImage(image_id).timestamp_ns;
    if (stamp) registered.emplace_back(*stamp, image_id);
  }
  std::sort(registered.begin(), registered.end());
  for (const auto& [stamp, image_id] : registered) {
    world_from_body.poses.push_back(
        {stamp, model.GetImage(image_id).cam_from_world.Inverse() * rig_.body_from_cam.Inverse()});
  }
  world_from_body.has_timestamps = true;
  WriteTumTrajectory(live / "trajectory_body.tum", world_from_body);
  WritePly(live / "points.ply", model);
  VIOSFM_LOG(INFO) << "run: the model after batch " << batch.batch_index + 1 << " in "
                   << live.string() << ": " << registered.size() << " frames, "
                   << model.NumPoints3D() << " points";
}

void Stream::RunRecordedVio(const Timer& stream_timer, double* vio_seconds) {
  const bool own_vio = !options_.vio_source && options_.vio_trajectory.empty();
  if (own_vio) {
    try {
      out_.vio = LoadVioPoses(*sequence_, options_, frame_cache_,
                              [&](const VioProgress& progress) { settled_.Report(progress); });
      // Frames it did not read (after the IMU's last sample): the
      // features' thread stops waiting for them.
      frame_cache_->StopWaiting();
    } catch (const std::exception& error) {
      settled_.Fail(error.what());
      frame_cache_->StopWaiting();
      throw;
    }
    *vio_seconds = stream_timer.ElapsedSeconds();
    return;
  }
  // An external VIO: its poses were read before; the selected frames are
  // decoded here for the features' thread, in order.
  for (const fs::path& path : paths_) {
    try {
      frame_cache_->Read(path, /*keep=*/true);
    } catch (const std::exception&) {
      // The verification's thread reads it again and reports what is wrong.
      frame_cache_->StopWaiting();
      return;
    }
  }
}

void Stream::FollowRecording(const Timer& stream_timer, double* vio_seconds) {
  // The recording as it comes: its rows into the VIO (one step at a time)
  // and the frame selection, whose frames go to the features and the
  // verification as they are decided.
  Sequence& so_far = out_.followed;
  so_far.root = root_;
  so_far.rig = rig_;
  try {
    VioOptions vio_options = OwnVioOptions(options_);
    vio_options.show_progress = false;  // a recording being made has no known length
    VioRunner vio(rig_, vio_options, frame_cache_, std::nullopt,
                  [&](const VioProgress& progress) { settled_.Report(progress); });
    // The selection once the texture probe has settled the rate (at once
    // without the probe).
    std::optional<GrowingFrameSelection> selection;
    const auto settle_rate = [&](bool ended) {
      if (selection) return;
      if (options_.texture_probe.enable) {
        if (!ended && (so_far.images.empty() ||
                       NsToSeconds(so_far.images.back().timestamp_ns -
                                   so_far.images.front().timestamp_ns) < kFollowProbeWindowS)) {
          return;
        }
        VIOSFM_LOG(INFO) << "run: --follow: the texture probe takes the recording's first "
                         << kFollowProbeWindowS << " s for the whole";
        ResolveRateByTexture(so_far, frame_cache_, &options_, &out_.probe);
        prefetch_->SetSiftOptions(options_.EffectiveSiftOptions());
      }
      out_.frame_rate_hz = options_.frame_selection.target_rate_hz;
      out_.max_num_features = options_.sift.max_num_features;
      selection.emplace(options_.frame_selection);
    };
    size_t released = 0;  // frames whose selection is decided
    const auto take = [&](const std::vector<size_t>& selected, size_t decided) {
      size_t next = 0;
      for (; released < decided; ++released) {
        const SequenceImage& image = so_far.images[released];
        if (next < selected.size() && selected[next] == released) {
          ++next;
          prefetch_->AddPath(image.path);
          frame_queue_.Add(image);
        } else {
          frame_cache_->Release(image.path);  // read by the VIO, not taken
        }
      }
    };
    const auto add = [&](const EurocFollower::Rows& rows) {
      imu_.Add(rows.imu);
      so_far.imu.insert(so_far.imu.end(), rows.imu.begin(), rows.imu.end());
      vio.AddImu(rows.imu);
      for (const SequenceImage& image : rows.images) {
        so_far.images.push_back(image);
        vio.AddImage(image);
      }
    };
    // The folder is looked at every 10 ms: rows come at the IMU's rate,
    // and a frame is taken tens of milliseconds after its stamp anyway (the
    // IMU has to pass it).
    Timer silence;
    while (true) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
      const EurocFollower::Rows rows = follower_->Poll();
      if (rows.empty()) {
        if (silence.ElapsedSeconds() >= options_.follow_idle_s) break;
        continue;
      }
      silence.Start();
      recording_end_seconds_ = stream_timer.ElapsedSeconds();
      add(rows);
      settle_rate(/*ended=*/false);
      if (!selection) continue;
      size_t decided = 0;
      const std::vector<size_t> selected = selection->Update(so_far, &decided);
      take(selected, decided);
    }
    VIOSFM_LOG(INFO) << "run: nothing appended to " << root_.string() << " for "
                     << options_.follow_idle_s << " s: the recording has ended ("
                     << so_far.images.size() << " images, " << so_far.imu.size() << " IMU samples)";
    add(follower_->Finish());
    if (so_far.images.empty()) {
      throw InputError(root_.string(), 0, "the recording followed has no images");
    }
    const VioResult result = vio.Finish(root_);
    // The ground truth, if the recording holds one (read now, when it is
    // complete), for the evaluation.
    so_far.ground_truth = follower_->ReadGroundTruth();
    settle_rate(/*ended=*/true);
    const std::vector<size_t> last = selection->Finish(so_far, &out_.followed_selection);
    for (const size_t k : last) {
      prefetch_->AddPath(so_far.images[k].path);
      frame_queue_.Add(so_far.images[k]);
    }
    prefetch_->ClosePaths();
    frame_queue_.Close();
    out_.vio = PosesOfOwnVio(so_far, options_, result);
    frame_cache_->StopWaiting();
  } catch (const std::exception& error) {
    settled_.Fail(error.what());
    frame_queue_.Fail(error.what());
    frame_cache_->StopWaiting();
    if (prefetch_) prefetch_->ClosePaths();
    throw;
  }
  *vio_seconds = stream_timer.ElapsedSeconds();
}

StreamOutput Stream::Run(const Timer& stream_timer) {
  const bool own_vio = !options_.vio_source && options_.vio_trajectory.empty();
  // The database, from here on written by this thread only.
  database_.emplace(ColmapDatabase::Open(folder_.path() / "database.db"));
  {
    ColmapDatabase::Transaction transaction(*database_);
    camera_ = database_->ReadCamera(database_->WriteCamera(rig_.camera));
    transaction.Commit();
  }
  if (!own_vio) {
    out_.vio = LoadVioPoses(*sequence_, options_);
    settled_.SetAll(out_.vio);
  }
  prefetch_.emplace(paths_, options_.EffectiveSiftOptions(), rig_.camera, frame_cache_,
                    kFeaturePrefetchBytes, /*wait_when_full=*/true,
                    /*more_paths=*/follower_ != nullptr);

  // The VIO; whatever fails, the other threads stop and are joined before
  // the stream and its inputs go.
  Worker vio_worker;
  double vio_seconds = 0.0;
  vio_worker.Start([&] {
    if (follower_ != nullptr) {
      FollowRecording(stream_timer, &vio_seconds);
    } else {
      RunRecordedVio(stream_timer, &vio_seconds);
    }
  });
  Worker mapper_worker;
  struct StopOnExit {
    Stream* stream;
    Worker* mapper;
    ~StopOnExit() {
      stream->pair_stream_.Fail("the run stopped before the mapping ended");
      mapper->Join();
      if (stream->prefetch_) stream->prefetch_->Finish();
    }
  } stop_on_exit{this, &mapper_worker};

  setup_ = settled_.WaitForSetup();
  rolling_shutter_ = setup_.readout_s > 0.0 && options_.compensate_rolling_shutter && !imu_.empty();
  out_.input.cameras = {camera_};
  out_.input.rig = setup_.rig;
  out_.input.rolling_shutter_readout_s = rolling_shutter_ ? setup_.readout_s : 0.0;
  if (sequence_ != nullptr) out_.input.imu = sequence_->imu;
  verifier_.emplace(verification_options_, setup_.rig.body_from_cam);
  step_seconds_.assign(
      static_cast<size_t>(NumThreadsFor(1 << 20, std::max(1, options_.num_threads))), {});
  const PairGeneratorOptions& pairs = verification_options_.pairs;
  if (pairs.mode == PairMode::kTemporalRetrieval && pairs.num_retrieval_neighbors > 0) {
    RetrievalOptions retrieval = verification_options_.retrieval;
    // Enough to leave N2 once the temporal neighbours are left out.
    retrieval.num_neighbors = pairs.num_retrieval_neighbors + pairs.num_temporal_neighbors;
    retrieval.num_threads = 1;
    retrieval.vocabulary.num_threads = options_.num_threads;
    retrieval.vocabulary.seed = verification_options_.seed;
    retrieval_.emplace(retrieval, options_.stream_vocabulary_frames, /*num_temporal_neighbors=*/0);
  }

  double mapper_seconds = 0.0;
  BatchedMapperOptions mapper_options = options_.EffectiveMapperOptions();
  mapper_options.show_progress = false;
  const MapperBatchCallback live = [this](const Reconstruction& model,
                                          const MapperBatchStatistics& batch) {
    WriteLiveModel(model, batch);
  };
  mapper_worker.Start([&] {
    out_.reconstruction =
        RunBatchedMapper(out_.input, mapper_options, &out_.stream_mapper_summary, &pair_stream_,
                         follower_ != nullptr ? live : MapperBatchCallback());
    mapper_seconds = stream_timer.ElapsedSeconds();
  });

  ProgressBar progress("stream", static_cast<int64_t>(paths_.size()),
                       options_.show_progress && follower_ == nullptr ? ProgressBar::Mode::kAuto
                                                                      : ProgressBar::Mode::kNever);
  SequenceImage image;
  for (size_t f = 0; !mapper_worker.failed() && frame_queue_.Get(f, &image); ++f) {
    Ingest(image);
    while (Decidable(next_to_decide_, /*all_ingested=*/false)) Decide(next_to_decide_);
    progress.Update();
  }
  progress.Finish();
  const double last_frame_seconds = stream_timer.ElapsedSeconds();
  if (retrieval_ && !mapper_worker.failed()) {
    for (RetrievedFrame& result : retrieval_->Finish()) {
      std::vector<image_t> ids;
      for (const ImageScore& score : result.similar) ids.push_back(score.image_id);
      retrieved_[frame_of_image_.at(result.image_id)] = std::move(ids);
    }
  }
  while (!mapper_worker.failed() && Decidable(next_to_decide_, /*all_ingested=*/true)) {
    Decide(next_to_decide_);
  }
  const double verification_seconds = stream_timer.ElapsedSeconds();
  // The mapper's final adjustment reads the whole IMU: a followed
  // recording's is complete once the VIO's thread has ended (its last rows
  // came before the frame queue closed).
  if (follower_ != nullptr) {
    vio_worker.JoinAndRethrow();
    out_.input.imu = imu_.All();
  }
  out_.stream.num_vocabulary_frames =
      retrieval_
          ? std::min<size_t>(frames_.size(), static_cast<size_t>(options_.stream_vocabulary_frames))
          : 0;
  // Every frame is verified: the pixels, features and retrieval index held for the
  // verification are freed, and the pages glibc keeps of them (in the arenas
  // of the threads that made them) go back to the system before the mapper's
  // final adjustment, which starts once the stream is closed.
  ForgetFeaturesBefore(frames_.size());
  retrieval_.reset();
  ReturnFreedMemory();
  pair_stream_.Close();
  mapper_worker.JoinAndRethrow();
  vio_worker.JoinAndRethrow();
  prefetch_->Finish();
  if (follower_ != nullptr) fs::remove_all(folder_.path() / "live");

  VerificationSummary& summary = out_.verification.summary;
  summary.options = verification_options_.ToKeyValues();
  summary.database_path = database_->path().string();
  summary.num_images = frames_.size();
  for (const Frame& frame : frames_) {
    if (frame.image.world_from_body) ++summary.num_images_with_prior;
  }
  for (const PairStepSeconds& seconds : step_seconds_) {
    summary.seconds_matching += seconds.matching;
    summary.seconds_vio += seconds.vio;
    summary.seconds_ransac += seconds.ransac;
  }
  summary.seconds_total = verification_seconds;
  std::sort(out_.verification.decisions.begin(), out_.verification.decisions.end(),
            [](const PairDecision& a, const PairDecision& b) {
              return std::make_pair(a.image_id1, a.image_id2) <
                     std::make_pair(b.image_id1, b.image_id2);
            });
  VIOSFM_LOG(INFO) << "run: verification " << FormatVerificationSummary(summary);
  out_.features.num_images = frames_.size();
  out_.features.num_extracted_before = out_.stream.num_features_beside;
  out_.features.seconds = last_frame_seconds;
  out_.stream.streamed = true;
  out_.stream.vio_seconds = vio_seconds;
  out_.stream.verification_seconds = verification_seconds;
  out_.stream.verification_busy_seconds = busy_seconds_;
  out_.stream.mapper_seconds = mapper_seconds;
  out_.stream.seconds_after_last_frame = mapper_seconds - last_frame_seconds;
  if (follower_ != nullptr) {
    out_.stream.followed = true;
    out_.stream.recording_end_seconds = recording_end_seconds_;
    out_.stream.seconds_after_recording_end = mapper_seconds - recording_end_seconds_;
  }
  database_->SyncToDisk();
  return std::move(out_);
}

}  // namespace

PipelineSummary RunStreamPipeline(const PipelineOptions& requested) {
  PipelineOptions options = requested;
  options.stream = true;
  PipelineSummary summary = StartRunSummary(options);
  Timer total_timer;
  total_timer.Start();
  StageClock clock(&summary.stages, kStreamStageNames);
  const bool own_vio = !options.vio_source && options.vio_trajectory.empty();
  const std::string vio_name =
      own_vio || options.vio_source ? std::string("the VIO") : options.vio_trajectory.string();

  CheckDatasetExists(options.dataset);
  const RunFolder folder(options);
  if (fs::exists(folder.path() / "database.db")) {
    throw InputError((folder.path() / "database.db").string(), 0,
                     "a streamed run (--stream, --follow) starts afresh and does not resume: this "
                     "folder holds an earlier run's features and matches; re-run with --overwrite "
                     "to remove that run's outputs, or choose another --out");
  }
  // One arena a thread the run asks for: the 2400-frame room's peak was 77
  // MiB lower at 2 than at glibc's default, for the same CPU
  // (docs/benchmarks.md "The stream, and a recording followed").
  LimitMallocArenas(std::max(2, options.num_threads));
  FrameCache frame_cache(kFrameCacheBytes);
  KeypointGreyValues keypoint_values;
  RunFingerprint fingerprint = FingerprintOfInputs(options);

  // A recorded dataset is read whole; a recording being made gives its
  // calibration now and its rows as they come.
  std::optional<Sequence> recorded;
  std::optional<EurocFollower> follower;
  clock.Run([&] {
    if (options.follow) {
      if (!IsEurocDatasetFolder(options.dataset)) {
        throw InputError(options.dataset.string(), 0,
                         "--follow: a EuRoC folder being recorded (mav0/cam0, mav0/imu0) is "
                         "followed; this is not one");
      }
      follower.emplace(options.dataset);
      ApplyCalibrationFiles(options.calibration, follower->mutable_header());
      return;
    }
    recorded = ReadDatasetStage(options, folder, &fingerprint);
    ResolveRateByTexture(*recorded, &frame_cache, &options, &summary);
    if (options.texture_probe.enable) AddSettledRateAndFeatures(options, &fingerprint);
    summary.num_frames_in = recorded->images.size();
    if (own_vio && !recorded->has_imu()) {
      throw InputError(options.dataset.string(), 0,
                       "--stream: the stream runs viosfm's own VIO, which needs an IMU, and the "
                       "dataset has none; run the images alone without --stream");
    }
    if (own_vio && FrameSelectionUsesTrajectory(*recorded, options.frame_selection)) {
      throw InputError(options.dataset.string(), 0,
                       "--stream: the frame selection would need the own VIO's trajectory "
                       "(frame_selection.static_source), which a stream has only at its end; "
                       "select the static frames by the IMU, or run without --stream");
    }
  });

  StreamOutput streamed = clock.Run([&] {
    const Timer stream_timer;
    // What the database is made from, before it changes: the VIO's poses
    // (and a followed recording's files) once the VIO has ended.
    if (own_vio) {
      fingerprint.Set("vio.poses", "pending: a streamed run writes them when its VIO ends");
    }
    if (follower) {
      fingerprint.Set("dataset.images", "pending: the recording is followed as it is made");
    }
    if (follower) {
      folder.MarkIncomplete();
      folder.WriteRecords(fingerprint, options.ToKeyValues());
      Stream stream(&*follower, options, folder, &frame_cache, &keypoint_values);
      return stream.Run(stream_timer);
    }
    // The frames to take: the selection needs no VIO here (an external
    // VIO's trajectory is read now for it when the selection asks).
    std::optional<Trajectory> external;
    if (!own_vio && FrameSelectionUsesTrajectory(*recorded, options.frame_selection)) {
      external = LoadVioTrajectory(*recorded, options);
    }
    const FrameSelection selection =
        SelectFrames(*recorded, options.frame_selection, external ? &*external : nullptr);
    if (!selection.ok()) {
      throw InputError(options.dataset.string(), 0,
                       "no frames to reconstruct: " + selection.message);
    }
    std::vector<fs::path> paths;
    for (const size_t index : selection.kept) paths.push_back(recorded->images[index].path);
    frame_cache.RetainOnly(paths);
    folder.WriteRecords(fingerprint, options.ToKeyValues());
    Stream stream(*recorded, selection.kept, options, folder, &frame_cache, &keypoint_values);
    return stream.Run(stream_timer);
  });
  // A followed recording: as it came, now complete, its rate and feature
  // count as its texture probe settled them.
  if (follower) {
    recorded = std::move(streamed.followed);
    summary.num_frames_in = recorded->images.size();
    summary.texture_probe = streamed.probe.texture_probe;
    summary.texture_probe_message = streamed.probe.texture_probe_message;
    options.frame_selection.target_rate_hz = streamed.frame_rate_hz;
    options.sift.max_num_features = streamed.max_num_features;
    summary.frame_rate_hz = streamed.frame_rate_hz;
    summary.max_num_features = streamed.max_num_features;
    fingerprint = FingerprintOfInputs(options);
    AddSequenceToFingerprint(*recorded, &fingerprint);
    if (options.texture_probe.enable) AddSettledRateAndFeatures(options, &fingerprint);
  }
  const Sequence& sequence = *recorded;
  const VioPoses& vio = streamed.vio;
  AddVioPosesToFingerprint(vio.world_from_body, vio.segments, &fingerprint);
  folder.WriteRecords(fingerprint, options.ToKeyValues());
  summary.fingerprint = fingerprint.Hash();
  summary.num_vio_segments = vio.num_segments();
  summary.vio_segment_rule = vio.segment_rule;
  summary.own_vio = vio.own_vio_summary;
  summary.stream = streamed.stream;
  summary.features = streamed.features;
  summary.verification = streamed.verification.summary;
  summary.mapper = std::move(streamed.stream_mapper_summary);

  // The frames as the stream took them, for the stages after it: a
  // recorded dataset's as SelectFramesStage selects them (the same frames
  // and VIO poses the stream took), a followed one's as its selection took
  // them.
  SelectedFrames frames;
  if (follower) {
    frames = SelectedFramesOf(sequence, streamed.followed_selection, vio, options, vio_name,
                              &frame_cache);
  } else {
    frames = SelectFramesStage(sequence, vio, options, vio_name, &frame_cache);
  }
  if (frames.sequence.images.size() != streamed.images.size()) {
    throw InternalError("the streamed run took " + std::to_string(streamed.images.size()) +
                        " frames, the frame selection " +
                        std::to_string(frames.sequence.images.size()));
  }
  for (size_t i = 0; i < streamed.images.size(); ++i) {
    if (frames.vio_index[i].has_value() != streamed.images[i].vio_cam_from_world.has_value()) {
      throw InternalError("the streamed run associated the VIO with frame " +
                          streamed.images[i].name + " otherwise than the frame selection");
    }
  }
  summary.frame_selection = frames.selection;
  summary.num_frames_selected = frames.sequence.images.size();
  summary.num_frames_without_vio_pose = frames.num_without_vio_pose;
  summary.rolling_shutter_readout_s = streamed.input.rolling_shutter_readout_s;
  summary.rolling_shutter_source = vio.rolling_shutter_source;
  FinishMapping(sequence, vio, options, &summary, &streamed.reconstruction);
  ReturnFreedMemory();

  BatchedMapperInput mapped = std::move(streamed.input);
  mapped.images = std::move(streamed.images);
  clock.Run([&] {
    ColorPointsStage(frames, mapped, options.show_progress, &keypoint_values, &frame_cache,
                     &streamed.reconstruction);
  });
  const TrajectoryEvaluation evaluation = clock.Run([&] {
    return EvaluateStage(sequence, frames, vio, mapped, streamed.reconstruction,
                         options.max_vio_time_difference_ns);
  });
  TakeEvaluation(evaluation, &summary);
  clock.Run([&] {
    WriteOutputsStage(options.output_folder, streamed.verification, streamed.reconstruction, frames,
                      evaluation);
  });

  // The database was synced and closed at the stream's end.
  FinishRunSummary(frame_cache, total_timer, folder, &summary);
  return summary;
}

}  // namespace viosfm

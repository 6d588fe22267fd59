#include "viosfm/pipeline/stream.h"

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
#include "viosfm/matching/incremental_pair_generator.h"
#include "viosfm/matching/pair_decider.h"
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
#include "viosfm/util/worker_thread.h"

namespace viosfm {

namespace fs = std::filesystem;

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
  ArrivingFrame arriving{&image, pose, Eigen::Vector3d::Zero()};
  if (rolling_shutter_)
    arriving.cam_angular_rate = imu_.CamAngularRateAt(setup_.rig, image.timestamp_ns);
  const IngestedFrame stored = ingest_->Store(image, &features);
  const image_t image_id = stored.image_id;
  keypoint_values_->Set(image_id, std::move(grey_values));
  out_.features.num_features += features.keypoints.size();
  ++out_.features.num_extracted;

  Frame frame;
  frame.image = ingest_->PairImageOf(arriving, stored, features.descriptors,
                                     verification_options_.use_vio_prior,
                                     verification_options_.guided_matching);
  frame.in_memory = true;
  MapperImage mapper_image = ingest_->MapperImageOf(arriving, stored);
  FeatureKeypoints mapper_keypoints = std::move(mapper_image.keypoints);
  out_.images.push_back(mapper_image);
  mapper_image.keypoints = std::move(mapper_keypoints);
  pair_stream_.AddFrame(std::move(mapper_image));

  frame_of_image_[image_id] = frames_.size();
  frames_.push_back(std::move(frame));
  pair_generator_->AddFrame({image_id, image.timestamp_ns});
  if (retrieval_) TakeRetrieved(retrieval_->Add(image_id, features.descriptors));
  busy_seconds_ += busy.ElapsedSeconds();
}

void Stream::TakeRetrieved(std::vector<RetrievedFrame> results) {
  for (RetrievedFrame& result : results) {
    std::vector<image_t> ids;
    for (const ImageScore& score : result.similar) ids.push_back(score.image_id);
    pair_generator_->SetRetrieved(frame_of_image_.at(result.image_id), std::move(ids));
  }
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

void Stream::DecideReady() {
  size_t d = 0;
  std::vector<ProposedPair> partners;
  while (pair_generator_->Next(&d, &partners)) Decide(d, partners);
}

void Stream::Decide(size_t d, const std::vector<ProposedPair>& partners) {
  const Timer busy;
  const size_t n1 = static_cast<size_t>(verification_options_.pairs.num_temporal_neighbors);
  // The pairs with their features.
  std::vector<PairToDecide> pairs;
  for (const ProposedPair& partner : partners) {
    const size_t i = partner.earlier_frame;
    const bool stored = decider_->IsStored(frames_[i].image.image_id, frames_[d].image.image_id);
    const bool prior = HasVioPrior(frames_[i].image, frames_[d].image);
    const bool normalised = !verification_options_.guided_matching || !prior;
    // Stored matches are judged again from the keypoints: no descriptor
    // is compared.
    const PairImage& earlier = WithFeatures(i, normalised && !stored);
    const PairImage& later = WithFeatures(d, normalised && !stored);
    pairs.push_back({&earlier, &later, &camera_, &camera_, partner.source});
  }
  std::vector<ImagePairMatches> accepted = decider_->Decide(pairs);
  // Every pair still to come has a later frame than d.
  pair_stream_.Add(std::move(accepted), frames_[d].image.timestamp_ns + 1);
  // The features of frames no temporal pair needs any more (a retrieved
  // frame's are read back).
  if (verification_options_.pairs.mode != PairMode::kExhaustive) {
    ForgetFeaturesBefore(d + 1 > n1 + 1 ? d - n1 : 0);
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

void Stream::SetUpVerification() {
  setup_ = settled_.WaitForSetup();
  rolling_shutter_ = setup_.readout_s > 0.0 && options_.compensate_rolling_shutter && !imu_.empty();
  out_.input.cameras = {camera_};
  out_.input.rig = setup_.rig;
  out_.input.rolling_shutter_readout_s = rolling_shutter_ ? setup_.readout_s : 0.0;
  if (sequence_ != nullptr) out_.input.imu = sequence_->imu;
  ingest_.emplace(&*database_, camera_.camera_id, setup_.rig.body_from_cam,
                  out_.input.rolling_shutter_readout_s);
  decider_.emplace(verification_options_, setup_.rig.body_from_cam, &*database_);
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
  pair_generator_.emplace(pairs);
  pair_generator_->SetRetrievalUsed(retrieval_.has_value());
}

void Stream::TakeVerification(double verification_seconds) {
  out_.verification = decider_->TakeResult();
  VerificationSummary& summary = out_.verification.summary;
  summary.options = verification_options_.ToKeyValues();
  summary.database_path = database_->path().string();
  summary.num_images = frames_.size();
  for (const Frame& frame : frames_) {
    if (frame.image.world_from_body) ++summary.num_images_with_prior;
  }
  summary.seconds_total = verification_seconds;
  std::sort(out_.verification.decisions.begin(), out_.verification.decisions.end(),
            [](const PairDecision& a, const PairDecision& b) {
              return std::make_pair(a.image_id1, a.image_id2) <
                     std::make_pair(b.image_id1, b.image_id2);
            });
  VIOSFM_LOG(INFO) << "run: verification: " << FormatVerificationHeadline(summary) << LogDetails()
                   << " (" << FormatVerificationSummary(summary) << ")";
}

void Stream::OpenDatabase() {
  database_.emplace(ColmapDatabase::Open(folder_.path() / "database.db"));
  ColmapDatabase::Transaction transaction(*database_);
  camera_ = database_->ReadCamera(database_->WriteCamera(rig_.camera));
  transaction.Commit();
}

void Stream::FinishVerification() {
  if (retrieval_) TakeRetrieved(retrieval_->Finish());
  DecideReady();
}

void Stream::TakeTimes(const StreamTimes& times) {
  out_.features.num_images = frames_.size();
  out_.features.num_extracted_before = out_.stream.num_features_beside;
  out_.features.seconds = times.last_frame;
  out_.stream.streamed = true;
  out_.stream.vio_seconds = times.vio;
  out_.stream.verification_seconds = times.verification;
  out_.stream.verification_busy_seconds = busy_seconds_;
  out_.stream.mapper_seconds = times.mapper;
  out_.stream.seconds_after_last_frame = times.mapper - times.last_frame;
  if (follower_ != nullptr) {
    out_.stream.followed = true;
    out_.stream.recording_end_seconds = recording_end_seconds_;
    out_.stream.seconds_after_recording_end = times.mapper - recording_end_seconds_;
  }
}

StreamOutput Stream::Run(const Timer& stream_timer) {
  // The database, from here on written by this thread only.
  OpenDatabase();
  if (!options_.UsesOwnVio()) {
    out_.vio = LoadVioPoses(*sequence_, options_);
    settled_.SetAll(out_.vio);
  }
  prefetch_.emplace(paths_, options_.EffectiveSiftOptions(), rig_.camera, frame_cache_,
                    kFeaturePrefetchBytes, /*wait_when_full=*/true,
                    /*more_paths=*/follower_ != nullptr);

  // The VIO; whatever fails, the other threads stop and are joined before
  // the stream and its inputs go.
  Worker vio_worker;
  StreamTimes times;
  vio_worker.Start([&] {
    if (follower_ != nullptr) {
      FollowRecording(stream_timer, &times.vio);
    } else {
      RunRecordedVio(stream_timer, &times.vio);
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

  SetUpVerification();

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
    times.mapper = stream_timer.ElapsedSeconds();
  });

  ProgressBar progress("stream", static_cast<int64_t>(paths_.size()),
                       options_.show_progress && follower_ == nullptr ? ProgressBar::Mode::kAuto
                                                                      : ProgressBar::Mode::kNever);
  SequenceImage image;
  for (size_t f = 0; !mapper_worker.failed() && frame_queue_.Get(f, &image); ++f) {
    Ingest(image);
    DecideReady();
    progress.Update();
  }
  progress.Finish();
  times.last_frame = stream_timer.ElapsedSeconds();
  pair_generator_->FinishFrames();
  if (!mapper_worker.failed()) FinishVerification();
  times.verification = stream_timer.ElapsedSeconds();
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

  TakeVerification(times.verification);
  TakeTimes(times);
  database_->SyncToDisk();
  return std::move(out_);
}

}  // namespace viosfm

// The VIO's thread of a stream: the own VIO over a recorded dataset, the
// reader of an external VIO's frames, or a recording being followed.
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
#include "viosfm/pipeline/stream.h"
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

namespace fs = std::filesystem;

void Stream::RunRecordedVio(const Timer& stream_timer, double* vio_seconds) {
  if (options_.UsesOwnVio()) {
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
      }
      // Without the probe the feature budget is settled at once, at the target rate.
      ResolveRateByTexture(so_far, frame_cache_, &options_, &out_.probe);
      prefetch_->SetSiftOptions(options_.EffectiveSiftOptions());
      out_.frame_rate_hz = options_.frame_selection.target_rate_hz;
      out_.max_num_features = options_.sift.max_num_features;
      out_.max_image_size = options_.sift.max_image_size;
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

}  // namespace viosfm

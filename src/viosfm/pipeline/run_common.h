// What a `viosfm run` does the same way whether its stages run one after
// the other (pipeline.h) or as one stream (stream_pipeline.h): the clock of
// its stages, the memory it reports and gives back, and the frame rate and
// feature count settled by the texture probe.
#pragma once

#include <cstddef>
#include <string>
#include <type_traits>
#include <vector>

#include "viosfm/io/frame_cache.h"
#include "viosfm/pipeline/pipeline_options.h"
#include "viosfm/pipeline/pipeline_summary.h"
#include "viosfm/pipeline/run_folder.h"
#include "viosfm/pipeline/stage_evaluation.h"
#include "viosfm/scene/sequence.h"
#include "viosfm/util/logging.h"
#include "viosfm/util/timer.h"

namespace viosfm {

// Pixels of decoded frames held between the VIO and feature extraction
// (io/frame_cache.h): 512 MiB, about 1480 frames of 752 x 480; frames past it
// are decoded again when their features are extracted.
inline constexpr size_t kFrameCacheBytes = size_t{512} << 20;
// Features extracted beside viosfm's own VIO (feature_prefetch.h) held until
// the features stage writes them: 256 MiB, about 1700 frames of 1000
// features, 200 of 8192; the rest are extracted by the features stage.
inline constexpr size_t kFeaturePrefetchBytes = size_t{256} << 20;

// The current time as "YYYY-MM-DDThh:mm:ssZ" (UTC).
std::string UtcNow();

// MB, the process's peak resident memory so far.
double PeakMemoryMb();

// Gives the memory freed by a stage back to the system. The decoded frames
// the VIO handed to feature extraction (up to kFrameCacheBytes) and the
// verification's descriptors are freed by then, but glibc keeps freed heap
// pages for reuse, and the mapper's final bundle adjustment (about 0.4 MB
// a frame) does not fit in them: without this, a long run's peak is the two
// added up. See docs/benchmarks.md, section "Scaling: 300 to 2400 frames".
void ReturnFreedMemory();

// At most `max_arenas` glibc malloc arenas (its default: 8 a core), so that
// memory one thread frees is found again by the others: a streamed run's
// threads each allocate and free in turn. Call before the threads start.
void LimitMallocArenas(int max_arenas);

// Runs the stages in order, recording each one's wall-clock and CPU time
// and logging a heading for it.
class StageClock {
 public:
  StageClock(std::vector<PipelineStageTime>* stages, std::vector<std::string> names)
      : stages_(stages), names_(std::move(names)) {}

  template <class Stage>
  auto Run(Stage&& stage) {
    const std::string name = names_.at(index_);
    ++index_;
    VIOSFM_LOG(INFO) << "run [" << index_ << "/" << names_.size() << "] " << name;
    Timer timer;
    timer.Start();
    const double cpu_start = ProcessCpuSeconds();
    if constexpr (std::is_void_v<decltype(stage())>) {
      stage();
      End(name, timer.ElapsedSeconds(), ProcessCpuSeconds() - cpu_start);
    } else {
      auto result = stage();
      End(name, timer.ElapsedSeconds(), ProcessCpuSeconds() - cpu_start);
      return result;
    }
  }

 private:
  void End(const std::string& name, double seconds, double cpu_seconds);

  std::vector<PipelineStageTime>* stages_;
  std::vector<std::string> names_;
  size_t index_ = 0;
};

// A run that starts now: `options` validated (InputError naming the bad
// field), the summary's start time, dataset and output folder.
PipelineSummary StartRunSummary(const PipelineOptions& options);
// A run's last step, once every other output is on disk: the image decodes
// (logged), the total time and the peak memory into `summary`, then
// summary.json, which says the folder is complete.
void FinishRunSummary(const FrameCache& frame_cache, const Timer& total_timer,
                      const RunFolder& folder, PipelineSummary* summary);

// The evaluation's figures into the summary (accuracy, every image's
// poses, the rotations against the gyro).
void TakeEvaluation(const TrajectoryEvaluation& evaluation, PipelineSummary* summary);

// Frames or features (texture_probe.h): the real-time feature budget at the
// rate the run reconstructs, then the frame rate and the feature count of a
// textured recording, settled before anything is extracted, into `options`
// and `summary`. The probed frames stay in `frame_cache` for the
// VIO.
void ResolveRateByTexture(const Sequence& sequence, FrameCache* frame_cache,
                          PipelineOptions* options, PipelineSummary* summary);

// A recorded sequence's settings by its pace, before anything is
// extracted: the paper's retrieval and adjustments where its frames come
// slower than the feature budget limits (ApplySparseRecordingSettings),
// then ResolveRateByTexture.
void ResolveSettingsByPace(const Sequence& sequence, FrameCache* frame_cache,
                           PipelineOptions* options, PipelineSummary* summary);

}  // namespace viosfm

#include "viosfm/pipeline/run_common.h"

#include <malloc.h>
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <iomanip>
#include <iterator>
#include <sstream>

#include "viosfm/pipeline/frame_selection.h"
#include "viosfm/pipeline/texture_probe.h"
#include "viosfm/util/errors.h"

namespace viosfm {

std::string UtcNow() {
  const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buffer[32];
  std::strftime(buffer, sizeof(buffer), "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buffer;
}

double PeakMemoryMb() {
  rusage usage{};
  if (getrusage(RUSAGE_SELF, &usage) != 0) return 0.0;
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // Linux: kilobytes
}

void ReturnFreedMemory() {
#ifdef __GLIBC__
  malloc_trim(0);
#endif
}

void LimitMallocArenas(int max_arenas) {
#ifdef __GLIBC__
  mallopt(M_ARENA_MAX, max_arenas);
#else
  (void)max_arenas;
#endif
}

PipelineSummary StartRunSummary(const PipelineOptions& options) {
  if (const std::string error = options.Validate(); !error.empty()) {
    throw InputError("invalid run options: " + error);
  }
  PipelineSummary summary;
  summary.started_utc = UtcNow();
  summary.dataset = options.dataset.string();
  summary.output_folder = options.output_folder;
  return summary;
}

void FinishRunSummary(const FrameCache& frame_cache, const Timer& total_timer,
                      const RunFolder& folder, PipelineSummary* summary) {
  summary->images = frame_cache.counts();
  summary->frame_cache_max_bytes = frame_cache.max_bytes();
  VIOSFM_LOG(INFO) << "run: " << summary->images.decodes << " image decodes for "
                   << summary->num_frames_in << " images (" << summary->images.reuses
                   << " taken from the frame cache)";
  summary->total_seconds = total_timer.ElapsedSeconds();
  summary->peak_memory_mb = PeakMemoryMb();
  WriteToLogFile(summary->ToString());
  folder.WriteSummary(PipelineSummaryToJson(*summary));
}

void TakeEvaluation(const TrajectoryEvaluation& evaluation, PipelineSummary* summary) {
  summary->evaluation = evaluation.summary;
  summary->all_frames = evaluation.all_frames.counts;
  summary->gyro_check = evaluation.gyro_check;
  summary->gyro_check_message = evaluation.gyro_check_message;
}

void StageClock::End(const std::string& name, double seconds, double cpu_seconds) {
  stages_->push_back({name, seconds, cpu_seconds});
  VIOSFM_LOG(INFO) << "run [" << index_ << "/" << names_.size() << "] " << name << ": "
                   << std::fixed << std::setprecision(2) << seconds << " s (" << cpu_seconds
                   << " s of CPU)";
}

void ResolveSettingsByPace(const Sequence& sequence, FrameCache* frame_cache,
                           PipelineOptions* options, PipelineSummary* summary) {
  const std::string sparse = ApplySparseRecordingSettings(
      ReconstructionRateHz(sequence, options->frame_selection.target_rate_hz), options);
  if (!sparse.empty()) VIOSFM_LOG(INFO) << "run: sparse recording: " << sparse;
  ResolveRateByTexture(sequence, frame_cache, options, summary);
}

void ResolveRateByTexture(const Sequence& sequence, FrameCache* frame_cache,
                          PipelineOptions* options, PipelineSummary* summary) {
  // The budget first: the probe extracts on the images the budget reduces.
  const std::string budget = ApplyFeatureBudget(
      options->feature_budget,
      ReconstructionRateHz(sequence, options->frame_selection.target_rate_hz), &options->sift);
  if (!budget.empty()) VIOSFM_LOG(INFO) << "run: real-time budget: " << budget;
  const TextureProbeOptions& probe = options->texture_probe;
  if (probe.enable) {
    std::vector<size_t> candidates;
    if (!FrameSelectionUsesTrajectory(sequence, options->frame_selection)) {
      // Frames selected at both rates (all the lower rate's frames when
      // the camera runs at the higher rate): the cache keeps the probed
      // frames for the features stage whatever it decides (a frame it
      // releases before the VIO reads it is decoded twice). A short
      // recording has fewer of them to probe.
      candidates = SelectFrames(sequence, options->frame_selection, nullptr).kept;
      FrameSelectionOptions textured_selection = options->frame_selection;
      textured_selection.target_rate_hz = probe.target_rate_hz;
      const std::vector<size_t> textured = SelectFrames(sequence, textured_selection, nullptr).kept;
      std::vector<size_t> both;
      std::set_intersection(candidates.begin(), candidates.end(), textured.begin(), textured.end(),
                            std::back_inserter(both));
      if (!both.empty()) candidates = std::move(both);
    } else {
      for (size_t k = 0; k < sequence.images.size(); ++k) candidates.push_back(k);
    }
    summary->texture_probe =
        ProbeTexture(sequence, candidates, options->EffectiveSiftOptions(), probe, frame_cache);
    std::ostringstream message;
    message << summary->texture_probe.ToString(probe);
    if (summary->texture_probe.textured) {
      double& rate = options->frame_selection.target_rate_hz;
      rate = rate > 0.0 ? std::min(rate, probe.target_rate_hz) : probe.target_rate_hz;
      int& features = options->sift.max_num_features;
      features = std::max(features, probe.max_num_features);
      message << "; fewer frames with more features: " << rate << " Hz, " << features
              << " features a frame";
    } else if (summary->texture_probe.probed) {
      message << "; the rate and the feature count as set";
    }
    message << " (" << std::fixed << std::setprecision(1) << summary->texture_probe.seconds
            << " s)";
    summary->texture_probe_message = message.str();
    VIOSFM_LOG(INFO) << "run: texture " << (summary->texture_probe.textured ? "rich" : "not rich")
                     << ": " << options->frame_selection.target_rate_hz << " Hz, "
                     << options->sift.max_num_features << " features a frame" << LogDetails()
                     << " (" << summary->texture_probe_message << ")";
  }
  summary->frame_rate_hz = options->frame_selection.target_rate_hz;
  summary->max_num_features = options->sift.max_num_features;
}

}  // namespace viosfm

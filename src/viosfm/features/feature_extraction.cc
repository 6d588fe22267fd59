#include "viosfm/features/feature_extraction.h"

#include <atomic>
#include <cmath>
#include <exception>
#include <iomanip>
#include <mutex>
#include <optional>
#include <sstream>
#include <thread>
#include <unordered_set>
#include <vector>

#include "viosfm/io/image_io.h"
#include "viosfm/util/bounded_queue.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/logging.h"
#include "viosfm/util/progress.h"
#include "viosfm/util/timer.h"

namespace viosfm {
namespace {

// Same model, size and parameters (to 1e-9 relative: the database stores
// the principal point shifted by 0.5 pixel and back).
bool SameCamera(const Camera& a, const Camera& b) {
  if (a.model_id != b.model_id || a.width != b.width || a.height != b.height ||
      a.params.size() != b.params.size()) {
    return false;
  }
  for (size_t i = 0; i < a.params.size(); ++i) {
    if (std::abs(a.params[i] - b.params[i]) > 1e-9 * std::max(1.0, std::abs(a.params[i]))) {
      return false;
    }
  }
  return true;
}

struct Task {
  size_t sequence_index = 0;
  image_t image_id = kInvalidImageId;
};

struct Result {
  image_t image_id = kInvalidImageId;
  ImageFeatures features;
  bool extracted_before = false;  // taken from FeatureImageAccess::take_extracted
};

// Registers the camera and the images in the database (one transaction) and
// returns the images that still need features.
std::vector<Task> RegisterImages(const Sequence& sequence, ColmapDatabase* database,
                                 size_t* num_skipped) {
  std::unordered_set<std::string> names;
  for (const SequenceImage& image : sequence.images) {
    if (!names.insert(DatabaseImageName(image)).second) {
      throw InputError(image.path.string(), 0,
                       "two images of the sequence have the file name '" +
                           DatabaseImageName(image) +
                           "' (the database names images by their file names)");
    }
  }

  ColmapDatabase::Transaction transaction(*database);
  std::optional<camera_t> camera_id;
  for (const Camera& stored : database->ReadAllCameras()) {
    if (SameCamera(stored, sequence.rig.camera)) {
      camera_id = stored.camera_id;
      break;
    }
  }

  std::vector<Task> tasks;
  *num_skipped = 0;
  for (size_t i = 0; i < sequence.images.size(); ++i) {
    const std::string name = DatabaseImageName(sequence.images[i]);
    const std::optional<DatabaseImage> existing = database->ReadImageWithName(name);
    if (existing) {
      if (!camera_id || existing->camera_id != *camera_id) {
        throw InputError(database->path().string(), 0,
                         "image '" + name + "' is stored with camera_id " +
                             std::to_string(existing->camera_id) +
                             ", whose intrinsics differ from the sequence's camera");
      }
      if (database->ExistsFeatures(existing->image_id)) {
        ++*num_skipped;
        continue;
      }
      tasks.push_back({i, existing->image_id});
      continue;
    }
    if (!camera_id) camera_id = database->WriteCamera(sequence.rig.camera);
    tasks.push_back({i, database->WriteImage(name, *camera_id)});
  }
  transaction.Commit();
  return tasks;
}

}  // namespace

std::string FeatureExtractionSummary::ToString() const {
  std::ostringstream text;
  text << num_images << " images, " << std::fixed << std::setprecision(1) << MeanFeatures()
       << " features per image, " << std::setprecision(2) << seconds << " s (" << num_extracted
       << " extracted";
  if (num_extracted_before > 0) text << ", " << num_extracted_before << " of them beside the VIO";
  text << "; " << num_skipped << " already stored)";
  return text.str();
}

FeatureExtractionSummary ExtractFeatures(const Sequence& sequence, const SiftOptions& options,
                                         ColmapDatabase* database, bool show_progress,
                                         const FeatureImageAccess& access) {
  VIOSFM_CHECK(database != nullptr);
  if (const std::string error = options.Validate(); !error.empty()) {
    throw InputError("SiftOptions: " + error);
  }
  Timer timer;
  FeatureExtractionSummary summary;
  summary.num_images = sequence.images.size();
  const std::vector<Task> tasks = RegisterImages(sequence, database, &summary.num_skipped);
  if (tasks.empty()) {
    summary.seconds = timer.ElapsedSeconds();
    return summary;
  }

  const Camera& camera = sequence.rig.camera;
  const size_t num_workers =
      std::min(tasks.size(), static_cast<size_t>(std::max(1, options.num_threads)));
  // Bounded hand-over from the workers to this (writer) thread.
  BoundedQueue<Result> results(2 * num_workers);
  std::atomic<size_t> next_task{0};
  std::atomic<size_t> num_workers_running{num_workers};
  std::mutex error_mutex;
  std::exception_ptr worker_error;

  auto worker = [&] {
    try {
      while (true) {
        const size_t t = next_task++;
        if (t >= tasks.size()) break;
        const SequenceImage& image = sequence.images[tasks[t].sequence_index];
        Result result{tasks[t].image_id, {}};
        result.extracted_before = access.take_extracted &&
                                  access.take_extracted(result.image_id, image, &result.features);
        if (!result.extracted_before) {
          const std::shared_ptr<const GreyImage> decoded =
              access.frames != nullptr
                  ? access.frames->Take(image.path)
                  : std::make_shared<const GreyImage>(ReadGreyImage(image.path));
          const GreyImage& pixels = *decoded;
          if (static_cast<uint64_t>(pixels.width) != camera.width ||
              static_cast<uint64_t>(pixels.height) != camera.height) {
            throw InputError(image.path.string(), 0,
                             "image of " + std::to_string(pixels.width) + " x " +
                                 std::to_string(pixels.height) + " pixels, expected the camera's " +
                                 std::to_string(camera.width) + " x " +
                                 std::to_string(camera.height));
          }
          result.features = ExtractSift(pixels, options);
          if (access.on_extracted) {
            access.on_extracted(result.image_id, pixels, result.features.keypoints);
          }
        }
        if (!results.Push(std::move(result))) break;  // the writer stopped
      }
    } catch (...) {
      {
        const std::lock_guard<std::mutex> lock(error_mutex);
        if (!worker_error) worker_error = std::current_exception();
      }
      results.Close();  // the other workers stop; the writer keeps what is done
    }
    // The last worker out closes the queue: the writer takes what is left.
    if (--num_workers_running == 0) results.Close();
  };

  std::vector<std::thread> threads;
  for (size_t i = 0; i < num_workers; ++i) threads.emplace_back(worker);

  ProgressBar progress("features", static_cast<int64_t>(tasks.size()),
                       show_progress ? ProgressBar::Mode::kAuto : ProgressBar::Mode::kNever);
  std::exception_ptr writer_error;
  try {
    while (std::optional<Result> result = results.Pop()) {
      database->WriteFeatures(result->image_id, result->features.keypoints,
                              result->features.descriptors);
      ++summary.num_extracted;
      if (result->extracted_before) ++summary.num_extracted_before;
      summary.num_features += result->features.keypoints.size();
      progress.Update();
    }
  } catch (...) {
    writer_error = std::current_exception();
    results.Abort();
  }
  for (std::thread& thread : threads) thread.join();
  progress.Finish();
  if (writer_error) std::rethrow_exception(writer_error);
  if (worker_error) std::rethrow_exception(worker_error);
  summary.seconds = timer.ElapsedSeconds();
  return summary;
}

}  // namespace viosfm

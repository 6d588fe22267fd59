// Feature extraction over a whole sequence into a COLMAP database, on
// several cores, resumable.
//
// Each image is named in the database by its file name (e.g.
// "1403715273262142976.png" for EuRoC); names must be unique in the
// sequence. The sequence's camera is written once (an identical camera
// already in the database is reused). Images are decoded once, each worker
// thread extracts one image at a time, and the calling thread writes each
// result (keypoints and descriptors in one transaction) as soon as it is
// ready, so an interrupted run keeps everything finished before it. A re-run
// skips the images whose keypoints and descriptors are already stored.
//
// Threads: options.num_threads workers, one image each; OpenCV's own
// parallel loops inside cv::SIFT are left as they are (cv::setNumThreads is
// process-wide, so it is not changed here): the CPU time a frame does not
// depend on the number of workers or on OpenCV's threading.
#pragma once

#include <cstddef>
#include <functional>
#include <string>

#include "viosfm/features/sift.h"
#include "viosfm/io/colmap_database.h"
#include "viosfm/io/frame_cache.h"
#include "viosfm/scene/sequence.h"

namespace viosfm {

struct FeatureExtractionSummary {
  size_t num_images = 0;     // images of the sequence
  size_t num_extracted = 0;  // extracted by this run
  size_t num_skipped = 0;    // already in the database (resume)
  size_t num_features = 0;   // keypoints extracted by this run
  // Of num_extracted: taken from FeatureImageAccess::take_extracted
  // (extracted beside the VIO, pipeline/feature_prefetch.h).
  size_t num_extracted_before = 0;
  double seconds = 0.0;  // wall-clock time of the run

  double MeanFeatures() const {
    return num_extracted == 0 ? 0.0 : static_cast<double>(num_features) / num_extracted;
  }
  // "95 images, 1523.4 features per image, 3.2 s (90 extracted; 5 already stored)"
  std::string ToString() const;
};

// Where feature extraction gets the pixels, and who else sees them.
struct FeatureImageAccess {
  // Images taken from here (io/frame_cache.h, each for the last time);
  // null: read from their files.
  FrameCache* frames = nullptr;
  // Called from the worker threads with each extracted image's id, pixels
  // and keypoints (so that a later stage needs no decode); must be
  // thread-safe. Empty: none.
  std::function<void(image_t, const GreyImage&, const FeatureKeypoints&)> on_extracted;
  // The features of an image extracted before this call, with the same
  // options, if there are: returns true and moves them into `features`
  // (then neither the image is decoded nor on_extracted called). Called from
  // the worker threads; must be thread-safe. Empty: none.
  std::function<bool(image_t, const SequenceImage&, ImageFeatures* features)> take_extracted;
};

// Extracts the features of every image of `sequence` that the database does
// not hold yet. With show_progress, draws a progress bar (util/progress.h).
// Throws InputError for an unreadable image, an image whose size is not the
// camera's, duplicate image names, or an image already in the database with
// a different camera.
FeatureExtractionSummary ExtractFeatures(const Sequence& sequence, const SiftOptions& options,
                                         ColmapDatabase* database, bool show_progress = true,
                                         const FeatureImageAccess& access = {});

}  // namespace viosfm

// Stage 1 of a `viosfm run` (pipeline.h): the dataset (io/dataset.h: a
// EuRoC folder, a ROS 1 bag or an image folder, then the calibration
// files), and the fingerprint of its files and of what was read.
#pragma once

#include <filesystem>

#include "viosfm/io/dataset.h"
#include "viosfm/pipeline/pipeline_options.h"
#include "viosfm/pipeline/run_folder.h"

namespace viosfm {

// The dataset as `viosfm run` reads it with these options (a bag's images
// go to options.EffectiveRosbagOptions().extract_folder).
DatasetReadOptions PipelineDatasetReadOptions(const PipelineOptions& options);

// The stage: checks the folder's stored data against the inputs'
// fingerprint before anything changes (a bag's extraction is the first
// write), reads the dataset, adds it to `fingerprint` and checks again.
// Marks the folder incomplete. Throws InputError as ReadDataset and
// RunFolder::CheckStoredData do.
Sequence ReadDatasetStage(const PipelineOptions& options, const RunFolder& folder,
                          RunFingerprint* fingerprint);

}  // namespace viosfm

#include "viosfm/pipeline/stage_dataset.h"

#include "viosfm/util/errors.h"
#include "viosfm/util/logging.h"

namespace viosfm {

DatasetReadOptions PipelineDatasetReadOptions(const PipelineOptions& options) {
  DatasetReadOptions read;
  read.image_folder = options.image_folder;
  read.rosbag = options.EffectiveRosbagOptions();
  read.calibration = options.calibration;
  read.checks = options.dataset_checks;
  read.require_imu = false;  // the IMU only helps (frame selection, metric scale)
  return read;
}

Sequence ReadDatasetStage(const PipelineOptions& options, const RunFolder& folder,
                          RunFingerprint* fingerprint) {
  folder.CheckStoredData(*fingerprint, /*complete=*/false);
  // A bag's images are extracted into the folder: the folder is incomplete
  // from here until summary.json is written again, last. A refused run
  // leaves an earlier run's complete folder as it was.
  if (IsBagPath(options.dataset)) folder.MarkIncomplete();
  Sequence sequence = ReadDataset(options.dataset, PipelineDatasetReadOptions(options));
  if (!options.use_imu && sequence.has_imu()) {
    VIOSFM_LOG(INFO) << "run: the dataset's IMU left out (use_imu false)";
    sequence.imu.clear();
  }
  AddSequenceToFingerprint(sequence, fingerprint);
  folder.CheckStoredData(*fingerprint, /*complete=*/false);
  folder.MarkIncomplete();
  VIOSFM_LOG(INFO) << "run: " << sequence.images.size() << " images"
                   << (sequence.has_imu() ? ", IMU" : "")
                   << (sequence.has_ground_truth() ? ", ground truth" : "") << " in "
                   << options.dataset.string();
  return sequence;
}

}  // namespace viosfm

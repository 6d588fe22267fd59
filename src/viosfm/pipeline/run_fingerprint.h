// The fingerprint of a `viosfm run`: what the features and verified matches
// stored in OUT/database.db were made from, so that a re-run into the same
// folder reuses them only when it would make the same ones.
//
// A fingerprint is a list of (key, value) texts, written to
// OUT/fingerprint.json (atomically, before the database is opened):
//   fingerprint.version           the layout of this list ("1")
//   dataset.kind                  euroc, image_folder, rosbag (or missing)
//   dataset.file.<path>           each file of a EuRoC folder the reader reads
//                                 (io/euroc.h EurocDatasetFiles: the cam0 and
//                                 imu0 data.csv and sensor.yaml, the ground
//                                 truth csv): size and XXH3 hash
//                                 (util/hash.h) of the whole content
//   dataset.bag                   a ROS 1 bag: size and hash of the whole
//                                 file (the bag is read whole anyway)
//   dataset.timestamps_file, dataset.camera_yaml, dataset.imu_yaml,
//   calibration.camchain, calibration.imu, vocabulary.file
//                                 the other input files, when given: size and
//                                 hash (never their paths, so a moved dataset
//                                 is the same dataset)
//   dataset.images                the images as read: count, time span, total
//                                 size, and a hash of every (name, stamp,
//                                 file size, XXH3 of the file's content)
//   dataset.rig                   the sensor rig as read and calibrated
//                                 (camera, body_from_cam, IMU noise, rates,
//                                 time offset; whatever file it came from)
//   vio.input                     viosfm's own VIO, a trajectory file (size
//                                 and hash) or a VioSource given in code
//   vio.poses                     the VIO's poses and segments as the run uses
//                                 them: count, segments, hash (bit for bit)
//   <option>                      every option of options.json that shapes
//                                 the stored data: the fields marked
//                                 kShapesStoredData in their struct's
//                                 VisitFields (util/option_fields.h;
//                                 PipelineOptions::StoredDataKeyValues): frame
//                                 selection, sift.*, verification.* (pairs
//                                 N1/N2, vocabulary, matching, VIO check,
//                                 RANSAC, seed), the VIO file's format,
//                                 frame, time tolerance and segment gap,
//                                 own_vio.* when the own VIO runs, and
//                                 vio_uncertainty.* when the verification band
//                                 follows the VIO's drift
// Options that only shape the mapper and what follows it (mapper.*,
// imu_scale.*, --no-imu-scale) and thread counts are not part of it: a
// re-run with other ones reuses the stored features and matches.
#pragma once

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "viosfm/io/colmap_database.h"
#include "viosfm/pipeline/pipeline_options.h"
#include "viosfm/scene/sequence.h"
#include "viosfm/scene/trajectory.h"

namespace viosfm {

struct RunFingerprint {
  // (key, value) in the order they were set; keys are unique.
  std::vector<std::pair<std::string, std::string>> entries;
  // Each image file's size and content hash, as dataset.images sums them
  // up (kept beside the database's rows, to name an image that changed).
  std::vector<ViosfmDatabaseRecord::ImageFile> image_files;

  // Replaces the value of `key`, or appends it.
  void Set(const std::string& key, const std::string& value);
  // The value of `key`, or nullptr.
  const std::string* Find(const std::string& key) const;
  // FNV-1a over every key and value: one text for summary.json.
  std::string Hash() const;
};

// The layout version written as fingerprint.version.
inline constexpr const char* kRunFingerprintVersion = "2";

// Whether the option `key` of PipelineOptions::ToKeyValues shapes the
// features or matches a run stores: whether it is one of
// options.StoredDataKeyValues() (the fields marked kShapesStoredData where
// they are described, util/option_fields.h).
bool ShapesStoredData(const std::string& key, const PipelineOptions& options);

// What is known before the dataset is read: the input files and the
// options. A file that does not exist is "missing" (its reader reports it).
// With the texture probe on, the frame rate and the feature count are left
// out until it has settled them, and with a sparse recording's settings on
// (pipeline_options.h ApplySparseRecordingSettings) N2 is, until the
// recording's pace has settled it (AddSettledRateAndFeatures): checks of a
// stored run before then do not compare them.
// Throws InputError naming a file that exists but cannot be read.
RunFingerprint FingerprintOfInputs(const PipelineOptions& options);
// Adds the frame rate and the feature count of `options`, as the texture
// probe settled them (texture_probe.h), and N2 as the recording's pace
// settled it.
void AddSettledRateAndFeatures(const PipelineOptions& options, RunFingerprint* fingerprint);
// Adds dataset.images and dataset.rig of the sequence as read.
void AddSequenceToFingerprint(const Sequence& sequence, RunFingerprint* fingerprint);
// Adds vio.poses: the poses (world_from_body, stamped) and their segments.
void AddVioPosesToFingerprint(const Trajectory& world_from_body, const std::vector<int>& segments,
                              RunFingerprint* fingerprint);

// The part of `fingerprint` whose keys start with one of `prefixes` (the
// record of what `viosfm features` or `viosfm match` made), image files
// included when a "dataset." prefix is.
RunFingerprint FingerprintPart(const RunFingerprint& fingerprint,
                               const std::vector<std::string>& prefixes);
// The key prefixes of what `viosfm features` stores, and of what `viosfm
// match` stores (options named as a run's).
std::vector<std::string> FeaturesFingerprintPrefixes();
std::vector<std::string> MatchesFingerprintPrefixes();

// What the database records of the fingerprint (io/colmap_database.h).
ViosfmDatabaseRecord DatabaseRecordOf(const RunFingerprint& fingerprint);

// fingerprint.json's text, and reading it back (InputError naming the file
// if it is not such a file).
std::string RunFingerprintToJson(const RunFingerprint& fingerprint);
RunFingerprint ReadRunFingerprint(const std::filesystem::path& path);

// The value of a key one of two compared fingerprints lacks.
inline constexpr const char* kFingerprintAbsent = "(absent)";
struct FingerprintDifference {
  std::string key;
  std::string stored;   // kFingerprintAbsent if the stored fingerprint lacks the key
  std::string current;  // kFingerprintAbsent if the current one lacks it
};
// The keys whose values differ. With `complete` false, `current` is a
// fingerprint still being built: keys only the stored one has are skipped.
std::vector<FingerprintDifference> CompareFingerprints(const RunFingerprint& stored,
                                                       const RunFingerprint& current,
                                                       bool complete);

}  // namespace viosfm

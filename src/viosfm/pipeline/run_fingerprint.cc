#include "viosfm/pipeline/run_fingerprint.h"

#include <algorithm>
#include <array>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "viosfm/io/dataset.h"
#include "viosfm/io/euroc.h"
#include "viosfm/io/rosbag_dataset.h"
#include "viosfm/pipeline/texture_probe.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/hash.h"
#include "viosfm/util/logging.h"
#include "viosfm/util/string_util.h"
#include "viosfm/util/timestamp.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;
using ordered_json = nlohmann::ordered_json;

// "1234 bytes, xxh3 ..." of an input file, or "missing" (its reader
// then says what is wrong with it).
std::string FileValue(const fs::path& path) {
  if (!fs::is_regular_file(path)) return "missing";
  return HashFile(path).ToString();
}

}  // namespace

void RunFingerprint::Set(const std::string& key, const std::string& value) {
  for (auto& [existing_key, existing_value] : entries) {
    if (existing_key == key) {
      existing_value = value;
      return;
    }
  }
  entries.emplace_back(key, value);
}

const std::string* RunFingerprint::Find(const std::string& key) const {
  for (const auto& [existing_key, value] : entries) {
    if (existing_key == key) return &value;
  }
  return nullptr;
}

std::string RunFingerprint::Hash() const {
  Fnv1a64 hash;
  for (const auto& [key, value] : entries) {
    hash.UpdateField(key);
    hash.UpdateField(value);
  }
  return hash.HexDigest();
}

bool ShapesStoredData(const std::string& key, const PipelineOptions& options) {
  for (const auto& [stored_key, value] : options.StoredDataKeyValues()) {
    if (stored_key == key) return true;
  }
  return false;
}

RunFingerprint FingerprintOfInputs(const PipelineOptions& options) {
  RunFingerprint fingerprint;
  fingerprint.Set("fingerprint.version", kRunFingerprintVersion);
  const fs::path& dataset = options.dataset;
  if (IsBagPath(dataset)) {
    fingerprint.Set("dataset.kind", "rosbag");
    if (fs::is_directory(dataset)) {
      // A rosbag2 folder: metadata.yaml and its storage files.
      for (const fs::path& file : BagFiles(dataset)) {
        fingerprint.Set("dataset.bag." + file.filename().string(), FileValue(file));
      }
    } else {
      fingerprint.Set("dataset.bag", FileValue(dataset));
    }
    const RosbagDatasetOptions rosbag = options.EffectiveRosbagOptions();
    if (!rosbag.camera_yaml.empty()) {
      fingerprint.Set("dataset.camera_yaml", FileValue(rosbag.camera_yaml));
    }
    if (!rosbag.imu_yaml.empty()) fingerprint.Set("dataset.imu_yaml", FileValue(rosbag.imu_yaml));
  } else if (!fs::is_directory(dataset)) {
    fingerprint.Set("dataset.kind", "missing");
  } else if (IsEurocDatasetFolder(dataset)) {
    fingerprint.Set("dataset.kind", "euroc");
    EurocReadOptions read;  // as ReadDataset (io/dataset.h) reads a run's EuRoC folder
    read.require_imu = false;
    for (const fs::path& file : EurocDatasetFiles(dataset, read)) {
      fingerprint.Set("dataset.file." + file.generic_string(), FileValue(dataset / file));
    }
  } else {
    fingerprint.Set("dataset.kind", "image_folder");
    if (!options.image_folder.timestamps_file.empty()) {
      fingerprint.Set("dataset.timestamps_file", FileValue(options.image_folder.timestamps_file));
    }
    if (!options.image_folder.camera_yaml.empty()) {
      fingerprint.Set("dataset.camera_yaml", FileValue(options.image_folder.camera_yaml));
    }
  }
  if (!options.calibration.camchain.empty()) {
    fingerprint.Set("calibration.camchain", FileValue(options.calibration.camchain));
  }
  if (!options.calibration.imu.empty()) {
    fingerprint.Set("calibration.imu", FileValue(options.calibration.imu));
  }
  if (options.vio_source) {
    fingerprint.Set("vio.input", "a VioSource given in code");
  } else if (options.vio_trajectory.empty()) {
    fingerprint.Set("vio.input", "viosfm's own VIO");
  } else {
    fingerprint.Set("vio.input", "file, " + FileValue(options.vio_trajectory));
  }
  if (!options.verification.retrieval.vocabulary_path.empty()) {
    fingerprint.Set("vocabulary.file", FileValue(options.verification.retrieval.vocabulary_path));
  }
  const bool sparse_may_settle = options.feature_budget.paper_settings_when_sparse &&
                                 options.feature_budget.features_per_second > 0;
  for (const auto& [key, value] : options.StoredDataKeyValues()) {
    // Set once the texture probe and the recording's pace have settled them
    // (AddSettledRateAndFeatures).
    if (options.texture_probe.enable && SettledByTextureProbe(key)) continue;
    if (sparse_may_settle && SettledBySparseRecording(key)) continue;
    fingerprint.Set(key, value);
  }
  return fingerprint;
}

void AddSettledRateAndFeatures(const PipelineOptions& options, RunFingerprint* fingerprint) {
  for (const auto& [key, value] : options.StoredDataKeyValues()) {
    if (SettledByTextureProbe(key) || SettledBySparseRecording(key)) fingerprint->Set(key, value);
  }
}

void AddSequenceToFingerprint(const Sequence& sequence, RunFingerprint* fingerprint) {
  Fnv1a64 images;
  uintmax_t total_bytes = 0;
  fingerprint->image_files.clear();
  fingerprint->image_files.reserve(sequence.images.size());
  for (const SequenceImage& image : sequence.images) {
    // The content, not only the size: an image replaced by another of the
    // same size is another image.
    const FileHash file = HashFile(image.path);
    const std::string name = DatabaseImageName(image);
    images.UpdateField(name);
    images.UpdateValue(image.timestamp_ns);
    images.UpdateValue(file.size);
    images.UpdateValue(file.hash);
    total_bytes += file.size;
    fingerprint->image_files.push_back({name, file.size, file.hash});
  }
  std::ostringstream text;
  text << sequence.images.size() << " images";
  if (!sequence.images.empty()) {
    text << " [" << FormatNsAsSeconds(sequence.images.front().timestamp_ns, 3) << ", "
         << FormatNsAsSeconds(sequence.images.back().timestamp_ns, 3) << "] s";
  }
  text << ", " << total_bytes << " bytes, fnv1a64 " << images.HexDigest();
  fingerprint->Set("dataset.images", text.str());

  const SensorRig& rig = sequence.rig;
  Fnv1a64 hash;
  hash.UpdateValue(static_cast<int>(rig.camera.model_id));
  hash.UpdateValue(rig.camera.width);
  hash.UpdateValue(rig.camera.height);
  for (const double param : rig.camera.params) hash.UpdateValue(param);
  for (const double value : rig.body_from_cam.rotation.coeffs()) hash.UpdateValue(value);
  for (const double value : rig.body_from_cam.translation) hash.UpdateValue(value);
  for (const double value : {rig.imu_noise.gyro_noise_density, rig.imu_noise.gyro_random_walk,
                             rig.imu_noise.accel_noise_density, rig.imu_noise.accel_random_walk,
                             rig.imu_noise.rate_hz, rig.camera_rate_hz}) {
    hash.UpdateValue(value);
  }
  hash.UpdateValue(rig.cam_time_offset_ns);
  fingerprint->Set("dataset.rig", rig.camera.ModelName() + " " + std::to_string(rig.camera.width) +
                                      "x" + std::to_string(rig.camera.height) + ", fnv1a64 " +
                                      hash.HexDigest());
}

void AddVioPosesToFingerprint(const Trajectory& world_from_body, const std::vector<int>& segments,
                              RunFingerprint* fingerprint) {
  Fnv1a64 hash;
  for (const StampedPose& pose : world_from_body.poses) {
    hash.UpdateValue(pose.timestamp_ns);
    for (const double value : pose.world_from_frame.rotation.coeffs()) hash.UpdateValue(value);
    for (const double value : pose.world_from_frame.translation) hash.UpdateValue(value);
  }
  for (const int segment : segments) hash.UpdateValue(segment);
  const int num_segments = segments.empty() ? 0 : segments.back() + 1;
  fingerprint->Set("vio.poses", std::to_string(world_from_body.size()) + " poses in " +
                                    std::to_string(num_segments) + " segment(s), fnv1a64 " +
                                    hash.HexDigest());
}

RunFingerprint FingerprintPart(const RunFingerprint& fingerprint,
                               const std::vector<std::string>& prefixes) {
  RunFingerprint part;
  for (const auto& [key, value] : fingerprint.entries) {
    for (const std::string& prefix : prefixes) {
      if (StartsWith(key, prefix)) {
        part.entries.emplace_back(key, value);
        break;
      }
    }
  }
  if (std::find(prefixes.begin(), prefixes.end(), "dataset.") != prefixes.end()) {
    part.image_files = fingerprint.image_files;
  }
  return part;
}

std::vector<std::string> FeaturesFingerprintPrefixes() {
  return {"fingerprint.version", "dataset.", "calibration.", "sift."};
}

std::vector<std::string> MatchesFingerprintPrefixes() {
  return {"fingerprint.version",
          "dataset.",
          "calibration.",
          "vio.input",
          "vio.format",
          "vio.frame",
          "vio.max_time_difference_ns",
          "vio.max_gap_ns",
          "vio_uncertainty.",
          "verification."};
}

ViosfmDatabaseRecord DatabaseRecordOf(const RunFingerprint& fingerprint) {
  return {fingerprint.entries, fingerprint.image_files};
}

std::string RunFingerprintToJson(const RunFingerprint& fingerprint) {
  ordered_json json;
  json["about"] =
      "what the features and matches in database.db were made from; a run into this folder "
      "reuses them only with the same entries (--overwrite starts afresh)";
  ordered_json entries = ordered_json::object();
  for (const auto& [key, value] : fingerprint.entries) entries[key] = value;
  json["entries"] = entries;
  return json.dump(2);
}

RunFingerprint ReadRunFingerprint(const fs::path& path) {
  const auto fail = [&path](const std::string& what) {
    throw InputError(path.string(), 0,
                     "expected the fingerprint of a viosfm run (" + what +
                         "); re-run with --overwrite to start afresh");
  };
  ordered_json json;
  try {
    json = ordered_json::parse(ReadTextFile(path));
  } catch (const nlohmann::json::exception& error) {
    fail(std::string("not JSON: ") + error.what());
  }
  if (!json.is_object() || !json.contains("entries") || !json["entries"].is_object()) {
    fail("no \"entries\" object");
  }
  RunFingerprint fingerprint;
  for (const auto& [key, value] : json["entries"].items()) {
    if (!value.is_string()) fail("the entry \"" + key + "\" is not a string");
    fingerprint.entries.emplace_back(key, value.get<std::string>());
  }
  return fingerprint;
}

std::vector<FingerprintDifference> CompareFingerprints(const RunFingerprint& stored,
                                                       const RunFingerprint& current,
                                                       bool complete) {
  std::vector<FingerprintDifference> differences;
  for (const auto& [key, value] : current.entries) {
    const std::string* previous = stored.Find(key);
    if (previous == nullptr || *previous != value) {
      differences.push_back({key, previous ? *previous : kFingerprintAbsent, value});
    }
  }
  if (complete) {
    for (const auto& [key, value] : stored.entries) {
      if (current.Find(key) == nullptr) differences.push_back({key, value, kFingerprintAbsent});
    }
  }
  return differences;
}

}  // namespace viosfm

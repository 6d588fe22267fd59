#include "viosfm/cli/option_flags.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <memory>
#include <set>

#include "viosfm/util/errors.h"
#include "viosfm/util/logging.h"
#include "viosfm/util/string_util.h"
#include "viosfm/util/timestamp.h"

namespace viosfm::cli {
namespace {

OptionFlag Text(std::string name, std::vector<std::string> keys, std::string help = "") {
  OptionFlag flag;
  flag.name = std::move(name);
  flag.keys = std::move(keys);
  flag.help = std::move(help);
  return flag;
}

OptionFlag Seconds(std::string name, std::string key, std::string help) {
  OptionFlag flag = Text(std::move(name), {std::move(key)}, std::move(help));
  flag.value = FlagValue::kSeconds;
  return flag;
}

OptionFlag Fixed(std::string name, std::string key, std::string fixed, std::string help) {
  OptionFlag flag = Text(std::move(name), {std::move(key)}, std::move(help));
  flag.value = FlagValue::kFixed;
  flag.fixed = std::move(fixed);
  return flag;
}

OptionFlag EveryKey(OptionFlag flag) {
  flag.every_key = true;
  return flag;
}

OptionFlag WithFormerName(OptionFlag flag, std::string former_name) {
  flag.former_name = std::move(former_name);
  return flag;
}

std::vector<OptionFlag> MakeOptionFlags() {
  std::vector<OptionFlag> flags = {
      // The dataset.
      Text("--timestamps", {"image_folder.timestamps_file"},
           "Image folder: a file of 'filename timestamp' lines (without it, images named by "
           "their stamps are a sequence, other names an unordered collection)"),
      Fixed("--no-imu", "use_imu", "false",
            "Leave the dataset's IMU out: the images alone (and a VIO trajectory file, if "
            "given) make the model"),
      // The VIO.
      Text("--vio-trajectory", {"vio.trajectory"},
           "A VIO's trajectory file (TUM by default, see --vio-format), world_from_body unless "
           "--vio-frame cam; without it viosfm's own VIO runs on the images and the IMU"),
      Text("--vio-format", {"vio.format"}, "Format of --vio-trajectory: tum, euroc or kitti"),
      Text("--vio-frame", {"vio.frame"}),
      WithFormerName(Seconds("--max-vio-time-difference", "vio.max_time_difference_ns",
                             "Largest gap between an image's stamp and its VIO pose (s)"),
                     "--max-pose-time-difference"),
      Seconds("--vio-max-gap", "vio.max_gap_ns",
              "Time gaps in a VIO trajectory file longer than this (s) are not taken on trust: "
              "`run` judges each by the images (one segment where they confirm the VIO's "
              "relative pose across it, a break where they contradict it or see nothing), "
              "`match` verifies the pairs across by RANSAC alone (0: no gap is judged)"),
      Fixed("--no-imu-scale", "use_imu_scale", "false",
            "Keep the VIO's metric scale instead of estimating it from the dataset's IMU over "
            "the registered frames"),
      EveryKey(Text("--rolling-shutter-readout",
                    {"own_vio.rolling_shutter_readout_s", "rolling_shutter.readout_s"},
                    "The camera's rolling-shutter readout, first row to last (s; 0: not given): "
                    "viosfm's own VIO uses it instead of its estimate, and with a VIO file the "
                    "keypoints are moved to the frame's stamp with it")),
      // Frames and features.
      Text("--rate", {"frame_selection.target_rate_hz"}),
      Text("--max-features", {"sift.max_num_features", "own_vio.tracker.max_num_features"}),
      Fixed("--no-trim-static", "frame_selection.trim_static", "false",
            "Keep the static frames at the start and the end"),
      Fixed("--no-root-sift", "sift.root_sift", "false",
            "L2-normalised SIFT descriptors instead of RootSIFT"),
      Text("--peak-threshold", {"sift.peak_threshold"}),
      Text("--first-octave", {"sift.first_octave"},
           "First octave of the scale space: -1 (the image doubled, COLMAP's) or 0 (the image "
           "itself: about half the time, coarser keypoints)"),
      // Pairs and verification.
      Text("--n1", {"verification.pairs.num_temporal_neighbors"}),
      Text("--n2", {"verification.pairs.num_retrieval_neighbors"}),
      Text("--pairs-mode", {"verification.pairs.mode"}),
      Text("--vocabulary", {"verification.retrieval.vocabulary_path"},
           "Vocabulary tree file for the retrieval (default: trained on the images)"),
      Fixed("--guided-matching", "verification.guided_matching", "true",
            "Match inside the VIO's epipolar band instead of by brute force"),
      Fixed("--no-vio-prior", "verification.use_vio_prior", "false",
            "RANSAC-only verification (COLMAP's; the baseline)"),
      Text("--max-epipolar-error", {"verification.prior.max_epipolar_error_px"}),
      Text("--max-outlier-ratio", {"verification.prior.max_outlier_ratio"}),
      Fixed("--no-depth-check", "verification.prior.check_depth", "false",
            "The paper's epipolar test only, without the depth-consistency check (matches "
            "must show the parallax the metric VIO baseline implies)"),
      Text("--max-scene-depth", {"verification.prior.max_scene_depth_m"}),
      Text("--depth-tolerance", {"verification.prior.depth_tolerance_px"}),
      Text("--min-depth-parallax", {"verification.prior.min_depth_parallax_px"}),
      Text("--max-correction-sigmas", {"verification.max_correction_sigmas"}),
      Text("--min-inliers", {"verification.geometry.min_num_inliers"}),
      Text("--max-error", {"verification.geometry.max_error_px"}),
      Fixed("--reverify", "verification.reverify_stored_matches", "true",
            "Verify again the pairs whose matches are stored (instead of skipping them), "
            "replacing their stored geometry"),
      Text("--verification-batch", {"verification.batch_size"}),
      // Mapping.
      Text("--batch-size", {"mapper.batch_size"}),
      Text("--ba-window", {"mapper.ba_window_batches"}),
      Text("--batch-ba-iterations", {"mapper.batch_ba_max_num_iterations"}),
      Text("--ba-sparse-max-images", {"mapper.ba.max_images_for_sparse_schur"}),
      Text("--bridge-spans", {"mapper.bridge_spans"}),
      Text("--bridge-max-matches", {"mapper.bridge_max_matches"}),
      Fixed("--no-bridging", "mapper.bridge_spans", "",
            "Relative-pose priors between consecutive frames only (the paper's)"),
      Text("--prior-loss-scale", {"mapper.ba.prior_loss_scale"}),
      Text("--prior-weighting", {"mapper.ba.prior_weighting"},
           "Relative-pose priors weighted by the VIO uncertainty model's covariance under a "
           "robust loss (covariance) or by the paper's alpha exp(-beta c) with fixed sigmas and "
           "rotation-only bridging priors (paper: the ablation; the verification is the same, "
           "see --fixed-band)"),
      Fixed("--no-rpc", "mapper.ba.use_relative_pose_priors", "false",
            "Bundle adjustment without the relative-pose constraints (ablation)"),
      Fixed("--no-verify-registration", "mapper.registration.verify_with_images", "false",
            "Place frames by the VIO alone (the paper's), without checking them against their "
            "2D-3D matches; frames without a VIO pose stay unposed"),
      // A stream.
      Fixed("--stream", "stream", "true",
            "The run as one stream: the VIO, the features, the verification and the mapper "
            "overlap, each frame's pairs with the frames before it verified as it comes and "
            "each batch mapped once its frames are in (retrieval among earlier frames only; a "
            "streamed run starts afresh, it does not resume)"),
      Fixed("--follow", "follow", "true",
            "The dataset is a EuRoC folder being recorded: follow it as it grows (its rows as "
            "they are appended, viosfm's own VIO), the model after every batch in OUT/live/, "
            "the final model once nothing was appended for --follow-idle seconds (implies "
            "--stream)"),
      Text("--follow-idle", {"follow_idle_s"},
           "Seconds of silence after which a followed recording has ended"),
      // viosfm's own VIO (`viosfm vio`).
      Text("--max-frames", {"own_vio.max_frames"}),
      Text("--window-size", {"own_vio.window.window_size"}),
      Text("--iterations", {"own_vio.window.max_num_iterations"}),
      // The run.
      Text("--threads", {"num_threads", "own_vio.window.num_threads"}),
      Text("--seed", {"seed"}),
      Fixed("--no-progress", "show_progress", "false", "No progress bars"),
  };
  return flags;
}

std::string Capitalised(std::string text) {
  if (!text.empty()) {
    text[0] = static_cast<char>(std::toupper(static_cast<unsigned char>(text[0])));
  }
  return text;
}

// "1000000000" (ns) as "1" (s).
std::string NsTextAsSeconds(const std::string& ns_text) {
  const std::optional<int64_t> ns = ParseInt(ns_text);
  if (!ns) return ns_text;
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.9g", NsToSeconds(*ns));
  return buffer;
}

const OptionDescription* FindDescription(const OptionTarget& target, const std::string& key) {
  const auto found =
      std::find_if(target.descriptions.begin(), target.descriptions.end(),
                   [&key](const OptionDescription& description) { return description.key == key; });
  return found == target.descriptions.end() ? nullptr : &*found;
}

// The keys of `flag` that lie in `target`, relative to it.
std::vector<std::string> KeysIn(const OptionFlag& flag, const OptionTarget& target) {
  std::vector<std::string> keys;
  for (const std::string& key : flag.keys) {
    if (!StartsWith(key, target.prefix)) continue;
    const std::string relative = key.substr(target.prefix.size());
    if (FindDescription(target, relative) == nullptr) continue;
    keys.push_back(relative);
    if (!flag.every_key) break;
  }
  return keys;
}

}  // namespace

const std::vector<OptionFlag>& OptionFlags() {
  static const std::vector<OptionFlag> flags = MakeOptionFlags();
  return flags;
}

const OptionFlag* FlagOfKey(const std::string& key) {
  for (const OptionFlag& flag : OptionFlags()) {
    if (std::find(flag.keys.begin(), flag.keys.end(), key) != flag.keys.end()) return &flag;
  }
  return nullptr;
}

std::string SecondsTextToNsText(const std::string& flag, const std::string& seconds) {
  const std::optional<double> value = ParseDouble(Trim(seconds));
  if (!value || !std::isfinite(*value) || std::abs(*value) > 9e9) {
    throw InputError(flag + ": expected seconds, got '" + seconds + "'");
  }
  return std::to_string(SecondsToNs(*value));
}

void AddOptionFlags(CLI::App* command, const OptionTarget& target,
                    const std::vector<std::string>& names) {
  for (const std::string& name : names) {
    const auto flag_it =
        std::find_if(OptionFlags().begin(), OptionFlags().end(),
                     [&name](const OptionFlag& flag) { return flag.name == name; });
    VIOSFM_CHECK(flag_it != OptionFlags().end()) << "no option flag " << name;
    const OptionFlag& flag = *flag_it;
    const std::vector<std::string> keys = KeysIn(flag, target);
    VIOSFM_CHECK(!keys.empty()) << name << ": none of its options lies in '" << target.prefix
                                << "'";
    const OptionDescription& description = *FindDescription(target, keys.front());
    std::string key_list;
    for (const std::string& key : keys) {
      key_list += (key_list.empty() ? "" : " and ") + target.prefix + key;
    }
    VIOSFM_CHECK(flag.value == FlagValue::kText || !flag.help.empty())
        << name << ": a flag that is not the option's text states its own help";
    const std::string help = (flag.help.empty() ? Capitalised(description.help) : flag.help) +
                             " (option" + (keys.size() > 1 ? "s " : " ") + key_list + ")";
    const auto set = [set = target.set, keys, flag_name = flag.name](const std::string& text) {
      for (const std::string& key : keys) {
        try {
          set(key, text);
        } catch (const InputError& error) {
          throw InputError(flag_name + ": " + error.what());
        }
      }
    };
    for (const std::string& bound : {flag.name, flag.former_name}) {
      if (bound.empty()) continue;
      CLI::Option* option = nullptr;
      if (flag.value == FlagValue::kFixed) {
        option = command->add_flag_callback(
            bound, [set, fixed = flag.fixed] { set(fixed); }, help);
      } else {
        const bool seconds = flag.value == FlagValue::kSeconds;
        option =
            command
                ->add_option(
                    bound,
                    [set, seconds, bound](const CLI::results_t& results) {
                      set(seconds ? SecondsTextToNsText(bound, results.front()) : results.front());
                      return true;
                    },
                    help)
                ->expected(1)
                ->type_name(seconds ? "S" : target.type_names.at(keys.front()))
                ->default_str(seconds ? NsTextAsSeconds(description.default_text)
                                      : description.default_text);
      }
      if (bound == flag.former_name) option->group("");  // kept working, not shown
    }
  }
}

}  // namespace viosfm::cli

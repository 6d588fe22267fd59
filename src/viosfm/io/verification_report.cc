#include "viosfm/io/verification_report.h"

#include <cmath>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <ostream>
#include <string>

#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"

namespace viosfm {
namespace {

void RequireCsvName(const std::filesystem::path& path, const std::string& name) {
  if (name.find_first_of(",\"\n\r") != std::string::npos) {
    throw InputError(path.string(), 0,
                     "image name '" + name +
                         "' contains a comma, quote or line break: cannot "
                         "be written to the CSV report");
  }
}

}  // namespace

void WritePairDecisionsCsv(const std::filesystem::path& path,
                           const std::vector<PairDecision>& decisions) {
  for (const PairDecision& d : decisions) {
    RequireCsvName(path, d.name1);
    RequireCsvName(path, d.name2);
  }
  WriteFileAtomically(path, [&decisions](std::ostream& out) {
    out << "image_id1,image_id2,name1,name2,source,num_matches,has_vio_prior,vio_outlier_ratio,"
           "vio_rotation_only,vio_rejected,num_inliers,accepted,resumed,reason\n";
    out << std::fixed << std::setprecision(6);
    for (const PairDecision& d : decisions) {
      out << d.image_id1 << ',' << d.image_id2 << ',' << d.name1 << ',' << d.name2 << ','
          << d.source << ',' << d.num_matches << ',' << int{d.has_vio_prior} << ',';
      if (std::isnan(d.vio_outlier_ratio)) {
        out << "nan";
      } else {
        out << d.vio_outlier_ratio;
      }
      out << ',' << int{d.vio_rotation_only} << ',' << int{d.vio_rejected} << ',' << d.num_inliers
          << ',' << int{d.accepted} << ',' << int{d.resumed} << ',' << d.reason << '\n';
    }
  });
}

void WriteVerificationJson(const std::filesystem::path& path, const VerificationSummary& summary,
                           const std::vector<PairDecision>& decisions) {
  nlohmann::ordered_json json;
  nlohmann::ordered_json& s = json["summary"];
  s["num_images"] = summary.num_images;
  s["num_images_with_prior"] = summary.num_images_with_prior;
  s["num_pairs"] = summary.num_pairs;
  s["num_pairs_without_prior"] = summary.num_pairs_without_prior;
  s["num_resumed"] = summary.num_resumed;
  s["num_no_matches"] = summary.num_no_matches;
  s["num_vio_rejected"] = summary.num_vio_rejected;
  s["num_ransac_rejected"] = summary.num_ransac_rejected;
  s["num_accepted"] = summary.num_accepted;
  s["seconds_total"] = summary.seconds_total;
  s["seconds_pair_generation"] = summary.seconds_pair_generation;
  s["seconds_loading"] = summary.seconds_loading;
  s["seconds_writing"] = summary.seconds_writing;
  s["thread_seconds_matching"] = summary.seconds_matching;
  s["thread_seconds_vio"] = summary.seconds_vio;
  s["thread_seconds_ransac"] = summary.seconds_ransac;
  nlohmann::ordered_json& options = json["options"];
  options = nlohmann::ordered_json::object();
  for (const auto& [name, value] : summary.options) options[name] = value;
  nlohmann::ordered_json& pairs = json["pairs"];
  pairs = nlohmann::ordered_json::array();
  for (const PairDecision& d : decisions) {
    nlohmann::ordered_json pair;
    pair["image_id1"] = d.image_id1;
    pair["image_id2"] = d.image_id2;
    pair["name1"] = d.name1;
    pair["name2"] = d.name2;
    pair["source"] = d.source;
    pair["num_matches"] = d.num_matches;
    pair["has_vio_prior"] = d.has_vio_prior;
    pair["vio_outlier_ratio"] = std::isnan(d.vio_outlier_ratio)
                                    ? nlohmann::ordered_json(nullptr)
                                    : nlohmann::ordered_json(d.vio_outlier_ratio);
    pair["vio_rotation_only"] = d.vio_rotation_only;
    pair["vio_rejected"] = d.vio_rejected;
    pair["num_inliers"] = d.num_inliers;
    pair["accepted"] = d.accepted;
    pair["resumed"] = d.resumed;
    pair["reason"] = d.reason;
    pairs.push_back(std::move(pair));
  }
  const std::string text = json.dump(2);
  WriteFileAtomically(path, [&text](std::ostream& out) { out << text << '\n'; });
}

}  // namespace viosfm

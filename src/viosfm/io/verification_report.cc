#include "viosfm/io/verification_report.h"

#include <cmath>
#include <fstream>
#include <iomanip>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <ostream>
#include <string>

#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/string_util.h"

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

void WriteRatio(std::ostream& out, double ratio) {
  if (std::isnan(ratio)) {
    out << "nan";
  } else {
    out << ratio;
  }
}

nlohmann::ordered_json RatioJson(double ratio) {
  return std::isnan(ratio) ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(ratio);
}

constexpr const char* kCsvHeader14 =
    "image_id1,image_id2,name1,name2,source,num_matches,has_vio_prior,vio_outlier_ratio,"
    "vio_rotation_only,vio_rejected,num_inliers,accepted,resumed,reason";
constexpr const char* kCsvDepthColumns =
    ",vio_depth_applied,vio_depth_inconsistent_ratio,vio_depth_rejected";
constexpr const char* kCsvCorrectionColumns = ",vio_correction_sigmas,vio_corrected";
constexpr const char* kCsvGuidedColumns = ",guided_band_px";

}  // namespace

void WritePairDecisionsCsv(const std::filesystem::path& path,
                           const std::vector<PairDecision>& decisions) {
  for (const PairDecision& d : decisions) {
    RequireCsvName(path, d.name1);
    RequireCsvName(path, d.name2);
  }
  WriteFileAtomically(path, [&decisions](std::ostream& out) {
    out << kCsvHeader14 << kCsvDepthColumns << kCsvCorrectionColumns << kCsvGuidedColumns << '\n';
    out << std::fixed << std::setprecision(6);
    for (const PairDecision& d : decisions) {
      out << d.image_id1 << ',' << d.image_id2 << ',' << d.name1 << ',' << d.name2 << ','
          << d.source << ',' << d.num_matches << ',' << int{d.has_vio_prior} << ',';
      WriteRatio(out, d.vio_outlier_ratio);
      out << ',' << int{d.vio_rotation_only} << ',' << int{d.vio_rejected} << ',' << d.num_inliers
          << ',' << int{d.accepted} << ',' << int{d.resumed} << ',' << d.reason << ','
          << int{d.vio_depth_applied} << ',';
      WriteRatio(out, d.vio_depth_inconsistent_ratio);
      out << ',' << int{d.vio_depth_rejected} << ',';
      WriteRatio(out, d.vio_correction_sigmas);
      out << ',' << int{d.vio_corrected} << ',';
      WriteRatio(out, d.guided_band_px);
      out << '\n';
    }
  });
}

void WriteVerificationJson(const std::filesystem::path& path, const VerificationSummary& summary,
                           const std::vector<PairDecision>& decisions) {
  nlohmann::ordered_json json;
  nlohmann::ordered_json& s = json["summary"];
  s["database"] = summary.database_path;
  s["num_images"] = summary.num_images;
  s["num_images_with_prior"] = summary.num_images_with_prior;
  s["num_pairs"] = summary.num_pairs;
  s["num_pairs_without_prior"] = summary.num_pairs_without_prior;
  s["num_resumed"] = summary.num_resumed;
  s["num_reverified"] = summary.num_reverified;
  s["num_no_matches"] = summary.num_no_matches;
  s["num_vio_rejected"] = summary.num_vio_rejected;
  s["num_vio_depth_rejected"] = summary.num_vio_depth_rejected;
  s["num_ransac_rejected"] = summary.num_ransac_rejected;
  s["num_accepted"] = summary.num_accepted;
  s["num_accepted_corrected"] = summary.num_accepted_corrected;
  s["seconds_total"] = summary.seconds_total;
  s["seconds_pair_generation"] = summary.seconds_pair_generation;
  s["seconds_loading"] = summary.seconds_loading;
  s["seconds_deciding"] = summary.seconds_deciding;
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
    pair["vio_outlier_ratio"] = RatioJson(d.vio_outlier_ratio);
    pair["vio_rotation_only"] = d.vio_rotation_only;
    pair["vio_rejected"] = d.vio_rejected;
    pair["num_inliers"] = d.num_inliers;
    pair["accepted"] = d.accepted;
    pair["resumed"] = d.resumed;
    pair["reason"] = d.reason;
    pair["vio_depth_applied"] = d.vio_depth_applied;
    pair["vio_depth_inconsistent_ratio"] = RatioJson(d.vio_depth_inconsistent_ratio);
    pair["vio_depth_rejected"] = d.vio_depth_rejected;
    pair["vio_correction_sigmas"] = RatioJson(d.vio_correction_sigmas);
    pair["vio_corrected"] = d.vio_corrected;
    pair["guided_band_px"] = RatioJson(d.guided_band_px);
    pairs.push_back(std::move(pair));
  }
  const std::string text = json.dump(2);
  WriteFileAtomically(path, [&text](std::ostream& out) { out << text << '\n'; });
}

std::vector<PairDecision> ReadPairDecisionsCsv(const std::filesystem::path& path) {
  const std::string file = path.string();
  if (!std::filesystem::is_regular_file(path)) {
    throw InputError(file, 0, "pair decisions CSV not found");
  }
  std::ifstream in(path);
  std::string line;
  std::vector<PairDecision> decisions;
  size_t num_fields = 0;
  int64_t line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line_number == 1) {
      const std::string header14 = kCsvHeader14;
      if (line == header14) {
        num_fields = 14;
      } else if (line == header14 + kCsvDepthColumns) {
        num_fields = 17;
      } else if (line == header14 + kCsvDepthColumns + kCsvCorrectionColumns) {
        num_fields = 19;
      } else if (line == header14 + kCsvDepthColumns + kCsvCorrectionColumns + kCsvGuidedColumns) {
        num_fields = 20;
      } else {
        throw InputError(file, line_number,
                         "expected the header '" + header14 + kCsvDepthColumns +
                             kCsvCorrectionColumns + kCsvGuidedColumns + "'");
      }
      continue;
    }
    if (Trim(line).empty()) continue;
    const std::vector<std::string_view> fields = Split(line, ",", /*skip_empty=*/false);
    if (fields.size() != num_fields) {
      throw InputError(file, line_number,
                       "expected " + std::to_string(num_fields) + " fields, found " +
                           std::to_string(fields.size()));
    }
    const auto integer = [&](size_t k, const char* name) {
      const std::optional<int64_t> value = ParseInt(fields[k]);
      if (!value || *value < 0) {
        throw InputError(file, line_number,
                         std::string(name) + ": expected a non-negative integer, found '" +
                             std::string(fields[k]) + "'");
      }
      return *value;
    };
    const auto boolean = [&](size_t k, const char* name) {
      if (fields[k] != "0" && fields[k] != "1") {
        throw InputError(
            file, line_number,
            std::string(name) + ": expected 0 or 1, found '" + std::string(fields[k]) + "'");
      }
      return fields[k] == "1";
    };
    const auto ratio = [&](size_t k, const char* name) {
      if (fields[k] == "nan") return std::numeric_limits<double>::quiet_NaN();
      const std::optional<double> value = ParseDouble(fields[k]);
      if (!value) {
        throw InputError(file, line_number,
                         std::string(name) + ": expected a number or 'nan', found '" +
                             std::string(fields[k]) + "'");
      }
      return *value;
    };
    PairDecision d;
    d.image_id1 = static_cast<image_t>(integer(0, "image_id1"));
    d.image_id2 = static_cast<image_t>(integer(1, "image_id2"));
    d.name1 = std::string(fields[2]);
    d.name2 = std::string(fields[3]);
    d.source = std::string(fields[4]);
    d.num_matches = static_cast<int>(integer(5, "num_matches"));
    d.has_vio_prior = boolean(6, "has_vio_prior");
    d.vio_outlier_ratio = ratio(7, "vio_outlier_ratio");
    d.vio_rotation_only = boolean(8, "vio_rotation_only");
    d.vio_rejected = boolean(9, "vio_rejected");
    d.num_inliers = static_cast<int>(integer(10, "num_inliers"));
    d.accepted = boolean(11, "accepted");
    d.resumed = boolean(12, "resumed");
    d.reason = std::string(fields[13]);
    if (num_fields >= 17) {
      d.vio_depth_applied = boolean(14, "vio_depth_applied");
      d.vio_depth_inconsistent_ratio = ratio(15, "vio_depth_inconsistent_ratio");
      d.vio_depth_rejected = boolean(16, "vio_depth_rejected");
    }
    if (num_fields >= 19) {
      d.vio_correction_sigmas = ratio(17, "vio_correction_sigmas");
      d.vio_corrected = boolean(18, "vio_corrected");
    }
    if (num_fields >= 20) d.guided_band_px = ratio(19, "guided_band_px");
    decisions.push_back(std::move(d));
  }
  if (line_number == 0) throw InputError(file, 1, "empty file: expected a header line");
  return decisions;
}

void WriteVerificationTruthJson(const std::filesystem::path& path,
                                const std::vector<VerificationTruthSummary>& summaries,
                                const std::vector<std::pair<std::string, std::string>>& options) {
  nlohmann::ordered_json json;
  nlohmann::ordered_json& options_json = json["options"];
  options_json = nlohmann::ordered_json::object();
  for (const auto& [name, value] : options) options_json[name] = value;
  nlohmann::ordered_json& runs = json["runs"];
  runs = nlohmann::ordered_json::array();
  for (const VerificationTruthSummary& s : summaries) {
    nlohmann::ordered_json run;
    run["name"] = s.name;
    run["num_candidates"] = s.num_candidates;
    run["num_correct_candidates"] = s.num_correct_candidates;
    run["num_accepted"] = s.num_accepted;
    run["num_accepted_correct"] = s.num_accepted_correct;
    run["num_accepted_wrong"] = s.num_accepted_wrong;
    run["num_accepted_other"] = s.num_accepted_other;
    run["num_baseline_correct"] = s.num_baseline_correct;
    run["num_baseline_correct_kept"] = s.num_baseline_correct_kept;
    run["recall_vs_baseline"] = RatioJson(s.recall_vs_baseline);
    nlohmann::ordered_json wrong = nlohmann::ordered_json::array();
    for (const auto& [name1, name2] : s.wrong_pairs) wrong.push_back({name1, name2});
    run["wrong_pairs"] = std::move(wrong);
    runs.push_back(std::move(run));
  }
  const std::string text = json.dump(2);
  WriteFileAtomically(path, [&text](std::ostream& out) { out << text << '\n'; });
}

std::string ReadVerificationDatabasePath(const std::filesystem::path& path) {
  if (!std::filesystem::is_regular_file(path)) {
    throw InputError(path.string(), 0, "verification JSON not found");
  }
  nlohmann::json json;
  try {
    json = nlohmann::json::parse(ReadTextFile(path));
  } catch (const nlohmann::json::exception& error) {
    throw InputError(path.string(), 0, std::string("invalid JSON: ") + error.what());
  }
  const auto summary = json.find("summary");
  if (summary == json.end() || !summary->is_object()) return "";
  const auto database = summary->find("database");
  if (database == summary->end() || !database->is_string()) return "";
  return database->get<std::string>();
}

}  // namespace viosfm

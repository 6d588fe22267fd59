#include "viosfm/io/euroc_follower.h"

#include <fstream>
#include <utility>

#include "viosfm/io/text_lines.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/string_util.h"

namespace viosfm {

namespace fs = std::filesystem;

EurocFollower::EurocFollower(const fs::path& root, const EurocReadOptions& options) {
  if (const std::string problem = options.Validate(); !problem.empty()) {
    throw InputError("EuRoC read options: " + problem);
  }
  if (!fs::is_directory(root)) throw InputError(root.string(), 0, "dataset folder not found");
  const fs::path mav0 = EurocMav0Folder(root, options);
  options_ = options;
  mav0_ = mav0;
  header_.root = root;
  header_.rig = ReadEurocRig(mav0, options, &body_from_imu_);
  const fs::path cam_folder = mav0 / options.cam_name;
  if (!(header_.rig.camera_rate_hz > 0)) {
    throw InputError((cam_folder / "sensor.yaml").string(), 0,
                     "a recording that is followed needs the camera's rate_hz (its frames "
                     "cannot tell it before they come)");
  }
  image_folder_ = cam_folder / "data";
  images_.path = cam_folder / "data.csv";
  imu_.path = mav0 / options.imu_name / "data.csv";
}

std::vector<std::pair<int64_t, std::string>> EurocFollower::NewLines(Tail* tail, bool ended) {
  std::vector<std::pair<int64_t, std::string>> lines;
  std::error_code error;
  const std::uintmax_t size = fs::file_size(tail->path, error);
  if (!error) {
    if (size < tail->offset) {
      throw InputError(tail->path.string(), tail->line,
                       "the file shrank from " + std::to_string(tail->offset) + " to " +
                           std::to_string(size) +
                           " bytes while it was followed (a recording's lists are appended to, "
                           "never rewritten)");
    }
    if (size > tail->offset) {
      std::ifstream in(tail->path, std::ios::binary);
      if (!in) throw InputError(tail->path.string(), 0, "cannot be opened");
      in.seekg(static_cast<std::streamoff>(tail->offset));
      std::string appended(size - tail->offset, '\0');
      in.read(appended.data(), static_cast<std::streamsize>(appended.size()));
      appended.resize(static_cast<size_t>(in.gcount()));
      tail->offset += appended.size();
      tail->partial += appended;
    }
  }
  size_t begin = 0;
  while (true) {
    const size_t end = tail->partial.find('\n', begin);
    if (end == std::string::npos) break;
    ++tail->line;
    std::string_view text(tail->partial.data() + begin, end - begin);
    text = Trim(text);
    if (!text.empty() && text.front() != '#') lines.emplace_back(tail->line, std::string(text));
    begin = end + 1;
  }
  tail->partial.erase(0, begin);
  if (ended && !tail->partial.empty()) {
    ++tail->line;
    const std::string_view text = Trim(tail->partial);
    if (!text.empty() && text.front() != '#') lines.emplace_back(tail->line, std::string(text));
    tail->partial.clear();
  }
  return lines;
}

EurocFollower::Rows EurocFollower::Read(bool ended) {
  Rows rows;
  for (const auto& [line, text] : NewLines(&imu_, ended)) {
    const ImuSample sample =
        ParseEurocImuRow(imu_.path, line, SplitFields(text, ","), options_.checks);
    CheckEurocStampIncreasing(imu_.path, line, sample.timestamp_ns, imu_.previous,
                              imu_.previous_line);
    imu_.previous = sample.timestamp_ns;
    imu_.previous_line = line;
    rows.imu.push_back(sample);
  }
  for (const auto& [line, text] : NewLines(&images_, ended)) {
    SequenceImage image =
        ParseEurocImageRow(images_.path, line, SplitFields(text, ","), image_folder_);
    CheckEurocStampIncreasing(images_.path, line, image.timestamp_ns, images_.previous,
                              images_.previous_line);
    images_.previous = image.timestamp_ns;
    images_.previous_line = line;
    waiting_images_.emplace_back(line, std::move(image));
  }
  size_t ready = 0;
  while (ready < waiting_images_.size() &&
         fs::is_regular_file(waiting_images_[ready].second.path)) {
    ++ready;
  }
  if (ended && ready < waiting_images_.size()) {
    const auto& [line, image] = waiting_images_[ready];
    throw InputError(images_.path.string(), line,
                     "listed image " + image.path.filename().string() +
                         " does not exist: " + image.path.string());
  }
  for (size_t k = 0; k < ready; ++k) rows.images.push_back(std::move(waiting_images_[k].second));
  waiting_images_.erase(waiting_images_.begin(),
                        waiting_images_.begin() + static_cast<ptrdiff_t>(ready));
  return rows;
}

EurocFollower::Rows EurocFollower::Poll() {
  return Read(/*ended=*/false);
}

EurocFollower::Rows EurocFollower::Finish() {
  return Read(/*ended=*/true);
}

std::vector<GroundTruthState> EurocFollower::ReadGroundTruth() const {
  return ReadEurocGroundTruthOf(mav0_, options_, body_from_imu_);
}

}  // namespace viosfm

#include "viosfm/io/euroc_writer.h"

#include <iomanip>
#include <ostream>
#include <sstream>

#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"

namespace viosfm {
namespace fs = std::filesystem;

namespace {

// "a,b,c" with full precision.
void WriteRow(std::ostream& out, std::initializer_list<double> values) {
  bool first = true;
  for (const double value : values) {
    if (!first) out << ',';
    out << value;
    first = false;
  }
}

void WriteTransformYaml(std::ostream& out, const Rigid3d& transform) {
  const Matrix3x4d matrix = transform.ToMatrix();
  out << "T_BS:\n  cols: 4\n  rows: 4\n  data: [";
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) out << matrix(r, c) << ", ";
    out << "\n         ";
  }
  out << "0.0, 0.0, 0.0, 1.0]\n";
}

void FullPrecision(std::ostream& out) {
  out << std::setprecision(17);
}

}  // namespace

void WriteEurocImageList(const fs::path& csv, const std::vector<SequenceImage>& images) {
  WriteFileAtomically(csv, [&](std::ostream& out) {
    out << "#timestamp [ns],filename\n";
    for (const SequenceImage& image : images) {
      out << image.timestamp_ns << ',' << image.path.filename().string() << '\n';
    }
  });
}

void WriteEurocImu(const fs::path& csv, const std::vector<ImuSample>& samples) {
  WriteFileAtomically(csv, [&](std::ostream& out) {
    FullPrecision(out);
    out << "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
           "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n";
    for (const ImuSample& s : samples) {
      out << s.timestamp_ns << ',';
      WriteRow(out, {s.gyro.x(), s.gyro.y(), s.gyro.z(), s.accel.x(), s.accel.y(), s.accel.z()});
      out << '\n';
    }
  });
}

void WriteEurocGroundTruth(const fs::path& csv, const std::vector<GroundTruthState>& states) {
  WriteFileAtomically(csv, [&](std::ostream& out) {
    FullPrecision(out);
    out << "#timestamp [ns], p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], "
           "q_RS_y [], q_RS_z [], v_RS_R_x [m s^-1], v_RS_R_y [m s^-1], v_RS_R_z [m s^-1], "
           "b_w_RS_S_x [rad s^-1], b_w_RS_S_y [rad s^-1], b_w_RS_S_z [rad s^-1], "
           "b_a_RS_S_x [m s^-2], b_a_RS_S_y [m s^-2], b_a_RS_S_z [m s^-2]\n";
    for (const GroundTruthState& s : states) {
      const Eigen::Vector3d& p = s.world_from_body.translation;
      const Eigen::Quaterniond& q = s.world_from_body.rotation;
      out << s.timestamp_ns << ',';
      WriteRow(out, {p.x(), p.y(), p.z(), q.w(), q.x(), q.y(), q.z()});
      if (s.has_velocity_and_biases) {
        out << ',';
        WriteRow(out, {s.velocity_in_world.x(), s.velocity_in_world.y(), s.velocity_in_world.z(),
                       s.gyro_bias.x(), s.gyro_bias.y(), s.gyro_bias.z(), s.accel_bias.x(),
                       s.accel_bias.y(), s.accel_bias.z()});
      }
      out << '\n';
    }
  });
}

std::string EurocCameraYamlText(const Camera& camera, const Rigid3d& body_from_cam,
                                double rate_hz) {
  const auto& p = camera.params;
  std::string distortion_model;
  std::vector<double> coefficients;
  switch (camera.model_id) {
    case CameraModelId::kPinhole: distortion_model = "none"; break;
    case CameraModelId::kOpenCV: distortion_model = "radial-tangential"; break;
    case CameraModelId::kOpenCVFisheye: distortion_model = "equidistant"; break;
    default:
      throw InputError("camera model " + camera.ModelName() +
                       " has no EuRoC equivalent (PINHOLE, OPENCV or OPENCV_FISHEYE)");
  }
  if (!camera.HasValidParams()) throw InputError("camera has the wrong number of parameters");
  coefficients.assign(p.begin() + 4, p.end());
  std::ostringstream out;
  FullPrecision(out);
  out << "# Camera calibration (Kalibr / EuRoC format), written by viosfm\n"
      << "sensor_type: camera\n";
  WriteTransformYaml(out, body_from_cam);
  out << "rate_hz: " << rate_hz << "\n"
      << "resolution: [" << camera.width << ", " << camera.height << "]\n"
      << "camera_model: pinhole\n"
      << "intrinsics: [" << p[0] << ", " << p[1] << ", " << p[2] << ", " << p[3] << "]\n"
      << "distortion_model: " << distortion_model << "\n"
      << "distortion_coefficients: [";
  for (size_t i = 0; i < coefficients.size(); ++i) out << (i ? ", " : "") << coefficients[i];
  out << "]\n";
  return out.str();
}

std::string EurocImuYamlText(const ImuNoise& noise) {
  std::ostringstream out;
  FullPrecision(out);
  out << "# IMU noise model (Kalibr / EuRoC format), written by viosfm\n"
      << "sensor_type: imu\n";
  WriteTransformYaml(out, Rigid3d());
  out << "rate_hz: " << noise.rate_hz << "\n"
      << "gyroscope_noise_density: " << noise.gyro_noise_density << "\n"
      << "gyroscope_random_walk: " << noise.gyro_random_walk << "\n"
      << "accelerometer_noise_density: " << noise.accel_noise_density << "\n"
      << "accelerometer_random_walk: " << noise.accel_random_walk << "\n";
  return out.str();
}

void WriteEurocCameraYaml(const fs::path& yaml, const Camera& camera, const Rigid3d& body_from_cam,
                          double rate_hz) {
  std::string text;
  try {
    text = EurocCameraYamlText(camera, body_from_cam, rate_hz);
  } catch (const InputError& e) {
    throw InputError(yaml.string(), 0, e.what());
  }
  WriteFileAtomically(yaml, [&](std::ostream& out) { out << text; });
}

void WriteEurocImuYaml(const fs::path& yaml, const ImuNoise& noise) {
  const std::string text = EurocImuYamlText(noise);
  WriteFileAtomically(yaml, [&](std::ostream& out) { out << text; });
}

void WriteEurocDataset(const fs::path& root, const Sequence& sequence) {
  const fs::path mav0 = root / "mav0";
  if (!sequence.images.empty()) {
    WriteEurocImageList(mav0 / "cam0" / "data.csv", sequence.images);
    WriteEurocCameraYaml(mav0 / "cam0" / "sensor.yaml", sequence.rig.camera,
                         sequence.rig.body_from_cam, sequence.rig.camera_rate_hz);
  }
  if (sequence.has_imu()) {
    WriteEurocImu(mav0 / "imu0" / "data.csv", sequence.imu);
    WriteEurocImuYaml(mav0 / "imu0" / "sensor.yaml", sequence.rig.imu_noise);
  }
  if (sequence.has_ground_truth()) {
    WriteEurocGroundTruth(mav0 / "state_groundtruth_estimate0" / "data.csv", sequence.ground_truth);
  }
}

}  // namespace viosfm

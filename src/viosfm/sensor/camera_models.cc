#include "viosfm/sensor/camera_models.h"

#include <Eigen/LU>
#include <limits>
#include <numbers>
#include <sstream>
#include <type_traits>
#include <utility>

namespace viosfm {
namespace {

// Newton undistortion stops when the step is below this (relative to 1 + |x|).
constexpr double kUndistortStepTolerance = 1e-14;
constexpr int kUndistortMaxIterations = 100;
// Step halvings tried when a Newton step does not reduce the residual.
constexpr int kUndistortMaxHalvings = 40;

void SetExtraJacobian(double* d_extra, int index, double du, double dv) {
  if (d_extra == nullptr) return;
  d_extra[2 * index] = du;
  d_extra[2 * index + 1] = dv;
}

// Jacobian of (1 + g(r^2)) * (u, v) for a radial factor with
// radial = 1 + g and d radial / d(r^2) = g_prime.
Eigen::Matrix2d RadialJacobian(double radial, double g_prime, double u, double v) {
  Eigen::Matrix2d jacobian;
  const double two_g = 2.0 * g_prime;
  jacobian << radial + two_g * u * u, two_g * u * v,  //
      two_g * u * v, radial + two_g * v * v;
  return jacobian;
}

// Solves Distort(x) = distorted by damped Newton iterations from x = distorted.
template <typename Model>
Eigen::Vector2d UndistortNewton(const double* extra, const Eigen::Vector2d& distorted) {
  if constexpr (Model::kNumExtra == 0) {
    return distorted;
  } else {
    const auto residual_of = [&](const Eigen::Vector2d& x) {
      Eigen::Vector2d d;
      Model::Distort(extra, x.x(), x.y(), &d.x(), &d.y());
      return Eigen::Vector2d(d - distorted);
    };
    Eigen::Vector2d x = distorted;
    Eigen::Vector2d residual = residual_of(x);
    for (int iteration = 0; iteration < kUndistortMaxIterations; ++iteration) {
      if (residual.squaredNorm() == 0.0) break;
      Eigen::Matrix2d jacobian;
      Model::DistortJacobian(extra, x.x(), x.y(), &jacobian, nullptr);
      const double det = jacobian.determinant();
      if (!(std::abs(det) > 0.0) || !std::isfinite(det)) break;
      Eigen::Vector2d step = jacobian.inverse() * residual;
      Eigen::Vector2d candidate = x - step;
      Eigen::Vector2d candidate_residual = residual_of(candidate);
      int halvings = 0;
      while (!(candidate_residual.squaredNorm() < residual.squaredNorm()) &&
             halvings < kUndistortMaxHalvings) {
        step *= 0.5;
        candidate = x - step;
        candidate_residual = residual_of(candidate);
        ++halvings;
      }
      if (!(candidate_residual.squaredNorm() < residual.squaredNorm())) break;  // converged
      x = candidate;
      residual = candidate_residual;
      if (step.norm() <= kUndistortStepTolerance * (1.0 + x.norm())) break;
    }
    return x;
  }
}

const double* CheckedParams(const Camera& camera) {
  if (!IsCameraModelSupported(camera.model_id)) {
    throw InputError(UnsupportedCameraModelMessage(camera.model_id));
  }
  if (!camera.HasValidParams()) {
    std::ostringstream message;
    message << "camera " << camera.camera_id << " with model " << camera.ModelName() << " expects "
            << CameraModelNumParams(camera.model_id) << " parameters, got " << camera.params.size();
    throw InputError(message.str());
  }
  return camera.params.data();
}

std::vector<int> IndexRange(int begin, int count) {
  std::vector<int> indices(count);
  for (int i = 0; i < count; ++i) indices[i] = begin + i;
  return indices;
}

}  // namespace

// ---------------------------------------------------------------------------
// Per-model Jacobians. d_extra is 2 x kNumExtra, column-major.

void SimplePinholeModel::DistortJacobian(const double* /*extra*/, double /*u*/, double /*v*/,
                                         Eigen::Matrix2d* d_uv, double* /*d_extra*/) {
  *d_uv = Eigen::Matrix2d::Identity();
}

void PinholeModel::DistortJacobian(const double* /*extra*/, double /*u*/, double /*v*/,
                                   Eigen::Matrix2d* d_uv, double* /*d_extra*/) {
  *d_uv = Eigen::Matrix2d::Identity();
}

void SimpleRadialModel::DistortJacobian(const double* extra, double u, double v,
                                        Eigen::Matrix2d* d_uv, double* d_extra) {
  const double k = extra[0];
  const double r2 = u * u + v * v;
  *d_uv = RadialJacobian(1.0 + k * r2, k, u, v);
  SetExtraJacobian(d_extra, 0, u * r2, v * r2);
}

void RadialModel::DistortJacobian(const double* extra, double u, double v, Eigen::Matrix2d* d_uv,
                                  double* d_extra) {
  const double k1 = extra[0];
  const double k2 = extra[1];
  const double r2 = u * u + v * v;
  *d_uv = RadialJacobian(1.0 + r2 * (k1 + k2 * r2), k1 + 2.0 * k2 * r2, u, v);
  SetExtraJacobian(d_extra, 0, u * r2, v * r2);
  SetExtraJacobian(d_extra, 1, u * r2 * r2, v * r2 * r2);
}

void OpenCVModel::DistortJacobian(const double* extra, double u, double v, Eigen::Matrix2d* d_uv,
                                  double* d_extra) {
  const double k1 = extra[0];
  const double k2 = extra[1];
  const double p1 = extra[2];
  const double p2 = extra[3];
  const double r2 = u * u + v * v;
  Eigen::Matrix2d jacobian = RadialJacobian(1.0 + r2 * (k1 + k2 * r2), k1 + 2.0 * k2 * r2, u, v);
  // Tangential part: (2 p1 u v + p2 (r2 + 2 u^2), p1 (r2 + 2 v^2) + 2 p2 u v).
  jacobian(0, 0) += 2.0 * p1 * v + 6.0 * p2 * u;
  jacobian(0, 1) += 2.0 * p1 * u + 2.0 * p2 * v;
  jacobian(1, 0) += 2.0 * p1 * u + 2.0 * p2 * v;
  jacobian(1, 1) += 6.0 * p1 * v + 2.0 * p2 * u;
  *d_uv = jacobian;
  SetExtraJacobian(d_extra, 0, u * r2, v * r2);
  SetExtraJacobian(d_extra, 1, u * r2 * r2, v * r2 * r2);
  SetExtraJacobian(d_extra, 2, 2.0 * u * v, r2 + 2.0 * v * v);
  SetExtraJacobian(d_extra, 3, r2 + 2.0 * u * u, 2.0 * u * v);
}

void OpenCVFisheyeModel::DistortJacobian(const double* extra, double u, double v,
                                         Eigen::Matrix2d* d_uv, double* d_extra) {
  const double k1 = extra[0];
  const double k2 = extra[1];
  const double k3 = extra[2];
  const double k4 = extra[3];
  const double r2 = u * u + v * v;
  // distorted = factor(r) * (u, v); d distorted / d(u, v) =
  // factor * I + (factor'(r) / r) * (u, v)^T (u, v).
  double factor;
  double factor_slope_over_r;
  // d factor / d k_i = theta^(2i+1) / r.
  double d_factor_d_k[4];
  if (r2 < kSmallRadiusSq) {
    factor = 1.0 + (k1 - 1.0 / 3.0) * r2;
    factor_slope_over_r = 2.0 * (k1 - 1.0 / 3.0);
    d_factor_d_k[0] = r2;
    d_factor_d_k[1] = r2 * r2;
    d_factor_d_k[2] = r2 * r2 * r2;
    d_factor_d_k[3] = r2 * r2 * r2 * r2;
  } else {
    const double r = std::sqrt(r2);
    const double theta = std::atan(r);
    const double t2 = theta * theta;
    const double poly = 1.0 + t2 * (k1 + t2 * (k2 + t2 * (k3 + t2 * k4)));
    const double d_theta_d_d_theta =
        1.0 + t2 * (3.0 * k1 + t2 * (5.0 * k2 + t2 * (7.0 * k3 + t2 * 9.0 * k4)));
    factor = theta * poly / r;
    // factor'(r) = (theta_d'(theta) / (1 + r^2) - factor) / r.
    factor_slope_over_r = (d_theta_d_d_theta / (1.0 + r2) - factor) / r2;
    const double theta_over_r = theta / r;
    d_factor_d_k[0] = theta_over_r * t2;
    d_factor_d_k[1] = d_factor_d_k[0] * t2;
    d_factor_d_k[2] = d_factor_d_k[1] * t2;
    d_factor_d_k[3] = d_factor_d_k[2] * t2;
  }
  Eigen::Matrix2d jacobian;
  jacobian << factor + factor_slope_over_r * u * u, factor_slope_over_r * u * v,  //
      factor_slope_over_r * u * v, factor + factor_slope_over_r * v * v;
  *d_uv = jacobian;
  for (int i = 0; i < 4; ++i)
    SetExtraJacobian(d_extra, i, d_factor_d_k[i] * u, d_factor_d_k[i] * v);
}

double OpenCVFisheyeModel::UndistortAngle(const double* extra, double theta_d) {
  const double k1 = extra[0];
  const double k2 = extra[1];
  const double k3 = extra[2];
  const double k4 = extra[3];
  const auto residual_of = [&](double theta) {
    const double t2 = theta * theta;
    return theta * (1.0 + t2 * (k1 + t2 * (k2 + t2 * (k3 + t2 * k4)))) - theta_d;
  };
  double theta = theta_d;
  double residual = residual_of(theta);
  for (int iteration = 0; iteration < kUndistortMaxIterations; ++iteration) {
    if (residual == 0.0) break;
    const double t2 = theta * theta;
    const double slope = 1.0 + t2 * (3.0 * k1 + t2 * (5.0 * k2 + t2 * (7.0 * k3 + t2 * 9.0 * k4)));
    if (!(slope > 0.0)) break;  // outside the invertible range
    double step = residual / slope;
    double candidate = theta - step;
    double candidate_residual = residual_of(candidate);
    int halvings = 0;
    while (!(std::abs(candidate_residual) < std::abs(residual)) &&
           halvings < kUndistortMaxHalvings) {
      step *= 0.5;
      candidate = theta - step;
      candidate_residual = residual_of(candidate);
      ++halvings;
    }
    if (!(std::abs(candidate_residual) < std::abs(residual))) break;  // converged
    theta = candidate;
    residual = candidate_residual;
    if (std::abs(step) <= kUndistortStepTolerance * (1.0 + std::abs(theta))) break;
  }
  return theta;
}

// ---------------------------------------------------------------------------

std::string UnsupportedCameraModelMessage(CameraModelId model_id) {
  std::ostringstream message;
  const std::string name = CameraModelName(model_id);
  message << "camera model " << (name.empty() ? "<unknown>" : name) << " (id "
          << static_cast<int>(model_id)
          << ") is not supported for projection; supported models: SIMPLE_PINHOLE, PINHOLE, "
             "SIMPLE_RADIAL, RADIAL, OPENCV, OPENCV_FISHEYE";
  return message.str();
}

bool IsCameraModelSupported(CameraModelId model_id) {
  switch (model_id) {
    case CameraModelId::kSimplePinhole:
    case CameraModelId::kPinhole:
    case CameraModelId::kSimpleRadial:
    case CameraModelId::kRadial:
    case CameraModelId::kOpenCV:
    case CameraModelId::kOpenCVFisheye: return true;
    default: return false;
  }
}

Camera MakeCamera(CameraModelId model_id, uint64_t width, uint64_t height,
                  std::vector<double> params) {
  const int expected = CameraModelNumParams(model_id);
  if (expected < 0) {
    throw InputError("unknown camera model id " + std::to_string(static_cast<int>(model_id)));
  }
  if (params.size() != static_cast<size_t>(expected)) {
    throw InputError("camera model " + CameraModelName(model_id) + " expects " +
                     std::to_string(expected) + " parameters, got " +
                     std::to_string(params.size()));
  }
  Camera camera;
  camera.model_id = model_id;
  camera.width = width;
  camera.height = height;
  camera.params = std::move(params);
  return camera;
}

Eigen::Matrix3d CalibrationMatrix(const Camera& camera) {
  const double* params = CheckedParams(camera);
  return VisitCameraModel(camera.model_id, [&](auto model) {
    using Model = decltype(model);
    Eigen::Matrix3d k = Eigen::Matrix3d::Identity();
    k(0, 0) = Model::FocalX(params);
    k(1, 1) = Model::FocalY(params);
    k(0, 2) = params[Model::kPrincipalIdx()];
    k(1, 2) = params[Model::kPrincipalIdx() + 1];
    return k;
  });
}

double MeanFocalLength(const Camera& camera) {
  const double* params = CheckedParams(camera);
  return VisitCameraModel(camera.model_id, [&](auto model) {
    using Model = decltype(model);
    return 0.5 * (Model::FocalX(params) + Model::FocalY(params));
  });
}

std::vector<int> FocalLengthIndices(const Camera& camera) {
  CheckedParams(camera);
  return VisitCameraModel(camera.model_id,
                          [](auto model) { return IndexRange(0, decltype(model)::kNumFocal); });
}

std::vector<int> PrincipalPointIndices(const Camera& camera) {
  CheckedParams(camera);
  return VisitCameraModel(
      camera.model_id, [](auto model) { return IndexRange(decltype(model)::kPrincipalIdx(), 2); });
}

std::vector<int> ExtraParamIndices(const Camera& camera) {
  CheckedParams(camera);
  return VisitCameraModel(camera.model_id, [](auto model) {
    using Model = decltype(model);
    return IndexRange(Model::kExtraIdx(), Model::kNumExtra);
  });
}

Eigen::Vector2d Distort(const Camera& camera, const Eigen::Vector2d& undistorted) {
  const double* params = CheckedParams(camera);
  return VisitCameraModel(camera.model_id, [&](auto model) {
    using Model = decltype(model);
    Eigen::Vector2d distorted;
    Model::Distort(params + Model::kExtraIdx(), undistorted.x(), undistorted.y(), &distorted.x(),
                   &distorted.y());
    return distorted;
  });
}

Eigen::Vector2d Undistort(const Camera& camera, const Eigen::Vector2d& distorted) {
  const double* params = CheckedParams(camera);
  return VisitCameraModel(camera.model_id, [&](auto model) -> Eigen::Vector2d {
    using Model = decltype(model);
    const double* extra = params + Model::kExtraIdx();
    if constexpr (std::is_same_v<Model, OpenCVFisheyeModel>) {
      const double theta_d = distorted.norm();
      if (theta_d == 0.0) return Eigen::Vector2d::Zero();
      const double theta = Model::UndistortAngle(extra, theta_d);
      if (!(theta < 0.5 * std::numbers::pi)) {
        return Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN());
      }
      return (std::tan(theta) / theta_d) * distorted;
    } else {
      return UndistortNewton<Model>(extra, distorted);
    }
  });
}

Eigen::Vector2d CamToImage(const Camera& camera, const Eigen::Vector2d& normalized) {
  const double* params = CheckedParams(camera);
  return VisitCameraModel(camera.model_id, [&](auto model) {
    using Model = decltype(model);
    Eigen::Vector2d pixel;
    Model::CamToImage(params, normalized.x(), normalized.y(), &pixel.x(), &pixel.y());
    return pixel;
  });
}

namespace {

// K^-1 * pixel: the distorted normalised coordinates.
Eigen::Vector2d PixelToDistorted(const Camera& camera, const Eigen::Vector2d& pixel) {
  const double* params = CheckedParams(camera);
  return VisitCameraModel(camera.model_id, [&](auto model) {
    using Model = decltype(model);
    return Eigen::Vector2d(
        (pixel.x() - params[Model::kPrincipalIdx()]) / Model::FocalX(params),
        (pixel.y() - params[Model::kPrincipalIdx() + 1]) / Model::FocalY(params));
  });
}

}  // namespace

Eigen::Vector2d ImageToCam(const Camera& camera, const Eigen::Vector2d& pixel) {
  return Undistort(camera, PixelToDistorted(camera, pixel));
}

std::optional<Eigen::Vector2d> Project(const Camera& camera, const Eigen::Vector3d& point_in_cam) {
  const double* params = CheckedParams(camera);
  if (!(point_in_cam.z() > 0.0)) return std::nullopt;
  return VisitCameraModel(camera.model_id, [&](auto model) {
    using Model = decltype(model);
    Eigen::Vector2d pixel;
    Model::Project(params, point_in_cam.data(), pixel.data());
    return pixel;
  });
}

Eigen::Vector3d Unproject(const Camera& camera, const Eigen::Vector2d& pixel) {
  const Eigen::Vector2d distorted = PixelToDistorted(camera, pixel);
  if (camera.model_id == CameraModelId::kOpenCVFisheye) {
    const double theta_d = distorted.norm();
    if (theta_d == 0.0) return Eigen::Vector3d::UnitZ();
    const double theta = OpenCVFisheyeModel::UndistortAngle(
        camera.params.data() + OpenCVFisheyeModel::kExtraIdx(), theta_d);
    const Eigen::Vector2d direction = distorted / theta_d;
    return Eigen::Vector3d(std::sin(theta) * direction.x(), std::sin(theta) * direction.y(),
                           std::cos(theta));
  }
  return Undistort(camera, distorted).homogeneous().normalized();
}

Eigen::Matrix2d DistortJacobian(const Camera& camera, const Eigen::Vector2d& undistorted) {
  const double* params = CheckedParams(camera);
  return VisitCameraModel(camera.model_id, [&](auto model) {
    using Model = decltype(model);
    Eigen::Matrix2d jacobian;
    Model::DistortJacobian(params + Model::kExtraIdx(), undistorted.x(), undistorted.y(), &jacobian,
                           nullptr);
    return jacobian;
  });
}

Eigen::Matrix<double, 2, 3> ProjectJacobianWrtPoint(const Camera& camera,
                                                    const Eigen::Vector3d& point_in_cam) {
  const double* params = CheckedParams(camera);
  return VisitCameraModel(camera.model_id, [&](auto model) {
    using Model = decltype(model);
    const double inv_z = 1.0 / point_in_cam.z();
    const double u = point_in_cam.x() * inv_z;
    const double v = point_in_cam.y() * inv_z;
    Eigen::Matrix<double, 2, 3> d_uv_d_point;
    d_uv_d_point << inv_z, 0.0, -u * inv_z,  //
        0.0, inv_z, -v * inv_z;
    Eigen::Matrix2d d_distorted_d_uv;
    Model::DistortJacobian(params + Model::kExtraIdx(), u, v, &d_distorted_d_uv, nullptr);
    const Eigen::Vector2d focal(Model::FocalX(params), Model::FocalY(params));
    return Eigen::Matrix<double, 2, 3>(focal.asDiagonal() * d_distorted_d_uv * d_uv_d_point);
  });
}

Eigen::Matrix<double, 2, Eigen::Dynamic> ProjectJacobianWrtParams(
    const Camera& camera, const Eigen::Vector3d& point_in_cam) {
  const double* params = CheckedParams(camera);
  return VisitCameraModel(camera.model_id, [&](auto model) {
    using Model = decltype(model);
    const double u = point_in_cam.x() / point_in_cam.z();
    const double v = point_in_cam.y() / point_in_cam.z();
    const double* extra = params + Model::kExtraIdx();
    Eigen::Vector2d distorted;
    Model::Distort(extra, u, v, &distorted.x(), &distorted.y());
    Eigen::Matrix<double, 2, Eigen::Dynamic> jacobian =
        Eigen::Matrix<double, 2, Eigen::Dynamic>::Zero(2, Model::kNumParams());
    if constexpr (Model::kNumFocal == 1) {
      jacobian.col(0) = distorted;
    } else {
      jacobian(0, 0) = distorted.x();
      jacobian(1, 1) = distorted.y();
    }
    jacobian(0, Model::kPrincipalIdx()) = 1.0;
    jacobian(1, Model::kPrincipalIdx() + 1) = 1.0;
    if constexpr (Model::kNumExtra > 0) {
      Eigen::Matrix2d d_uv;
      Eigen::Matrix<double, 2, Model::kNumExtra> d_extra;
      Model::DistortJacobian(extra, u, v, &d_uv, d_extra.data());
      const Eigen::Vector2d focal(Model::FocalX(params), Model::FocalY(params));
      jacobian.template rightCols<Model::kNumExtra>() = focal.asDiagonal() * d_extra;
    }
    return jacobian;
  });
}

}  // namespace viosfm

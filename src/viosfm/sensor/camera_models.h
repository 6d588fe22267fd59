// Camera projection models: COLMAP's names, ids and parameter orders (see
// camera.h). Supported for projection:
//   SIMPLE_PINHOLE  f, cx, cy
//   PINHOLE         fx, fy, cx, cy
//   SIMPLE_RADIAL   f, cx, cy, k
//   RADIAL          f, cx, cy, k1, k2
//   OPENCV          fx, fy, cx, cy, k1, k2, p1, p2   (Kalibr/EuRoC radial-tangential)
//   OPENCV_FISHEYE  fx, fy, cx, cy, k1, k2, k3, k4   (Kalibr equidistant)
// The other COLMAP models can be stored and written, but projecting with them
// throws InputError naming the model.
//
// Terms: "normalised" coordinates are (x/z, y/z) of a point in the camera
// frame; "distorted" normalised coordinates are those after the lens model,
// before the focal lengths and principal point: pixel = f * distorted + c.
// Pixels follow the convention the intrinsics were calibrated in (OpenCV and
// Kalibr: (0, 0) is the centre of the top-left pixel; COLMAP: (0.5, 0.5)).
//
// Each model is a struct of static, templated functions, usable with
// ceres::Jet inside AutoDiff cost functors; the free functions at the bottom
// dispatch on Camera::model_id.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "viosfm/sensor/camera.h"
#include "viosfm/util/errors.h"

namespace viosfm {

// Shared parts of the models. Derived provides
//   kModelId, kNumFocal (1 or 2), kNumExtra,
//   template <typename T> static void Distort(const T* extra, const T& u, const T& v,
//                                             T* u_d, T* v_d);
//   static void DistortJacobian(const double* extra, double u, double v,
//                               Eigen::Matrix2d* d_uv, double* d_extra);
// where extra points at the distortion parameters and d_extra (if not null)
// receives the 2 x kNumExtra Jacobian in column-major order.
// Params layout: focal length(s), then cx, cy, then the extra parameters.
template <typename Derived>
struct CameraModelBase {
  static constexpr int kPrincipalIdx() { return Derived::kNumFocal; }
  static constexpr int kExtraIdx() { return Derived::kNumFocal + 2; }
  static constexpr int kNumParams() { return Derived::kNumFocal + 2 + Derived::kNumExtra; }

  template <typename T>
  static T FocalX(const T* params) {
    return params[0];
  }
  template <typename T>
  static T FocalY(const T* params) {
    return params[Derived::kNumFocal - 1];
  }

  // Normalised (undistorted) coordinates -> pixel.
  template <typename T>
  static void CamToImage(const T* params, const T& u, const T& v, T* x, T* y) {
    T u_d;
    T v_d;
    Derived::Distort(params + kExtraIdx(), u, v, &u_d, &v_d);
    *x = FocalX(params) * u_d + params[kPrincipalIdx()];
    *y = FocalY(params) * v_d + params[kPrincipalIdx() + 1];
  }

  // Point in the camera frame -> pixel. Does not check the depth (callers
  // that may see points behind the camera check z > 0 themselves).
  template <typename T>
  static void Project(const T* params, const T* point_in_cam, T* pixel) {
    const T u = point_in_cam[0] / point_in_cam[2];
    const T v = point_in_cam[1] / point_in_cam[2];
    CamToImage(params, u, v, &pixel[0], &pixel[1]);
  }
};

struct SimplePinholeModel : CameraModelBase<SimplePinholeModel> {
  static constexpr CameraModelId kModelId = CameraModelId::kSimplePinhole;
  static constexpr int kNumFocal = 1;
  static constexpr int kNumExtra = 0;
  template <typename T>
  static void Distort(const T* /*extra*/, const T& u, const T& v, T* u_d, T* v_d) {
    *u_d = u;
    *v_d = v;
  }
  static void DistortJacobian(const double* extra, double u, double v, Eigen::Matrix2d* d_uv,
                              double* d_extra);
};

struct PinholeModel : CameraModelBase<PinholeModel> {
  static constexpr CameraModelId kModelId = CameraModelId::kPinhole;
  static constexpr int kNumFocal = 2;
  static constexpr int kNumExtra = 0;
  template <typename T>
  static void Distort(const T* /*extra*/, const T& u, const T& v, T* u_d, T* v_d) {
    *u_d = u;
    *v_d = v;
  }
  static void DistortJacobian(const double* extra, double u, double v, Eigen::Matrix2d* d_uv,
                              double* d_extra);
};

// Radial distortion (1 + k r^2).
struct SimpleRadialModel : CameraModelBase<SimpleRadialModel> {
  static constexpr CameraModelId kModelId = CameraModelId::kSimpleRadial;
  static constexpr int kNumFocal = 1;
  static constexpr int kNumExtra = 1;
  template <typename T>
  static void Distort(const T* extra, const T& u, const T& v, T* u_d, T* v_d) {
    const T radial = T(1) + extra[0] * (u * u + v * v);
    *u_d = radial * u;
    *v_d = radial * v;
  }
  static void DistortJacobian(const double* extra, double u, double v, Eigen::Matrix2d* d_uv,
                              double* d_extra);
};

// Radial distortion (1 + k1 r^2 + k2 r^4).
struct RadialModel : CameraModelBase<RadialModel> {
  static constexpr CameraModelId kModelId = CameraModelId::kRadial;
  static constexpr int kNumFocal = 1;
  static constexpr int kNumExtra = 2;
  template <typename T>
  static void Distort(const T* extra, const T& u, const T& v, T* u_d, T* v_d) {
    const T r2 = u * u + v * v;
    const T radial = T(1) + r2 * (extra[0] + extra[1] * r2);
    *u_d = radial * u;
    *v_d = radial * v;
  }
  static void DistortJacobian(const double* extra, double u, double v, Eigen::Matrix2d* d_uv,
                              double* d_extra);
};

// Radial-tangential (Brown-Conrady with k1, k2, p1, p2), as OpenCV and Kalibr.
struct OpenCVModel : CameraModelBase<OpenCVModel> {
  static constexpr CameraModelId kModelId = CameraModelId::kOpenCV;
  static constexpr int kNumFocal = 2;
  static constexpr int kNumExtra = 4;
  template <typename T>
  static void Distort(const T* extra, const T& u, const T& v, T* u_d, T* v_d) {
    const T& k1 = extra[0];
    const T& k2 = extra[1];
    const T& p1 = extra[2];
    const T& p2 = extra[3];
    const T uu = u * u;
    const T vv = v * v;
    const T uv = u * v;
    const T r2 = uu + vv;
    const T radial = T(1) + r2 * (k1 + k2 * r2);
    *u_d = radial * u + T(2) * p1 * uv + p2 * (r2 + T(2) * uu);
    *v_d = radial * v + p1 * (r2 + T(2) * vv) + T(2) * p2 * uv;
  }
  static void DistortJacobian(const double* extra, double u, double v, Eigen::Matrix2d* d_uv,
                              double* d_extra);
};

// Equidistant fisheye (OpenCV fisheye, Kalibr equidistant):
// theta = atan(r), theta_d = theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6
// + k4 theta^8), distorted = (theta_d / r) * (u, v).
struct OpenCVFisheyeModel : CameraModelBase<OpenCVFisheyeModel> {
  static constexpr CameraModelId kModelId = CameraModelId::kOpenCVFisheye;
  static constexpr int kNumFocal = 2;
  static constexpr int kNumExtra = 4;
  // Below this r^2 the factor theta_d / r is evaluated by its Taylor series
  // 1 + (k1 - 1/3) r^2 (exact to double precision there, and differentiable
  // at r = 0 for Jets).
  static constexpr double kSmallRadiusSq = 1e-16;
  template <typename T>
  static void Distort(const T* extra, const T& u, const T& v, T* u_d, T* v_d) {
    using std::atan;
    using std::sqrt;
    const T r2 = u * u + v * v;
    T factor;
    if (r2 < T(kSmallRadiusSq)) {
      factor = T(1) + (extra[0] - T(1.0 / 3.0)) * r2;
    } else {
      const T r = sqrt(r2);
      const T theta = atan(r);
      const T t2 = theta * theta;
      const T theta_d =
          theta * (T(1) + t2 * (extra[0] + t2 * (extra[1] + t2 * (extra[2] + t2 * extra[3]))));
      factor = theta_d / r;
    }
    *u_d = factor * u;
    *v_d = factor * v;
  }
  static void DistortJacobian(const double* extra, double u, double v, Eigen::Matrix2d* d_uv,
                              double* d_extra);
  // Angle theta (radians) from the optical axis of the ray whose distorted
  // radius is theta_d, by Newton's method on the polynomial.
  static double UndistortAngle(const double* extra, double theta_d);
};

// "camera model FULL_OPENCV (id 6) is not supported for projection; ..."
std::string UnsupportedCameraModelMessage(CameraModelId model_id);
// Whether the model can project (one of the six above).
bool IsCameraModelSupported(CameraModelId model_id);

// Calls visitor(Model{}) for the model of `model_id`, returning its result.
// Throws InputError for models that cannot project.
template <typename Visitor>
decltype(auto) VisitCameraModel(CameraModelId model_id, Visitor&& visitor) {
  switch (model_id) {
    case CameraModelId::kSimplePinhole: return visitor(SimplePinholeModel{});
    case CameraModelId::kPinhole: return visitor(PinholeModel{});
    case CameraModelId::kSimpleRadial: return visitor(SimpleRadialModel{});
    case CameraModelId::kRadial: return visitor(RadialModel{});
    case CameraModelId::kOpenCV: return visitor(OpenCVModel{});
    case CameraModelId::kOpenCVFisheye: return visitor(OpenCVFisheyeModel{});
    default: break;
  }
  throw InputError(UnsupportedCameraModelMessage(model_id));
}

// Builds a camera, checking that the model is known and params has its number
// of values (InputError otherwise, naming the model and both counts).
Camera MakeCamera(CameraModelId model_id, uint64_t width, uint64_t height,
                  std::vector<double> params);

// Unless stated otherwise, the functions below throw InputError if the model
// cannot project or the camera does not have its model's number of
// parameters.

// K = [fx 0 cx; 0 fy cy; 0 0 1] (ignores distortion).
Eigen::Matrix3d CalibrationMatrix(const Camera& camera);
// (fx + fy) / 2, or f.
double MeanFocalLength(const Camera& camera);
// Parameter indices of the focal length(s), principal point and distortion.
std::vector<int> FocalLengthIndices(const Camera& camera);
std::vector<int> PrincipalPointIndices(const Camera& camera);
std::vector<int> ExtraParamIndices(const Camera& camera);

// Normalised coordinates -> pixel (distortion, then K).
Eigen::Vector2d CamToImage(const Camera& camera, const Eigen::Vector2d& normalized);
// Pixel -> normalised coordinates (K^-1, then iterative undistortion to
// ~1e-12 relative). For OPENCV_FISHEYE pixels 90 degrees or more from the
// optical axis have no normalised coordinates: NaN is returned (use
// Unproject for those).
Eigen::Vector2d ImageToCam(const Camera& camera, const Eigen::Vector2d& pixel);
// Point in the camera frame -> pixel; nullopt if the point is not in front of
// the camera (z <= 0).
std::optional<Eigen::Vector2d> Project(const Camera& camera, const Eigen::Vector3d& point_in_cam);
// Pixel -> unit-norm viewing ray in the camera frame (valid also for fisheye
// rays beyond 90 degrees).
Eigen::Vector3d Unproject(const Camera& camera, const Eigen::Vector2d& pixel);

// Lens model on normalised coordinates: undistorted -> distorted and back.
// Undistort uses Newton's method (1D on the angle for the fisheye), stops at
// a step below 1e-14 (relative) and returns its best estimate if the
// distortion is not invertible there (e.g. far outside the calibrated field).
Eigen::Vector2d Distort(const Camera& camera, const Eigen::Vector2d& undistorted);
Eigen::Vector2d Undistort(const Camera& camera, const Eigen::Vector2d& distorted);

// Analytic Jacobians.
// d distorted / d undistorted (2x2), at the undistorted normalised point.
Eigen::Matrix2d DistortJacobian(const Camera& camera, const Eigen::Vector2d& undistorted);
// d pixel / d point_in_cam (2x3); the point must have z != 0.
Eigen::Matrix<double, 2, 3> ProjectJacobianWrtPoint(const Camera& camera,
                                                    const Eigen::Vector3d& point_in_cam);
// d pixel / d params (2 x number of params, in the params order).
Eigen::Matrix<double, 2, Eigen::Dynamic> ProjectJacobianWrtParams(
    const Camera& camera, const Eigen::Vector3d& point_in_cam);

}  // namespace viosfm

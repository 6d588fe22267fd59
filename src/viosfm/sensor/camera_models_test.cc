#include "viosfm/sensor/camera_models.h"

#include <ceres/jet.h>  // header-only: checks that the models work with Jets
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <numbers>

#include "viosfm/util/random.h"

namespace viosfm {
namespace {

using ::testing::HasSubstr;

// EuRoC MAV cam0 (radial-tangential), 752x480.
constexpr double kEurocFx = 458.654;
constexpr double kEurocFy = 457.296;
constexpr double kEurocCx = 367.215;
constexpr double kEurocCy = 248.375;
// TUM-VI cam0 (equidistant), 512x512.
constexpr double kTumFx = 190.97847715128717;
constexpr double kTumFy = 190.9733070521226;
constexpr double kTumCx = 254.93170605935475;
constexpr double kTumCy = 256.8974428996504;

Camera EurocOpenCV() {
  return MakeCamera(CameraModelId::kOpenCV, 752, 480,
                    {kEurocFx, kEurocFy, kEurocCx, kEurocCy, -0.28340811, 0.07395907, 0.00019359,
                     1.76187114e-05});
}

Camera TumFisheye() {
  return MakeCamera(CameraModelId::kOpenCVFisheye, 512, 512,
                    {kTumFx, kTumFy, kTumCx, kTumCy, 0.0034823894022493434, 0.0007150348452162257,
                     -0.0020532361418706202, 0.00020293673591811182});
}

// One realistic camera per supported model.
std::vector<Camera> TestCameras() {
  return {
      MakeCamera(CameraModelId::kSimplePinhole, 752, 480, {458.0, kEurocCx, kEurocCy}),
      MakeCamera(CameraModelId::kPinhole, 752, 480, {kEurocFx, kEurocFy, kEurocCx, kEurocCy}),
      MakeCamera(CameraModelId::kSimpleRadial, 752, 480, {458.0, kEurocCx, kEurocCy, -0.1}),
      MakeCamera(CameraModelId::kRadial, 752, 480,
                 {458.0, kEurocCx, kEurocCy, -0.28340811, 0.07395907}),
      EurocOpenCV(),
      TumFisheye(),
  };
}

TEST(CameraModels, MakeCameraValidatesParameterCount) {
  const Camera camera = MakeCamera(CameraModelId::kPinhole, 640, 480, {500, 501, 320, 240});
  EXPECT_EQ(camera.model_id, CameraModelId::kPinhole);
  EXPECT_EQ(camera.width, 640u);
  EXPECT_EQ(camera.height, 480u);
  EXPECT_TRUE(camera.HasValidParams());
  try {
    MakeCamera(CameraModelId::kOpenCV, 640, 480, {500, 500, 320, 240, 0.1});
    FAIL() << "expected InputError";
  } catch (const InputError& error) {
    EXPECT_THAT(error.what(), HasSubstr("OPENCV"));
    EXPECT_THAT(error.what(), HasSubstr("expects 8 parameters, got 5"));
  }
  EXPECT_THROW(MakeCamera(static_cast<CameraModelId>(42), 640, 480, {}), InputError);
  // Models that cannot project can still be made (for file round trips).
  EXPECT_NO_THROW(MakeCamera(CameraModelId::kFOV, 640, 480, {500, 500, 320, 240, 0.9}));
}

TEST(CameraModels, UnsupportedModelsThrowNamingTheModel) {
  const Camera camera = MakeCamera(CameraModelId::kFullOpenCV, 640, 480,
                                   {500, 500, 320, 240, 0, 0, 0, 0, 0, 0, 0, 0});
  EXPECT_FALSE(IsCameraModelSupported(CameraModelId::kFullOpenCV));
  try {
    Project(camera, Eigen::Vector3d(0, 0, 1));
    FAIL() << "expected InputError";
  } catch (const InputError& error) {
    EXPECT_THAT(error.what(), HasSubstr("FULL_OPENCV"));
    EXPECT_THAT(error.what(), HasSubstr("not supported"));
  }
  EXPECT_THROW(ImageToCam(camera, Eigen::Vector2d(1, 2)), InputError);
  EXPECT_THROW(CalibrationMatrix(camera), InputError);
  // A supported model with a wrong number of parameters.
  Camera broken = EurocOpenCV();
  broken.params.pop_back();
  try {
    CamToImage(broken, Eigen::Vector2d(0, 0));
    FAIL() << "expected InputError";
  } catch (const InputError& error) {
    EXPECT_THAT(error.what(), HasSubstr("expects 8 parameters, got 7"));
  }
}

TEST(CameraModels, CalibrationMatrixAndFocalLength) {
  const Camera opencv = EurocOpenCV();
  Eigen::Matrix3d expected;
  expected << kEurocFx, 0, kEurocCx, 0, kEurocFy, kEurocCy, 0, 0, 1;
  EXPECT_EQ(CalibrationMatrix(opencv), expected);
  EXPECT_DOUBLE_EQ(MeanFocalLength(opencv), 0.5 * (kEurocFx + kEurocFy));
  const Camera simple = MakeCamera(CameraModelId::kSimpleRadial, 100, 100, {300, 50, 40, 0.01});
  expected << 300, 0, 50, 0, 300, 40, 0, 0, 1;
  EXPECT_EQ(CalibrationMatrix(simple), expected);
  EXPECT_EQ(MeanFocalLength(simple), 300.0);
  EXPECT_EQ(FocalLengthIndices(simple), (std::vector<int>{0}));
  EXPECT_EQ(PrincipalPointIndices(simple), (std::vector<int>{1, 2}));
  EXPECT_EQ(ExtraParamIndices(simple), (std::vector<int>{3}));
  EXPECT_EQ(FocalLengthIndices(opencv), (std::vector<int>{0, 1}));
  EXPECT_EQ(ExtraParamIndices(opencv), (std::vector<int>{4, 5, 6, 7}));
}

TEST(CameraModels, KnownProjectionsMatchOpenCV) {
  // Reference pixels from cv::projectPoints and cv::fisheye::projectPoints
  // (OpenCV 4.6) with zero rvec/tvec and the same intrinsics.
  const Camera opencv = EurocOpenCV();
  EXPECT_LT((*Project(opencv, Eigen::Vector3d(0.3, -0.2, 1.5)) -
             Eigen::Vector2d(457.462762288115, 188.393389741685))
                .norm(),
            1e-9);
  EXPECT_LT((*Project(opencv, Eigen::Vector3d(-1.1, 0.7, 2.0)) -
             Eigen::Vector2d(141.943826629234, 391.344737423854))
                .norm(),
            1e-9);
  const Camera fisheye = TumFisheye();
  EXPECT_LT((*Project(fisheye, Eigen::Vector3d(0.3, -0.2, 1.5)) -
             Eigen::Vector2d(292.423608586207, 231.903517859756))
                .norm(),
            1e-9);
  EXPECT_LT((*Project(fisheye, Eigen::Vector3d(-1.1, 0.7, 0.4)) -
             Eigen::Vector2d(49.767191241241, 387.453145150400))
                .norm(),
            1e-9);
  // By hand: SIMPLE_RADIAL f=100, c=(50, 40), k=0.1; (u, v) = (0.5, -0.25):
  // r^2 = 0.3125, factor 1.03125 -> (50 + 51.5625, 40 - 25.78125).
  const Camera simple_radial =
      MakeCamera(CameraModelId::kSimpleRadial, 100, 100, {100, 50, 40, 0.1});
  EXPECT_LT(
      (CamToImage(simple_radial, Eigen::Vector2d(0.5, -0.25)) - Eigen::Vector2d(101.5625, 14.21875))
          .norm(),
      1e-12);
  // The optical axis projects to the principal point for every model.
  for (const Camera& camera : TestCameras()) {
    const Eigen::Matrix3d k = CalibrationMatrix(camera);
    EXPECT_LT(
        (*Project(camera, Eigen::Vector3d(0, 0, 2)) - Eigen::Vector2d(k(0, 2), k(1, 2))).norm(),
        1e-12)
        << camera.ModelName();
  }
}

TEST(CameraModels, ProjectRejectsPointsBehindCamera) {
  for (const Camera& camera : TestCameras()) {
    EXPECT_FALSE(Project(camera, Eigen::Vector3d(0.1, 0.2, -1.0)).has_value());
    EXPECT_FALSE(Project(camera, Eigen::Vector3d(0.1, 0.2, 0.0)).has_value());
    EXPECT_TRUE(Project(camera, Eigen::Vector3d(0.1, 0.2, 1.0)).has_value());
  }
}

TEST(CameraModels, ProjectUnprojectConsistentOverWholeImage) {
  for (const Camera& camera : TestCameras()) {
    constexpr int kSteps = 40;
    int in_front = 0;
    int behind = 0;
    double max_error = 0.0;
    for (int i = 0; i <= kSteps; ++i) {
      for (int j = 0; j <= kSteps; ++j) {
        const Eigen::Vector2d pixel(static_cast<double>(camera.width - 1) * i / kSteps,
                                    static_cast<double>(camera.height - 1) * j / kSteps);
        const Eigen::Vector3d ray = Unproject(camera, pixel);
        EXPECT_NEAR(ray.norm(), 1.0, 1e-14);
        if (ray.z() > 1e-6) {
          const auto reprojected = Project(camera, ray);
          ASSERT_TRUE(reprojected.has_value());
          max_error = std::max(max_error, (*reprojected - pixel).norm());
          // Same through normalised coordinates.
          const Eigen::Vector2d normalized = ImageToCam(camera, pixel);
          max_error = std::max(max_error, (CamToImage(camera, normalized) - pixel).norm());
          EXPECT_LT((normalized.homogeneous().normalized() - ray).norm(), 1e-12);
          ++in_front;
        } else {
          // Only the fisheye sees beyond 90 degrees.
          EXPECT_EQ(camera.model_id, CameraModelId::kOpenCVFisheye);
          EXPECT_FALSE(Project(camera, ray).has_value());
          EXPECT_TRUE(ImageToCam(camera, pixel).hasNaN());
          ++behind;
        }
      }
    }
    EXPECT_LT(max_error, 1e-9) << camera.ModelName();
    // The fisheye's image corners are ~108 degrees off axis.
    EXPECT_GT(in_front, (kSteps + 1) * (kSteps + 1) * 3 / 4) << camera.ModelName();
    if (camera.model_id == CameraModelId::kOpenCVFisheye) {
      EXPECT_GT(behind, 0);
    }
  }
}

TEST(CameraModels, UnprojectRecoversRayDirection) {
  Random random(31);
  for (const Camera& camera : TestCameras()) {
    for (int i = 0; i < 500; ++i) {
      // A point whose projection lands in the image.
      const Eigen::Vector2d pixel(random.Uniform(0, camera.width - 1),
                                  random.Uniform(0, camera.height - 1));
      const Eigen::Vector3d ray = Unproject(camera, pixel);
      if (ray.z() < 1e-3) continue;
      const Eigen::Vector3d point = random.Uniform(0.5, 30.0) * ray;
      const auto projected = Project(camera, point);
      ASSERT_TRUE(projected.has_value());
      EXPECT_LT((*projected - pixel).norm(), 1e-9) << camera.ModelName();
      EXPECT_LT((Unproject(camera, *projected) - point.normalized()).norm(), 1e-12);
    }
  }
}

TEST(CameraModels, DistortUndistortRoundTrip) {
  Random random(32);
  for (const Camera& camera : TestCameras()) {
    for (int i = 0; i < 500; ++i) {
      const Eigen::Vector2d undistorted(random.Uniform(-0.9, 0.9), random.Uniform(-0.6, 0.6));
      const Eigen::Vector2d distorted = Distort(camera, undistorted);
      EXPECT_LT((Undistort(camera, distorted) - undistorted).norm(), 1e-12) << camera.ModelName();
    }
    EXPECT_EQ(Undistort(camera, Eigen::Vector2d::Zero()), Eigen::Vector2d::Zero());
  }
}

// Test points: in front of the camera, spread over the image, and the axis.
std::vector<Eigen::Vector3d> JacobianTestPoints(const Camera& camera, Random& random) {
  std::vector<Eigen::Vector3d> points = {Eigen::Vector3d(0, 0, 2), Eigen::Vector3d(1e-9, 0, 1)};
  while (points.size() < 100) {
    const Eigen::Vector2d pixel(random.Uniform(0, camera.width - 1),
                                random.Uniform(0, camera.height - 1));
    const Eigen::Vector3d ray = Unproject(camera, pixel);
    if (ray.z() < 0.2) continue;
    points.push_back(random.Uniform(0.5, 10.0) * ray);
  }
  return points;
}

// Relative difference of two matrices, with an absolute floor.
double RelativeDifference(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).norm() / std::max(1.0, b.norm());
}

TEST(CameraModels, AnalyticJacobiansMatchFiniteDifferences) {
  Random random(33);
  for (const Camera& camera : TestCameras()) {
    for (const Eigen::Vector3d& point : JacobianTestPoints(camera, random)) {
      // d pixel / d point.
      Eigen::Matrix<double, 2, 3> numeric_point;
      const double point_step = 1e-6 * point.norm();
      for (int j = 0; j < 3; ++j) {
        const Eigen::Vector3d delta = point_step * Eigen::Vector3d::Unit(j);
        numeric_point.col(j) =
            (*Project(camera, point + delta) - *Project(camera, point - delta)) / (2 * point_step);
      }
      EXPECT_LT(RelativeDifference(ProjectJacobianWrtPoint(camera, point), numeric_point), 1e-6)
          << camera.ModelName() << " " << point.transpose();

      // d pixel / d params.
      const Eigen::MatrixXd analytic_params = ProjectJacobianWrtParams(camera, point);
      ASSERT_EQ(analytic_params.cols(), static_cast<Eigen::Index>(camera.params.size()));
      Eigen::MatrixXd numeric_params(2, camera.params.size());
      for (size_t j = 0; j < camera.params.size(); ++j) {
        const double step = 1e-6 * std::max(1.0, std::abs(camera.params[j]));
        Camera plus = camera;
        Camera minus = camera;
        plus.params[j] += step;
        minus.params[j] -= step;
        numeric_params.col(j) = (*Project(plus, point) - *Project(minus, point)) / (2 * step);
      }
      EXPECT_LT(RelativeDifference(analytic_params, numeric_params), 1e-6)
          << camera.ModelName() << " " << point.transpose();

      // d distorted / d undistorted.
      const Eigen::Vector2d undistorted = point.hnormalized();
      Eigen::Matrix2d numeric_distort;
      constexpr double kStep = 1e-6;
      for (int j = 0; j < 2; ++j) {
        const Eigen::Vector2d delta = kStep * Eigen::Vector2d::Unit(j);
        numeric_distort.col(j) =
            (Distort(camera, undistorted + delta) - Distort(camera, undistorted - delta)) /
            (2 * kStep);
      }
      EXPECT_LT(RelativeDifference(DistortJacobian(camera, undistorted), numeric_distort), 1e-6)
          << camera.ModelName();
    }
  }
}

// The templated Project with Jets gives the same values and derivatives as
// the analytic Jacobians (as a Ceres AutoDiff cost functor would see them).
template <typename Model>
void CheckJetProjection(const Camera& camera, const std::vector<Eigen::Vector3d>& points) {
  constexpr int kNumParams = Model::kNumParams();
  using Jet = ceres::Jet<double, 3 + kNumParams>;
  for (const Eigen::Vector3d& point : points) {
    Jet point_jet[3];
    Jet params_jet[kNumParams];
    for (int i = 0; i < 3; ++i) point_jet[i] = Jet(point[i], i);
    for (int i = 0; i < kNumParams; ++i) params_jet[i] = Jet(camera.params[i], 3 + i);
    Jet pixel[2];
    Model::Project(params_jet, point_jet, pixel);
    const Eigen::Vector2d expected = *Project(camera, point);
    const Eigen::Matrix<double, 2, 3> d_point = ProjectJacobianWrtPoint(camera, point);
    const Eigen::MatrixXd d_params = ProjectJacobianWrtParams(camera, point);
    for (int r = 0; r < 2; ++r) {
      EXPECT_NEAR(pixel[r].a, expected[r], 1e-9);
      for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(pixel[r].v[c], d_point(r, c), 1e-9 * std::max(1.0, std::abs(d_point(r, c))));
      }
      for (int c = 0; c < kNumParams; ++c) {
        EXPECT_NEAR(pixel[r].v[3 + c], d_params(r, c),
                    1e-9 * std::max(1.0, std::abs(d_params(r, c))))
            << camera.ModelName() << " param " << c;
      }
    }
  }
}

TEST(CameraModels, TemplatedProjectionWorksWithJets) {
  Random random(34);
  for (const Camera& camera : TestCameras()) {
    const std::vector<Eigen::Vector3d> points = JacobianTestPoints(camera, random);
    VisitCameraModel(camera.model_id, [&](auto model) {
      CheckJetProjection<decltype(model)>(camera, points);
      return 0;
    });
  }
  // Exactly on the optical axis, the fisheye's derivatives are finite.
  const Camera fisheye = TumFisheye();
  CheckJetProjection<OpenCVFisheyeModel>(fisheye, {Eigen::Vector3d(0, 0, 1)});
}

TEST(CameraModels, UndistortionIsRobustFarOutsideTheImage) {
  // Beyond the invertible range the result is finite (best estimate), not NaN.
  const Camera camera = MakeCamera(CameraModelId::kSimpleRadial, 752, 480, {458.0, 367, 248, -0.3});
  const Eigen::Vector2d normalized = ImageToCam(camera, Eigen::Vector2d(5000, 5000));
  EXPECT_TRUE(normalized.allFinite());
  // The fisheye at exactly 90 degrees and beyond: the ray is still defined.
  const Camera fisheye = TumFisheye();
  const Eigen::Vector3d sideways =
      Unproject(fisheye, *Project(fisheye, Eigen::Vector3d(1, 0, 1e-3)));
  EXPECT_LT((sideways - Eigen::Vector3d(1, 0, 1e-3).normalized()).norm(), 1e-9);
}

}  // namespace
}  // namespace viosfm

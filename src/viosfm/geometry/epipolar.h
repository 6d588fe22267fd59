// Epipolar geometry: essential and fundamental matrices from a relative pose,
// and the point-to-epipolar-line errors used to verify correspondences.
//
// Convention: for a point seen at normalised coordinates x1 in camera 1 and
// x2 in camera 2, x2^T E x1 = 0; with pixels, x2^T F x1 = 0.
#pragma once

#include <Eigen/Core>

#include "viosfm/geometry/rigid3.h"

namespace viosfm {

// E = [t]x R for cam2_from_cam1 = (R, t).
Eigen::Matrix3d EssentialFromRelativePose(const Rigid3d& cam2_from_cam1);

// F = K2^-T E K1^-1 for calibration matrices K1 (camera 1) and K2 (camera 2).
Eigen::Matrix3d FundamentalFromEssential(const Eigen::Matrix3d& essential,
                                         const Eigen::Matrix3d& calibration1,
                                         const Eigen::Matrix3d& calibration2);

Eigen::Matrix3d FundamentalFromRelativePose(const Rigid3d& cam2_from_cam1,
                                            const Eigen::Matrix3d& calibration1,
                                            const Eigen::Matrix3d& calibration2);

// Distance (pixels) of x2 from the epipolar line F * x1 in image 2: the
// paper's epipolar error EE (eq. 1). Invariant to the scale and sign of F.
// Infinity when the line is undefined (x1 at the epipole of image 1).
double EpipolarLineDistance(const Eigen::Matrix3d& fundamental, const Eigen::Vector2d& x1,
                            const Eigen::Vector2d& x2);

// Mean of the two point-to-line distances (pixels): x2 to F x1 and x1 to F^T x2.
double SymmetricEpipolarDistance(const Eigen::Matrix3d& fundamental, const Eigen::Vector2d& x1,
                                 const Eigen::Vector2d& x2);

// Squared Sampson error (pixels^2), the first-order geometric error:
// (x2^T F x1)^2 / ((F x1)_0^2 + (F x1)_1^2 + (F^T x2)_0^2 + (F^T x2)_1^2).
// Infinity if the denominator is zero.
double SampsonError(const Eigen::Matrix3d& fundamental, const Eigen::Vector2d& x1,
                    const Eigen::Vector2d& x2);

// The 3x3 matrix whose rows are entries[0..2], [3..5], [6..8]: the null
// vector of a linear epipolar system as a matrix.
Eigen::Matrix3d Matrix3FromRowMajor(const Eigen::Ref<const Eigen::VectorXd>& entries);

}  // namespace viosfm

// Closed-form least-squares alignment of corresponding point sets.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "viosfm/geometry/sim3.h"

namespace viosfm {

// Umeyama (IEEE PAMI 1991): the similarity dst_from_src minimising
// sum_i |dst_i - (s R src_i + t)|^2, with s = 1 (an SE(3)) unless with_scale.
// R is the rotation of the SVD U S V^T of the cross-covariance
// (1/n) sum (dst_i - mean_dst)(src_i - mean_src)^T, with S = diag(1, 1, -1)
// when det(U) det(V) < 0 so that R is never a reflection; the scale is
// trace(D S) / var(src) (eq. 40-42). Returns nullopt when the sizes differ,
// there are fewer than 3 points, or the points are (nearly) collinear
// (second singular value of the cross-covariance below 1e-12 of the first).
std::optional<Sim3d> AlignPointsUmeyama(const std::vector<Eigen::Vector3d>& src,
                                        const std::vector<Eigen::Vector3d>& dst, bool with_scale);

// Position + yaw (4 DoF) alignment for trajectories whose z axes are both
// aligned with gravity: the rotation is about z only, the scale is 1. With
// centred points a_i = src_i - mean_src and b_i = dst_i - mean_dst, the yaw
// maximising sum b_i . Rz(yaw) a_i is atan2(sum (b_y a_x - b_x a_y),
// sum (b_x a_x + b_y a_y)); t = mean_dst - Rz mean_src. Returns nullopt when
// the sizes differ, there are fewer than 2 points, or the horizontal
// cross-covariance vanishes (no yaw information).
std::optional<Sim3d> AlignPointsPositionYaw(const std::vector<Eigen::Vector3d>& src,
                                            const std::vector<Eigen::Vector3d>& dst);

}  // namespace viosfm

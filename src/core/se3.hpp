// SPDX-License-Identifier: MIT
// Rigid motions as the pose graph reads them: the exponential and logarithm of SE(3) and the inverse of its right
// Jacobian, with xi = (rotation [rad], translation part) rotation first, as kissm_result.information orders it.
// Exp(xi) = [Exp_SO3(w), J_l(w) v]; the right Jacobian J_r(xi) is the one with Exp(xi + d) ~ Exp(xi) Exp(J_r d)
// (Barfoot, "State Estimation for Robotics", section 7.1.5, reordered rotation first).
#pragma once

#include <Eigen/Core>

#include "detail_namespace.hpp"

KISSM_DETAIL_BEGIN

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

struct Rigid {
    Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
    Eigen::Vector3d t = Eigen::Vector3d::Zero();

    Rigid operator*(const Rigid &o) const { return {R * o.R, R * o.t + t}; }
    Rigid inverse() const { return {R.transpose(), -(R.transpose() * t)}; }
};

Rigid se3_exp(const Vector6d &xi);
Vector6d se3_log(const Rigid &T);
// J_r(xi)^-1: Log(Exp(xi) Exp(d)) ~ xi + J_r(xi)^-1 d.
Matrix6d se3_right_jacobian_inverse(const Vector6d &xi);
// The adjoint of T on xi (rotation first): T Exp(xi) inv(T) = Exp(Ad(T) xi).
Matrix6d se3_adjoint(const Rigid &T);

KISSM_DETAIL_END

// SPDX-License-Identifier: MIT
#include "se3.hpp"

#include <cmath>

#include <Eigen/Geometry>

KISSM_DETAIL_BEGIN

namespace {

Eigen::Matrix3d hat(const Eigen::Vector3d &v) {
    Eigen::Matrix3d m;
    m << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
    return m;
}

// Below this angle the closed forms lose digits to cancellation: their Taylor series are used instead, exact to
// far below double precision there.
constexpr double kSmallAngle = 1e-4;

Eigen::Matrix3d so3_exp(const Eigen::Vector3d &w) {
    const double theta = w.norm();
    const Eigen::Matrix3d W = hat(w);
    if (theta < kSmallAngle) return Eigen::Matrix3d::Identity() + W + 0.5 * W * W;
    return Eigen::Matrix3d::Identity() + (std::sin(theta) / theta) * W +
           ((1.0 - std::cos(theta)) / (theta * theta)) * W * W;
}

Eigen::Vector3d so3_log(const Eigen::Matrix3d &R) {
    // The axis-angle from Eigen's quaternion: stable near 0 and near pi, where the trace formula is not.
    const Eigen::AngleAxisd aa(Eigen::Quaterniond(R).normalized());
    return aa.angle() * aa.axis();
}

// SO(3)'s left Jacobian J_l(w) and its inverse.
Eigen::Matrix3d so3_left_jacobian(const Eigen::Vector3d &w) {
    const double theta = w.norm();
    const Eigen::Matrix3d W = hat(w);
    if (theta < kSmallAngle) return Eigen::Matrix3d::Identity() + 0.5 * W + (1.0 / 6.0) * W * W;
    const double t2 = theta * theta;
    return Eigen::Matrix3d::Identity() + ((1.0 - std::cos(theta)) / t2) * W +
           ((theta - std::sin(theta)) / (t2 * theta)) * W * W;
}

Eigen::Matrix3d so3_left_jacobian_inverse(const Eigen::Vector3d &w) {
    const double theta = w.norm();
    const Eigen::Matrix3d W = hat(w);
    if (theta < kSmallAngle) return Eigen::Matrix3d::Identity() - 0.5 * W + (1.0 / 12.0) * W * W;
    // (1 + cos) / sin = cot(theta / 2): finite up to theta = pi, where the plain ratio is 0 / 0.
    const double c = 1.0 / (theta * theta) - std::cos(0.5 * theta) / (2.0 * theta * std::sin(0.5 * theta));
    // W W = w w^T - theta^2 I: an outer product rather than a 3x3 product (every logarithm comes through here).
    Eigen::Matrix3d out = (c * w) * w.transpose() - 0.5 * W;
    out.diagonal().array() += 1.0 - c * theta * theta;
    return out;
}

// The coupling block Q(w, v) of SE(3)'s left Jacobian [[J_l(w), 0], [Q, J_l(w)]] (rotation first):
// Q = V / 2 + a (P V + V P + P V P) + b (P P V + V P P - 3 P V P) + c (P V P P + P P V P) with P = hat(w),
// V = hat(v) (Barfoot's series summed). The products of hat matrices reduce to outer products (P w = 0, and with
// d = w.v, u = w x v: P V = v w^T - d I, P V P = -d P, P P V = u w^T - d P, V P P = -w u^T - d P, P P = w w^T -
// |w|^2 I), so Q is assembled from a few rank-one terms: the pose graph's normal equations form one per edge and
// step, and the seventeen 3x3 products of the literal formula were a tenth of a solve's instructions.
Eigen::Matrix3d se3_q(const Eigen::Vector3d &w, const Eigen::Vector3d &v) {
    const double theta = w.norm();
    double a, b, c;
    if (theta < kSmallAngle) {
        // Series of the three coefficients below at theta = 0.
        const double t2 = theta * theta;
        a = 1.0 / 6.0 - t2 / 120.0;
        b = 1.0 / 24.0 - t2 / 720.0;
        c = 1.0 / 120.0 - t2 / 2520.0;
    } else {
        const double t2 = theta * theta, t3 = t2 * theta, t4 = t2 * t2, t5 = t4 * theta;
        const double s = std::sin(theta), co = std::cos(theta);
        a = (theta - s) / t3;
        b = (t2 + 2.0 * co - 2.0) / (2.0 * t4);
        c = (2.0 * theta - 3.0 * s + theta * co) / (2.0 * t5);
    }
    const double d = w.dot(v);
    const Eigen::Vector3d u = w.cross(v);
    // a (v w^T + w v^T - 2 d I - d P) + b (u w^T - w u^T + d P) - 2 c d (w w^T - theta^2 I), plus V / 2.
    const Eigen::Vector3d av = a * v, bu = b * u, cw = (2.0 * c * d) * w;
    const double diagonal = 2.0 * d * (c * theta * theta - a), skew = d * (b - a);
    Eigen::Matrix3d q = (av + bu) * w.transpose() + w * (av - bu - cw).transpose();
    q.diagonal().array() += diagonal;
    const Eigen::Vector3d k = skew * w + 0.5 * v; // skew P + V / 2 = hat(skew w + v / 2)
    q(0, 1) -= k.z(), q(0, 2) += k.y(), q(1, 0) += k.z(), q(1, 2) -= k.x(), q(2, 0) -= k.y(), q(2, 1) += k.x();
    return q;
}

} // namespace

Rigid se3_exp(const Vector6d &xi) {
    const Eigen::Vector3d w = xi.head<3>(), v = xi.tail<3>();
    return {so3_exp(w), so3_left_jacobian(w) * v};
}

Vector6d se3_log(const Rigid &T) {
    const Eigen::Vector3d w = so3_log(T.R);
    Vector6d xi;
    xi << w, so3_left_jacobian_inverse(w) * T.t;
    return xi;
}

Matrix6d se3_right_jacobian_inverse(const Vector6d &xi) {
    // J_r(xi) = J_l(-xi); with J_l = [[J, 0], [Q, J]] its inverse is [[J^-1, 0], [-J^-1 Q J^-1, J^-1]].
    const Eigen::Vector3d w = -xi.head<3>(), v = -xi.tail<3>();
    const Eigen::Matrix3d Ji = so3_left_jacobian_inverse(w);
    Matrix6d out = Matrix6d::Zero();
    out.topLeftCorner<3, 3>() = Ji;
    out.bottomRightCorner<3, 3>() = Ji;
    out.bottomLeftCorner<3, 3>() = -Ji * se3_q(w, v) * Ji;
    return out;
}

Matrix6d se3_adjoint(const Rigid &T) {
    Matrix6d out = Matrix6d::Zero();
    out.topLeftCorner<3, 3>() = T.R;
    out.bottomRightCorner<3, 3>() = T.R;
    out.bottomLeftCorner<3, 3>() = hat(T.t) * T.R;
    return out;
}

KISSM_DETAIL_END

// SPDX-License-Identifier: MIT
// Small rigid-transform helpers shared by the command-line tool and the simulator (header-only, no dependency).
// Conventions match kissm.h: 4x4 transforms are row-major doubles and map source points into the target
// frame, p_target = R p_source + t.
#pragma once

#include <cmath>
#include <cstddef>

namespace kissm_pose {

constexpr double kPi = 3.14159265358979323846;

inline double deg_to_rad(double deg) { return deg * (kPi / 180.0); }
inline double rad_to_deg(double rad) { return rad * (180.0 / kPi); }

// A rigid pose: p_parent = R p_local + t, R row-major.
struct Pose {
    double R[9];
    double t[3];
};

inline Pose pose_identity() { return Pose{{1, 0, 0, 0, 1, 0, 0, 0, 1}, {0, 0, 0}}; }

// R = Rz(yaw) * Ry(pitch) * Rx(roll), angles in radians.
inline Pose pose_from_ypr(double yaw, double pitch, double roll, double x, double y, double z) {
    const double cy = std::cos(yaw), sy = std::sin(yaw);
    const double cp = std::cos(pitch), sp = std::sin(pitch);
    const double cr = std::cos(roll), sr = std::sin(roll);
    return Pose{{cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr, //
                 sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr, //
                 -sp, cp * sr, cp * cr},
                {x, y, z}};
}

// a * b: first b, then a.
inline Pose pose_compose(const Pose &a, const Pose &b) {
    Pose out{};
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            out.R[3 * i + j] = a.R[3 * i + 0] * b.R[0 + j] + a.R[3 * i + 1] * b.R[3 + j] + a.R[3 * i + 2] * b.R[6 + j];
        }
        out.t[i] = a.R[3 * i + 0] * b.t[0] + a.R[3 * i + 1] * b.t[1] + a.R[3 * i + 2] * b.t[2] + a.t[i];
    }
    return out;
}

inline Pose pose_inverse(const Pose &a) {
    Pose out{};
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) out.R[3 * i + j] = a.R[3 * j + i];
    }
    for (int i = 0; i < 3; ++i) {
        out.t[i] = -(out.R[3 * i + 0] * a.t[0] + out.R[3 * i + 1] * a.t[1] + out.R[3 * i + 2] * a.t[2]);
    }
    return out;
}

inline void pose_to_matrix(const Pose &p, double T[16]) {
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) T[4 * i + j] = p.R[3 * i + j];
        T[4 * i + 3] = p.t[i];
    }
    T[12] = 0.0;
    T[13] = 0.0;
    T[14] = 0.0;
    T[15] = 1.0;
}

inline Pose pose_from_matrix(const double T[16]) {
    Pose p{};
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) p.R[3 * i + j] = T[4 * i + j];
        p.t[i] = T[4 * i + 3];
    }
    return p;
}

inline void transform_point(const double T[16], const double p[3], double out[3]) {
    for (int i = 0; i < 3; ++i) {
        out[i] = T[4 * i + 0] * p[0] + T[4 * i + 1] * p[1] + T[4 * i + 2] * p[2] + T[4 * i + 3];
    }
}

inline bool matrix_is_finite(const double T[16]) {
    for (int i = 0; i < 16; ++i) {
        if (!std::isfinite(T[i])) return false;
    }
    return true;
}

// Angle of the rotation R (upper-left 3x3 of T), degrees, in [0, 180].
inline double rotation_angle_deg(const double T[16]) {
    double c = (T[0] + T[5] + T[10] - 1.0) * 0.5;
    c = c > 1.0 ? 1.0 : (c < -1.0 ? -1.0 : c);
    return rad_to_deg(std::acos(c));
}

// Angle of A_R^T B_R in degrees: the rotation error between two transforms.
inline double rotation_error_deg(const double A[16], const double B[16]) {
    double trace = 0.0;
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) trace += A[4 * i + j] * B[4 * i + j];
    }
    double c = (trace - 1.0) * 0.5;
    c = c > 1.0 ? 1.0 : (c < -1.0 ? -1.0 : c);
    return rad_to_deg(std::acos(c));
}

inline double translation_error(const double A[16], const double B[16]) {
    const double dx = A[3] - B[3], dy = A[7] - B[7], dz = A[11] - B[11];
    return std::sqrt(dx * dx + dy * dy + dz * dz);
}

inline double translation_norm(const double T[16]) { return std::sqrt(T[3] * T[3] + T[7] * T[7] + T[11] * T[11]); }

// Inverse of pose_from_ypr's rotation (Z-Y-X Euler angles), degrees.
inline void yaw_pitch_roll_deg(const double T[16], double *yaw, double *pitch, double *roll) {
    double s = -T[8];
    s = s > 1.0 ? 1.0 : (s < -1.0 ? -1.0 : s);
    *pitch = rad_to_deg(std::asin(s));
    *yaw = rad_to_deg(std::atan2(T[4], T[0]));
    *roll = rad_to_deg(std::atan2(T[9], T[10]));
}

} // namespace kissm_pose

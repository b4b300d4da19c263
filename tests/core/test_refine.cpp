// SPDX-License-Identifier: MIT
// Stage 6 (refine_pose) on synthetic scenes with exact planes and exact normals, independent of the
// normals stage: convergence to a known pose in both modes, the same bits at any thread count and with or
// without the index's cell hash, the information matrix against an independent sum of w J^T n n^T J (the
// point-to-plane term in both modes) with J taken by finite differences of the right perturbation T exp(xi)
// (in the source's local frame and, moved by information_in_caller_frame, in a caller's frame), the slide
// direction of a corridor and a plane as the null direction with a small condition, the overlap against brute
// force, clouds that never meet, and the validity rules that read these numbers.
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "core/refine.hpp"
#include "core/refine_index.hpp"
#include "core/validity.hpp"
#include "harness.h"
#include "test_rng.hpp"

using namespace kissm::detail;

namespace {

using Vector6d = Eigen::Matrix<double, 6, 1>;
constexpr double kPi = 3.14159265358979323846;

struct Scene {
    std::vector<Vec3f> points;
    Normals normals;
    void push(const Vec3d &p, const Vec3d &n) {
        points.push_back(p.cast<float>());
        normals.normal.push_back(n.normalized().cast<float>());
        normals.valid.push_back(1);
    }
    RefineCloud cloud() const { return RefineCloud{&points, &normals}; }
};

// A rectangle o + s u + r v (s, r in [0, 1]) sampled on a grid of about `step` metres, shifted by `phase`
// cells (0 to 1): two phases are two samplings of the same surface. Never on the rectangle's edges, so no
// point lies on two faces of a box.
void rect(Scene &s, const Vec3d &o, const Vec3d &u, const Vec3d &v, double step, double phase) {
    const int nu = std::max(1, static_cast<int>(std::lround(u.norm() / step)));
    const int nv = std::max(1, static_cast<int>(std::lround(v.norm() / step)));
    const Vec3d n = u.cross(v);
    for (int i = 0; i < nu; ++i)
        for (int j = 0; j < nv; ++j)
            s.push(o + ((i + 0.25 + 0.5 * phase) / nu) * u + ((j + 0.25 + 0.5 * phase) / nv) * v, n);
}

// A closed room 8 m x 5 m x 3 m (every direction constrained) with a box and a slanted panel inside, so
// that no symmetry is left.
Scene room(double step, double phase) {
    Scene s;
    const Vec3d X(8, 0, 0), Y(0, 5, 0), Z(0, 0, 3), o(-4, -2.5, -1.5);
    rect(s, o, X, Y, step, phase);     // floor
    rect(s, o + Z, X, Y, step, phase); // ceiling
    rect(s, o, X, Z, step, phase);     // walls
    rect(s, o + Y, X, Z, step, phase);
    rect(s, o, Y, Z, step, phase);
    rect(s, o + X, Y, Z, step, phase);
    const Vec3d b(1.0, 0.5, -1.5), bx(1.2, 0, 0), by(0, 0.8, 0), bz(0, 0, 1.0);
    rect(s, b, bx, bz, step, phase);
    rect(s, b + by, bx, bz, step, phase);
    rect(s, b, by, bz, step, phase);
    rect(s, b + bx, by, bz, step, phase);
    rect(s, b + bz, bx, by, step, phase);
    rect(s, Vec3d(-3.0, -2.0, -1.5), Vec3d(1.5, 0.5, 0.0), Vec3d(0.3, 0.0, 1.8), step, phase);
    return s;
}

// A corridor along x: floor and two side walls, open at both ends (the pose slides along x).
Scene corridor(double step, double phase) {
    Scene s;
    const Vec3d o(-10, -1.5, 0), X(20, 0, 0), Y(0, 3, 0), Z(0, 0, 2.5);
    rect(s, o, X, Y, step, phase);
    rect(s, o, X, Z, step, phase);
    rect(s, o + Y, X, Z, step, phase);
    return s;
}

// A tunnel along x: a cylinder of radius 2 about the line through `axis_point` (slides along x and turns about
// its axis).
Scene tunnel(double step, double phase, const Vec3d &axis_point) {
    Scene s;
    const int around = static_cast<int>(std::lround(2.0 * kPi * 2.0 / step));
    const int along = static_cast<int>(std::lround(20.0 / step));
    for (int i = 0; i < along; ++i)
        for (int j = 0; j < around; ++j) {
            const double a = 2.0 * kPi * (j + 0.5 * phase) / around;
            const Vec3d radial(0.0, std::cos(a), std::sin(a));
            s.push(axis_point + Vec3d(-10.0 + step * (i + 0.25 + 0.5 * phase), 0, 0) + 2.0 * radial, -radial);
        }
    return s;
}

Scene plane(double step, double phase) {
    Scene s;
    rect(s, Vec3d(-8, -8, 0), Vec3d(16, 0, 0), Vec3d(0, 16, 0), step, phase);
    return s;
}

// The same surfaces seen from the source: a = R^T (b - t), normals R^T n.
Scene to_source(const Scene &target, const Eigen::Matrix3d &R, const Eigen::Vector3d &t) {
    Scene s;
    for (std::size_t i = 0; i < target.points.size(); ++i)
        s.push(R.transpose() * (target.points[i].cast<double>() - t),
               R.transpose() * target.normals.normal[i].cast<double>());
    return s;
}

Eigen::Matrix3d rotation(const Vec3d &axis, double degrees) {
    return Eigen::AngleAxisd(degrees * kPi / 180.0, axis.normalized()).toRotationMatrix();
}

double angle_deg(const Eigen::Matrix3d &A, const Eigen::Matrix3d &B) {
    const double c = std::max(-1.0, std::min(1.0, 0.5 * ((A.transpose() * B).trace() - 1.0)));
    return std::acos(c) * 180.0 / kPi;
}

// The truth every scene is placed at: target = R_true source + t_true.
const Eigen::Matrix3d kRtrue = rotation(Vec3d(0.3, -1.0, 0.6), 37.0);
const Eigen::Vector3d kTtrue(1.7, -0.8, 0.35);

RefineParams params_for(RefineMode mode) {
    RefineParams p;
    p.mode = mode;
    p.max_iterations = 50;
    p.max_distance = 1.0;
    p.kernel_scale = 0.3;
    return p;
}

// The index as the pipeline builds it: cells of about the sampling step.
RefineOutput run(const Scene &source, const Scene &target, const Eigen::Matrix3d &R0, const Eigen::Vector3d &t0,
                 const RefineParams &p, int threads, double cell = 0.2) {
    const RefineIndex index(target.points, cell);
    RunContext ctx(threads, nullptr, Hooks());
    return refine_pose(source.cloud(), target.cloud(), index, R0, t0, p, ctx);
}

// ---- An independent evaluation of the cost at a pose -----------------------------------------------------

struct Corr {
    Vec3d a, b;
    Eigen::Matrix3d M;
    double w, r2;
};

// The definition refine.hpp gives for the numbers of the final pose: each source point with a normal, moved by
// (R, t) and rounded to float, to its nearest target point (float squared distance, lowest index on ties)
// within max_distance, kept when that target point has a normal; in both modes the point-to-plane term
// M = n_b n_b^T (GICP's along-plane weights are a regularisation, not information) with the Cauchy weight
// 1 / (1 + r^2 / k^2) of its r^2 = (n_b . e)^2.
std::vector<Corr> correspondences(const Scene &src, const Scene &tgt, const Eigen::Matrix3d &R,
                                  const Eigen::Vector3d &t, const RefineParams &p) {
    const float max_d2 = static_cast<float>(p.max_distance * p.max_distance);
    std::vector<Corr> out;
    for (std::size_t i = 0; i < src.points.size(); ++i) {
        if (!src.normals.valid[i]) continue;
        const Vec3f q = (R * src.points[i].cast<double>() + t).cast<float>();
        std::size_t best = tgt.points.size();
        float best_d2 = max_d2;
        for (std::size_t j = 0; j < tgt.points.size(); ++j) {
            const float dx = tgt.points[j].x() - q.x(), dy = tgt.points[j].y() - q.y(), dz = tgt.points[j].z() - q.z();
            const float d2 = dx * dx + dy * dy + dz * dz;
            if (d2 < best_d2 || (d2 == best_d2 && best == tgt.points.size())) best = j, best_d2 = d2;
        }
        if (best == tgt.points.size() || !tgt.normals.valid[best]) continue;
        Corr c;
        c.a = src.points[i].cast<double>();
        c.b = tgt.points[best].cast<double>();
        const Vec3d nb = tgt.normals.normal[best].cast<double>();
        c.M = nb * nb.transpose();
        const Vec3d e = c.b - (R * c.a + t);
        c.r2 = e.dot(c.M * e);
        c.w = 1.0 / (1.0 + c.r2 / (p.kernel_scale * p.kernel_scale));
        out.push_back(c);
    }
    return out;
}

// sum w J^T M J where J = d e / d xi of e(xi) = b' - T' exp(xi) a' by central differences, for the pose T'
// = (R, t') and points a' = a + os, b' = b + ot of a frame whose origins are os (source) and ot (target).
Matrix6d information_by_differences(const std::vector<Corr> &corr, const Eigen::Matrix3d &R,
                                    const Eigen::Vector3d &t_local, const Vec3d &os, const Vec3d &ot) {
    const Vec3d t = t_local + ot - R * os;
    auto error = [&](const Corr &c, const Vector6d &xi) {
        const Eigen::Matrix3d dR = Eigen::AngleAxisd(xi.head<3>().norm(), xi.head<3>().normalized()).toRotationMatrix();
        const Eigen::Matrix3d E = xi.head<3>().norm() > 0 ? dR : Eigen::Matrix3d::Identity();
        return Vec3d((c.b + ot) - (R * (E * (c.a + os) + xi.tail<3>()) + t));
    };
    const double h = 1e-6;
    Matrix6d H = Matrix6d::Zero();
    for (const Corr &c : corr) {
        Eigen::Matrix<double, 3, 6> J;
        for (int k = 0; k < 6; ++k) {
            Vector6d d = Vector6d::Zero();
            d[k] = h;
            J.col(k) = (error(c, d) - error(c, -d)) / (2.0 * h);
        }
        H += c.w * J.transpose() * c.M * J;
    }
    return H;
}

double rel_diff(const Matrix6d &a, const Matrix6d &b) { return (a - b).norm() / std::max(b.norm(), 1e-300); }

bool same_bits(const RefineOutput &a, const RefineOutput &b) {
    return std::memcmp(a.rotation.data(), b.rotation.data(), 9 * sizeof(double)) == 0 &&
           std::memcmp(a.translation.data(), b.translation.data(), 3 * sizeof(double)) == 0 &&
           std::memcmp(a.hessian.data(), b.hessian.data(), 36 * sizeof(double)) == 0 &&
           std::memcmp(&a.rmse, &b.rmse, sizeof(double)) == 0 &&
           std::memcmp(&a.weight_sum, &b.weight_sum, sizeof(double)) == 0 &&
           std::memcmp(&a.overlap, &b.overlap, sizeof(double)) == 0 &&
           std::memcmp(&a.condition, &b.condition, sizeof(double)) == 0 && a.iterations == b.iterations &&
           a.converged == b.converged && a.num_correspondences == b.num_correspondences;
}

const RefineMode kModes[] = {RefineMode::Gicp, RefineMode::PointToPlane};
const char *mode_name(RefineMode m) { return m == RefineMode::Gicp ? "GICP" : "point-to-plane"; }

} // namespace

// The same sampling on both sides: at the truth every source point lands on its own target point, so the
// refined pose must be the truth to the float rounding of the clouds.
static void test_converges_to_truth_same_sampling() {
    const Scene target = room(0.2, 0.0);
    const Scene source = to_source(target, kRtrue, kTtrue);
    struct Start {
        Vec3d axis;
        double deg;
        Vec3d shift;
    };
    const Start starts[] = {{Vec3d(1, 0, 0), 2.0, Vec3d(0.1, 0.0, 0.0)},
                            {Vec3d(0, 1, 1), -3.0, Vec3d(-0.15, 0.1, 0.05)},
                            {Vec3d(1, -2, 0.5), 5.0, Vec3d(0.0, -0.2, 0.25)},
                            {Vec3d(0, 0, 1), 0.5, Vec3d(0.3, 0.0, -0.1)}};
    for (const RefineMode mode : kModes) {
        for (const Start &s : starts) {
            // T0 = T_true exp(perturbation), the perturbation in the source frame.
            const Eigen::Matrix3d R0 = kRtrue * rotation(s.axis, s.deg);
            const Eigen::Vector3d t0 = kTtrue + kRtrue * s.shift;
            const RefineOutput o = run(source, target, R0, t0, params_for(mode), 2);
            const double rot = angle_deg(o.rotation, kRtrue), tr = (o.translation - kTtrue).norm();
            CHECK_MSG(rot < 1e-4 && tr < 1e-5, "%s from %.1f deg: %.3g deg, %.3g m off after %d iterations",
                      mode_name(mode), s.deg, rot, tr, o.iterations);
            CHECK_MSG(o.converged && o.iterations >= 2 && o.iterations < 50, "%s: %d iterations, converged %d",
                      mode_name(mode), o.iterations, (int)o.converged);
            CHECK_EQ_INT(o.num_correspondences, source.points.size());
            CHECK_MSG(o.rmse < 1e-5, "rmse %g", o.rmse);
            CHECK(o.overlap == 1.0);
            CHECK_MSG(o.condition > 1e-2 && o.condition <= 1.0, "condition %g", o.condition);
            CHECK_NEAR((o.rotation.transpose() * o.rotation - Eigen::Matrix3d::Identity()).norm(), 0.0, 1e-14);
            CHECK_NEAR(o.rotation.determinant(), 1.0, 1e-14);
        }
    }
    // From the truth itself: one iteration, converged, nothing moved.
    const RefineOutput o = run(source, target, kRtrue, kTtrue, params_for(RefineMode::Gicp), 1);
    CHECK(o.converged);
    CHECK_MSG(o.iterations <= 2, "%d iterations from the truth", o.iterations);
    CHECK(angle_deg(o.rotation, kRtrue) < 1e-4 && (o.translation - kTtrue).norm() < 1e-5);
}

// Two independent samplings with noise: the planes agree at the truth, the points do not.
static void test_converges_with_other_sampling_and_noise() {
    TestRng rng(83);
    const Scene target = room(0.15, 0.0);
    Scene source = to_source(room(0.15, 1.0), kRtrue, kTtrue);
    for (Vec3f &p : source.points)
        p += Vec3f(static_cast<float>(0.005 * rng.normal()), static_cast<float>(0.005 * rng.normal()),
                   static_cast<float>(0.005 * rng.normal()));
    for (const RefineMode mode : kModes) {
        const Eigen::Matrix3d R0 = kRtrue * rotation(Vec3d(2, 1, -1), 4.0);
        const Eigen::Vector3d t0 = kTtrue + Eigen::Vector3d(0.2, -0.25, 0.1);
        const RefineOutput o = run(source, target, R0, t0, params_for(mode), 3);
        const double rot = angle_deg(o.rotation, kRtrue), tr = (o.translation - kTtrue).norm();
        CHECK_MSG(rot < 0.05 && tr < 0.005, "%s: %.4f deg, %.4f m off after %d iterations", mode_name(mode), rot, tr,
                  o.iterations);
        CHECK(o.converged);
        CHECK_MSG(o.rmse > 0.001 && o.rmse < 0.02, "%s: rmse %g", mode_name(mode), o.rmse);
        CHECK(o.overlap > 0.95);
        // The start is worse than the result by a margin.
        CHECK(angle_deg(R0, kRtrue) > 100.0 * rot);
    }
}

static void test_thread_counts_bitwise() {
    TestRng rng(89);
    const Scene target = room(0.12, 0.0);
    Scene source = to_source(room(0.12, 0.5), kRtrue, kTtrue);
    for (Vec3f &p : source.points) p.z() += static_cast<float>(0.003 * rng.normal());
    REQUIRE(source.points.size() > 4 * 1024); // several parallel chunks
    for (const RefineMode mode : kModes) {
        const Eigen::Matrix3d R0 = kRtrue * rotation(Vec3d(1, 1, 1), 3.0);
        const Eigen::Vector3d t0 = kTtrue + Eigen::Vector3d(-0.1, 0.2, 0.05);
        const RefineOutput one = run(source, target, R0, t0, params_for(mode), 1);
        CHECK(one.converged && one.num_correspondences > 4000);
        for (const int threads : {2, 3, 8}) {
            const RefineOutput other = run(source, target, R0, t0, params_for(mode), threads);
            CHECK_MSG(same_bits(one, other), "%s: %d threads differ from 1", mode_name(mode), threads);
        }
        // The index's cell hash is a shortcut to the same answers: without it, or with other cells, the same bits.
        for (const double cell : {0.0, 0.05, 1.0}) {
            const RefineOutput other = run(source, target, R0, t0, params_for(mode), 2, cell);
            CHECK_MSG(same_bits(one, other), "%s: cells of %g m differ", mode_name(mode), cell);
        }
    }
}

// The Gauss-Newton information against finite differences of e(xi) = b - T exp(xi) a, at the final pose,
// with the correspondences, normals and weights found by brute force: the same point-to-plane information
// whichever cost was minimised.
static void test_information_matches_differences() {
    TestRng rng(97);
    const Scene target = room(0.2, 0.0);
    Scene source = to_source(room(0.2, 0.7), kRtrue, kTtrue);
    for (Vec3f &p : source.points) p.x() += static_cast<float>(0.004 * rng.normal());
    for (const RefineMode mode : kModes) {
        const RefineParams p = params_for(mode);
        const RefineOutput o =
            run(source, target, kRtrue * rotation(Vec3d(0, 1, 0), 2.0), kTtrue + Vec3d(0.1, 0, 0), p, 2);
        const std::vector<Corr> corr = correspondences(source, target, o.rotation, o.translation, p);
        CHECK_EQ_INT(o.num_correspondences, corr.size());
        double wsum = 0.0, wr2 = 0.0;
        for (const Corr &c : corr) wsum += c.w, wr2 += c.w * c.r2;
        CHECK_NEAR(o.weight_sum, wsum, 1e-9 * wsum);
        CHECK_NEAR(o.rmse, std::sqrt(wr2 / wsum), 1e-9);

        // Source's local frame.
        const Matrix6d H = information_by_differences(corr, o.rotation, o.translation, Vec3d::Zero(), Vec3d::Zero());
        CHECK_MSG(rel_diff(o.hessian, H) < 1e-6, "%s: hessian off by %g (relative)", mode_name(mode),
                  rel_diff(o.hessian, H));
        CHECK_NEAR((o.hessian - o.hessian.transpose()).norm(), 0.0, 0.0);

        // A caller's frame: the clouds were recentred by os and ot; the information is that of the right
        // perturbation of the caller's pose, divided by the variance it is given (here the a posteriori residual
        // variance sum w r^2 / (sum w - 6); the library gives calibrated_variance).
        const Vec3d os(40.0, -25.0, 12.0), ot(-7.0, 3.0, 100.0);
        const double floor_length = 0.5;
        const double variance = std::max(wr2 / (wsum - 6.0), 1e-6 * floor_length * floor_length);
        // The calibrated variance: kResidualShare (1.4826 median |r|)^2, the median of the brute-force residuals.
        std::vector<double> r;
        for (const Corr &c : corr) r.push_back(std::sqrt(c.r2));
        std::sort(r.begin(), r.end());
        CHECK_NEAR(o.residual_median, r[r.size() / 2], 1e-12);
        const double spread = 1.4826 * r[r.size() / 2];
        CHECK_NEAR(calibrated_variance(o, floor_length), kResidualShare * spread * spread, 1e-9 * spread * spread);
        CHECK(calibrated_variance(o, floor_length) > variance); // more than the a posteriori variance here
        const Matrix6d expected = information_by_differences(corr, o.rotation, o.translation, os, ot) / variance;
        const Matrix6d info = information_in_caller_frame(o, os, variance);
        CHECK_MSG(rel_diff(info, expected) < 1e-6, "%s: caller-frame information off by %g", mode_name(mode),
                  rel_diff(info, expected));
        CHECK(info == info.transpose());
        // Not the same as the local one: the frame change matters here (os is far from the clouds).
        CHECK(rel_diff(info, o.hessian / variance) > 0.1);
        // Positive definite for a room.
        const Eigen::SelfAdjointEigenSolver<Matrix6d> es(info);
        CHECK(es.eigenvalues()[0] > 0.0);
    }
    // The variance floor: a perfect fit (zero residuals) is divided by (1e-3 floor_length)^2, not by 0.
    const Scene exact_target = room(0.25, 0.0);
    const Scene exact_source = to_source(exact_target, kRtrue, kTtrue);
    const RefineOutput o = run(exact_source, exact_target, kRtrue, kTtrue, params_for(RefineMode::Gicp), 1);
    CHECK(calibrated_variance(o, 2.0) == 4e-6);
    const Matrix6d info = information_in_caller_frame(o, Vec3d::Zero(), calibrated_variance(o, 2.0));
    CHECK(info.allFinite());
    CHECK_MSG(rel_diff(info, o.hessian / 4e-6) < 1e-12, "floored information off by %g",
              rel_diff(info, o.hessian / 4e-6));
}

// A corridor leaves the translation along its axis free: the weakest direction of the information, in the
// source frame, is (0, R^T x), and the condition is near 0; a plane leaves three directions free. With exact
// normals the point-to-plane information (what both modes report) has nothing at all along them.
static void test_corridor_and_plane_are_unconstrained() {
    constexpr double free_share = 1e-9;
    for (const RefineMode mode : kModes) {
        const Scene target = corridor(0.2, 0.0);
        const Scene source = to_source(corridor(0.2, 0.6), kRtrue, kTtrue);
        const RefineOutput o = run(source, target, kRtrue * rotation(Vec3d(1, 0, 1), 1.0),
                                   kTtrue + Eigen::Vector3d(0.05, 0.05, -0.05), params_for(mode), 2);
        std::fprintf(stderr, "  %s corridor: condition %.3g\n", mode_name(mode), o.condition);
        CHECK(o.num_correspondences > 1000);
        CHECK_MSG(o.condition < 1e-6, "%s corridor: condition %g", mode_name(mode), o.condition);
        CHECK(o.rotation.allFinite() && o.translation.allFinite());
        // The constrained directions are still found: the walls and the floor where they belong.
        CHECK_MSG(angle_deg(o.rotation, kRtrue) < 0.05, "%s corridor: rotation %g deg off", mode_name(mode),
                  angle_deg(o.rotation, kRtrue));
        const Vec3d slide_error = o.translation - kTtrue; // only along x may it be off
        CHECK_MSG(std::abs(slide_error.y()) < 0.005 && std::abs(slide_error.z()) < 0.005, "%s corridor: (%g %g %g)",
                  mode_name(mode), slide_error.x(), slide_error.y(), slide_error.z());
        const Eigen::SelfAdjointEigenSolver<Matrix6d> es(o.hessian);
        Vector6d slide = Vector6d::Zero();
        slide.tail<3>() = o.rotation.transpose() * Vec3d::UnitX();
        const double along = std::abs(es.eigenvectors().col(0).dot(slide));
        CHECK_MSG(along > 0.999, "%s corridor: weakest direction . slide = %g", mode_name(mode), along);
        CHECK_MSG(slide.dot(o.hessian * slide) <= 1.01 * free_share * o.weight_sum, "%s corridor: slide information %g",
                  mode_name(mode), slide.dot(o.hessian * slide) / o.weight_sum);
        // Across the corridor and up: constrained by the walls and the floor (their shares of the points).
        for (int axis = 1; axis < 3; ++axis) {
            Vector6d v = Vector6d::Zero();
            v.tail<3>() = o.rotation.transpose() * Vec3d::Unit(axis);
            CHECK_MSG(v.dot(o.hessian * v) > 0.2 * o.weight_sum, "%s corridor: axis %d information %g", mode_name(mode),
                      axis, v.dot(o.hessian * v) / o.weight_sum);
        }
    }
    for (const RefineMode mode : kModes) {
        const Scene target = plane(0.25, 0.0);
        const Scene source = to_source(plane(0.25, 0.4), kRtrue, kTtrue);
        const RefineOutput o = run(source, target, kRtrue * rotation(Vec3d(0, 1, 0), 1.0), kTtrue, params_for(mode), 2);
        std::fprintf(stderr, "  %s plane: condition %.3g\n", mode_name(mode), o.condition);
        CHECK(o.num_correspondences > 1000);
        CHECK_MSG(o.condition < 1e-6, "%s plane: condition %g", mode_name(mode), o.condition);
        CHECK(o.rotation.allFinite() && o.translation.allFinite());
        // The in-plane translations carry at most the regularisation's share, the normal one all of it.
        for (int axis = 0; axis < 3; ++axis) {
            Vector6d v = Vector6d::Zero();
            v.tail<3>() = o.rotation.transpose() * Vec3d::Unit(axis);
            if (axis < 2)
                CHECK(v.dot(o.hessian * v) <= 1.01 * free_share * o.weight_sum);
            else
                CHECK(v.dot(o.hessian * v) > 0.99 * o.weight_sum);
        }
        // The plane's tilt is found: its normal maps onto the target's.
        const Vec3d n = o.rotation * (kRtrue.transpose() * Vec3d::UnitZ());
        CHECK_MSG(n.z() > std::cos(0.01 * kPi / 180.0), "%s plane: normal (%g %g %g)", mode_name(mode), n.x(), n.y(),
                  n.z());
    }
}

// Degeneracy: the directions the refined pose leaves free, in the callers' frame (the source's local frame
// moved by `origin`), against the true null directions of each scene: a corridor's slide, a tunnel's slide and
// turn about its axis, a plane's two slides and its turn about the normal. Each true direction must lie within
// 10 degrees of the span of the reported ones, and their count must be right; a closed room has none.
static double angle_to_span_deg(const Vector6d &v, const std::vector<Vector6d> &span) {
    Eigen::MatrixXd A(6, static_cast<Eigen::Index>(span.size()));
    for (std::size_t i = 0; i < span.size(); ++i) A.col(static_cast<Eigen::Index>(i)) = span[i];
    const Eigen::HouseholderQR<Eigen::MatrixXd> qr(A);
    const Eigen::MatrixXd Q = qr.householderQ() * Eigen::MatrixXd::Identity(6, A.cols());
    const double inside = (Q.transpose() * v).norm() / v.norm();
    return std::acos(std::min(1.0, inside)) * 180.0 / kPi;
}

static void test_weak_directions() {
    const Vec3d origin(3.0, -2.0, 1.0);
    // A turn about the target-frame line (a, d) by theta, as a perturbation of T exp(xi) in the callers' source
    // frame: omega = R^T d, tau_local = R^T (d x (t - a)), tau = tau_local + origin x omega.
    const auto turn = [&](const Vec3d &a, const Vec3d &d) {
        Vector6d v;
        v.head<3>() = kRtrue.transpose() * d;
        v.tail<3>() = kRtrue.transpose() * d.cross(kTtrue - a) + origin.cross(Vec3d(v.head<3>()));
        return v;
    };
    const auto slide = [&](const Vec3d &d) {
        Vector6d v = Vector6d::Zero();
        v.tail<3>() = kRtrue.transpose() * d;
        return v;
    };
    struct Case {
        const char *name;
        Scene target;
        std::vector<Vector6d> free;
    };
    const Vec3d axis_point(0.0, 0.5, 1.0);
    std::vector<Case> cases;
    cases.push_back({"corridor", corridor(0.2, 0.0), {slide(Vec3d::UnitX())}});
    cases.push_back(
        {"tunnel", tunnel(0.2, 0.0, axis_point), {slide(Vec3d::UnitX()), turn(axis_point, Vec3d::UnitX())}});
    cases.push_back({"plane",
                     plane(0.25, 0.0),
                     {slide(Vec3d::UnitX()), slide(Vec3d::UnitY()), turn(Vec3d::Zero(), Vec3d::UnitZ())}});
    cases.push_back({"room", room(0.2, 0.0), {}});
    for (const RefineMode mode : kModes) {
        for (const Case &c : cases) {
            const Scene source = to_source(c.target, kRtrue, kTtrue);
            const RefineOutput o = run(source, c.target, kRtrue, kTtrue, params_for(mode), 2);
            const std::vector<Vector6d> weak = weak_directions_in_caller_frame(o, origin, 0.01);
            std::fprintf(stderr, "  %s %s: %zu weak, ratios %.2g %.2g %.2g %.2g\n", mode_name(mode), c.name,
                         weak.size(), o.direction_ratio[0], o.direction_ratio[1], o.direction_ratio[2],
                         o.direction_ratio[3]);
            CHECK_MSG(weak.size() == c.free.size(), "%s %s: %zu weak directions, expected %zu", mode_name(mode), c.name,
                      weak.size(), c.free.size());
            if (weak.size() != c.free.size()) continue;
            for (const Vector6d &w : weak) {
                CHECK(std::abs(w.norm() - 1.0) < 1e-12);
                Eigen::Index k = 0;
                w.cwiseAbs().maxCoeff(&k);
                CHECK(w[k] > 0.0);
            }
            for (std::size_t i = 0; i < c.free.size(); ++i) {
                const double a = angle_to_span_deg(c.free[i], weak);
                CHECK_MSG(a < 10.0, "%s %s: free direction %zu is %.2f deg off the reported ones", mode_name(mode),
                          c.name, i, a);
            }
            // And the reported ones lie in the true span (none of them is a constrained direction).
            for (std::size_t i = 0; i < weak.size(); ++i) {
                const double a = angle_to_span_deg(weak[i], c.free);
                CHECK_MSG(a < 10.0, "%s %s: reported direction %zu is %.2f deg off the free ones", mode_name(mode),
                          c.name, i, a);
            }
        }
    }
    // With no correspondence at all every direction is free.
    const RefineOutput none = run(to_source(room(0.2, 0.0), kRtrue, kTtrue), room(0.2, 0.0), kRtrue,
                                  kTtrue + Vec3d(50, 0, 0), params_for(RefineMode::Gicp), 1);
    CHECK(none.num_correspondences == 0);
    CHECK(weak_directions_in_caller_frame(none, origin, 0.01).size() == 6);
}

// The overlap is the share of all source points (normals or not) within max_distance of a target point.
static void test_overlap_against_brute_force() {
    const Scene full = room(0.2, 0.0);
    Scene half; // the target without the part x > 1
    for (std::size_t i = 0; i < full.points.size(); ++i)
        if (full.points[i].x() <= 1.0f) half.push(full.points[i].cast<double>(), full.normals.normal[i].cast<double>());
    Scene source = to_source(room(0.2, 0.5), kRtrue, kTtrue);
    for (std::size_t i = 0; i < source.points.size(); i += 3) source.normals.valid[i] = 0; // some without a normal
    const RefineParams p = params_for(RefineMode::Gicp);
    const RefineOutput o = run(source, half, kRtrue, kTtrue, p, 2);
    std::size_t hits = 0;
    const float max_d2 = 1.0f;
    for (const Vec3f &a : source.points) {
        const Vec3f q = (o.rotation * a.cast<double>() + o.translation).cast<float>();
        bool hit = false;
        for (const Vec3f &b : half.points) {
            const float dx = b.x() - q.x(), dy = b.y() - q.y(), dz = b.z() - q.z();
            hit = hit || dx * dx + dy * dy + dz * dz <= max_d2;
        }
        hits += hit;
    }
    CHECK(o.overlap == static_cast<double>(hits) / static_cast<double>(source.points.size()));
    CHECK_MSG(o.overlap > 0.5 && o.overlap < 0.9, "overlap %g", o.overlap);
    CHECK(angle_deg(o.rotation, kRtrue) < 0.05 && (o.translation - kTtrue).norm() < 0.005);
    // Fewer correspondences than source points with a normal: a third has none and part of the room is gone.
    CHECK(o.num_correspondences < 2 * source.points.size() / 3);
}

// Nothing within reach, no normals, an empty target: no correspondence, no iteration, no crash; the start
// pose comes back (re-orthonormalised) and the numbers say that nothing was measured.
static void test_nothing_to_match() {
    const Scene target = room(0.25, 0.0);
    const Scene source = to_source(target, kRtrue, kTtrue);
    const Eigen::Vector3d far = kTtrue + Eigen::Vector3d(100.0, -50.0, 0.0);
    for (const RefineMode mode : kModes) {
        const RefineOutput o = run(source, target, kRtrue, far, params_for(mode), 2);
        CHECK_EQ_INT(o.num_correspondences, 0);
        CHECK_EQ_INT(o.iterations, 0);
        CHECK(!o.converged);
        CHECK(o.overlap == 0.0);
        CHECK(o.rmse == 0.0 && o.weight_sum == 0.0 && o.condition == 0.0);
        CHECK(o.hessian.isZero(0.0));
        CHECK(angle_deg(o.rotation, kRtrue) < 1e-6);
        CHECK(o.translation == far);
        const Matrix6d info = information_in_caller_frame(o, Vec3d(1, 2, 3), 0.5);
        CHECK(info.allFinite() && info.isZero(0.0));
    }
    // Sources without normals: nothing to match, though the overlap still counts them.
    Scene bare = source;
    std::fill(bare.normals.valid.begin(), bare.normals.valid.end(), std::uint8_t{0});
    RefineOutput o = run(bare, target, kRtrue, kTtrue, params_for(RefineMode::PointToPlane), 1);
    CHECK_EQ_INT(o.num_correspondences, 0);
    CHECK(o.overlap == 1.0);
    // Targets without normals.
    Scene bare_target = target;
    std::fill(bare_target.normals.valid.begin(), bare_target.normals.valid.end(), std::uint8_t{0});
    o = run(source, bare_target, kRtrue, kTtrue, params_for(RefineMode::Gicp), 1);
    CHECK_EQ_INT(o.num_correspondences, 0);
    // An empty target and an empty source.
    const Scene empty;
    o = run(source, empty, kRtrue, kTtrue, params_for(RefineMode::Gicp), 2);
    CHECK_EQ_INT(o.num_correspondences, 0);
    CHECK(o.overlap == 0.0);
    o = run(empty, target, kRtrue, kTtrue, params_for(RefineMode::Gicp), 2);
    CHECK_EQ_INT(o.num_correspondences, 0);
    CHECK(o.overlap == 0.0);
    // Five correspondences (fewer than the pose's six degrees of freedom): no iteration either.
    Scene five;
    for (int i = 0; i < 5; ++i)
        five.push(source.points[static_cast<std::size_t>(100 * i)].cast<double>(), Vec3d::UnitZ());
    o = run(five, target, kRtrue, kTtrue, params_for(RefineMode::Gicp), 1);
    CHECK_EQ_INT(o.iterations, 0);
    CHECK_EQ_INT(o.num_correspondences, 5);
}

// The iteration cap holds, and a cap of 1 runs one step that already improves on the start.
static void test_iteration_cap() {
    const Scene target = room(0.2, 0.0);
    const Scene source = to_source(room(0.2, 0.3), kRtrue, kTtrue);
    RefineParams p = params_for(RefineMode::Gicp);
    const Eigen::Matrix3d R0 = kRtrue * rotation(Vec3d(1, 2, 3), 4.0);
    const Eigen::Vector3d t0 = kTtrue + Eigen::Vector3d(0.2, 0.1, -0.2);
    p.max_iterations = 1;
    const RefineOutput one = run(source, target, R0, t0, p, 1);
    CHECK_EQ_INT(one.iterations, 1);
    CHECK(!one.converged);
    CHECK(angle_deg(one.rotation, kRtrue) < angle_deg(R0, kRtrue));
    // Epsilons of 0: only "no step lowers the cost" or the cap stops it.
    p.max_iterations = 7;
    p.rotation_epsilon = 0.0;
    p.translation_epsilon = 0.0;
    const RefineOutput capped = run(source, target, R0, t0, p, 1);
    CHECK(capped.iterations <= 7);
    CHECK(capped.iterations == 7 || capped.converged);
}

// The validity rules (validity.cpp) on evidence built by hand, each bound passing and the value next to it
// failing. Without refinement: min_inliers, then the inliers' shape, then the rotation uncertainty. From a
// prior: 6 correspondences and the overlap, the condition, convergence, the residual. With refinement:
// refine_min_inliers, the shape, the overlap, then the inliers' coverage of it, then condition, convergence and
// the residual.
static void test_validity_rules() {
    InlierEvidence spread;
    spread.rotation_uncertainty = 0.01;
    InlierEvidence flat = spread;
    flat.shape = Reason::Degenerate;
    const CoarseRule coarse{15, 0.01};
    CHECK(coarse_validity(15, spread, coarse) == Reason::None);
    CHECK(coarse_validity(14, spread, coarse) == Reason::TooFewInliers);
    CHECK(coarse_validity(14, flat, coarse) == Reason::TooFewInliers);
    CHECK(coarse_validity(100, flat, coarse) == Reason::Degenerate);
    InlierEvidence loose = spread;
    loose.rotation_uncertainty = std::nextafter(0.01, 1.0);
    CHECK(coarse_validity(100, loose, coarse) == Reason::UncertainRotation);
    loose.rotation_uncertainty = std::numeric_limits<double>::infinity(); // all inliers on one point
    CHECK(coarse_validity(100, loose, coarse) == Reason::UncertainRotation);

    const RefinedRule rule{10, 0.1, 0.4, 1e-2, 0.25, 0.1, 0.1, false}; // the loose-and-weak box off
    RefinedEvidence good;
    good.num_correspondences = 6;
    good.overlap = 0.4;
    good.condition = 1e-2;
    good.inlier_coverage = 0.25;
    good.converged = true;
    good.rmse = 0.1;
    CHECK(prior_validity(good, rule) == Reason::None);
    CHECK(refined_validity(10, spread, good, rule) == Reason::None);
    RefinedEvidence e = good;
    e.num_correspondences = 5;
    CHECK(prior_validity(e, rule) == Reason::LowOverlap);
    e = good;
    e.overlap = std::nextafter(0.4, 0.0);
    CHECK(prior_validity(e, rule) == Reason::LowOverlap);
    e.condition = 0.0, e.converged = false; // several fail: the overlap is reported
    CHECK(prior_validity(e, rule) == Reason::LowOverlap);
    CHECK(refined_validity(10, spread, e, rule) == Reason::LowOverlap);
    e = good;
    e.condition = std::nextafter(1e-2, 0.0);
    CHECK(prior_validity(e, rule) == Reason::Unconstrained);
    e.converged = false;
    CHECK(prior_validity(e, rule) == Reason::Unconstrained);
    // The refined rotation: known to within max_rotation_uncertainty (0.1) at kRefinedRotationSigmas of its sigma,
    // tested after the residual; a degenerate pose the caller accepts is not asked.
    e = good;
    e.rotation_sigma = 0.1 / kRefinedRotationSigmas;
    CHECK(prior_validity(e, rule) == Reason::None);
    CHECK(refined_validity(10, spread, e, rule) == Reason::None);
    e.rotation_sigma = std::nextafter(0.1 / kRefinedRotationSigmas, 1.0);
    CHECK(prior_validity(e, rule) == Reason::UncertainRotation);
    CHECK(refined_validity(10, spread, e, rule) == Reason::UncertainRotation);
    e.rotation_sigma = std::numeric_limits<double>::infinity();
    CHECK(prior_validity(e, rule) == Reason::UncertainRotation);
    e.rmse = std::nextafter(0.1, 1.0);
    CHECK(prior_validity(e, rule) == Reason::LooseAlignment);
    e = good;
    e.rotation_sigma = std::numeric_limits<double>::infinity();
    e.degenerate = true;
    CHECK(prior_validity(e, rule) == Reason::UncertainRotation);
    {
        RefinedRule accepting = rule;
        accepting.allow_degenerate = true;
        CHECK(prior_validity(e, accepting) == Reason::None);
        e.degenerate = false;
        CHECK(prior_validity(e, accepting) == Reason::UncertainRotation);
    }
    e = good;
    e.condition = std::nextafter(1e-2, 0.0), e.converged = false;
    // allow_degenerate: the condition is not asked for, every other test still is.
    RefinedRule allowing = rule;
    allowing.allow_degenerate = true;
    CHECK(prior_validity(e, allowing) == Reason::NotConverged);
    e.converged = true;
    CHECK(prior_validity(e, allowing) == Reason::None);
    CHECK(refined_validity(10, spread, e, allowing) == Reason::None);
    e.condition = 0.0;
    CHECK(prior_validity(e, allowing) == Reason::None);
    e.overlap = std::nextafter(0.4, 0.0);
    CHECK(prior_validity(e, allowing) == Reason::LowOverlap);
    e = good;
    e.converged = false;
    CHECK(prior_validity(e, rule) == Reason::NotConverged);
    CHECK(refined_validity(10, spread, e, rule) == Reason::NotConverged);
    // A prior's refinement has no inliers: their coverage is not asked for.
    e = good;
    e.inlier_coverage = std::numeric_limits<double>::quiet_NaN();
    CHECK(prior_validity(e, rule) == Reason::None);
    // With refinement: the inliers first, then coverage before condition and convergence.
    CHECK(refined_validity(9, spread, good, rule) == Reason::TooFewInliers);
    CHECK(refined_validity(100, flat, good, rule) == Reason::Degenerate);
    CHECK(refined_validity(100, loose, good, rule) == Reason::None); // the uncertainty is the coarse rule's
    e.inlier_coverage = std::nextafter(0.25, 0.0);
    e.condition = 0.0;
    CHECK(refined_validity(100, spread, e, rule) == Reason::ClusteredInliers);
    e.inlier_coverage = std::numeric_limits<double>::quiet_NaN();
    CHECK(refined_validity(100, spread, e, rule) == Reason::ClusteredInliers);
    e.inlier_coverage = 3.0; // inliers reaching beyond the overlap
    CHECK(refined_validity(100, spread, e, rule) == Reason::Unconstrained);
    // The residual, last: a loose alignment that passes every other test, with or without the solver's inliers.
    e = good;
    e.rmse = std::nextafter(0.1, 1.0);
    CHECK(prior_validity(e, rule) == Reason::LooseAlignment);
    CHECK(refined_validity(10, spread, e, rule) == Reason::LooseAlignment);
    e.rmse = std::numeric_limits<double>::quiet_NaN();
    CHECK(prior_validity(e, rule) == Reason::LooseAlignment);
    e.converged = false; // several fail: the others' reasons first
    CHECK(prior_validity(e, rule) == Reason::NotConverged);
    e = good;
    e.rmse = 1.0, e.inlier_coverage = 0.0;
    CHECK(refined_validity(10, spread, e, rule) == Reason::ClusteredInliers);
    // Loose and weak: a residual above loose_rmse with a condition below kWeakCondition, after the residual bound
    // and before the rotation; under allow_degenerate too, and a condition that is not a number counts as weak.
    {
        RefinedRule box = rule;
        box.loose_rmse = 0.05;
        e = good; // rmse 0.1, condition 0.01
        CHECK(prior_validity(e, box) == Reason::LooseAndWeak);
        CHECK(refined_validity(10, spread, e, box) == Reason::LooseAndWeak);
        e.condition = kWeakCondition;
        CHECK(prior_validity(e, box) == Reason::None);
        e.condition = std::nextafter(kWeakCondition, 0.0);
        CHECK(prior_validity(e, box) == Reason::LooseAndWeak);
        e.rmse = 0.05;
        CHECK(prior_validity(e, box) == Reason::None);
        e.rmse = std::nextafter(0.1, 1.0);
        CHECK(prior_validity(e, box) == Reason::LooseAlignment);
        e = good;
        e.rotation_sigma = std::numeric_limits<double>::infinity();
        CHECK(prior_validity(e, box) == Reason::LooseAndWeak);
        box.allow_degenerate = true;
        e = good;
        e.condition = std::numeric_limits<double>::quiet_NaN();
        CHECK(prior_validity(e, box) == Reason::LooseAndWeak);
        e.condition = 0.5;
        CHECK(prior_validity(e, box) == Reason::None);
    }
}

int main() {
    RUN_TEST(test_converges_to_truth_same_sampling);
    RUN_TEST(test_converges_with_other_sampling_and_noise);
    RUN_TEST(test_thread_counts_bitwise);
    RUN_TEST(test_information_matches_differences);
    RUN_TEST(test_corridor_and_plane_are_unconstrained);
    RUN_TEST(test_weak_directions);
    RUN_TEST(test_overlap_against_brute_force);
    RUN_TEST(test_nothing_to_match);
    RUN_TEST(test_iteration_cap);
    RUN_TEST(test_validity_rules);
    return TEST_SUMMARY();
}

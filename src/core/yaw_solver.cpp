// SPDX-License-Identifier: MIT
#include "yaw_solver.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

KISSM_DETAIL_BEGIN

namespace {

// An orthonormal right-handed frame (e1, e2, up): e1 x e2 = up, so the rotation by theta about up acts on
// (e1, e2) coordinates as the plain 2-D rotation by theta.
struct UpFrame {
    Eigen::Vector3d e1, e2, up;
    explicit UpFrame(const Eigen::Vector3d &u) : up(u) {
        // The world axis least aligned with up keeps the cross product well conditioned.
        Eigen::Index i = 0;
        up.cwiseAbs().minCoeff(&i);
        e1 = up.cross(Eigen::Vector3d::Unit(i)).normalized();
        e2 = up.cross(e1);
    }
};

// One GNC pass over the TIMs in the (e1, e2) plane: residuals under theta, weights under the current mu and the
// weighted 2-D Procrustes sums. Fixed chunks, partial sums added in chunk order (RunContext::map_fold): the
// same bits for any thread count. The vertical disagreement of a TIM does not depend on theta, so it enters the
// residual as a constant (v2) that only decides the weights.
class YawPass {
public:
    static constexpr std::size_t kChunk = 2048;
    struct Partial {
        double cross = 0.0; // sum w (a x b).up
        double dot = 0.0;   // sum w a.b (horizontal parts)
        double cost = 0.0;
        double max_r2 = 0.0;
        bool binary = true;
    };

    YawPass(const std::vector<Eigen::Vector3d> &ta, const std::vector<Eigen::Vector3d> &tb, const UpFrame &f)
        : n_(ta.size()), ax_(n_), ay_(n_), bx_(n_), by_(n_), v2_(n_), r2_(n_), w_(n_, 1.0) {
        for (std::size_t k = 0; k < n_; ++k) {
            ax_[k] = ta[k].dot(f.e1), ay_[k] = ta[k].dot(f.e2);
            bx_[k] = tb[k].dot(f.e1), by_[k] = tb[k].dot(f.e2);
            const double dv = tb[k].dot(f.up) - ta[k].dot(f.up);
            v2_[k] = dv * dv;
            cross0_ += ax_[k] * by_[k] - ay_[k] * bx_[k];
            dot0_ += ax_[k] * bx_[k] + ay_[k] * by_[k];
        }
    }

    // The least-squares angle over all TIMs (unit weights): the sums do not depend on the angle.
    double least_squares_angle() const { return std::atan2(cross0_, dot0_); }

    std::size_t size() const { return n_; }
    const std::vector<double> &residuals() const { return r2_; }

    // mu <= 0: residuals (and their maximum) only. Otherwise the GNC-TLS weights for c2
    // and mu and the weighted sums.
    Partial run(double theta, double c2, double mu, RunContext &ctx) {
        const double c = std::cos(theta), s = std::sin(theta);
        const auto chunk = [&](std::size_t begin, std::size_t end) {
            Partial p;
            const double *ax = ax_.data(), *ay = ay_.data(), *bx = bx_.data(), *by = by_.data(), *v2 = v2_.data();
            double *r2 = r2_.data(), *w = w_.data();
            for (std::size_t k = begin; k < end; ++k) {
                const double ex = bx[k] - (c * ax[k] - s * ay[k]);
                const double ey = by[k] - (s * ax[k] + c * ay[k]);
                r2[k] = ex * ex + ey * ey + v2[k];
            }
            if (mu <= 0.0) {
                for (std::size_t k = begin; k < end; ++k) p.max_r2 = std::max(p.max_r2, r2[k]);
                return p;
            }
            const bool binary = gnc_tls_weights(r2, w, begin, end, c2, mu);
            double cross = 0.0, dot = 0.0, cost = 0.0;
            for (std::size_t k = begin; k < end; ++k) {
                const double wk = w[k];
                cost += wk * r2[k];
                cross += wk * (ax[k] * by[k] - ay[k] * bx[k]);
                dot += wk * (ax[k] * bx[k] + ay[k] * by[k]);
            }
            p.cross = cross, p.dot = dot, p.cost = cost, p.binary = binary;
            return p;
        };
        return ctx.map_fold(n_, kChunk, Partial{}, chunk, [](Partial &total, Partial &&p) {
            total.cross += p.cross, total.dot += p.dot, total.cost += p.cost;
            total.max_r2 = std::max(total.max_r2, p.max_r2);
            total.binary = total.binary && p.binary;
        });
    }

private:
    std::size_t n_;
    std::vector<double> ax_, ay_, bx_, by_, v2_, r2_, w_;
    double cross0_ = 0.0, dot0_ = 0.0;
};

// GNC-TLS over the angle (the schedule of gnc_tls_rotation: mu from where the surrogate is convex over all
// residuals, growing by gnc_factor until the weights are binary or the cost settles). Weights end binary: 1 for
// TIMs within the bound under the final angle. Returns false when fewer than two agree.
bool gnc_tls_yaw(YawPass &pass, double bound, const SolverParams &params, double &theta, std::vector<double> &weights,
                 int &iterations, RunContext &ctx) {
    const std::size_t n = pass.size();
    weights.assign(n, 0.0);
    iterations = 0;
    if (n < 2) return false;
    theta = pass.least_squares_angle();
    return gnc_tls_schedule(
        pass, n, bound, params, theta, [](const YawPass::Partial &p) { return std::atan2(p.cross, p.dot); }, weights,
        iterations, ctx);
}

} // namespace

Eigen::Matrix3d rotation_about(const Eigen::Vector3d &axis, double angle) {
    const double c = std::cos(angle), s = std::sin(angle);
    Eigen::Matrix3d K;
    K << 0.0, -axis.z(), axis.y(), axis.z(), 0.0, -axis.x(), -axis.y(), axis.x(), 0.0;
    return c * Eigen::Matrix3d::Identity() + s * K + (1.0 - c) * axis * axis.transpose();
}

std::size_t polish_pose_yaw(const std::vector<Eigen::Vector3d> &a, const std::vector<Eigen::Vector3d> &b, double bound,
                            const Eigen::Vector3d &up, Eigen::Matrix3d &R, Eigen::Vector3d &t,
                            std::vector<std::uint8_t> &inlier) {
    const UpFrame f(up);
    // min sum |b - R a - t|^2: t = cb - R ca for any R, then the angle of the centred horizontal parts (the
    // vertical parts do not depend on it).
    const auto yaw_fit = [&](const std::vector<std::uint8_t> &in, const Eigen::Vector3d &ca,
                             const Eigen::Vector3d &cb) {
        double cross = 0.0, dot = 0.0;
        for (std::size_t k = 0; k < a.size(); ++k) {
            if (!in[k]) continue;
            const Eigen::Vector3d da = a[k] - ca, db = b[k] - cb;
            const double ax = da.dot(f.e1), ay = da.dot(f.e2), bx = db.dot(f.e1), by = db.dot(f.e2);
            cross += ax * by - ay * bx;
            dot += ax * bx + ay * by;
        }
        return rotation_about(f.up, std::atan2(cross, dot));
    };
    return polish_pose_by(a, b, bound, yaw_fit, R, t, inlier);
}

SolverOutput solve_pose_yaw(const std::vector<Eigen::Vector3d> &a, const std::vector<Eigen::Vector3d> &b,
                            std::vector<IndexPair> pairs, const Eigen::Vector3d &up, const SolverParams &params,
                            RunContext &ctx) {
    SolverOutput out;
    const std::size_t n = a.size();
    out.rotation_inlier.assign(n, 0);
    out.inlier.assign(n, 0);
    const double up_norm = up.norm();
    if (n < 3 || !up.allFinite() || !(up_norm > 1e-12)) return out;
    const UpFrame frame(up / up_norm);
    const double beta = params.noise_bound;

    // Differences of correspondences: translation cancels, each end adds up to beta of noise. A TIM whose
    // vertical parts differ by more than the bound is an outlier whatever the angle: it is left out of GNC
    // (w = 0) instead of steering its first, nearly convex iterations.
    if (pairs.empty()) pairs = strided_pairs(n, params.max_tims);
    const double bound = 2.0 * beta;
    std::vector<Eigen::Vector3d> ta, tb;
    std::vector<std::size_t> kept;
    ta.reserve(pairs.size()), tb.reserve(pairs.size()), kept.reserve(pairs.size());
    for (std::size_t k = 0; k < pairs.size(); ++k) {
        const Eigen::Vector3d da = a[pairs[k].second] - a[pairs[k].first];
        const Eigen::Vector3d db = b[pairs[k].second] - b[pairs[k].first];
        if (!(std::fabs(db.dot(frame.up) - da.dot(frame.up)) <= bound)) continue;
        ta.push_back(da), tb.push_back(db), kept.push_back(k);
    }
    YawPass pass(ta, tb, frame);
    double theta = 0.0;
    std::vector<double> wk;
    if (!gnc_tls_yaw(pass, bound, params, theta, wk, out.iterations, ctx)) return out;
    std::vector<double> w(pairs.size(), 0.0);
    for (std::size_t k = 0; k < kept.size(); ++k) w[kept[k]] = wk[k];
    Eigen::Matrix3d R = rotation_about(frame.up, theta);

    out.num_rotation_inliers = rotation_inliers(pairs, w, n, out.rotation_inlier);
    Eigen::Vector3d t = tls_translation(a, b, R, out.rotation_inlier, out.num_rotation_inliers, beta);
    out.num_inliers = polish_pose_yaw(a, b, beta, frame.up, R, t, out.inlier);
    out.rotation = R;
    out.translation = t;
    out.solved = true;
    return out;
}

double residual_tilt(const std::vector<Eigen::Vector3d> &a, const std::vector<Eigen::Vector3d> &b,
                     const std::vector<IndexPair> &pairs, const SolverOutput &yaw, const Eigen::Vector3d &up,
                     const SolverParams &params, RunContext &ctx) {
    const double up_norm = up.norm();
    const double nan = std::numeric_limits<double>::quiet_NaN();
    if (!up.allFinite() || !(up_norm > 1e-12)) return nan;
    Eigen::Matrix3d R;
    Eigen::Vector3d t;
    std::vector<std::uint8_t> mask;
    if (yaw.solved && yaw.num_inliers >= 3 && yaw.inlier.size() == a.size()) {
        // The best unconstrained rotation on the yaw inliers (centred Kabsch), then grown as polish_pose does:
        // under a real tilt the yaw inliers are a patch around the tilt axis, and the rotation that fits the
        // patch explains more correspondences, which pin the tilt down. The first fit is always taken (a
        // zero-tilt answer must not come from keeping the yaw rotation).
        Eigen::Vector3d ca = Eigen::Vector3d::Zero(), cb = Eigen::Vector3d::Zero();
        for (std::size_t k = 0; k < a.size(); ++k)
            if (yaw.inlier[k]) ca += a[k], cb += b[k];
        ca /= static_cast<double>(yaw.num_inliers);
        cb /= static_cast<double>(yaw.num_inliers);
        std::vector<Eigen::Vector3d> da, db;
        for (std::size_t k = 0; k < a.size(); ++k)
            if (yaw.inlier[k]) da.push_back(a[k] - ca), db.push_back(b[k] - cb);
        R = weighted_rotation(da, db, std::vector<double>(da.size(), 1.0));
        t = cb - R * ca;
        polish_pose(a, b, params.noise_bound, R, t, mask);
    } else {
        // The yaw model explains (almost) nothing: a large tilt, or no overlap. Only the 3-DoF solver can tell.
        const SolverOutput free = solve_pose(a, b, pairs, params, ctx);
        if (!free.solved || free.num_inliers < 3) return nan;
        R = free.rotation;
    }
    const Eigen::Vector3d u = up / up_norm, Ru = R * u;
    // atan2 of sine and cosine: accurate at the small angles that matter here (acos is not).
    return std::atan2(u.cross(Ru).norm(), u.dot(Ru));
}

KISSM_DETAIL_END

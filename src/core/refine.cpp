// SPDX-License-Identifier: MIT
#include "refine.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>

KISSM_DETAIL_BEGIN

namespace {

constexpr double kPlaneEps = 1e-3;       // GICP's plane regularisation (Segal et al.)
constexpr std::size_t kChunk = 1024;     // correspondences per parallel chunk
constexpr int kMaxDampingTries = 10;     // LM: how often a rejected step may grow the damping
constexpr double kInitialDamping = 1e-6; // LM: GN-like first tries, as small_gicp's default

using Vector6d = Eigen::Matrix<double, 6, 1>;

struct Pair {
    std::uint32_t source, target;
};

// One correspondence as an iteration uses it: the source point a (local, double), the target point b, the
// symmetric weight matrix M of its cost (6 values: xx xy xz yy yz zz) and its robust weight.
struct Term {
    Eigen::Vector3d a, b;
    double m[6];
    double w;
};

inline Eigen::Matrix3d unpack(const double m[6]) {
    Eigen::Matrix3d M;
    M << m[0], m[1], m[2], m[1], m[3], m[4], m[2], m[4], m[5];
    return M;
}

inline Eigen::Matrix3d skew(const Eigen::Vector3d &v) {
    Eigen::Matrix3d S;
    S << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
    return S;
}

// Exp of a rotation vector (Rodrigues), exact at 0.
Eigen::Matrix3d exp_so3(const Eigen::Vector3d &w) {
    const double angle = w.norm();
    if (angle < 1e-12) return Eigen::Matrix3d::Identity() + skew(w);
    return Eigen::AngleAxisd(angle, w / angle).toRotationMatrix();
}

// The weight matrix of one correspondence: GICP's (C_b + R C_a R^T)^-1 with plane-regularised covariances
// C(n) = (n n^T + (I - n n^T) / eps) / 2, or the point-to-plane n_b n_b^T.
Eigen::Matrix3d weight_matrix(RefineMode mode, const Vec3f &na, const Vec3f &nb, const Eigen::Matrix3d &R) {
    const Eigen::Vector3d n = nb.cast<double>();
    if (mode == RefineMode::PointToPlane) return n * n.transpose();
    const Eigen::Vector3d m = R * na.cast<double>();
    const double k = 0.5 * (1.0 - 1.0 / kPlaneEps);
    Eigen::Matrix3d C = Eigen::Matrix3d::Identity() * (1.0 / kPlaneEps);
    C.noalias() += k * (n * n.transpose() + m * m.transpose());
    return C.inverse();
}

struct Sums {
    double H[36] = {}; // row-major
    double g[6] = {};
    double cost = 0.0;
    double wsum = 0.0;
};

void add(Sums &acc, const Sums &p) {
    for (int i = 0; i < 36; ++i) acc.H[i] += p.H[i];
    for (int i = 0; i < 6; ++i) acc.g[i] += p.g[i];
    acc.cost += p.cost;
    acc.wsum += p.wsum;
}

// The median of |r| over the terms at (R, t), r^2 = e^T M e (one pass and a selection on a copy: the order of the
// terms is fixed, so the bits are).
double median_distance(const UninitVector<Term> &terms, const Eigen::Matrix3d &R, const Eigen::Vector3d &t) {
    if (terms.size() == 0) return 0.0;
    std::vector<double> r(terms.size());
    for (std::size_t k = 0; k < terms.size(); ++k) {
        const Term &term = terms[k];
        const Eigen::Vector3d e = term.b - (R * term.a + t);
        r[k] = std::sqrt(std::max(0.0, e.dot(unpack(term.m) * e)));
    }
    const auto mid = r.begin() + static_cast<std::ptrdiff_t>(r.size() / 2);
    std::nth_element(r.begin(), mid, r.end());
    return *mid;
}

class Refiner {
public:
    Refiner(const RefineCloud &source, const RefineCloud &target, const RefineIndex &index, const RefineParams &params,
            RunContext &ctx)
        : src_(*source.points), src_n_(*source.normals), tgt_(*target.points), tgt_n_(*target.normals), index_(index),
          params_(params), ctx_(ctx) {
        // Source voxels that can take part: those with a normal (GICP needs both normals; point-to-plane only
        // the target's, but a voxel without a normal is an edge or a stray, whose nearest target voxel is no
        // plane of its surface either).
        for (std::size_t i = 0; i < src_.size(); ++i) {
            all_.push_back(static_cast<std::uint32_t>(i));
            if (src_n_.valid[i]) candidates_.push_back(static_cast<std::uint32_t>(i));
        }
        hint_.assign(src_.size(), RefineIndex::kNone);
    }

    struct Matches {
        std::vector<Pair> pairs; // both voxels with a normal, in source order
        std::uint64_t hits = 0;  // source voxels with a target voxel within max_distance
    };

    // The nearest target voxel within max_distance of each source voxel in `which` moved by (R, t). Each answer
    // is the next search's hint for that voxel: the pose moves little between iterations, so the previous
    // nearest voxel bounds the search from the start (the answer is the same, found faster).
    // The result lives in matches_ until the next call.
    const Matches &match(const std::vector<std::uint32_t> &which, const Eigen::Matrix3d &R, const Eigen::Vector3d &t) {
        const float max_d2 = static_cast<float>(params_.max_distance * params_.max_distance);
        auto parts = ctx_.map_chunks(which.size(), kChunk, [&](std::size_t begin, std::size_t end) {
            Matches out;
            out.pairs.reserve(end - begin);
            for (std::size_t k = begin; k < end; ++k) {
                const std::uint32_t i = which[k];
                const Vec3f q = (R * src_[i].cast<double>() + t).cast<float>();
                float d2;
                const std::uint32_t j = index_.nearest(q, max_d2, &d2, hint_[i]);
                hint_[i] = j;
                if (j == RefineIndex::kNone) continue;
                ++out.hits;
                if (src_n_.valid[i] && tgt_n_.valid[j]) out.pairs.push_back(Pair{i, j});
            }
            return out;
        });
        Matches &all = matches_;
        all.pairs.clear(); // keeps its capacity: see matches_
        all.hits = 0;
        std::size_t total = 0;
        for (const auto &p : parts) total += p.pairs.size();
        all.pairs.reserve(total);
        for (const auto &p : parts) {
            all.pairs.insert(all.pairs.end(), p.pairs.begin(), p.pairs.end());
            all.hits += p.hits;
        }
        return all;
    }

    // Terms of the correspondences at (R, t) under the cost of `mode`: weight matrices and Cauchy weights. The
    // result lives in terms_ until the next call.
    const UninitVector<Term> &terms(const std::vector<Pair> &pairs, const Eigen::Matrix3d &R, const Eigen::Vector3d &t,
                                    RefineMode mode) {
        UninitVector<Term> &out = terms_;
        out.resize(pairs.size()); // every term is written below
        const double k2 = params_.kernel_scale * params_.kernel_scale;
        ctx_.parallel_for(pairs.size(), kChunk, [&](std::size_t begin, std::size_t end) {
            for (std::size_t k = begin; k < end; ++k) {
                Term &term = out[k];
                term.a = src_[pairs[k].source].cast<double>();
                term.b = tgt_[pairs[k].target].cast<double>();
                const Eigen::Matrix3d M =
                    weight_matrix(mode, src_n_.normal[pairs[k].source], tgt_n_.normal[pairs[k].target], R);
                term.m[0] = M(0, 0), term.m[1] = M(0, 1), term.m[2] = M(0, 2);
                term.m[3] = M(1, 1), term.m[4] = M(1, 2), term.m[5] = M(2, 2);
                const Eigen::Vector3d e = term.b - (R * term.a + t);
                const double r2 = e.dot(M * e);
                term.w = 1.0 / (1.0 + r2 / k2);
            }
        });
        return out;
    }

    // Weighted cost of the terms at (R, t), and (with `system`) the Gauss-Newton system of the left
    // perturbation (R, t) <- (Exp(w) R, Exp(w) t + v): J = de/d(w, v) = [[q]x, -I], q = R a + t.
    Sums sums(const UninitVector<Term> &terms, const Eigen::Matrix3d &R, const Eigen::Vector3d &t, bool system) {
        return ctx_.map_fold(
            terms.size(), kChunk, Sums{},
            [&](std::size_t begin, std::size_t end) {
                Sums p;
                Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
                Vector6d g = Vector6d::Zero();
                for (std::size_t k = begin; k < end; ++k) {
                    const Term &term = terms[k];
                    const Eigen::Matrix3d M = unpack(term.m);
                    const Eigen::Vector3d q = R * term.a + t;
                    const Eigen::Vector3d e = term.b - q;
                    const Eigen::Vector3d Me = M * e;
                    p.cost += term.w * e.dot(Me);
                    p.wsum += term.w;
                    if (!system) continue;
                    const Eigen::Matrix3d S = skew(q);
                    const Eigen::Matrix3d StM = S.transpose() * M; // J^T M, upper block; lower block is -M
                    H.topLeftCorner<3, 3>().noalias() += term.w * (StM * S);
                    H.topRightCorner<3, 3>().noalias() -= term.w * StM;
                    H.bottomRightCorner<3, 3>().noalias() += term.w * M;
                    g.head<3>().noalias() += term.w * (StM * e);
                    g.tail<3>().noalias() -= term.w * Me;
                }
                if (system) {
                    H.bottomLeftCorner<3, 3>() = H.topRightCorner<3, 3>().transpose();
                    for (int i = 0; i < 6; ++i) {
                        p.g[i] = g[i];
                        for (int j = 0; j < 6; ++j) p.H[6 * i + j] = H(i, j);
                    }
                }
                return p;
            },
            [](Sums &acc, Sums &&p) { add(acc, p); });
    }

    RefineOutput run(const Eigen::Matrix3d &R0, const Eigen::Vector3d &t0) {
        RefineOutput out;
        Eigen::Matrix3d R = R0;
        Eigen::Vector3d t = t0;
        double damping = kInitialDamping;
        for (int it = 0; it < params_.max_iterations; ++it) {
            ctx_.checkpoint(Stage::Refine, static_cast<double>(it) / static_cast<double>(params_.max_iterations));
            const std::vector<Pair> &pairs = match(candidates_, R, t).pairs;
            if (pairs.size() < 6) break; // fewer than the pose's degrees of freedom
            const UninitVector<Term> &ts = terms(pairs, R, t, params_.mode);
            const Sums s = sums(ts, R, t, true);
            const Matrix6d H = Eigen::Map<const Eigen::Matrix<double, 6, 6, Eigen::RowMajor>>(s.H);
            const Vector6d g = Eigen::Map<const Vector6d>(s.g);
            // Marquardt's scaling, with a floor so that a direction the data leaves free (a plane, a corridor)
            // still gets a bounded step instead of a singular system.
            Vector6d scale = H.diagonal();
            const double floor = 1e-9 * std::max(scale.maxCoeff(), 1e-300);
            for (int i = 0; i < 6; ++i) scale[i] = std::max(scale[i], floor);
            ++out.iterations;
            bool kept = false;
            for (int tries = 0; tries < kMaxDampingTries && !kept; ++tries) {
                Matrix6d A = H;
                A.diagonal() += damping * scale;
                const Vector6d delta = A.ldlt().solve(-g);
                if (!delta.allFinite()) {
                    damping *= 10.0;
                    continue;
                }
                const Eigen::Matrix3d dR = exp_so3(delta.head<3>());
                const Eigen::Matrix3d R1 = dR * R;
                const Eigen::Vector3d t1 = dR * t + delta.tail<3>();
                if (sums(ts, R1, t1, false).cost < s.cost) {
                    R = R1, t = t1;
                    kept = true;
                    damping = std::max(damping * 0.1, 1e-12);
                    if (delta.head<3>().norm() < params_.rotation_epsilon &&
                        delta.tail<3>().norm() < params_.translation_epsilon)
                        out.converged = true;
                } else {
                    damping *= 10.0;
                }
            }
            // No step lowers the cost: the pose is a minimum for these correspondences, which it would find again.
            if (!kept) out.converged = true;
            if (out.converged) break;
        }
        // Re-orthonormalise: many products of rotations drift from SO(3) in the last bits.
        const Eigen::Quaterniond qr(R);
        out.rotation = qr.normalized().toRotationMatrix();
        out.translation = t;
        finish(out);
        return out;
    }

private:
    // The numbers of the final pose: correspondences, weighted RMS, and the information of the right
    // perturbation in the source's local frame: xi_left = Ad_T xi_right, so H_right = Ad^T H_left Ad with
    // Ad = [[R, 0], [[t]x R, R]].
    void finish(RefineOutput &out) {
        const Eigen::Matrix3d &R = out.rotation;
        const Eigen::Vector3d &t = out.translation;
        const Matches &final_matches = match(all_, R, t);
        const std::vector<Pair> &pairs = final_matches.pairs;
        if (!src_.empty()) out.overlap = static_cast<double>(final_matches.hits) / static_cast<double>(src_.size());
        out.num_correspondences = pairs.size();
        if (pairs.empty()) return;
        // The pose's numbers come from the point-to-plane term in both modes: GICP's plane regularisation gives
        // every correspondence 1/eps less weight along its plane, which is a model, not a measurement; counted
        // as information it would make a lone plane look constrained along itself.
        const UninitVector<Term> &ts = terms(pairs, R, t, RefineMode::PointToPlane);
        const Sums s = sums(ts, R, t, true);
        out.weight_sum = s.wsum;
        out.rmse = s.wsum > 0.0 ? std::sqrt(s.cost / s.wsum) : 0.0;
        out.residual_median = median_distance(ts, R, t);
        const Matrix6d H = Eigen::Map<const Eigen::Matrix<double, 6, 6, Eigen::RowMajor>>(s.H);
        Matrix6d Ad = Matrix6d::Zero();
        Ad.topLeftCorner<3, 3>() = R;
        Ad.bottomLeftCorner<3, 3>() = skew(t) * R;
        Ad.bottomRightCorner<3, 3>() = R;
        out.hessian = Ad.transpose() * H * Ad;
        out.hessian = 0.5 * (out.hessian + out.hessian.transpose()).eval();
        // Centroid and covariance of the matched source voxels: the aligned overlap's extent.
        Eigen::Vector3d c = Eigen::Vector3d::Zero();
        for (const Pair &p : pairs) c += src_[p.source].cast<double>();
        c /= static_cast<double>(pairs.size());
        Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
        for (const Pair &p : pairs) {
            const Eigen::Vector3d d = src_[p.source].cast<double>() - c;
            cov.noalias() += d * d.transpose();
        }
        cov /= static_cast<double>(pairs.size());
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov, Eigen::EigenvaluesOnly);
        out.overlap_spread = std::sqrt(std::max(0.0, es.eigenvalues()[2]));
        condition(c, cov, out);
    }

    // Moves the information's rotation centre to the matched source points' centroid c (xi_local =
    // [[I, 0], [[c]x, I]] xi_c) and turns rotations into the displacements they cause there: a rotation omega
    // moves the points by omega x (p - c), whose mean square is omega^T (tr(C) I - C) omega for their covariance C,
    // so xi_s = (M omega, tau) with M = (tr(C) I - C)^(1/2) puts all six directions in metres (a corridor's roll,
    // held by its cross-section, is not mistaken for free because the corridor is long). Then each eigenvalue
    // over the largest (condition: the smallest ratio) and the eigenvectors taken back to xi_local.
    static void condition(const Eigen::Vector3d &c, const Eigen::Matrix3d &cov, RefineOutput &out) {
        out.condition = 0.0;
        out.direction_ratio.setZero();
        out.directions.setIdentity();
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> arm(cov.trace() * Eigen::Matrix3d::Identity() - cov);
        const Eigen::Vector3d arm2 = arm.eigenvalues();
        if (!(arm2[0] > 0.0)) return; // the points on one line or one point: a rotation about it moves nothing
        const Eigen::Matrix3d V = arm.eigenvectors();
        const Eigen::Matrix3d M_inv = V * arm2.cwiseSqrt().cwiseInverse().asDiagonal() * V.transpose();
        Matrix6d Ad = Matrix6d::Identity();
        Ad.bottomLeftCorner<3, 3>() = skew(c);
        Matrix6d S_inv = Matrix6d::Identity(); // xi_c = S^-1 xi_s
        S_inv.topLeftCorner<3, 3>() = M_inv;
        const Matrix6d T = Ad * S_inv; // xi_local = T xi_s
        const Matrix6d Hs = T.transpose() * out.hessian * T;
        const Eigen::SelfAdjointEigenSolver<Matrix6d> es(0.5 * (Hs + Hs.transpose()));
        const double hi = es.eigenvalues()[5];
        if (!(hi > 0.0)) return;
        for (int i = 0; i < 6; ++i) out.direction_ratio[i] = std::max(es.eigenvalues()[i], 0.0) / hi;
        out.condition = out.direction_ratio[0];
        out.directions = T * es.eigenvectors();
    }

    const std::vector<Vec3f> &src_;
    const Normals &src_n_;
    const std::vector<Vec3f> &tgt_;
    const Normals &tgt_n_;
    const RefineIndex &index_;
    const RefineParams &params_;
    RunContext &ctx_;
    std::vector<std::uint32_t> all_;        // every source voxel (the overlap counts them all)
    std::vector<std::uint32_t> candidates_; // those with a normal
    std::vector<std::uint32_t> hint_;       // per source voxel: its last nearest target voxel
    // The correspondences and terms of the current iteration, kept across iterations (only the last one's are
    // read): a new megabyte-sized array per iteration is fresh pages every time wherever freed memory goes back
    // to the system at once (a Dask worker's MALLOC_TRIM_THRESHOLD_), and three quarters of a pair's page
    // faults were these (docs/design/performance.md, "Buffers kept across chunks and iterations").
    Matches matches_;
    UninitVector<Term> terms_;
};

} // namespace

RefineOutput refine_pose(const RefineCloud &source, const RefineCloud &target, const RefineIndex &target_index,
                         const Eigen::Matrix3d &R0, const Eigen::Vector3d &t0, const RefineParams &params,
                         RunContext &ctx) {
    Refiner refiner(source, target, target_index, params, ctx);
    return refiner.run(R0, t0);
}

double calibrated_variance(const RefineOutput &out, double floor_length) {
    const double spread = 1.4826 * out.residual_median; // the standard deviation a normal law with this median has
    return std::max(kResidualShare * spread * spread, 1e-6 * floor_length * floor_length);
}

Matrix6d information_in_caller_frame(const RefineOutput &out, const Eigen::Vector3d &source_origin, double variance) {
    // xi_local = Ad_{Tr(-o)} xi_caller with Ad = [[I, 0], [[-o]x, I]].
    Matrix6d Ad = Matrix6d::Identity();
    Ad.bottomLeftCorner<3, 3>() = skew(-source_origin);
    Matrix6d info = Ad.transpose() * out.hessian * Ad / variance;
    return 0.5 * (info + info.transpose());
}

std::vector<Vector6d> weak_directions_in_caller_frame(const RefineOutput &out, const Eigen::Vector3d &source_origin,
                                                      double min_condition) {
    // xi_caller = Ad^-1 xi_local, Ad^-1 = [[I, 0], [[o]x, I]] (information_in_caller_frame's Ad inverted).
    Matrix6d Ad_inv = Matrix6d::Identity();
    Ad_inv.bottomLeftCorner<3, 3>() = skew(source_origin);
    std::vector<Vector6d> weak;
    for (int i = 0; i < 6; ++i) {
        if (out.direction_ratio[i] >= min_condition) break; // ascending
        Vector6d v = Ad_inv * out.directions.col(i);
        const double n = v.norm();
        if (!(n > 0.0)) continue;
        v /= n;
        Eigen::Index k = 0;
        v.cwiseAbs().maxCoeff(&k);
        if (v[k] < 0.0) v = -v;
        weak.push_back(v);
    }
    return weak;
}

KISSM_DETAIL_END

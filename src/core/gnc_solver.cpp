// SPDX-License-Identifier: MIT
#include "gnc_solver.hpp"

#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

KISSM_DETAIL_BEGIN

namespace {

Eigen::Matrix3d rotation_from_correlation(const Eigen::Matrix3d &H) {
    Eigen::JacobiSVD<Eigen::Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const Eigen::Matrix3d U = svd.matrixU(), V = svd.matrixV();
    Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
    if ((V * U.transpose()).determinant() < 0.0) S(2, 2) = -1.0; // a reflection is not a rotation
    return V * S * U.transpose();
}

// One GNC pass: residuals under R, weights under the current mu, the weighted correlation sum and cost.
// Fixed chunks with partial sums added in chunk order (RunContext::map_fold): the same numbers for any
// thread count. The measurements are kept as structure of arrays and each chunk runs three plain loops
// (residuals, which the compiler vectorises; weights; sums), which is faster than one loop doing everything.
class GncPass {
public:
    static constexpr std::size_t kChunk = 2048;
    struct Partial {
        double H[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0}; // row-major sum of w a b^T
        double cost = 0.0;
        double max_r2 = 0.0;
        bool binary = true;
    };

    GncPass(const std::vector<Eigen::Vector3d> &a, const std::vector<Eigen::Vector3d> &b)
        : n_(a.size()), ax_(n_), ay_(n_), az_(n_), bx_(n_), by_(n_), bz_(n_), r2_(n_), w_(n_, 1.0) {
        for (std::size_t k = 0; k < n_; ++k) {
            ax_[k] = a[k].x(), ay_[k] = a[k].y(), az_[k] = a[k].z();
            bx_[k] = b[k].x(), by_[k] = b[k].y(), bz_[k] = b[k].z();
        }
    }

    const std::vector<double> &residuals() const { return r2_; }

    // mu <= 0: residuals (and their maximum) only. Otherwise also the GNC-TLS weights for c2 and mu.
    Partial run(const Eigen::Matrix3d &R, double c2, double mu, RunContext &ctx) {
        const double r00 = R(0, 0), r01 = R(0, 1), r02 = R(0, 2), r10 = R(1, 0), r11 = R(1, 1), r12 = R(1, 2),
                     r20 = R(2, 0), r21 = R(2, 1), r22 = R(2, 2);
        const auto chunk = [&](std::size_t begin, std::size_t end) {
            Partial p;
            const double *ax = ax_.data(), *ay = ay_.data(), *az = az_.data();
            const double *bx = bx_.data(), *by = by_.data(), *bz = bz_.data();
            double *r2 = r2_.data(), *w = w_.data();
            for (std::size_t k = begin; k < end; ++k) {
                const double ex = bx[k] - (r00 * ax[k] + r01 * ay[k] + r02 * az[k]);
                const double ey = by[k] - (r10 * ax[k] + r11 * ay[k] + r12 * az[k]);
                const double ez = bz[k] - (r20 * ax[k] + r21 * ay[k] + r22 * az[k]);
                r2[k] = ex * ex + ey * ey + ez * ez;
            }
            if (mu <= 0.0) {
                for (std::size_t k = begin; k < end; ++k) p.max_r2 = std::max(p.max_r2, r2[k]);
                return p;
            }
            const bool binary = gnc_tls_weights(r2, w, begin, end, c2, mu);
            // Outliers add exact zeros, so no test is needed.
            double cost = 0.0, h00 = 0, h01 = 0, h02 = 0, h10 = 0, h11 = 0, h12 = 0, h20 = 0, h21 = 0, h22 = 0;
            for (std::size_t k = begin; k < end; ++k) {
                const double wk = w[k];
                cost += wk * r2[k];
                const double wx = wk * ax[k], wy = wk * ay[k], wz = wk * az[k];
                h00 += wx * bx[k], h01 += wx * by[k], h02 += wx * bz[k];
                h10 += wy * bx[k], h11 += wy * by[k], h12 += wy * bz[k];
                h20 += wz * bx[k], h21 += wz * by[k], h22 += wz * bz[k];
            }
            const double H[9] = {h00, h01, h02, h10, h11, h12, h20, h21, h22};
            std::copy(H, H + 9, p.H);
            p.cost = cost;
            p.binary = binary;
            return p;
        };
        // Partial sums added in chunk order, starting from zero.
        return ctx.map_fold(n_, kChunk, Partial{}, chunk, [](Partial &total, Partial &&p) {
            for (int i = 0; i < 9; ++i) total.H[i] += p.H[i];
            total.cost += p.cost;
            total.max_r2 = std::max(total.max_r2, p.max_r2);
            total.binary = total.binary && p.binary;
        });
    }

private:
    std::size_t n_;
    std::vector<double> ax_, ay_, az_, bx_, by_, bz_, r2_, w_;
};

} // namespace

Eigen::Matrix3d weighted_rotation(const std::vector<Eigen::Vector3d> &a, const std::vector<Eigen::Vector3d> &b,
                                  const std::vector<double> &w) {
    Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
    for (std::size_t k = 0; k < a.size(); ++k)
        if (w[k] > 0.0) H.noalias() += w[k] * a[k] * b[k].transpose();
    return rotation_from_correlation(H);
}

bool gnc_tls_rotation(const std::vector<Eigen::Vector3d> &a, const std::vector<Eigen::Vector3d> &b, double bound,
                      const SolverParams &params, Eigen::Matrix3d &rotation, std::vector<double> &weights,
                      int &iterations, RunContext &ctx) {
    const std::size_t n = a.size();
    weights.assign(n, 1.0);
    iterations = 0;
    if (n < 2) return false;
    GncPass pass(a, b);

    rotation = weighted_rotation(a, b, weights);
    return gnc_tls_schedule(
        pass, n, bound, params, rotation,
        [](const GncPass::Partial &p) {
            return rotation_from_correlation(Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(p.H));
        },
        weights, iterations, ctx);
}

double scalar_tls(std::vector<double> values, double bound) {
    const std::size_t n = values.size();
    if (n == 0) return 0.0;
    // The optimum is the mean of some consensus set {x_k : |x_k - x| <= bound}; sweeping the 2n interval
    // endpoints visits every such set once.
    struct Event {
        double at;
        int enter; // +1 entering, -1 leaving
        double value;
    };
    std::vector<Event> events;
    events.reserve(2 * n);
    for (double v : values) {
        events.push_back({v - bound, +1, v});
        events.push_back({v + bound, -1, v});
    }
    std::sort(events.begin(), events.end(), [](const Event &x, const Event &y) {
        if (x.at != y.at) return x.at < y.at;
        if (x.enter != y.enter) return x.enter > y.enter; // closed intervals: enter before leave
        return x.value < y.value;
    });
    const double outlier_cost = bound * bound;
    double sum = 0.0, sum2 = 0.0, best_cost = std::numeric_limits<double>::infinity();
    double best = values[0];
    std::size_t count = 0;
    for (const Event &e : events) {
        if (e.enter > 0) {
            sum += e.value, sum2 += e.value * e.value, ++count;
            const double mean = sum / static_cast<double>(count);
            const double cost = std::max(0.0, sum2 - sum * mean) + static_cast<double>(n - count) * outlier_cost;
            if (cost < best_cost) best_cost = cost, best = mean;
        } else {
            sum -= e.value, sum2 -= e.value * e.value, --count;
            if (count == 0) sum = sum2 = 0.0; // drop accumulated rounding
        }
    }
    return best;
}

std::size_t count_inliers(const std::vector<Eigen::Vector3d> &a, const std::vector<Eigen::Vector3d> &b, double bound,
                          const Eigen::Matrix3d &R, const Eigen::Vector3d &t, std::vector<std::uint8_t> &mask) {
    mask.assign(a.size(), 0);
    std::size_t c = 0;
    for (std::size_t k = 0; k < a.size(); ++k) {
        mask[k] = (R * a[k] + t - b[k]).norm() <= bound;
        c += mask[k];
    }
    return c;
}

std::size_t polish_pose(const std::vector<Eigen::Vector3d> &a, const std::vector<Eigen::Vector3d> &b, double bound,
                        Eigen::Matrix3d &R, Eigen::Vector3d &t, std::vector<std::uint8_t> &inlier) {
    const auto kabsch = [&](const std::vector<std::uint8_t> &in, const Eigen::Vector3d &ca, const Eigen::Vector3d &cb) {
        std::vector<Eigen::Vector3d> da, db;
        std::vector<double> ones;
        for (std::size_t k = 0; k < a.size(); ++k)
            if (in[k]) da.push_back(a[k] - ca), db.push_back(b[k] - cb), ones.push_back(1.0);
        return weighted_rotation(da, db, ones);
    };
    return polish_pose_by(a, b, bound, kabsch, R, t, inlier);
}

std::vector<IndexPair> strided_pairs(std::size_t n, std::size_t max_pairs) {
    std::vector<IndexPair> pairs;
    if (n < 2) return pairs;
    if (n * (n - 1) / 2 <= max_pairs) {
        for (std::size_t i = 0; i < n; ++i)
            for (std::size_t j = i + 1; j < n; ++j)
                pairs.emplace_back(static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j));
        return pairs;
    }
    const std::size_t strides = std::max<std::size_t>(1, max_pairs / n);
    for (std::size_t s = 0; s < strides; ++s) {
        // Strides spread over (0, n/2]: short and long baselines alike.
        const std::size_t step = 1 + (s * (n / 2 - 1)) / strides;
        for (std::size_t i = 0; i < n; ++i)
            pairs.emplace_back(static_cast<std::uint32_t>(i), static_cast<std::uint32_t>((i + step) % n));
    }
    return pairs;
}

std::size_t rotation_inliers(const std::vector<IndexPair> &pairs, const std::vector<double> &w, std::size_t n,
                             std::vector<std::uint8_t> &mask) {
    std::vector<std::uint32_t> good(n, 0), total(n, 0);
    for (std::size_t k = 0; k < pairs.size(); ++k) {
        ++total[pairs[k].first], ++total[pairs[k].second];
        if (w[k] > 0.0) ++good[pairs[k].first], ++good[pairs[k].second];
    }
    mask.assign(n, 0);
    std::size_t count = 0;
    for (std::size_t k = 0; k < n; ++k) {
        mask[k] = total[k] > 0 && 2 * good[k] >= total[k];
        count += mask[k];
    }
    return count;
}

Eigen::Vector3d tls_translation(const std::vector<Eigen::Vector3d> &a, const std::vector<Eigen::Vector3d> &b,
                                const Eigen::Matrix3d &R, const std::vector<std::uint8_t> &mask, std::size_t count,
                                double beta) {
    std::vector<Eigen::Vector3d> t_k;
    for (std::size_t k = 0; k < a.size(); ++k)
        if (mask[k] || count < 3) t_k.push_back(b[k] - R * a[k]);
    Eigen::Vector3d t;
    for (int axis = 0; axis < 3; ++axis) {
        std::vector<double> vals(t_k.size());
        for (std::size_t k = 0; k < t_k.size(); ++k) vals[k] = t_k[k][axis];
        t[axis] = scalar_tls(std::move(vals), beta);
    }
    for (int it = 0; it < 10; ++it) {
        Eigen::Vector3d sum = Eigen::Vector3d::Zero();
        std::size_t c = 0;
        for (const auto &v : t_k)
            if ((v - t).norm() <= beta) sum += v, ++c;
        if (c == 0) break;
        const Eigen::Vector3d next = sum / static_cast<double>(c);
        if (next == t) break;
        t = next;
    }
    return t;
}

SolverOutput solve_pose(const std::vector<Eigen::Vector3d> &a, const std::vector<Eigen::Vector3d> &b,
                        std::vector<IndexPair> pairs, const SolverParams &params, RunContext &ctx) {
    SolverOutput out;
    const std::size_t n = a.size();
    out.rotation_inlier.assign(n, 0);
    out.inlier.assign(n, 0);
    if (n < 3) return out;
    const double beta = params.noise_bound;

    // Rotation from differences of correspondences: translation cancels, each end adds up to beta of noise.
    if (pairs.empty()) pairs = strided_pairs(n, params.max_tims);
    std::vector<Eigen::Vector3d> ta(pairs.size()), tb(pairs.size());
    for (std::size_t k = 0; k < pairs.size(); ++k) {
        ta[k] = a[pairs[k].second] - a[pairs[k].first];
        tb[k] = b[pairs[k].second] - b[pairs[k].first];
    }
    Eigen::Matrix3d R;
    std::vector<double> w;
    if (!gnc_tls_rotation(ta, tb, 2.0 * beta, params, R, w, out.iterations, ctx)) return out;

    out.num_rotation_inliers = rotation_inliers(pairs, w, n, out.rotation_inlier);
    Eigen::Vector3d t = tls_translation(a, b, R, out.rotation_inlier, out.num_rotation_inliers, beta);

    out.num_inliers = polish_pose(a, b, beta, R, t, out.inlier);
    out.rotation = R;
    out.translation = t;
    out.solved = true;
    return out;
}

KISSM_DETAIL_END

// SPDX-License-Identifier: MIT
#include "normals.hpp"

#include <Eigen/Eigenvalues>

KISSM_DETAIL_BEGIN

void symmetric_eigen3(const Eigen::Matrix3d &cov, Eigen::Vector3d &eigenvalues_desc, Eigen::Vector3d &smallest_vec) {
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es;
    es.computeDirect(cov); // closed form (trigonometric), ascending eigenvalues
    const Eigen::Vector3d ev = es.eigenvalues();
    eigenvalues_desc = Eigen::Vector3d(ev[2], ev[1], ev[0]);
    smallest_vec = es.eigenvectors().col(0);
}

Normals estimate_normals(const std::vector<Vec3f> &points, const Neighborhoods &nb, const NormalParams &params,
                         RunContext &ctx) {
    const std::size_t n = points.size();
    Normals out;
    out.normal.assign(n, Vec3f::Zero());
    out.valid.assign(n, 0);
    const float rn2 = params.normal_radius * params.normal_radius;
    const std::uint64_t tau = static_cast<std::uint64_t>(params.min_neighbors);

    ctx.parallel_for(n, 2048, [&](std::size_t b, std::size_t e) {
        std::vector<std::uint32_t> near; // neighbours within the normal radius, reused across points
        for (std::size_t i = b; i < e; ++i) {
            const std::size_t size = nb.count(i);
            if (size < tau) continue;
            // Covariance about the mean, in double: centred sums avoid cancellation.
            near.clear();
            Eigen::Vector3d mean = Eigen::Vector3d::Zero();
            const std::uint32_t *row = nb.row(i);
            for (std::size_t t = 0; t < size; ++t) {
                const std::uint32_t j = row[t];
                if ((points[j] - points[i]).squaredNorm() < rn2) {
                    near.push_back(j);
                    mean += points[j].cast<double>();
                }
            }
            const std::uint64_t count = near.size();
            if (count < tau) continue;
            mean /= static_cast<double>(count);
            Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
            for (const std::uint32_t j : near) {
                const Eigen::Vector3d d = points[j].cast<double>() - mean;
                cov.noalias() += d * d.transpose();
            }
            cov /= static_cast<double>(count);
            Eigen::Vector3d lambda, normal;
            symmetric_eigen3(cov, lambda, normal);
            if (!(lambda[0] > 0.0)) continue;
            const double linearity = (lambda[0] - lambda[1]) / lambda[0];
            if (linearity > params.max_linearity) continue;
            const double len = normal.norm();
            if (!(len > 0.0) || !std::isfinite(len)) continue;
            normal /= len;
            const Eigen::Vector3d to_view = params.viewpoint.cast<double>() - points[i].cast<double>();
            if (normal.dot(to_view) < 0.0) normal = -normal;
            out.normal[i] = normal.cast<float>();
            out.valid[i] = 1;
        }
    });
    return out;
}

std::vector<std::uint32_t> select_keypoints(const Neighborhoods &nb, const Normals &normals, int min_neighbors) {
    std::vector<std::uint32_t> keypoints;
    const std::size_t n = normals.valid.size();
    for (std::size_t i = 0; i < n; ++i) {
        if (!normals.valid[i]) continue;
        int valid_neighbors = 0;
        const std::uint32_t *row = nb.row(i);
        for (std::size_t t = 0, size = nb.count(i); t < size && valid_neighbors < min_neighbors; ++t)
            valid_neighbors += normals.valid[row[t]];
        if (valid_neighbors >= min_neighbors) keypoints.push_back(static_cast<std::uint32_t>(i));
    }
    return keypoints;
}

KISSM_DETAIL_END

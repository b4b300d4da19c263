// SPDX-License-Identifier: MIT
#include "normals.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

KISSM_DETAIL_BEGIN

void symmetric_eigen3(const Eigen::Matrix3d &cov, Eigen::Vector3d &eigenvalues_desc, Eigen::Vector3d &smallest_vec) {
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es;
    es.computeDirect(cov); // closed form (trigonometric), ascending eigenvalues
    const Eigen::Vector3d ev = es.eigenvalues();
    eigenvalues_desc = Eigen::Vector3d(ev[2], ev[1], ev[0]);
    smallest_vec = es.eigenvectors().col(0);
}

namespace {

// The smallest-eigenvalue direction of a covariance, if the points it sums are not on a line (linearity at most
// max_linearity): the unit normal, else nothing.
bool plane_normal(const Eigen::Matrix3d &cov, double max_linearity, Eigen::Vector3d &normal) {
    Eigen::Vector3d lambda;
    symmetric_eigen3(cov, lambda, normal);
    if (!(lambda[0] > 0.0)) return false;
    const double linearity = (lambda[0] - lambda[1]) / lambda[0];
    if (linearity > max_linearity) return false;
    const double len = normal.norm();
    if (!(len > 0.0) || !std::isfinite(len)) return false;
    normal /= len;
    return true;
}

} // namespace

Normals estimate_normals(const std::vector<Vec3f> &points, const Neighborhoods &nb, const NormalParams &params,
                         RunContext &ctx) {
    return estimate_normal_sets(points, nb, params, 0.0f, ctx).normals;
}

namespace {

// One pass over the neighbours: the planes when plane_radius > 0, the normals when wanted. A plane is a function of
// the same rows whether the normals are computed beside it or not, so estimate_planes gives the bits of
// estimate_normal_sets' planes.
NormalSets normal_pass(const std::vector<Vec3f> &points, const Neighborhoods &nb, const NormalParams &params,
                       float plane_radius, bool want_normals, RunContext &ctx) {
    const std::size_t n = points.size();
    NormalSets sets;
    Normals &out = sets.normals;
    const bool planes = plane_radius > 0.0f;
    if (planes) {
        sets.planes.normal.assign(n, Vec3f::Zero());
        sets.planes.valid.assign(n, 0);
    }
    if (want_normals) {
        out.normal.assign(n, Vec3f::Zero());
        out.valid.assign(n, 0);
    }
    const bool open_signs =
        want_normals && params.orientation == NormalOrientation::AwayFromNeighbours && params.open_sign_offset > 0.0f;
    if (open_signs) out.open_sign.assign(n, 0);
    const double open_offset = params.open_sign_offset;
    const bool away = want_normals && params.orientation == NormalOrientation::AwayFromNeighbours;
    const float rn2 = params.normal_radius * params.normal_radius, rp2 = plane_radius * plane_radius;
    const std::uint64_t tau = static_cast<std::uint64_t>(params.min_neighbors);
    const std::uint64_t plane_tau = std::max<std::uint64_t>(kPlaneMinNeighbors, tau);

    ctx.parallel_for(n, 2048, [&](std::size_t b, std::size_t e) {
        std::vector<std::uint32_t> near; // neighbours within the normal radius, reused across points
        std::vector<float> near_d2;      // their squared distances
        for (std::size_t i = b; i < e; ++i) {
            const std::size_t size = nb.count(i);
            if (size < tau) continue;
            // Covariance about the mean, in double: centred sums avoid cancellation.
            // Sized once per row, written by index: a push_back in the loop would make the compiler keep the sums
            // below in memory around the call it may make.
            if (near.size() < size) near.resize(size), near_d2.resize(size);
            std::size_t count = 0;
            Eigen::Vector3d mean = Eigen::Vector3d::Zero();
            // AwayFromNeighbours: offsets of all the neighbours from the point, in double and in row order (no
            // cancellation, the same at any thread count), summed in the same pass.
            const Eigen::Vector3d p = points[i].cast<double>();
            Eigen::Vector3d to_centroid = Eigen::Vector3d::Zero();
            const std::uint32_t *row = nb.row(i);
            for (std::size_t t = 0; t < size; ++t) {
                const std::uint32_t j = row[t];
                const float d2 = (points[j] - points[i]).squaredNorm();
                if (away) to_centroid += points[j].cast<double>() - p;
                if (d2 < rn2) {
                    near[count] = j;
                    near_d2[count++] = d2;
                    mean += points[j].cast<double>();
                }
            }
            if (count < tau) continue;
            if (planes) {
                // The smaller neighbourhood, summed about the point itself (a few voxels wide: no cancellation).
                Eigen::Vector3d s = Eigen::Vector3d::Zero();
                Eigen::Matrix3d ss = Eigen::Matrix3d::Zero();
                std::uint64_t m = 0;
                for (std::size_t t = 0; t < count; ++t) {
                    if (!(near_d2[t] < rp2)) continue;
                    const Eigen::Vector3d d = points[near[t]].cast<double>() - p;
                    s += d;
                    ss.noalias() += d * d.transpose();
                    ++m;
                }
                Eigen::Vector3d normal;
                if (m >= plane_tau) {
                    const double inv = 1.0 / static_cast<double>(m);
                    if (plane_normal(ss * inv - (s * inv) * (s * inv).transpose(), params.max_linearity, normal)) {
                        sets.planes.normal[i] = normal.cast<float>();
                        sets.planes.valid[i] = 1;
                    }
                }
            }
            if (!want_normals) continue;
            mean /= static_cast<double>(count);
            // The six distinct sums of d d^T (the other three are the same products, so the same bits).
            double sxx = 0, sxy = 0, sxz = 0, syy = 0, syz = 0, szz = 0;
            for (std::size_t t = 0; t < count; ++t) {
                const std::uint32_t j = near[t];
                const double dx = static_cast<double>(points[j].x()) - mean.x();
                const double dy = static_cast<double>(points[j].y()) - mean.y();
                const double dz = static_cast<double>(points[j].z()) - mean.z();
                sxx += dx * dx, sxy += dx * dy, sxz += dx * dz, syy += dy * dy, syz += dy * dz, szz += dz * dz;
            }
            Eigen::Matrix3d cov;
            cov << sxx, sxy, sxz, sxy, syy, syz, sxz, syz, szz;
            cov /= static_cast<double>(count);
            Eigen::Vector3d normal;
            if (!plane_normal(cov, params.max_linearity, normal)) continue;
            if (params.orientation == NormalOrientation::TowardViewpoint) {
                const Eigen::Vector3d to_view = params.viewpoint.cast<double>() - points[i].cast<double>();
                if (normal.dot(to_view) < 0.0) normal = -normal;
            } else if (away) {
                const double along = normal.dot(to_centroid);
                if (along > 0.0) normal = -normal;
                if (open_signs && std::fabs(along) < open_offset * static_cast<double>(size)) out.open_sign[i] = 1;
            }
            out.normal[i] = normal.cast<float>();
            out.valid[i] = 1;
        }
    });
    return sets;
}

} // namespace

NormalSets estimate_normal_sets(const std::vector<Vec3f> &points, const Neighborhoods &nb, const NormalParams &params,
                                float plane_radius, RunContext &ctx) {
    return normal_pass(points, nb, params, plane_radius, true, ctx);
}

Normals estimate_planes(const std::vector<Vec3f> &points, const Neighborhoods &nb, const NormalParams &params,
                        float plane_radius, RunContext &ctx) {
    return normal_pass(points, nb, params, plane_radius, false, ctx).planes;
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

// SPDX-License-Identifier: MIT
// A caller's 4x4 rigid transform (kissm_refine's initial pose), checked and made exactly rigid.
#include <Eigen/LU>
#include <Eigen/SVD>
#include <cmath>
#include <string>

#include "capi/boundary.hpp"
#include "capi/conversions.hpp"

KISSM_DETAIL_BEGIN
namespace capi {

namespace {
// Rotation blocks printed with 6-7 digits, or composed in single precision, are orthonormal to about 1e-6;
// ground-truth files of public datasets to 7e-5. 1e-3 accepts all of them and refuses a scaled or sheared
// matrix.
constexpr double kOrthonormalTolerance = 1e-3;
// Georeferenced coordinates reach 1e7 m; a translation beyond 1e9 m is a unit or layout mistake.
constexpr double kMaxTranslation = 1e9;
} // namespace

void rigid_transform(const double *m, const char *name, Eigen::Matrix3d &R, Eigen::Vector3d &t) {
    require_non_null(m, name);
    for (int k = 0; k < 16; ++k)
        if (!std::isfinite(m[k]))
            fail(ErrorKind::InvalidArgument, std::string(name) + "[" + std::to_string(k) + "] is not finite");
    if (m[12] != 0.0 || m[13] != 0.0 || m[14] != 0.0 || m[15] != 1.0)
        fail(ErrorKind::InvalidArgument, std::string(name) + "'s last row is (" + number(m[12]) + ", " + number(m[13]) +
                                             ", " + number(m[14]) + ", " + number(m[15]) +
                                             "); a rigid transform has (0, 0, 0, 1)");
    Eigen::Matrix3d A;
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) A(i, j) = m[4 * i + j];
        t[i] = m[4 * i + 3];
    }
    const double off = (A.transpose() * A - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
    if (!(off <= kOrthonormalTolerance) || !(A.determinant() > 0.0))
        fail(ErrorKind::InvalidArgument, std::string(name) + "'s rotation block is not a rotation (R^T R - I is " +
                                             number(off) + " off, det R = " + number(A.determinant()) + "; at most " +
                                             number(kOrthonormalTolerance) + " off and det > 0)");
    if (!(t.cwiseAbs().maxCoeff() <= kMaxTranslation))
        fail(ErrorKind::InvalidArgument,
             std::string(name) + "'s translation (" + number(t.norm()) + ") is beyond " + number(kMaxTranslation));
    // The nearest rotation (polar decomposition): the pose the caller meant, exactly rigid.
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(A, Eigen::ComputeFullU | Eigen::ComputeFullV);
    R = svd.matrixU() * svd.matrixV().transpose();
}

} // namespace capi
KISSM_DETAIL_END

#include "input.hpp"

#include <cmath>
#include <cstring>

#include "failure.hpp"

namespace kissm {
// Versioned so that two kissm versions linked statically into one program never share a symbol.
inline namespace v0_1 {
namespace detail {

namespace {

template <typename T>
Vec3d load(const unsigned char *p) {
    T xyz[3];
    std::memcpy(xyz, p, sizeof(xyz)); // strides need not be aligned
    return Vec3d(static_cast<double>(xyz[0]), static_cast<double>(xyz[1]), static_cast<double>(xyz[2]));
}

} // namespace

InputCloud gather_points(const PointsView &view, NonFinitePolicy policy, const std::string &name) {
    InputCloud cloud;
    cloud.num_given = view.count;
    cloud.points.reserve(view.count);
    const auto *base = static_cast<const unsigned char *>(view.data);
    bool first = true;
    for (std::uint64_t i = 0; i < view.count; ++i) {
        const unsigned char *p = base + i * view.stride_bytes;
        const Vec3d v = view.is_double ? load<double>(p) : load<float>(p);
        if (!std::isfinite(v.x()) || !std::isfinite(v.y()) || !std::isfinite(v.z())) {
            if (policy == NonFinitePolicy::Reject)
                fail(ErrorKind::NonFinite, name + " point " + std::to_string(i) +
                                               " has a non-finite coordinate (set nonfinite_policy to "
                                               "KISSM_NONFINITE_DROP to skip such points)");
            ++cloud.num_nonfinite;
            continue;
        }
        if (first) {
            cloud.min = cloud.max = v;
            first = false;
        } else {
            cloud.min = cloud.min.cwiseMin(v);
            cloud.max = cloud.max.cwiseMax(v);
        }
        cloud.points.push_back(v);
    }
    return cloud;
}

} // namespace detail
} // namespace v0_1
} // namespace kissm

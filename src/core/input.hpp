// Stage 0: reading the caller's points (zero-copy view), applying the non-finite policy.
#pragma once

#include <string>

#include "cloud.hpp"
#include "params.hpp"

namespace kissm {
namespace detail {

// `name` ("source", "target", "cloud") is used in error messages.
InputCloud gather_points(const PointsView &view, NonFinitePolicy policy, const std::string &name);

} // namespace detail
} // namespace kissm

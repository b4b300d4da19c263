// SPDX-License-Identifier: MIT
// Stage 0: reading the caller's points (zero-copy view), applying the non-finite policy.
#pragma once

#include <string>

#include "cloud.hpp"
#include "params.hpp"
#include "run_context.hpp"

namespace kissm {
// Versioned so that two kissm versions linked statically into one program never share a symbol.
inline namespace v0_1 {
namespace detail {

// `name` ("source", "target", "cloud") is used in error messages. Under NonFinitePolicy::Reject the error
// names the first non-finite point, whatever the thread count.
InputCloud gather_points(const PointsView &view, NonFinitePolicy policy, const std::string &name, RunContext &ctx);

} // namespace detail
} // namespace v0_1
} // namespace kissm

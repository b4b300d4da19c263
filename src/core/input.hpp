// SPDX-License-Identifier: MIT
// Stage 0: reading the caller's points (zero-copy view), applying the non-finite policy.
#pragma once

#include <string>

#include "detail_namespace.hpp"
#include "params.hpp"
#include "run_context.hpp"
#include "stage_types.hpp"

KISSM_DETAIL_BEGIN

// `name` ("source", "target", "cloud") is used in error messages. Under NonFinitePolicy::Reject the error
// names the first non-finite point, whatever the thread count.
InputCloud gather_points(const PointsView &view, NonFinitePolicy policy, const std::string &name, RunContext &ctx);

KISSM_DETAIL_END

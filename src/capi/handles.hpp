// SPDX-License-Identifier: MIT
// The C++ objects behind the opaque C handles.
#pragma once

#include <atomic>
#include <vector>

#include "core/params.hpp"
#include "core/pipeline.hpp"
#include "kissm.h"

struct kissm_matcher {
    kissm_config config;                  // as given (validated), for kissm_get_config and the hooks
    kissm::detail::Params params;         // the same, as the pipeline reads it
    std::atomic<int> cancel_requested{0}; // set by kissm_cancel from any thread
};

struct kissm_features {
    kissm::detail::CloudFeatures data; // immutable after creation: safe to share between threads
};

struct kissm_cloud {
    std::vector<double> xyz;
};

// SPDX-License-Identifier: MIT
// The C++ objects behind the opaque C handles.
#pragma once

#include <atomic>
#include <vector>

#include "capi/conversions.hpp"
#include "core/params.hpp"
#include "core/pipeline.hpp"
#include "core/pose_graph.hpp"
#include "core/run_context.hpp"
#include "kissm.h"

struct kissm_matcher {
    kissm_config config;                  // as given (validated), for kissm_get_config and the hooks
    kissm::detail::Params params;         // the same, as the pipeline reads it
    std::atomic<int> cancel_requested{0}; // set by kissm_cancel from any thread

    // The context of one call: a cancel request made before the call is dropped, the threads and hooks are
    // the config's.
    kissm::detail::RunContext begin_call() {
        cancel_requested.store(0);
        return kissm::detail::RunContext(params.num_threads, &cancel_requested, kissm::detail::capi::hooks_of(config));
    }
};

struct kissm_features {
    kissm::detail::CloudFeatures data; // immutable after creation: safe to share between threads
};

struct kissm_cloud {
    std::vector<double> xyz;
};

struct kissm_pose_graph {
    std::size_t num_nodes = 0;
    std::vector<kissm::detail::PoseGraphEdge> edges;
    bool solved = false; // solution is that of the current edges
    kissm::detail::PoseGraphSolution solution;
    std::atomic<int> cancel_requested{0}; // set by kissm_pose_graph_cancel from any thread
};

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
    std::uint64_t withheld = 0; // points the reader left out on purpose (LAS/LAZ withheld)
};

struct kissm_pose_graph {
    std::size_t num_nodes = 0;
    std::vector<kissm::detail::PoseGraphEdge> edges;
    bool solved = false; // solution is that of the current edges
    kissm::detail::PoseGraphSolution solution;
    std::atomic<int> cancel_requested{0}; // set by kissm_pose_graph_cancel from any thread
};

KISSM_DETAIL_BEGIN
namespace capi {

// One registration of kissm_align_features, in the order the pairs ran, with the edge the graph made of it.
struct AlignedPair {
    std::size_t source = 0, target = 0;
    kissm_result result;   // this kissm's full layout
    bool robust = true;    // false: a session's odometry, a trusted edge
    bool held_out = false; // a valid registration between pieces of a sequence that the others do not corroborate
    int32_t edge = -1;     // -1: not an edge (not valid, or the graph refused it); 0 rejected; 1 accepted
    double information[36];
    double residual = 0.0;
};

} // namespace capi
KISSM_DETAIL_END

struct kissm_alignment {
    std::size_t num_scans = 0;
    std::vector<kissm::detail::capi::AlignedPair> registrations;
    kissm::detail::PoseGraphSolution solution;
};

KISSM_DETAIL_BEGIN
namespace capi {

// kissm_pose_graph_add_edge's checks and the edge added (the graph's last solution forgotten); throws Failure.
void add_pose_graph_edge(kissm_pose_graph &graph, uint64_t source, uint64_t target, const double transform[16],
                         const double information[36], int32_t robust);

// A solution's nodes as kissm_pose_graph_poses() writes them; any output may be null.
void write_pose_graph_poses(const PoseGraphSolution &solution, std::size_t num_nodes, double *out_poses,
                            uint8_t *out_placed, uint64_t *out_components);

} // namespace capi
KISSM_DETAIL_END

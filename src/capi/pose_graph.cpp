// SPDX-License-Identifier: MIT
// The pose graph handle: edges in, one optimisation, the solution out (src/core/pose_graph.hpp).
#include <cmath>
#include <memory>
#include <string>

#include <Eigen/Cholesky>

#include "capi/boundary.hpp"
#include "capi/conversions.hpp"
#include "capi/handles.hpp"

using namespace kissm::detail::capi;
namespace core = kissm::detail;

namespace {

// How far from symmetric an information may be, relative to its largest entry: a matrix written out by another
// program in decimal, or summed in another order, is symmetric to about this.
constexpr double kSymmetryTolerance = 1e-9;

std::size_t node_index(uint64_t node, const kissm_pose_graph &g, const char *name) {
    if (node >= g.num_nodes)
        core::fail(core::ErrorKind::InvalidArgument, std::string(name) + " is " + std::to_string(node) +
                                                         "; the graph has nodes 0 to " +
                                                         std::to_string(g.num_nodes - 1));
    return static_cast<std::size_t>(node);
}

core::Matrix6d information_matrix(const double *m) {
    require_non_null(m, "information");
    core::Matrix6d I;
    double largest = 0.0;
    for (int k = 0; k < 36; ++k) {
        if (!std::isfinite(m[k]))
            core::fail(core::ErrorKind::InvalidArgument, "information[" + std::to_string(k) + "] is not finite");
        I(k / 6, k % 6) = m[k];
        largest = std::max(largest, std::abs(m[k]));
    }
    const double asymmetry = (I - I.transpose()).cwiseAbs().maxCoeff();
    if (!(asymmetry <= kSymmetryTolerance * largest))
        core::fail(core::ErrorKind::InvalidArgument, "information is not symmetric (|I - I^T| reaches " +
                                                         number(asymmetry) + " of a largest entry " + number(largest) +
                                                         ")");
    I = 0.5 * (I + I.transpose());
    const Eigen::LLT<core::Matrix6d> llt(I);
    if (llt.info() != Eigen::Success || !(llt.matrixL().toDenseMatrix().diagonal().minCoeff() > 0.0))
        core::fail(core::ErrorKind::InvalidArgument, "information is not positive definite");
    return I;
}

void require_solution(const kissm_pose_graph *graph) {
    if (!graph->solved)
        core::fail(core::ErrorKind::InvalidArgument,
                   "graph has no solution (not optimised since its last edge, or the optimisation failed)");
}

} // namespace

KISSM_DETAIL_BEGIN
namespace capi {

void add_pose_graph_edge(kissm_pose_graph &graph, uint64_t source, uint64_t target, const double transform[16],
                         const double information[36], int32_t robust) {
    require_non_null(transform, "transform");
    require_non_null(information, "information");
    core::PoseGraphEdge e;
    e.source = node_index(source, graph, "source");
    e.target = node_index(target, graph, "target");
    if (e.source == e.target)
        core::fail(core::ErrorKind::InvalidArgument,
                   "source and target are both " + std::to_string(source) + "; an edge joins two nodes");
    rigid_transform(transform, "transform", e.measured.R, e.measured.t);
    e.information = information_matrix(information);
    if (robust != 0 && robust != 1)
        core::fail(core::ErrorKind::InvalidArgument, "robust is " + std::to_string(robust) + "; 0 or 1");
    e.robust = robust == 1;
    graph.edges.push_back(e);
    graph.solved = false;
}

void write_pose_graph_poses(const core::PoseGraphSolution &s, std::size_t num_nodes, double *out_poses,
                            uint8_t *out_placed, uint64_t *out_components) {
    for (std::size_t i = 0; i < num_nodes; ++i) {
        if (out_poses != nullptr) {
            double *m = out_poses + 16 * i;
            for (int r = 0; r < 3; ++r) {
                for (int c = 0; c < 3; ++c) m[4 * r + c] = s.poses[i].R(r, c);
                m[4 * r + 3] = s.poses[i].t[r];
            }
            const double last = s.placed[i] ? 1.0 : std::nan("");
            m[12] = m[13] = m[14] = s.placed[i] ? 0.0 : std::nan("");
            m[15] = last;
        }
        if (out_placed != nullptr) out_placed[i] = s.placed[i];
        if (out_components != nullptr) out_components[i] = s.component[i];
    }
}

} // namespace capi
KISSM_DETAIL_END

extern "C" {

int32_t kissm_pose_graph_create(uint64_t num_nodes, kissm_pose_graph **out_graph) {
    return guarded("kissm_pose_graph_create", [&] {
        require_non_null(out_graph, "out_graph");
        if (num_nodes == 0 || num_nodes > KISSM_POSE_GRAPH_MAX_NODES)
            core::fail(core::ErrorKind::InvalidArgument, "num_nodes is " + std::to_string(num_nodes) + "; 1 to " +
                                                             std::to_string(KISSM_POSE_GRAPH_MAX_NODES));
        auto g = std::make_unique<kissm_pose_graph>();
        g->num_nodes = static_cast<std::size_t>(num_nodes);
        *out_graph = g.release();
        return ok();
    });
}

void kissm_pose_graph_destroy(kissm_pose_graph *graph) { delete graph; }

uint64_t kissm_pose_graph_num_nodes(const kissm_pose_graph *graph) { return graph ? graph->num_nodes : 0; }
uint64_t kissm_pose_graph_num_edges(const kissm_pose_graph *graph) { return graph ? graph->edges.size() : 0; }

int32_t kissm_pose_graph_add_edge(kissm_pose_graph *graph, uint64_t source, uint64_t target, const double transform[16],
                                  const double information[36], int32_t robust, uint64_t *out_edge) {
    return guarded("kissm_pose_graph_add_edge", [&] {
        require_non_null(graph, "graph");
        add_pose_graph_edge(*graph, source, target, transform, information, robust);
        if (out_edge != nullptr) *out_edge = graph->edges.size() - 1;
        return ok();
    });
}

int32_t kissm_pose_graph_optimize(kissm_pose_graph *graph, uint64_t anchor, double bound) {
    return guarded("kissm_pose_graph_optimize", [&] {
        require_non_null(graph, "graph");
        const std::size_t a = node_index(anchor, *graph, "anchor");
        if (!(bound > 0.0) || !std::isfinite(bound))
            core::fail(core::ErrorKind::InvalidArgument, "bound is " + number(bound) + "; a finite number above 0");
        graph->cancel_requested.store(0);
        graph->solved = false;
        graph->solution = core::optimize_pose_graph(graph->num_nodes, graph->edges, a, bound, &graph->cancel_requested);
        graph->solved = true;
        return ok();
    });
}

void kissm_pose_graph_cancel(kissm_pose_graph *graph) {
    if (graph != nullptr) graph->cancel_requested.store(1);
}

int32_t kissm_pose_graph_poses(const kissm_pose_graph *graph, double *out_poses, uint8_t *out_placed,
                               uint64_t *out_components) {
    return guarded("kissm_pose_graph_poses", [&] {
        require_non_null(graph, "graph");
        require_solution(graph);
        write_pose_graph_poses(graph->solution, graph->num_nodes, out_poses, out_placed, out_components);
        return ok();
    });
}

int32_t kissm_pose_graph_edges(const kissm_pose_graph *graph, uint8_t *out_accepted, double *out_residuals) {
    return guarded("kissm_pose_graph_edges", [&] {
        require_non_null(graph, "graph");
        require_solution(graph);
        const core::PoseGraphSolution &s = graph->solution;
        for (std::size_t e = 0; e < graph->edges.size(); ++e) {
            if (out_accepted != nullptr) out_accepted[e] = s.accepted[e];
            if (out_residuals != nullptr) out_residuals[e] = s.residual[e];
        }
        return ok();
    });
}

} // extern "C"

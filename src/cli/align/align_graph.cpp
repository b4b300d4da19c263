// SPDX-License-Identifier: MIT
#include "align_graph.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include <kissm.h>

#include "cli_args.hpp"
#include "report.hpp"

namespace kissm_cli {
namespace {

struct GraphDeleter {
    void operator()(kissm_pose_graph *graph) const { kissm_pose_graph_destroy(graph); }
};
using GraphPtr = std::unique_ptr<kissm_pose_graph, GraphDeleter>;

bool all_finite(const std::vector<double> &values) {
    return std::all_of(values.begin(), values.end(), [](double v) { return std::isfinite(v); });
}

} // namespace

void edge_information(const DoneRecord &record, double information[36]) {
    if (record.information.size() == 36 && all_finite(record.information)) {
        std::copy(record.information.begin(), record.information.end(), information);
        return;
    }
    // As Python's max(value, floor) (NaN stays NaN, and the graph then refuses the edge) and value ** -2 (pow).
    const auto at_least = [](double value, double floor) { return floor > value ? floor : value; };
    const double rotation = std::pow(at_least(record.rotation_uncertainty, 1e-4), -2.0);
    const double translation = std::pow(at_least(record.noise_bound, 1e-9), -2.0);
    std::fill(information, information + 36, 0.0);
    for (int i = 0; i < 6; ++i) information[7 * i] = i < 3 ? rotation : translation;
}

Alignment solve_alignment(size_t scans, const std::vector<ScanPair> &pairs, const std::vector<DoneRecord> &records,
                          double bound, const std::vector<uint8_t> &held_out) {
    std::vector<const DoneRecord *> by_pair(pairs.size(), nullptr);
    for (const DoneRecord &record : records) {
        if (record.pair >= 1 && record.pair <= static_cast<int64_t>(pairs.size())) {
            by_pair[static_cast<size_t>(record.pair - 1)] = &record;
        }
    }
    kissm_pose_graph *raw = nullptr;
    int32_t status = kissm_pose_graph_create(scans, &raw);
    if (status != KISSM_OK) throw UsageError("cannot make the pose graph: " + library_error(status));
    const GraphPtr graph(raw);

    Alignment a;
    std::vector<size_t> in_graph; // the edges the graph holds, in its order
    for (size_t k = 0; k < pairs.size(); ++k) {
        const DoneRecord *record = by_pair[k];
        if (!record) throw UsageError("the results have no record of pair " + std::to_string(k + 1));
        if (record->error) {
            ++a.errors;
            continue;
        }
        if (!record->valid) {
            ++a.invalid;
            continue;
        }
        ++a.valid;
        AlignEdge edge;
        edge.pair = record->pair;
        edge.source = pairs[k].source;
        edge.target = pairs[k].target;
        const std::string what = "pair " + std::to_string(edge.pair) + " ('" + one_line(record->source) + "' to '" +
                                 one_line(record->target) + "')";
        if (record->transform.size() != 16 || !all_finite(record->transform)) {
            a.skipped.push_back(what + " is valid but its record has no finite transform");
            continue;
        }
        std::copy(record->transform.begin(), record->transform.end(), edge.transform);
        edge_information(*record, edge.information);
        if (k < held_out.size() && held_out[k]) {
            edge.residual = std::numeric_limits<double>::quiet_NaN();
            a.edges.push_back(edge);
            continue;
        }
        status = kissm_pose_graph_add_edge(graph.get(), edge.source, edge.target, edge.transform, edge.information,
                                           pairs[k].trusted ? 0 : 1, nullptr);
        if (status != KISSM_OK) {
            a.skipped.push_back(what + ": the pose graph refuses it: " + library_error(status));
            continue;
        }
        in_graph.push_back(a.edges.size());
        a.edges.push_back(edge);
    }

    status = kissm_pose_graph_optimize(graph.get(), 0, bound);
    if (status != KISSM_OK) throw UsageError("cannot optimise the pose graph: " + library_error(status));
    a.poses.assign(16 * scans, 0.0);
    a.placed.assign(scans, 0);
    a.components.assign(scans, 0);
    status = kissm_pose_graph_poses(graph.get(), a.poses.data(), a.placed.data(), a.components.data());
    std::vector<uint8_t> accepted(in_graph.size(), 0);
    std::vector<double> residuals(in_graph.size(), std::numeric_limits<double>::quiet_NaN());
    if (status == KISSM_OK && !in_graph.empty()) {
        status = kissm_pose_graph_edges(graph.get(), accepted.data(), residuals.data());
    }
    if (status != KISSM_OK) throw UsageError("cannot read the pose graph's solution: " + library_error(status));
    for (size_t e = 0; e < in_graph.size(); ++e) {
        a.edges[in_graph[e]].accepted = accepted[e] != 0;
        a.edges[in_graph[e]].residual = residuals[e];
    }
    return a;
}

} // namespace kissm_cli

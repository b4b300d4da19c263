// SPDX-License-Identifier: MIT
// Multiway alignment (kissm_align_features) and its loop-candidate rule (kissm_sequence_loops). The job is the C
// API's own calls composed as Python's kissm.multiway.align composes them: kissm_register_features per pair, each
// valid kissm_result made an edge through kissm_pose_graph_add_edge's conversions, one optimisation. So the same
// features, settings and pairs give the same bits in C, Python and the CLI (docs/multiway.md).
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "capi/boundary.hpp"
#include "capi/conversions.hpp"
#include "capi/handles.hpp"
#include "core/loop_agreement.hpp"
#include "core/loop_candidates.hpp"
#include "core/signature.hpp"
#include "core/similar_loops.hpp"

using namespace kissm::detail::capi;
namespace core = kissm::detail;

namespace {

constexpr uint64_t kMaxPairs = 100000000;
constexpr int64_t kMaxLoopSetting = 1000000;
// A loop radius of 0 means this many voxels (Python's kissm.multiway default).
constexpr double kDefaultRadiusVoxels = 30.0;

// kissm_align_options has no published layout yet: only this kissm's size is taken.
constexpr StructSizes kAlignOptionsSizes{"kissm_align_options", nullptr, 0, sizeof(kissm_align_options)};

kissm_align_options default_options() {
    kissm_align_options o{};
    o.struct_size = sizeof o;
    o.pairs = KISSM_PAIRS_ALL;
    o.pair_list = nullptr;
    o.num_pairs = 0;
    o.priors = nullptr;
    o.loop_radius = 0.0;
    o.loop_gap = 10;
    o.loops_per_scan = 5;
    o.bound = KISSM_POSE_GRAPH_DEFAULT_BOUND;
    o.sessions = nullptr;
    o.stride = 10;
    o.reserved = 0;
    o.similar_per_scan = 3;
    o.reserved2 = 0;
    return o;
}

[[noreturn]] void invalid(const std::string &message) { core::fail(core::ErrorKind::InvalidArgument, message); }

void check_scans(uint64_t num_scans) {
    if (num_scans == 0 || num_scans > KISSM_POSE_GRAPH_MAX_NODES)
        invalid("num_scans is " + std::to_string(num_scans) + "; 1 to " + std::to_string(KISSM_POSE_GRAPH_MAX_NODES));
}

void check_loop_settings(double radius, const char *radius_name, bool zero_allowed, uint64_t gap, const char *gap_name,
                         uint64_t per_scan, const char *per_scan_name) {
    if (!std::isfinite(radius) || radius < 0.0 || (radius == 0.0 && !zero_allowed))
        invalid(std::string(radius_name) + " is " + number(radius) +
                (zero_allowed ? "; 0 (30 voxels) or a finite number above 0" : "; a finite number above 0"));
    if (gap < 1 || gap > static_cast<uint64_t>(kMaxLoopSetting))
        invalid(std::string(gap_name) + " is " + std::to_string(gap) + "; 1 to " + std::to_string(kMaxLoopSetting));
    if (per_scan > static_cast<uint64_t>(kMaxLoopSetting))
        invalid(std::string(per_scan_name) + " is " + std::to_string(per_scan) + "; 0 to " +
                std::to_string(kMaxLoopSetting));
}

// The options as given (NULL: the defaults), checked against the policy.
kissm_align_options checked_options(const kissm_align_options *given, uint64_t num_scans) {
    if (given == nullptr) return default_options();
    check_struct_size("options->struct_size", given->struct_size, kAlignOptionsSizes, given);
    const kissm_align_options o = *given;
    if (o.pairs < KISSM_PAIRS_ALL || o.pairs > KISSM_PAIRS_SESSIONS)
        invalid("options->pairs is " + std::to_string(o.pairs) +
                "; KISSM_PAIRS_ALL (0), KISSM_PAIRS_SEQUENCE (1), KISSM_PAIRS_LIST (2) or KISSM_PAIRS_SESSIONS (3)");
    if (o.pairs == KISSM_PAIRS_LIST) {
        if (o.num_pairs > kMaxPairs)
            invalid("options->num_pairs is " + std::to_string(o.num_pairs) + "; 0 to " + std::to_string(kMaxPairs));
        if (o.num_pairs > 0) require_non_null(o.pair_list, "options->pair_list");
        for (uint64_t k = 0; k < o.num_pairs; ++k) {
            const uint64_t s = o.pair_list[2 * k], t = o.pair_list[2 * k + 1];
            if (s >= num_scans || t >= num_scans)
                invalid("options->pair_list pair " + std::to_string(k) + " is (" + std::to_string(s) + ", " +
                        std::to_string(t) + "); scans are 0 to " + std::to_string(num_scans - 1));
            if (s == t)
                invalid("options->pair_list pair " + std::to_string(k) + " pairs scan " + std::to_string(s) +
                        " with itself");
        }
    } else if (o.pair_list != nullptr || o.num_pairs != 0) {
        invalid("options->pair_list and options->num_pairs are read by KISSM_PAIRS_LIST only; NULL and 0 here");
    }
    if (o.pairs != KISSM_PAIRS_SEQUENCE && o.priors != nullptr)
        invalid("options->priors is read by KISSM_PAIRS_SEQUENCE only; NULL here");
    check_loop_settings(
        o.loop_radius, "options->loop_radius", true, o.loop_gap < 0 ? 0 : uint64_t(o.loop_gap), "options->loop_gap",
        o.loops_per_scan < 0 ? uint64_t(kMaxLoopSetting) + 1 : uint64_t(o.loops_per_scan), "options->loops_per_scan");
    if (!(o.bound > 0.0) || !std::isfinite(o.bound))
        invalid("options->bound is " + number(o.bound) + "; a finite number above 0");
    if (o.pairs == KISSM_PAIRS_SESSIONS) {
        require_non_null(o.sessions, "options->sessions");
        for (uint64_t k = 0; k < num_scans; ++k) {
            const uint32_t before = k == 0 ? 0 : o.sessions[k - 1];
            if (o.sessions[k] != before && !(k > 0 && o.sessions[k] == before + 1))
                invalid("options->sessions[" + std::to_string(k) + "] is " + std::to_string(o.sessions[k]) +
                        (k == 0 ? "; 0 (the first scan's session)"
                                : "; " + std::to_string(before) + " or " + std::to_string(before + 1) +
                                      " (the scans in session order)"));
        }
    } else if (o.sessions != nullptr) {
        invalid("options->sessions is read by KISSM_PAIRS_SESSIONS only; NULL here");
    }
    if (o.stride < 1 || o.stride > kMaxLoopSetting)
        invalid("options->stride is " + std::to_string(o.stride) + "; 1 to " + std::to_string(kMaxLoopSetting));
    if (o.reserved != 0) invalid("options->reserved is " + std::to_string(o.reserved) + "; 0");
    if (o.similar_per_scan < 0 || o.similar_per_scan > kMaxLoopSetting)
        invalid("options->similar_per_scan is " + std::to_string(o.similar_per_scan) + "; 0 to " +
                std::to_string(kMaxLoopSetting));
    if (o.reserved2 != 0) invalid("options->reserved2 is " + std::to_string(o.reserved2) + "; 0");
    return o;
}

// The pairs of round 1 (all, consecutive, or the list), in the policy's order.
std::vector<core::ScanPair> first_pairs(const kissm_align_options &o, std::size_t n) {
    std::vector<core::ScanPair> pairs;
    if (o.pairs == KISSM_PAIRS_ALL) {
        for (std::size_t i = 0; i < n; ++i)
            for (std::size_t j = i + 1; j < n; ++j) pairs.push_back({j, i});
    } else if (o.pairs == KISSM_PAIRS_SEQUENCE) {
        for (std::size_t i = 0; i + 1 < n; ++i) pairs.push_back({i + 1, i});
    } else {
        for (uint64_t k = 0; k < o.num_pairs; ++k)
            pairs.push_back(
                {static_cast<std::size_t>(o.pair_list[2 * k]), static_cast<std::size_t>(o.pair_list[2 * k + 1])});
    }
    return pairs;
}

// Registers the pairs whose scans both have features, one pair per thread of the matcher, each on a context of
// one thread (the results do not depend on the thread count), appending them to the alignment in pair order.
void register_pairs(kissm_matcher &matcher, core::RunContext &ctx, const kissm_features *const *features,
                    const std::vector<core::ScanPair> &pairs, kissm_alignment &out, bool robust = true) {
    std::vector<core::ScanPair> runnable;
    for (const core::ScanPair &p : pairs)
        if (features[p.source] != nullptr && features[p.target] != nullptr) runnable.push_back(p);
    std::vector<core::Registration> done(runnable.size());
    ctx.parallel_for(runnable.size(), 1, [&](std::size_t begin, std::size_t end) {
        core::RunContext one(1, &matcher.cancel_requested, core::Hooks{});
        for (std::size_t k = begin; k < end; ++k) {
            const core::ScanPair &p = runnable[k];
            done[k] = core::register_features(features[p.source]->data, features[p.target]->data, matcher.params, one);
        }
    });
    for (std::size_t k = 0; k < runnable.size(); ++k) {
        AlignedPair r;
        r.source = runnable[k].source;
        r.target = runnable[k].target;
        r.robust = robust;
        r.result.struct_size = sizeof r.result;
        fill_result(done[k], &r.result);
        out.registrations.push_back(r);
    }
}

double loop_radius(const kissm_align_options &o, double voxel) {
    return o.loop_radius > 0.0 ? o.loop_radius : kDefaultRadiusVoxels * voxel;
}

// Round 1's valid consecutive registrations chained (a sequence without priors).
core::ScanPlaces sequence_chain(const kissm_alignment &a) {
    std::vector<const double *> steps(a.num_scans - 1, nullptr);
    for (const AlignedPair &r : a.registrations)
        if (r.source == r.target + 1 && r.result.valid) steps[r.target] = r.result.transform;
    return core::dead_reckoned(steps, a.num_scans);
}

// Each scan's signature (a row of NaN for a scan without features), as kissm_features_signature() gives it.
std::vector<double> signatures_of(const kissm_features *const *features, std::size_t n) {
    std::vector<double> rows(core::kSignatureSize * n, std::numeric_limits<double>::quiet_NaN());
    for (std::size_t k = 0; k < n; ++k) {
        if (features[k] == nullptr) continue;
        const auto &f = features[k]->data;
        core::cloud_signature(f.voxels.points, f.descriptors.keypoint, f.descriptors.values.data(), f.params.voxel_size,
                              &rows[core::kSignatureSize * k]);
    }
    return rows;
}

// The pieces' labels alone say whether the chain broke: no break, no similarity candidates (and no signatures).
bool chain_breaks(const core::ScanPlaces &chain) { return !chain.piece.empty() && chain.piece.back() > 0; }

// Round 2 of a sequence: the loop candidates of round 1's consecutive registrations (or of the priors), and
// without priors those by similarity across the chain's breaks, ordered by (source, target) without repeats as
// Python's kissm.multiway.align merges them.
// `chain`: sequence_chain() of round 1 (unread with priors).
std::vector<core::ScanPair> sequence_loops(const kissm_align_options &o, const core::ScanPlaces &chain,
                                           const kissm_features *const *features, std::size_t n, double voxel) {
    if (n < 2) return {};
    const double radius = loop_radius(o, voxel);
    const auto gap = static_cast<std::size_t>(o.loop_gap), per_scan = static_cast<std::size_t>(o.loops_per_scan);
    if (o.priors != nullptr) return core::loop_candidates(core::prior_places(o.priors, n), radius, gap, per_scan, 0.0);
    std::vector<core::ScanPair> loops = core::loop_candidates(chain, radius, gap, per_scan, core::kLoopDrift);
    if (o.similar_per_scan == 0 || !chain_breaks(chain)) return loops;
    const std::vector<core::ScanPair> similar =
        core::similar_candidates(signatures_of(features, n).data(), core::kSignatureSize, chain.piece, gap,
                                 static_cast<std::size_t>(o.similar_per_scan));
    loops.insert(loops.end(), similar.begin(), similar.end());
    const auto order = [](const core::ScanPair &x, const core::ScanPair &y) {
        return x.source != y.source ? x.source < y.source : x.target < y.target;
    };
    std::sort(loops.begin(), loops.end(), order);
    loops.erase(std::unique(loops.begin(), loops.end(),
                            [](const core::ScanPair &x, const core::ScanPair &y) {
                                return x.source == y.source && x.target == y.target;
                            }),
                loops.end());
    return loops;
}

// A sequence without priors whose chain breaks: the valid registrations between pieces that the others do not
// corroborate are held out of the graph (Python's kissm.multiway._uncorroborated).
void hold_out_uncorroborated(const kissm_align_options &o, const core::ScanPlaces &chain, kissm_alignment &a,
                             double voxel) {
    if (o.priors != nullptr || o.similar_per_scan == 0 || a.num_scans < 2 || !chain_breaks(chain)) return;
    std::vector<core::PieceLink> links;
    std::vector<AlignedPair *> owners;
    for (AlignedPair &r : a.registrations) {
        if (!r.result.valid) continue;
        links.push_back({r.target, r.source, r.result.transform});
        owners.push_back(&r);
    }
    const std::vector<std::uint8_t> kept = core::corroborated(links, chain, loop_radius(o, voxel), core::kLoopDrift);
    for (std::size_t k = 0; k < owners.size(); ++k) owners[k]->held_out = kept[k] == 0;
}

// The edge's weight, as Python's kissm.multiway._information: the refined information when it is all finite,
// else an isotropic one from the rotation uncertainty (at least 1e-4 rad) and a translation sigma of the noise
// bound (at least 1e-9), so that coarse edges weigh alike.
void edge_information(const kissm_result &r, double information[36]) {
    if (std::all_of(r.information, r.information + 36, [](double v) { return std::isfinite(v); })) {
        std::copy(r.information, r.information + 36, information);
        return;
    }
    const auto at_least = [](double value, double floor) { return floor > value ? floor : value; };
    const double rotation = std::pow(at_least(r.rotation_uncertainty, 1e-4), -2.0);
    const double translation = std::pow(at_least(r.noise_bound, 1e-9), -2.0);
    std::fill(information, information + 36, 0.0);
    for (int i = 0; i < 6; ++i) information[7 * i] = i < 3 ? rotation : translation;
}

// Every valid registration a robust edge, in order; one optimisation from scan 0.
void solve(kissm_alignment &a, double bound, const std::atomic<int> *cancel) {
    kissm_pose_graph graph;
    graph.num_nodes = a.num_scans;
    std::vector<AlignedPair *> edges;
    for (AlignedPair &r : a.registrations) {
        std::fill(r.information, r.information + 36, std::numeric_limits<double>::quiet_NaN());
        r.residual = std::numeric_limits<double>::quiet_NaN();
        r.edge = -1;
        if (!r.result.valid) continue;
        double information[36];
        edge_information(r.result, information);
        if (r.held_out) {
            // Reported as an edge the graph did not accept, as Python reports it; never added.
            std::copy(information, information + 36, r.information);
            r.edge = 0;
            continue;
        }
        try {
            add_pose_graph_edge(graph, r.source, r.target, r.result.transform, information, r.robust ? 1 : 0);
        } catch (const core::Failure &f) {
            // A pose the graph refuses (an information that is not positive definite) is no edge; anything else
            // is not this edge's doing.
            if (f.kind() != core::ErrorKind::InvalidArgument) throw;
            continue;
        }
        std::copy(information, information + 36, r.information);
        edges.push_back(&r);
    }
    a.solution = core::optimize_pose_graph(a.num_scans, graph.edges, 0, bound, cancel);
    for (std::size_t e = 0; e < edges.size(); ++e) {
        edges[e]->edge = a.solution.accepted[e] ? 1 : 0;
        edges[e]->residual = a.solution.residual[e];
    }
}

// KISSM_PAIRS_SESSIONS, as Python's kissm.multiway.align_sessions: each session's odometry (trusted), then its
// loop candidates and the stride grid across sessions, one optimisation; then each placed scan of a later session
// with the nearest placed scans of earlier sessions, and the optimisation again.
void align_sessions(kissm_matcher &matcher, core::RunContext &ctx, const kissm_features *const *features,
                    const kissm_align_options &o, kissm_alignment &a) {
    const std::size_t n = a.num_scans;
    std::vector<std::size_t> first; // each session's first scan, then n
    for (std::size_t k = 0; k < n; ++k)
        if (k == 0 || o.sessions[k] != o.sessions[k - 1]) first.push_back(k);
    first.push_back(n);
    const std::size_t sessions = first.size() - 1;
    std::vector<core::ScanPair> odometry;
    for (std::size_t s = 0; s < sessions; ++s)
        for (std::size_t k = first[s]; k + 1 < first[s + 1]; ++k) odometry.push_back({k + 1, k});
    register_pairs(matcher, ctx, features, odometry, a, false);

    const double radius = o.loop_radius > 0.0 ? o.loop_radius : kDefaultRadiusVoxels * matcher.config.voxel_size;
    const auto gap = static_cast<std::size_t>(o.loop_gap), per_scan = static_cast<std::size_t>(o.loops_per_scan);
    const auto stride = static_cast<std::size_t>(o.stride);
    std::vector<const double *> step_of(n, nullptr); // step_of[k]: scan k+1 into k, when valid
    for (const AlignedPair &r : a.registrations)
        if (r.result.valid) step_of[r.target] = r.result.transform;
    std::vector<core::ScanPair> wanted;
    for (std::size_t s = 0; s < sessions; ++s) {
        const std::size_t begin = first[s], size = first[s + 1] - begin;
        const std::vector<const double *> steps(step_of.begin() + static_cast<std::ptrdiff_t>(begin),
                                                step_of.begin() + static_cast<std::ptrdiff_t>(begin + size - 1));
        for (const core::ScanPair &p :
             core::loop_candidates(core::dead_reckoned(steps, size), radius, gap, per_scan, core::kLoopDrift))
            wanted.push_back({begin + p.source, begin + p.target});
        for (std::size_t t = 0; t < s; ++t)
            for (std::size_t j = first[s]; j < first[s + 1]; j += stride)
                for (std::size_t i = first[t]; i < first[t + 1]; i += stride) wanted.push_back({j, i});
    }
    register_pairs(matcher, ctx, features, wanted, a);
    solve(a, o.bound, &matcher.cancel_requested);

    // The second round across sessions, from the merged poses.
    std::vector<std::pair<std::size_t, std::size_t>> registered;
    for (const AlignedPair &r : a.registrations) registered.push_back({r.source, r.target});
    std::sort(registered.begin(), registered.end());
    std::vector<std::size_t> placed;
    for (std::size_t k = 0; k < n; ++k)
        if (a.solution.placed[k]) placed.push_back(k);
    std::vector<core::ScanPair> across;
    std::vector<std::pair<double, std::size_t>> near;
    for (const std::size_t k : placed) {
        near.clear();
        const core::Rigid &here = a.solution.poses[k];
        for (const std::size_t e : placed) {
            if (o.sessions[e] >= o.sessions[k]) continue;
            const core::Rigid &there = a.solution.poses[e];
            const double dx = there.t[0] - here.t[0], dy = there.t[1] - here.t[1], dz = there.t[2] - here.t[2];
            const double d = std::sqrt(dx * dx + dy * dy + dz * dz);
            if (d <= radius) near.push_back({d, e});
        }
        std::sort(near.begin(), near.end());
        if (near.size() > per_scan) near.resize(per_scan);
        for (const auto &[d, e] : near) {
            (void)d;
            if (!std::binary_search(registered.begin(), registered.end(),
                                    std::make_pair(k, e))) // register_pairs skips scans without features
                across.push_back({k, e});
        }
    }
    if (!across.empty()) {
        register_pairs(matcher, ctx, features, across, a);
        solve(a, o.bound, &matcher.cancel_requested);
    }
}

// step_valid's flags checked (NULL: every step valid), each valid step pointing into `steps` (or, without steps,
// at the identity: only the pieces are read then).
std::vector<const double *> checked_chain(std::size_t n, const double *steps, const uint8_t *step_valid) {
    static const double kIdentity[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    std::vector<const double *> chain(n - 1, nullptr);
    for (std::size_t k = 0; k + 1 < n; ++k) {
        const uint8_t flag = step_valid ? step_valid[k] : 1;
        if (flag > 1) invalid("step_valid[" + std::to_string(k) + "] is " + std::to_string(flag) + "; 0 or 1");
        if (flag == 1) chain[k] = steps ? steps + 16 * k : kIdentity;
    }
    return chain;
}

void check_gap_and_per_scan(uint64_t gap, uint64_t per_scan) {
    // The radius is not read here: any valid one.
    check_loop_settings(1.0, "radius", false, gap, "gap", per_scan, "per_scan");
}

// Pairs as the candidate calls write them: the count always, the pairs when out_pairs is given and has room.
void write_pairs(const std::vector<core::ScanPair> &pairs, uint64_t *out_pairs, uint64_t capacity,
                 uint64_t *out_count) {
    if (out_pairs != nullptr && capacity < pairs.size()) {
        *out_count = pairs.size();
        invalid("capacity is " + std::to_string(capacity) + "; the candidates are " + std::to_string(pairs.size()) +
                " pairs");
    }
    *out_count = pairs.size();
    if (out_pairs == nullptr) return;
    for (std::size_t k = 0; k < pairs.size(); ++k) {
        out_pairs[2 * k] = pairs[k].source;
        out_pairs[2 * k + 1] = pairs[k].target;
    }
}

const AlignedPair &registration_at(const kissm_alignment &a, uint64_t index) {
    if (index >= a.registrations.size())
        invalid("index is " + std::to_string(index) + "; the alignment has " + std::to_string(a.registrations.size()) +
                " registrations");
    return a.registrations[static_cast<std::size_t>(index)];
}

} // namespace

extern "C" {

int32_t kissm_align_options_init(kissm_align_options *options, uint32_t struct_size) {
    return guarded("kissm_align_options_init", [&] {
        require_non_null(options, "options");
        check_struct_size("struct_size", struct_size, kAlignOptionsSizes);
        const kissm_align_options full = default_options();
        store_struct(options, struct_size, &full, sizeof full);
        options->struct_size = struct_size;
        return ok();
    });
}

int32_t kissm_align_features(kissm_matcher *matcher, const kissm_features *const *features, uint64_t num_scans,
                             const kissm_align_options *options, kissm_alignment **out_alignment) {
    return guarded("kissm_align_features", [&] {
        require_non_null(out_alignment, "out_alignment");
        *out_alignment = nullptr;
        require_non_null(matcher, "matcher");
        require_non_null(features, "features");
        check_scans(num_scans);
        const kissm_align_options o = checked_options(options, num_scans);
        if (matcher->params.voxel_size == 0.0) // the loop radius and the pairs need the one voxel of every scan
            core::fail(core::ErrorKind::InvalidArgument,
                       "matcher's config.voxel_size is 0 (automatic); an alignment needs one voxel for every scan: "
                       "set it to kissm_suggest_voxel_size() of all the scans and compute their features with it");
        for (uint64_t k = 0; k < num_scans; ++k) {
            if (features[k] != nullptr && !core::same_descriptor_settings(features[k]->data.params, matcher->params))
                core::fail(core::ErrorKind::FeaturesMismatch,
                           "features[" + std::to_string(k) +
                               "] were computed with descriptor settings (voxel size, radii, tau, viewpoint) that "
                               "differ from the matcher's");
        }
        auto a = std::make_unique<kissm_alignment>();
        a->num_scans = static_cast<std::size_t>(num_scans);
        core::RunContext ctx = matcher->begin_call(); // one context: a cancel between the rounds is not dropped
        if (o.pairs == KISSM_PAIRS_SESSIONS) {
            align_sessions(*matcher, ctx, features, o, *a);
        } else {
            register_pairs(*matcher, ctx, features, first_pairs(o, a->num_scans), *a);
            if (o.pairs == KISSM_PAIRS_SEQUENCE && a->num_scans > 1) {
                const double voxel = matcher->config.voxel_size;
                const core::ScanPlaces chain = sequence_chain(*a); // round 1's, before the loops join
                register_pairs(*matcher, ctx, features, sequence_loops(o, chain, features, a->num_scans, voxel), *a);
                hold_out_uncorroborated(o, chain, *a, voxel);
            }
            solve(*a, o.bound, &matcher->cancel_requested);
        }
        *out_alignment = a.release();
        return ok();
    });
}

void kissm_alignment_destroy(kissm_alignment *alignment) { delete alignment; }

uint64_t kissm_alignment_num_scans(const kissm_alignment *alignment) { return alignment ? alignment->num_scans : 0; }

uint64_t kissm_alignment_num_registrations(const kissm_alignment *alignment) {
    return alignment ? alignment->registrations.size() : 0;
}

int32_t kissm_alignment_poses(const kissm_alignment *alignment, double *out_poses, uint8_t *out_placed,
                              uint64_t *out_components) {
    return guarded("kissm_alignment_poses", [&] {
        require_non_null(alignment, "alignment");
        write_pose_graph_poses(alignment->solution, alignment->num_scans, out_poses, out_placed, out_components);
        return ok();
    });
}

int32_t kissm_alignment_registration(const kissm_alignment *alignment, uint64_t index, uint64_t *out_source,
                                     uint64_t *out_target, kissm_result *out_result, int32_t *out_edge,
                                     double out_information[36], double *out_residual) {
    return guarded("kissm_alignment_registration", [&] {
        require_non_null(alignment, "alignment");
        const AlignedPair &r = registration_at(*alignment, index);
        if (out_result != nullptr) check_result(out_result);
        if (out_source != nullptr) *out_source = r.source;
        if (out_target != nullptr) *out_target = r.target;
        if (out_result != nullptr) store_struct(out_result, out_result->struct_size, &r.result, sizeof r.result);
        if (out_edge != nullptr) *out_edge = r.edge;
        if (out_information != nullptr) std::copy(r.information, r.information + 36, out_information);
        if (out_residual != nullptr) *out_residual = r.residual;
        return ok();
    });
}

int32_t kissm_sequence_loops(uint64_t num_scans, const double *steps, const uint8_t *step_valid, const double *priors,
                             double radius, uint64_t gap, uint64_t per_scan, uint64_t *out_pairs, uint64_t capacity,
                             uint64_t *out_count) {
    return guarded("kissm_sequence_loops", [&] {
        require_non_null(out_count, "out_count");
        check_scans(num_scans);
        if (steps != nullptr && priors != nullptr) invalid("steps and priors are both given; one of them");
        if (step_valid != nullptr && steps == nullptr) invalid("step_valid is given without steps");
        if (num_scans > 1 && steps == nullptr && priors == nullptr)
            core::fail(core::ErrorKind::NullArgument, "steps and priors are both NULL; one of them");
        check_loop_settings(radius, "radius", false, gap, "gap", per_scan, "per_scan");
        const auto n = static_cast<std::size_t>(num_scans);
        std::vector<core::ScanPair> pairs;
        if (priors != nullptr) {
            pairs = core::loop_candidates(core::prior_places(priors, n), radius, gap, per_scan, 0.0);
        } else {
            pairs = core::loop_candidates(core::dead_reckoned(checked_chain(n, steps, step_valid), n), radius, gap,
                                          per_scan, core::kLoopDrift);
        }
        write_pairs(pairs, out_pairs, capacity, out_count);
        return ok();
    });
}

int32_t kissm_sequence_similar(uint64_t num_scans, const uint8_t *step_valid, const double *signatures, uint64_t gap,
                               uint64_t per_scan, uint64_t *out_pairs, uint64_t capacity, uint64_t *out_count) {
    return guarded("kissm_sequence_similar", [&] {
        require_non_null(out_count, "out_count");
        require_non_null(signatures, "signatures");
        check_scans(num_scans);
        check_gap_and_per_scan(gap, per_scan);
        const auto n = static_cast<std::size_t>(num_scans);
        const core::ScanPlaces chain = core::dead_reckoned(checked_chain(n, nullptr, step_valid), n);
        write_pairs(core::similar_candidates(signatures, core::kSignatureSize, chain.piece,
                                             static_cast<std::size_t>(gap), static_cast<std::size_t>(per_scan)),
                    out_pairs, capacity, out_count);
        return ok();
    });
}

int32_t kissm_sequence_corroborated(uint64_t num_scans, const double *steps, const uint8_t *step_valid, double radius,
                                    uint64_t num_pairs, const uint64_t *pairs, const double *transforms,
                                    uint8_t *out_kept) {
    return guarded("kissm_sequence_corroborated", [&] {
        check_scans(num_scans);
        if (num_scans > 1) require_non_null(steps, "steps");
        if (step_valid != nullptr && steps == nullptr) invalid("step_valid is given without steps");
        if (!std::isfinite(radius) || !(radius > 0.0))
            invalid("radius is " + number(radius) + "; a finite number above 0");
        if (num_pairs > kMaxPairs)
            invalid("num_pairs is " + std::to_string(num_pairs) + "; 0 to " + std::to_string(kMaxPairs));
        if (num_pairs > 0) {
            require_non_null(pairs, "pairs");
            require_non_null(transforms, "transforms");
            require_non_null(out_kept, "out_kept");
        }
        const auto n = static_cast<std::size_t>(num_scans);
        std::vector<core::PieceLink> links(static_cast<std::size_t>(num_pairs));
        for (std::size_t k = 0; k < links.size(); ++k) {
            const uint64_t source = pairs[2 * k], target = pairs[2 * k + 1];
            if (source >= num_scans || target >= num_scans)
                invalid("pairs[" + std::to_string(k) + "] is (" + std::to_string(source) + ", " +
                        std::to_string(target) + "); scans are 0 to " + std::to_string(num_scans - 1));
            links[k] = {static_cast<std::size_t>(target), static_cast<std::size_t>(source), transforms + 16 * k};
        }
        const std::vector<std::uint8_t> kept = core::corroborated(
            links, core::dead_reckoned(checked_chain(n, steps, step_valid), n), radius, core::kLoopDrift);
        std::copy(kept.begin(), kept.end(), out_kept);
        return ok();
    });
}

} // extern "C"

// SPDX-License-Identifier: MIT
#include "align_similar.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <memory>

#include "cli_args.hpp"
#include "commands.hpp"
#include "report.hpp"

namespace kissm_cli {
namespace {

struct FeaturesDeleter {
    void operator()(kissm_features *f) const { kissm_features_destroy(f); }
};

// One scan's signature into `row`; false when it cannot be read or described.
bool signature_of(const Scan &scan, kissm_matcher *matcher, double *row) {
    kissm_cloud *raw = nullptr;
    if (kissm_read_points(scan.file.c_str(), scan.format, &raw) != KISSM_OK) return false;
    const CloudPtr cloud(raw);
    kissm_points points{};
    kissm_features *described = nullptr;
    if (kissm_cloud_points(cloud.get(), &points) != KISSM_OK ||
        kissm_features_compute(matcher, &points, &described) != KISSM_OK)
        return false;
    const std::unique_ptr<kissm_features, FeaturesDeleter> features(described);
    return kissm_features_signature(features.get(), row) == KISSM_OK;
}

} // namespace

bool chain_breaks(const SequenceChain &chain) {
    return std::find(chain.valid.begin(), chain.valid.end(), 0) != chain.valid.end();
}

std::vector<double> scan_signatures(const std::vector<Scan> &scans, const kissm_config &config) {
    kissm_matcher *raw = nullptr;
    const int32_t status = kissm_create(&config, &raw);
    if (status != KISSM_OK)
        throw UsageError("cannot describe the scans for their signatures: " + library_error(status));
    const MatcherPtr matcher(raw);
    std::vector<double> rows(KISSM_SIGNATURE_SIZE * scans.size());
    for (size_t k = 0; k < scans.size(); ++k) {
        double *row = &rows[KISSM_SIGNATURE_SIZE * k];
        if (!signature_of(scans[k], matcher.get(), row))
            std::fill(row, row + KISSM_SIGNATURE_SIZE, std::numeric_limits<double>::quiet_NaN());
    }
    return rows;
}

std::vector<ScanPair> similar_loops(const SequenceChain &chain, const std::vector<double> &signatures,
                                    const SequenceOptions &opt) {
    const uint64_t scans = signatures.size() / KISSM_SIGNATURE_SIZE;
    const auto gap = static_cast<uint64_t>(opt.loop_gap), per_scan = static_cast<uint64_t>(opt.similar_per_scan);
    const uint8_t *valid = chain.valid.empty() ? nullptr : chain.valid.data();
    uint64_t count = 0;
    int32_t status = kissm_sequence_similar(scans, valid, signatures.data(), gap, per_scan, nullptr, 0, &count);
    std::vector<uint64_t> found(2 * count);
    if (status == KISSM_OK)
        status = kissm_sequence_similar(scans, valid, signatures.data(), gap, per_scan, found.data(), count, &count);
    if (status != KISSM_OK)
        throw UsageError("cannot choose the loop candidates by similarity: " + library_error(status));
    std::vector<ScanPair> pairs(count);
    for (size_t k = 0; k < count; ++k)
        pairs[k] = {static_cast<size_t>(found[2 * k]), static_cast<size_t>(found[2 * k + 1])};
    return pairs;
}

std::vector<ScanPair> merged_loops(const std::vector<ScanPair> &loops, const std::vector<ScanPair> &similar) {
    const auto before = [](const ScanPair &a, const ScanPair &b) {
        return a.source != b.source ? a.source < b.source : a.target < b.target;
    };
    std::vector<ScanPair> out;
    std::merge(loops.begin(), loops.end(), similar.begin(), similar.end(), std::back_inserter(out), before);
    out.erase(
        std::unique(out.begin(), out.end(),
                    [](const ScanPair &a, const ScanPair &b) { return a.source == b.source && a.target == b.target; }),
        out.end());
    return out;
}

std::vector<uint8_t> held_out_pairs(const SequenceChain &chain, const std::vector<ScanPair> &pairs,
                                    const std::vector<DoneRecord> &records, const SequenceOptions &opt) {
    std::vector<uint8_t> held(pairs.size(), 0);
    if (!chain_breaks(chain)) return held;
    // In pair order, whatever order the records were written in: the first of equals decides.
    std::vector<const DoneRecord *> by_pair(pairs.size(), nullptr);
    for (const DoneRecord &record : records)
        if (record.pair >= 1 && record.pair <= static_cast<int64_t>(pairs.size()))
            by_pair[static_cast<size_t>(record.pair - 1)] = &record;
    std::vector<size_t> which;
    std::vector<uint64_t> links;
    std::vector<double> transforms;
    for (size_t k = 0; k < pairs.size(); ++k) {
        const DoneRecord *record = by_pair[k];
        if (!record || record->error || !record->valid || record->transform.size() != 16 ||
            !std::all_of(record->transform.begin(), record->transform.end(), [](double v) { return std::isfinite(v); }))
            continue;
        which.push_back(k);
        links.push_back(pairs[k].source);
        links.push_back(pairs[k].target);
        transforms.insert(transforms.end(), record->transform.begin(), record->transform.end());
    }
    std::vector<uint8_t> kept(which.size(), 0);
    const uint64_t scans = chain.valid.size() + 1;
    const int32_t status =
        kissm_sequence_corroborated(scans, chain.steps.data(), chain.valid.data(), opt.loop_radius, which.size(),
                                    which.empty() ? nullptr : links.data(), which.empty() ? nullptr : transforms.data(),
                                    which.empty() ? nullptr : kept.data());
    if (status != KISSM_OK)
        throw UsageError("cannot check the registrations between the chain's pieces: " + library_error(status));
    for (size_t k = 0; k < which.size(); ++k) held[which[k]] = kept[k] == 0;
    return held;
}

} // namespace kissm_cli

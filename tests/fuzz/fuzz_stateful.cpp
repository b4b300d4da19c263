// SPDX-License-Identifier: MIT
// libFuzzer target for one matcher used for a sequence of calls: registrations, features computed and
// reused, refinements from decoded transforms (kissm_refine, kissm_refine_features), a cancellation request
// between calls, configs read back. Invariants on top of fuzz_register's: repeating a call on the reused
// handle gives the identical result, features give the same result as the direct call (a refinement from
// features differs only in the descriptor counts it reports), a features' signature is sane and repeatable, a
// cancel request made between calls does not leak into the next one, and a multiway alignment of the features
// there are (kissm_align_features, with decoded options, valid or not) succeeds exactly when its options are
// valid, places scan 0 at the identity, every placed scan at a finite rigid pose and the others at NaN, and
// repeated gives the same bits.
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>

#include "fuzz_input.hpp"

namespace {

void require(bool ok) {
    if (!ok) std::abort();
}

// kissm_sequence_similar and kissm_sequence_corroborated on the features and an alignment's registrations, with a
// chain broken where `bits` say: similar pairs lie gap apart across pieces, in order; the flags are 0 or 1; both
// repeat bit for bit.
void fuzz_sequence_rules(const kissm_alignment *a, kissm_features *const features[3], std::uint8_t bits, uint64_t gap,
                         uint64_t per_scan) {
    double signatures[3 * KISSM_SIGNATURE_SIZE];
    for (int k = 0; k < 3; ++k) {
        double *row = signatures + KISSM_SIGNATURE_SIZE * k;
        if (!features[k] || kissm_features_signature(features[k], row) != KISSM_OK)
            for (int i = 0; i < KISSM_SIGNATURE_SIZE; ++i) row[i] = std::numeric_limits<double>::quiet_NaN();
    }
    const uint8_t step_valid[2] = {static_cast<uint8_t>(bits & 1u), static_cast<uint8_t>((bits >> 1) & 1u)};
    const int piece[3] = {0, step_valid[0] ? 0 : 1, (step_valid[0] ? 0 : 1) + (step_valid[1] ? 0 : 1)};
    uint64_t pairs[12], again[12], count = 0, count2 = 0;
    int32_t st = kissm_sequence_similar(3, step_valid, signatures, gap, per_scan, pairs, 6, &count);
    require(st == KISSM_OK || st == KISSM_ERR_OUT_OF_MEMORY);
    if (st == KISSM_OK) {
        require(count <= 3);
        for (uint64_t k = 0; k < count; ++k) {
            const uint64_t j = pairs[2 * k], i = pairs[2 * k + 1];
            require(j < 3 && i + gap <= j && piece[i] != piece[j] && (k == 0 || pairs[2 * k - 2] <= j));
        }
        if (kissm_sequence_similar(3, step_valid, signatures, gap, per_scan, again, 6, &count2) == KISSM_OK)
            require(count2 == count && std::memcmp(pairs, again, 2 * count * sizeof(uint64_t)) == 0);
    }
    double steps[32], transforms[16 * 8];
    uint64_t links[16];
    uint8_t kept[8], kept2[8];
    uint64_t n = 0;
    for (int k = 0; k < 2; ++k)
        for (int i = 0; i < 16; ++i) steps[16 * k + i] = i % 5 == 0 ? 1.0 : 0.0;
    for (uint64_t k = 0; k < kissm_alignment_num_registrations(a) && n < 8; ++k) {
        kissm_result r;
        require(kissm_result_init(&r, sizeof r) == KISSM_OK);
        uint64_t s = 0, t = 0;
        require(kissm_alignment_registration(a, k, &s, &t, &r, nullptr, nullptr, nullptr) == KISSM_OK);
        if (!r.valid) continue;
        links[2 * n] = s, links[2 * n + 1] = t;
        std::memcpy(transforms + 16 * n, r.transform, sizeof r.transform);
        ++n;
    }
    st = kissm_sequence_corroborated(3, steps, step_valid, 1.0, n, links, transforms, kept);
    require(st == KISSM_OK || st == KISSM_ERR_OUT_OF_MEMORY);
    if (st != KISSM_OK) return;
    for (uint64_t k = 0; k < n; ++k)
        require(kept[k] <= 1 && (piece[links[2 * k]] != piece[links[2 * k + 1]] || kept[k]));
    if (kissm_sequence_corroborated(3, steps, step_valid, 1.0, n, links, transforms, kept2) == KISSM_OK)
        require(std::memcmp(kept, kept2, n) == 0);
}

// kissm_align_features over the three feature slots with options decoded from the input; see the file comment.
void fuzz_alignment(kissm_fuzz::Bytes &in, kissm_matcher *m, kissm_features *const features[3]) {
    static const double radii[] = {0.0, 1.0, 50.0, -1.0, std::numeric_limits<double>::quiet_NaN()};
    static const double bounds[] = {KISSM_POSE_GRAPH_DEFAULT_BOUND, 1e-3, 0.0, std::numeric_limits<double>::infinity()};
    static const uint32_t patterns[][3] = {{0, 0, 0}, {0, 0, 1}, {0, 1, 1}, {0, 1, 2}, {1, 1, 1}, {0, 2, 2}};
    kissm_align_options o;
    require(kissm_align_options_init(&o, sizeof o) == KISSM_OK);
    const std::uint8_t policy = in.u8() % 5, settings = in.u8(), more = in.u8();
    const uint64_t list[4] = {more % 4u, (more / 4u) % 4u, (more / 16u) % 4u, (more / 64u) % 4u};
    const uint32_t *pattern = patterns[(more / 8u) % 6u];
    o.pairs = policy;
    o.loop_gap = settings % 3; // 0 is refused
    o.loops_per_scan = (settings / 3) % 3;
    o.loop_radius = radii[(settings / 9) % 5]; // -1 and NaN are refused
    o.bound = bounds[(settings / 45) % 4];     // 0 and infinity are refused
    o.stride = (more >> 4) % 3;                // 0 is refused
    if (policy == KISSM_PAIRS_LIST) o.pair_list = list, o.num_pairs = 2;
    if (policy == KISSM_PAIRS_SESSIONS) o.sessions = pattern;
    o.similar_per_scan = static_cast<int32_t>(more % 5u) - 1; // -1 is refused
    bool valid = policy < 4 && o.loop_gap >= 1 && std::isfinite(o.loop_radius) && o.loop_radius >= 0.0 &&
                 o.bound > 0.0 && std::isfinite(o.bound) && o.stride >= 1 && o.similar_per_scan >= 0;
    if (policy == KISSM_PAIRS_LIST)
        for (int k = 0; k < 2; ++k)
            valid = valid && list[2 * k] < 3 && list[2 * k + 1] < 3 && list[2 * k] != list[2 * k + 1];
    if (policy == KISSM_PAIRS_SESSIONS) {
        valid = valid && pattern[0] == 0;
        for (int k = 1; k < 3; ++k) valid = valid && pattern[k] >= pattern[k - 1] && pattern[k] - pattern[k - 1] <= 1;
    }
    kissm_alignment *a = nullptr;
    kissm_config config;
    config.struct_size = sizeof config;
    require(kissm_get_config(m, &config) == KISSM_OK);
    valid = valid && config.voxel_size != 0.0; // an automatic voxel size cannot align: refused by name
    const int32_t st = kissm_align_features(m, features, 3, &o, &a);
    require(st == KISSM_OK || st == KISSM_ERR_INVALID_ARGUMENT || st == KISSM_ERR_OUT_OF_MEMORY);
    require((st == KISSM_OK) == (a != nullptr) && (st != KISSM_ERR_INVALID_ARGUMENT || !valid));
    if (st != KISSM_OK) return;
    require(valid && kissm_alignment_num_scans(a) == 3);
    double poses[48], again[48];
    uint8_t placed[3];
    require(kissm_alignment_poses(a, poses, placed, nullptr) == KISSM_OK && placed[0] == 1);
    for (int i = 0; i < 16; ++i) require(poses[i] == (i % 5 == 0 ? 1.0 : 0.0));
    for (int k = 1; k < 3; ++k)
        for (int i = 0; i < 16; ++i)
            require(placed[k] ? std::isfinite(poses[16 * k + i]) : std::isnan(poses[16 * k + i]));
    for (uint64_t k = 0; k < kissm_alignment_num_registrations(a); ++k) {
        uint64_t s = 9, t = 9;
        int32_t edge = 9;
        require(kissm_alignment_registration(a, k, &s, &t, nullptr, &edge, nullptr, nullptr) == KISSM_OK);
        require(s < 3 && t < 3 && s != t && features[s] && features[t] && edge >= -1 && edge <= 1);
    }
    fuzz_sequence_rules(a, features, more, static_cast<uint64_t>(o.loop_gap),
                        static_cast<uint64_t>(o.similar_per_scan));
    kissm_alignment *b = nullptr;
    const int32_t st2 = kissm_align_features(m, features, 3, &o, &b);
    require(st2 == KISSM_OK || st2 == KISSM_ERR_OUT_OF_MEMORY);
    if (st2 == KISSM_OK) {
        require(kissm_alignment_poses(b, again, nullptr, nullptr) == KISSM_OK);
        require(std::memcmp(poses, again, sizeof poses) == 0);
    }
    kissm_alignment_destroy(b);
    kissm_alignment_destroy(a);
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t *data, std::size_t size) {
    kissm_fuzz::Bytes in(data, size);
    const kissm_config config = kissm_fuzz::make_config(in);
    kissm_fuzz::Cloud clouds[3];
    for (auto &c : clouds) c = kissm_fuzz::make_cloud(in, 1200);
    kissm_matcher *m = nullptr;
    if (kissm_create(&config, &m) != KISSM_OK) return 0;
    kissm_features *features[3] = {nullptr, nullptr, nullptr};
    kissm_result first[9];
    bool have_first[9] = {};
    // Up to 12 operations, each byte picks one and its clouds: the high nibble 0-4 as before refinement existed
    // (so old seeds replay the same calls), 5 and 6 the refinements, 7-14 the first five again, 15 an alignment.
    for (int step = 0; step < 12 && in.left() > 0; ++step) {
        const std::uint8_t op = in.u8();
        const int a = op % 3, b = (op / 3) % 3;
        const kissm_points pa = clouds[a].view(), pb = clouds[b].view();
        kissm_result r;
        require(kissm_result_init(&r, sizeof r) == KISSM_OK);
        const int kind = (op >> 4) < 7 || (op >> 4) == 15 ? (op >> 4) : (op >> 4) % 5;
        switch (kind) {
        case 0: { // register; again later must be identical
            const int32_t st = kissm_register(m, &pa, &pb, &r);
            require(kissm_fuzz::expected_status(st) && st != KISSM_ERR_CANCELLED);
            if (st != KISSM_OK) break;
            require(kissm_fuzz::result_sane(r, config));
            const int slot = 3 * a + b;
            if (have_first[slot]) require(kissm_fuzz::same_result(first[slot], r));
            first[slot] = r, have_first[slot] = true;
            break;
        }
        case 1: { // features (replacing any earlier ones of this cloud)
            kissm_features_destroy(features[a]);
            features[a] = nullptr;
            const int32_t st = kissm_features_compute(m, &pa, &features[a]);
            require(kissm_fuzz::expected_status(st) && (st == KISSM_OK) == (features[a] != nullptr));
            // at least the voxels and every keypoint's descriptor twice (rows and the search index's copy)
            if (features[a])
                require(kissm_features_memory_bytes(features[a]) >=
                        kissm_features_num_voxels(features[a]) * 12 + kissm_features_num_keypoints(features[a]) * 264);
            // the signature: always computed, finite, in [0, 1] (unit-length blocks of non-negative numbers), and
            // the same bits when asked again
            if (features[a]) {
                double signature[KISSM_SIGNATURE_SIZE], again[KISSM_SIGNATURE_SIZE];
                require(kissm_features_signature(features[a], signature) == KISSM_OK);
                require(kissm_features_signature(features[a], again) == KISSM_OK);
                require(std::memcmp(signature, again, sizeof signature) == 0);
                for (const double v : signature) require(std::isfinite(v) && v >= 0.0 && v <= 1.0);
            }
            break;
        }
        case 2: { // register from features: same as the direct call when both exist
            if (!features[a] || !features[b]) break;
            const int32_t st = kissm_register_features(m, features[a], features[b], &r);
            // Under voxel_size 0 each cloud's features have their own suggested voxel: two voxels are refused.
            require(st == KISSM_OK || st == KISSM_ERR_OUT_OF_MEMORY ||
                    (config.voxel_size == 0.0 && st == KISSM_ERR_FEATURES_MISMATCH));
            if (st != KISSM_OK) break;
            require(kissm_fuzz::result_sane(r, config));
            const int slot = 3 * a + b;
            if (have_first[slot]) require(kissm_fuzz::same_result(first[slot], r));
            break;
        }
        case 5:   // refine from a decoded transform, twice: the same bits
        case 6: { // ... and from features too, when both exist: the same but for the descriptor counts
            double initial[16];
            const bool rigid = kissm_fuzz::make_transform(in, initial);
            const int32_t st = kissm_refine(m, &pa, &pb, initial, &r);
            require(kissm_fuzz::expected_status(st) && st != KISSM_ERR_CANCELLED);
            if (!rigid)
                require(st == KISSM_ERR_INVALID_ARGUMENT || st == KISSM_ERR_EMPTY_INPUT ||
                        st == KISSM_ERR_TOO_FEW_POINTS);
            if (st != KISSM_OK) {
                require(kissm_fuzz::result_reset(r));
                break;
            }
            require(kissm_fuzz::refine_result_sane(r, config, initial));
            kissm_result again;
            require(kissm_result_init(&again, sizeof again) == KISSM_OK);
            if (kind == 5) {
                require(kissm_refine(m, &pa, &pb, initial, &again) == KISSM_OK);
                require(kissm_fuzz::same_result(r, again));
            } else if (features[a] && features[b]) {
                const int32_t fst = kissm_refine_features(m, features[a], features[b], initial, &again);
                require(fst == KISSM_OK || fst == KISSM_ERR_OUT_OF_MEMORY);
                if (fst == KISSM_OK) require(kissm_fuzz::same_result(r, again));
            }
            break;
        }
        case 15: fuzz_alignment(in, m, features); break;
        case 3: { // a cancel request while no call runs: cleared when the next call starts; and the voxel suggestion
            // for the pair, the same either way round
            kissm_cancel(m);
            const kissm_points ab[2] = {pa, pb}, ba[2] = {pb, pa};
            double v = -1.0, w = -2.0;
            const int32_t st = kissm_suggest_voxel_size(ab, 2, &v);
            require(kissm_fuzz::expected_status(st) && st != KISSM_ERR_CANCELLED);
            require(st == KISSM_OK ? v > 0.0 && std::isfinite(v) : v == -1.0);
            // Either way round: the same voxel, or a failure (which cloud's, and so which status, follows the order).
            const int32_t swapped = kissm_suggest_voxel_size(ba, 2, &w);
            require((swapped == KISSM_OK) == (st == KISSM_OK) && (st != KISSM_OK || w == v));
            break;
        }
        default: { // the config reads back as given
            kissm_config back;
            std::memset(&back, 0, sizeof back);
            back.struct_size = sizeof back;
            require(kissm_get_config(m, &back) == KISSM_OK);
            require(back.voxel_size == config.voxel_size && back.num_threads == config.num_threads &&
                    back.min_inliers == config.min_inliers);
            break;
        }
        }
    }
    for (auto *f : features) kissm_features_destroy(f);
    kissm_destroy(m);
    return 0;
}

// SPDX-License-Identifier: MIT
// libFuzzer target for one matcher used for a sequence of calls: registrations, features computed and
// reused, refinements from decoded transforms (kissm_refine, kissm_refine_features), a cancellation request
// between calls, configs read back. Invariants on top of fuzz_register's: repeating a call on the reused
// handle gives the identical result, features give the same result as the direct call (a refinement from
// features differs only in the descriptor counts it reports), and a cancel request made between calls does
// not leak into the next one.
#include <cstdlib>
#include <cstring>

#include "fuzz_input.hpp"

namespace {

void require(bool ok) {
    if (!ok) std::abort();
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
    // (so old seeds replay the same calls), 5 and 6 the refinements, 7-15 the first five again.
    for (int step = 0; step < 12 && in.left() > 0; ++step) {
        const std::uint8_t op = in.u8();
        const int a = op % 3, b = (op / 3) % 3;
        const kissm_points pa = clouds[a].view(), pb = clouds[b].view();
        kissm_result r;
        require(kissm_result_init(&r, sizeof r) == KISSM_OK);
        const int kind = (op >> 4) < 7 ? (op >> 4) : (op >> 4) % 5;
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
            break;
        }
        case 2: { // register from features: same as the direct call when both exist
            if (!features[a] || !features[b]) break;
            const int32_t st = kissm_register_features(m, features[a], features[b], &r);
            require(st == KISSM_OK || st == KISSM_ERR_OUT_OF_MEMORY);
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
        case 3: // a cancel request while no call runs: cleared when the next call starts
            kissm_cancel(m);
            break;
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

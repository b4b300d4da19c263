// SPDX-License-Identifier: MIT
// libFuzzer target for the whole pipeline through the public C API: a config and two clouds from the
// bytes (fuzz_input.hpp), one fresh matcher, kissm_register, then kissm_refine of the same clouds from a
// transform decoded from the remaining bytes (the identity when none are left), then kissm_ground_mask of the
// source. Invariants: the status is one
// a caller can get from such inputs (a transform that is not rigid is KISSM_ERR_INVALID_ARGUMENT unless a
// points table was refused first); a failed call leaves a reset result; a valid pose is finite and a proper
// rotation; the refinement's fields are "not run" or in range.
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t *data, std::size_t size) {
    kissm_fuzz::Bytes in(data, size);
    const kissm_config config = kissm_fuzz::make_config(in);
    const kissm_fuzz::Cloud source = kissm_fuzz::make_cloud(in, 3000);
    const kissm_fuzz::Cloud target = kissm_fuzz::make_cloud(in, 3000);
    double initial[16];
    const bool rigid = kissm_fuzz::make_transform(in, initial);
    kissm_matcher *m = nullptr;
    const int32_t created = kissm_create(&config, &m);
    if (created != KISSM_OK) {
        if (created != KISSM_ERR_INVALID_ARGUMENT || m != nullptr) std::abort();
        return 0;
    }
    const kissm_points s = source.view(), t = target.view();
    kissm_result r;
    if (kissm_result_init(&r, sizeof r) != KISSM_OK) std::abort();
    const int32_t st = kissm_register(m, &s, &t, &r);
    const bool verbose = std::getenv("KISSM_FUZZ_VERBOSE") != nullptr; // to see what the seed corpus reaches
    if (verbose)
        std::fprintf(stderr, "  %llu / %llu points: status %d, valid %d, reason %d, %llu final inliers, refine %d\n",
                     static_cast<unsigned long long>(s.count), static_cast<unsigned long long>(t.count), (int)st,
                     (int)r.valid, (int)r.reason, static_cast<unsigned long long>(r.num_final_inliers),
                     (int)config.refine_mode);
    if (!kissm_fuzz::expected_status(st)) std::abort();
    if (st != KISSM_OK && !kissm_fuzz::result_reset(r)) std::abort();
    if (st == KISSM_OK && !kissm_fuzz::result_sane(r, config)) std::abort();

    const int32_t rst = kissm_refine(m, &s, &t, initial, &r);
    if (verbose)
        std::fprintf(stderr, "  kissm_refine (%s transform): status %d, valid %d, reason %d, %llu correspondences\n",
                     rigid ? "rigid" : "bad", (int)rst, (int)r.valid, (int)r.reason,
                     static_cast<unsigned long long>(r.num_refine_correspondences));
    if (!kissm_fuzz::expected_status(rst)) std::abort();
    // The points tables are checked before the transform, the clouds' contents after it.
    if (!rigid && rst != KISSM_ERR_INVALID_ARGUMENT && rst != KISSM_ERR_EMPTY_INPUT && rst != KISSM_ERR_TOO_FEW_POINTS)
        std::abort();
    if (rst != KISSM_OK && !kissm_fuzz::result_reset(r)) std::abort();
    if (rst == KISSM_OK && !kissm_fuzz::refine_result_sane(r, config, initial)) std::abort();

    // The ground model on the source: labels 0 or 1 on success, the caller's bytes untouched on failure.
    // At least one byte, so an empty cloud's call gets a buffer (a NULL one is a different error) and must leave it.
    std::vector<std::uint8_t> mask(s.count > 0 ? static_cast<std::size_t>(s.count) : 1, 0xAB);
    const int32_t gst = kissm_ground_mask(m, &s, mask.data());
    if (!kissm_fuzz::expected_status(gst)) std::abort();
    for (const std::uint8_t b : mask)
        if ((gst == KISSM_OK && b > 1) || (gst != KISSM_OK && b != 0xAB)) std::abort();
    kissm_destroy(m);
    return 0;
}

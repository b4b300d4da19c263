// SPDX-License-Identifier: MIT
// libFuzzer target for the whole pipeline through the public C API: a config and two clouds from the
// bytes (fuzz_input.hpp), one fresh matcher, kissm_register. Invariants: the status is one a caller can
// get from such inputs; a failed call leaves valid = 0; a valid pose is finite and a proper rotation.
#include <cstdio>
#include <cstdlib>

#include "fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t *data, std::size_t size) {
    kissm_fuzz::Bytes in(data, size);
    const kissm_config config = kissm_fuzz::make_config(in);
    const kissm_fuzz::Cloud source = kissm_fuzz::make_cloud(in, 3000);
    const kissm_fuzz::Cloud target = kissm_fuzz::make_cloud(in, 3000);
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
    if (std::getenv("KISSM_FUZZ_VERBOSE") != nullptr) // to see what the seed corpus reaches
        std::fprintf(stderr, "  %llu / %llu points: status %d, valid %d, reason %d, %llu final inliers\n",
                     static_cast<unsigned long long>(s.count), static_cast<unsigned long long>(t.count), (int)st,
                     (int)r.valid, (int)r.reason, static_cast<unsigned long long>(r.num_final_inliers));
    if (!kissm_fuzz::expected_status(st)) std::abort();
    if (st != KISSM_OK && r.valid != 0) std::abort();
    if (st == KISSM_OK && !kissm_fuzz::result_sane(r)) std::abort();
    kissm_destroy(m);
    return 0;
}

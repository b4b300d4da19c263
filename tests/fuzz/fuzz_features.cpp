// SPDX-License-Identifier: MIT
// libFuzzer target for features read from bytes (kissm_features_deserialize): arbitrary bytes are refused
// with KISSM_ERR_PARSE and the output untouched, or accepted; accepted features serialise back to exactly
// the same bytes, and register and refine against themselves under a matcher built from the settings their
// header carries (docs/features-format.md) without a crash and with a status such a call may give.
// Checksums make random bytes fail early; the seeds (tests/fuzz/corpus/features, written by
// `capi_features_bytes --corpus DIR`) are real features; every input is also tried with its checksum fixed up,
// so that mutations reach the checks of each field and not only the checksum.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "core/little_endian.hpp"
#include "kissm.h"

namespace {

void require(bool ok) {
    if (!ok) std::abort();
}

using kissm::detail::load_le;
using kissm::detail::load_le_f64;
using kissm::detail::load_le_i32;
using kissm::detail::store_le;

// The format's checksum (over everything before the last 8 bytes: FNV-1a steps on 64-bit little-endian words,
// then on the remaining bytes), written from the format document.
void reseal(std::vector<std::uint8_t> &b) {
    const std::size_t n = b.size() - 8;
    std::uint64_t h = 14695981039346656037ull;
    std::size_t i = 0;
    for (; i + 8 <= n; i += 8) h = (h ^ load_le<std::uint64_t>(b.data() + i)) * 1099511628211ull;
    for (; i < n; ++i) h = (h ^ b[i]) * 1099511628211ull;
    store_le(h, b.data() + n);
}

// A config with the settings of the header (offsets of docs/features-format.md), for a matcher that accepts
// the features.
kissm_config config_of(const std::uint8_t *b) {
    kissm_config c;
    require(kissm_config_init(&c, sizeof c) == KISSM_OK);
    c.num_threads = 1;
    c.voxel_size = load_le_f64(b + 24);
    c.fpfh_radius_gain = load_le_f64(b + 32);
    c.normal_radius_gain = load_le_f64(b + 40);
    c.max_linearity = load_le_f64(b + 48);
    c.refine_normal_radius_gain = load_le_f64(b + 56);
    c.sensor_height = load_le_f64(b + 64);
    for (int i = 0; i < 3; ++i) c.viewpoint[i] = load_le_f64(b + 72 + 8 * i), c.up[i] = load_le_f64(b + 96 + 8 * i);
    c.min_normal_neighbors = load_le_i32(b + 120);
    c.nonfinite_policy = b[124];
    c.viewpoint_mode = b[125];
    c.refine_mode = b[126];
    c.suppression = b[127];
    return c;
}

bool registration_status(int32_t st) {
    // FEATURES_MISMATCH: re-normalising `up` in the config may move it by a rounding step.
    return st == KISSM_OK || st == KISSM_ERR_FEATURES_MISMATCH || st == KISSM_ERR_OUT_OF_MEMORY;
}

} // namespace

namespace {

void check(const std::vector<std::uint8_t> &bytes, const std::uint8_t *empty) {
    kissm_features *const sentinel = reinterpret_cast<kissm_features *>(const_cast<std::uint8_t *>(empty));
    kissm_features *f = sentinel;
    // A copy of exactly the given length, so that a read past the end is a read past an allocation.
    const int32_t st = kissm_features_deserialize(bytes.empty() ? empty : bytes.data(), bytes.size(), &f);
    if (st != KISSM_OK) {
        require((st == KISSM_ERR_PARSE || st == KISSM_ERR_OUT_OF_MEMORY) && f == sentinel);
        return;
    }
    require(f != nullptr && f != sentinel);
    require(kissm_features_num_voxels(f) >= 1 && kissm_features_num_keypoints(f) <= kissm_features_num_voxels(f));

    // The same bytes back.
    std::uint64_t n = 0;
    require(kissm_features_serialize(f, nullptr, 0, &n) == KISSM_OK && n == bytes.size());
    std::vector<std::uint8_t> again(static_cast<std::size_t>(n));
    require(kissm_features_serialize(f, again.data(), n, &n) == KISSM_OK && again == bytes);

    // Registered and refined against themselves.
    const kissm_config c = config_of(bytes.data());
    kissm_matcher *m = nullptr;
    if (kissm_create(&c, &m) == KISSM_OK) {
        kissm_result r;
        require(kissm_result_init(&r, sizeof r) == KISSM_OK);
        const int32_t rst = kissm_register_features(m, f, f, &r);
        require(registration_status(rst));
        const double identity[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
        const int32_t fst = kissm_refine_features(m, f, f, identity, &r);
        require(registration_status(fst));
        if (std::getenv("KISSM_FUZZ_VERBOSE") != nullptr) // to see what the seed corpus reaches
            std::fprintf(stderr, "  %llu voxels, %llu keypoints: register %d, refine %d (valid %d)\n",
                         static_cast<unsigned long long>(kissm_features_num_voxels(f)),
                         static_cast<unsigned long long>(kissm_features_num_keypoints(f)), (int)rst, (int)fst,
                         (int)r.valid);
        if (r.valid) {
            for (const double v : r.transform) require(std::isfinite(v));
        }
        kissm_destroy(m);
    }
    kissm_features_destroy(f);
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t *data, std::size_t size) {
    static const std::uint8_t empty[1] = {0};
    std::vector<std::uint8_t> bytes(data, data + size);
    check(bytes, empty);
    // Again with the checksum fixed up, so that mutations also reach the checks of every field.
    if (bytes.size() >= 8) {
        const std::vector<std::uint8_t> given = bytes;
        reseal(bytes);
        if (bytes != given) check(bytes, empty);
    }
    return 0;
}

// SPDX-License-Identifier: MIT
#include "simd_level.hpp"

#include <cstdlib>
#include <cstring>

KISSM_DETAIL_BEGIN

namespace {

bool decide() {
#if KISSM_HAVE_AVX2_KERNELS
    const char *forced = std::getenv("KISSM_SIMD");
    if (forced != nullptr && std::strcmp(forced, "sse2") == 0) return false;
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") != 0;
#else
    return false;
#endif
}

} // namespace

bool use_avx2() {
    static const bool avx2 = decide(); // thread-safe once (C++11 statics)
    return avx2;
}

KISSM_DETAIL_END

// SPDX-License-Identifier: MIT
// Which vector width the kernels that have two use: AVX2 where the CPU has it, SSE2 (part of every x86-64)
// otherwise. Each AVX2 kernel performs its SSE2 twin's operations lane by lane, in the same order and without
// fused multiply-adds, so the results are the same bits on every x86-64 CPU; only the time differs.
// KISSM_SIMD=sse2 in the environment holds a process to the SSE2 kernels (the tests run both; the instruction
// count check counts the same code on every machine).
#pragma once

#include "detail_namespace.hpp"

// A helper both widths' kernels call must be inlined into each (a call per element would cost more than the test).
#if defined(__GNUC__) || defined(__clang__)
#  define KISSM_ALWAYS_INLINE inline __attribute__((always_inline))
#else
#  define KISSM_ALWAYS_INLINE inline
#endif

#if (defined(__x86_64__) || defined(_M_X64)) && (defined(__GNUC__) || defined(__clang__))
#  define KISSM_HAVE_AVX2_KERNELS 1
#  define KISSM_TARGET_AVX2 __attribute__((target("avx2")))
#else
#  define KISSM_HAVE_AVX2_KERNELS 0
#  define KISSM_TARGET_AVX2
#endif

KISSM_DETAIL_BEGIN

// True when the AVX2 kernels run: the CPU has AVX2 and KISSM_SIMD does not say sse2. Decided once per process.
bool use_avx2();

KISSM_DETAIL_END

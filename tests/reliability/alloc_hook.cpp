// SPDX-License-Identifier: MIT
// The global operator new and delete of the reliability tests: counts allocations, tracks how many are
// live, and can refuse one chosen allocation (alloc_hook.hpp). Linked into a test executable, it sees
// every C++ allocation of the statically linked library.
#include "alloc_hook.hpp"

#include <atomic>
#include <cstddef>
#include <cstdlib>
#include <new>

namespace {

std::atomic<long> g_count{0};    // allocations so far
std::atomic<long> g_live{0};     // allocations not yet freed
std::atomic<long> g_fail_at{-1}; // the g_count value whose allocation fails; -1: none
std::atomic<long> g_failed{0};   // allocations refused

void *allocate(std::size_t n, std::size_t align) {
    const long k = ++g_count;
    if (k == g_fail_at.load(std::memory_order_relaxed)) {
        ++g_failed;
        return nullptr;
    }
    void *p = nullptr;
    if (align <= alignof(std::max_align_t)) {
        p = std::malloc(n == 0 ? 1 : n);
    } else if (posix_memalign(&p, align, n == 0 ? 1 : n) != 0) {
        p = nullptr;
    }
    if (p != nullptr) ++g_live;
    return p;
}

void release(void *p) {
    if (p == nullptr) return;
    --g_live;
    std::free(p);
}

} // namespace

void *operator new(std::size_t n) {
    void *p = allocate(n, 0);
    if (p == nullptr) throw std::bad_alloc();
    return p;
}
void *operator new[](std::size_t n) { return operator new(n); }
void *operator new(std::size_t n, const std::nothrow_t &) noexcept { return allocate(n, 0); }
void *operator new[](std::size_t n, const std::nothrow_t &) noexcept { return allocate(n, 0); }
void *operator new(std::size_t n, std::align_val_t a) {
    void *p = allocate(n, static_cast<std::size_t>(a));
    if (p == nullptr) throw std::bad_alloc();
    return p;
}
void *operator new[](std::size_t n, std::align_val_t a) { return operator new(n, a); }
void operator delete(void *p) noexcept { release(p); }
void operator delete[](void *p) noexcept { release(p); }
void operator delete(void *p, std::size_t) noexcept { release(p); }
void operator delete[](void *p, std::size_t) noexcept { release(p); }
void operator delete(void *p, std::align_val_t) noexcept { release(p); }
void operator delete[](void *p, std::align_val_t) noexcept { release(p); }
void operator delete(void *p, std::size_t, std::align_val_t) noexcept { release(p); }
void operator delete[](void *p, std::size_t, std::align_val_t) noexcept { release(p); }

namespace alloc_hook {
long count() { return g_count.load(); }
long live() { return g_live.load(); }
void fail_at(long k) { g_fail_at.store(k); }
long failed() { return g_failed.load(); }
} // namespace alloc_hook

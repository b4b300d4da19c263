// SPDX-License-Identifier: MIT
// A std::vector whose resize() leaves new elements of trivial types unset, for the large arrays whose every
// element a parallel loop writes anyway. Zero-filling them first is a pass over all of it on one thread, and
// that pass also takes every page fault of the fresh memory on that thread: on a VM whose balloon driver has
// handed free pages back to the host, a first touch costs microseconds per page (docs/design/performance.md,
// "Fresh memory is expensive here"), so the fill was a serial stretch that grew with the cloud.
#pragma once

#include <memory>
#include <new>
#include <utility>
#include <vector>

#include "detail_namespace.hpp"

KISSM_DETAIL_BEGIN

template <class T>
struct DefaultInitAllocator : std::allocator<T> {
    template <class U>
    struct rebind {
        using other = DefaultInitAllocator<U>;
    };
    DefaultInitAllocator() noexcept = default;
    template <class U>
    DefaultInitAllocator(const DefaultInitAllocator<U> &) noexcept {}

    template <class U>
    void construct(U *p) noexcept(noexcept(::new (static_cast<void *>(p)) U)) {
        ::new (static_cast<void *>(p)) U; // default-initialisation: nothing for trivial types
    }
    template <class U, class... Args>
    void construct(U *p, Args &&...args) {
        ::new (static_cast<void *>(p)) U(std::forward<Args>(args)...);
    }
};

template <class T>
using UninitVector = std::vector<T, DefaultInitAllocator<T>>;

KISSM_DETAIL_END

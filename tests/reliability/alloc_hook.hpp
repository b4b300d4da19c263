// SPDX-License-Identifier: MIT
// Test-only allocation hook (alloc_hook.cpp replaces the global operator new and delete).
#pragma once

namespace alloc_hook {
long count();         // allocations made so far
long live();          // allocations not freed yet
void fail_at(long k); // make the allocation whose count() value is k fail (bad_alloc); -1: none
long failed();        // allocations refused so far
} // namespace alloc_hook

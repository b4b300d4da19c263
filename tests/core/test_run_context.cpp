// SPDX-License-Identifier: MIT
// RunContext::map_chunks / map_fold: chunk c's result lands in slot c, the fold sees the slots in chunk
// order on the calling thread, the chunks do not depend on the thread count, and errors and cancellation
// still reach the caller; loops posted while the pool's workers are still starting run every chunk once.
#include <algorithm>
#include <atomic>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/failure.hpp"
#include "core/run_context.hpp"
#include "harness.h"

using namespace kissm::detail;

namespace {

const int kThreadCounts[] = {1, 2, 3, 8};

// Terms whose sum depends on the order of addition: huge values that cancel, interleaved with small ones
// that are lost or kept depending on what they are added to.
std::vector<double> order_sensitive_terms(std::size_t n) {
    std::vector<double> x(n);
    std::uint64_t s = 0x9E3779B97F4A7C15ull;
    for (std::size_t i = 0; i < n; ++i) {
        s = s * 6364136223846793005ull + 1442695040888963407ull;
        const double u = static_cast<double>(s >> 11) / 9007199254740992.0; // [0, 1)
        x[i] = i % 7 == 0 ? (i % 14 == 0 ? 1e16 : -1e16) * (1.0 + u) : u * 3.0 - 1.0;
    }
    return x;
}

std::uint64_t bits(double v) {
    std::uint64_t b;
    std::memcpy(&b, &v, sizeof b);
    return b;
}

double chunk_sum(const std::vector<double> &x, std::size_t b, std::size_t e) {
    double s = 0.0;
    for (std::size_t i = b; i < e; ++i) s += x[i];
    return s;
}

void test_fold_in_chunk_order_for_every_thread_count() {
    const std::size_t n = 10007, chunk = 97; // the last chunk is short
    const std::vector<double> x = order_sensitive_terms(n);
    const std::size_t chunks = RunContext::num_chunks(n, chunk);
    CHECK_EQ_INT(chunks, (n + chunk - 1) / chunk);

    // The reference: chunk sums added in chunk order, serially. The same partials added in reverse order
    // give another number, so the comparison below can tell the orders apart.
    double forward = 0.0, backward = 0.0;
    std::vector<double> partial(chunks);
    for (std::size_t c = 0; c < chunks; ++c) partial[c] = chunk_sum(x, c * chunk, std::min(n, (c + 1) * chunk));
    for (std::size_t c = 0; c < chunks; ++c) forward += partial[c];
    for (std::size_t c = chunks; c-- > 0;) backward += partial[c];
    REQUIRE(bits(forward) != bits(backward));

    for (const int threads : kThreadCounts) {
        RunContext ctx(threads, nullptr, Hooks{});
        std::vector<std::size_t> order;
        struct Range {
            std::size_t begin = 0, end = 0;
            double sum = 0.0;
        };
        const double total = ctx.map_fold(
            n, chunk, 0.0,
            [&](std::size_t b, std::size_t e) {
                Range r;
                r.begin = b, r.end = e, r.sum = chunk_sum(x, b, e);
                return r;
            },
            [&](double &acc, Range &&r) {
                order.push_back(r.begin / chunk);
                CHECK_EQ_INT(r.end, std::min(n, r.begin + chunk)); // the chunks of parallel_for, whatever the threads
                acc += r.sum;
            });
        CHECK_MSG(bits(total) == bits(forward), "%d threads: %.17g vs %.17g", threads, total, forward);
        REQUIRE(order.size() == chunks);
        bool in_order = true;
        for (std::size_t c = 0; c < chunks; ++c) in_order = in_order && order[c] == c;
        CHECK_MSG(in_order, "%d threads: fold not in chunk order", threads);

        // map_chunks: slot c holds chunk c's result.
        const std::vector<std::size_t> firsts = ctx.map_chunks(n, chunk, [](std::size_t b, std::size_t) { return b; });
        REQUIRE(firsts.size() == chunks);
        bool slots = true;
        for (std::size_t c = 0; c < chunks; ++c) slots = slots && firsts[c] == c * chunk;
        CHECK_MSG(slots, "%d threads: a chunk's result is not in its own slot", threads);
    }
}

void test_empty_range_returns_init() {
    RunContext ctx(2, nullptr, Hooks{});
    int maps = 0, folds = 0;
    const int r = ctx.map_fold(
        0, 16, 42, [&](std::size_t, std::size_t) { return ++maps; }, [&](int &, int &&) { ++folds; });
    CHECK_EQ_INT(r, 42);
    CHECK_EQ_INT(maps, 0);
    CHECK_EQ_INT(folds, 0);
    CHECK(ctx.map_chunks(0, 16, [](std::size_t, std::size_t) { return 1; }).empty());
    // chunk 0 counts as 1, as in parallel_for.
    CHECK_EQ_INT(ctx.map_chunks(5, 0, [](std::size_t b, std::size_t) { return b; }).size(), 5);
}

void test_map_exception_propagates_and_skips_the_fold() {
    for (const int threads : kThreadCounts) {
        RunContext ctx(threads, nullptr, Hooks{});
        int folds = 0;
        bool caught = false;
        try {
            ctx.map_fold(
                1000, 10, 0,
                [](std::size_t b, std::size_t) {
                    if (b == 500) throw std::runtime_error("chunk 50");
                    return 1;
                },
                [&](int &acc, int &&v) { acc += v, ++folds; });
        } catch (const std::runtime_error &e) {
            caught = std::strcmp(e.what(), "chunk 50") == 0;
        }
        CHECK_MSG(caught, "%d threads", threads);
        CHECK_EQ_INT(folds, 0);
    }
}

void test_fold_exception_propagates_at_its_chunk() {
    for (const int threads : kThreadCounts) {
        RunContext ctx(threads, nullptr, Hooks{});
        std::size_t folded = 0;
        std::size_t thrown_at = 0;
        try {
            ctx.map_fold(
                1000, 10, 0, [](std::size_t b, std::size_t) { return b; },
                [&](int &, std::size_t &&b) {
                    if (b >= 300 && b % 200 == 100) throw Failure(ErrorKind::NonFinite, std::to_string(b));
                    ++folded;
                });
        } catch (const Failure &f) {
            thrown_at = static_cast<std::size_t>(std::stoul(f.what()));
            CHECK(f.kind() == ErrorKind::NonFinite);
        }
        // The first failing chunk in chunk order, after all chunks before it were folded.
        CHECK_EQ_INT(thrown_at, 300);
        CHECK_EQ_INT(folded, 30);
    }
}

void test_cancellation_propagates() {
    for (const int threads : kThreadCounts) {
        std::atomic<int> flag{0};
        RunContext ctx(threads, &flag, Hooks{});
        int folds = 0;
        bool cancelled = false;
        try {
            ctx.map_fold(
                1000, 10, 0,
                [&](std::size_t b, std::size_t) {
                    if (b == 200) flag.store(1);
                    return 1;
                },
                [&](int &, int &&) { ++folds; });
        } catch (const Failure &f) {
            cancelled = f.kind() == ErrorKind::Cancelled;
        }
        CHECK_MSG(cancelled, "%d threads", threads);
        CHECK_EQ_INT(folds, 0);

        // Already cancelled: nothing runs.
        int maps = 0;
        cancelled = false;
        try {
            ctx.map_chunks(100, 10, [&](std::size_t, std::size_t) { return ++maps; });
        } catch (const Failure &f) {
            cancelled = f.kind() == ErrorKind::Cancelled;
        }
        CHECK(cancelled);
        CHECK_EQ_INT(maps, 0);
    }
}

// Fresh contexts run loops at once, while their workers are still starting: a worker that joins a loop late, or
// wakes after it is over, must neither run a chunk twice nor miss one, and a loop must not end before its chunks
// have (each loop writes every element once and reads the one before's results).
void test_loops_right_after_the_pool_starts() {
    for (int round = 0; round < 300; ++round) {
        const int threads = 2 + round % 3;
        RunContext ctx(threads, nullptr, Hooks{});
        std::vector<int> count;
        for (const std::size_t n : {std::size_t(1), std::size_t(2), std::size_t(3), std::size_t(64), std::size_t(7)}) {
            count.assign(n, 0);
            ctx.parallel_for(n, 1, [&](std::size_t b, std::size_t e) {
                for (std::size_t i = b; i < e; ++i) ++count[i];
            });
            CHECK_MSG(std::all_of(count.begin(), count.end(), [](int c) { return c == 1; }),
                      "round %d, %zu chunks: a chunk ran %s", round, n,
                      std::any_of(count.begin(), count.end(), [](int c) { return c == 0; }) ? "never" : "twice");
        }
    }
}

} // namespace

int main() {
    RUN_TEST(test_fold_in_chunk_order_for_every_thread_count);
    RUN_TEST(test_empty_range_returns_init);
    RUN_TEST(test_map_exception_propagates_and_skips_the_fold);
    RUN_TEST(test_fold_exception_propagates_at_its_chunk);
    RUN_TEST(test_cancellation_propagates);
    RUN_TEST(test_loops_right_after_the_pool_starts);
    return TEST_SUMMARY();
}

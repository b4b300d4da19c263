// SPDX-License-Identifier: MIT
// What every stage of one call shares: the worker threads, cancellation and the log sink.
//
// Parallel loops split [0, n) into fixed chunks whose size does not depend on the thread count, and every
// chunk writes only its own outputs; merges happen afterwards in chunk order on the calling thread. That is
// what makes results bitwise identical for any num_threads. map_chunks and map_fold are that rule as an
// API: a chunk's result goes to its own slot, and the fold sees the slots in chunk order.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "detail_namespace.hpp"

KISSM_DETAIL_BEGIN

class ThreadPool;

enum class LogLevel { Error, Warn, Info, Debug };

// The stages, in the order a registration runs them (progress never goes back).
enum class Stage { Voxelize, Features, Matching, Pruning, Solver, Refine };

struct Hooks {
    // Returns true to cancel. Called on the calling thread only.
    std::function<bool(Stage stage, double fraction)> progress;
    std::function<void(LogLevel, const std::string &)> log;
    LogLevel log_level = LogLevel::Warn;
};

class RunContext {
public:
    // cancel_flag may be null. The pool (if threads > 1) lives for this context only, so no thread
    // outlives a call and a fork()ed child never inherits half a pool.
    RunContext(int num_threads, const std::atomic<int> *cancel_flag, Hooks hooks);
    ~RunContext();
    RunContext(const RunContext &) = delete;
    RunContext &operator=(const RunContext &) = delete;

    int threads() const { return threads_; }

    // Runs body(begin, end) over [0, n) in chunks of `chunk` items (chunk >= 1). Throws Failure(Cancelled)
    // when cancellation is requested; rethrows the first exception a chunk threw.
    void parallel_for(std::size_t n, std::size_t chunk, const std::function<void(std::size_t, std::size_t)> &body);

    // The number of chunks parallel_for(n, chunk, ...) runs; chunk c covers [c * chunk, min(n, (c + 1) * chunk)).
    static std::size_t num_chunks(std::size_t n, std::size_t chunk) {
        if (chunk == 0) chunk = 1;
        return (n + chunk - 1) / chunk;
    }

    // Runs map(begin, end) for every chunk, as parallel_for does, and returns the results indexed by chunk:
    // element c is what chunk c returned, whichever thread ran it and whenever. The chunks are those of
    // parallel_for, so they depend on n and chunk alone, never on the thread count; the result is therefore
    // the same for any num_threads as long as map(begin, end) depends only on its range (it may also write
    // outputs that only its range owns); map runs on several threads at once, so it must not touch what
    // another chunk reads or writes. Partial must be default-constructible and not bool (a
    // std::vector<bool> cannot be written from two threads). Cancellation and exceptions as parallel_for:
    // nothing is returned then.
    template <class Map>
    auto map_chunks(std::size_t n, std::size_t chunk, Map &&map)
        -> std::vector<std::decay_t<std::invoke_result_t<Map &, std::size_t, std::size_t>>> {
        using Partial = std::decay_t<std::invoke_result_t<Map &, std::size_t, std::size_t>>;
        static_assert(!std::is_same<Partial, bool>::value, "use an integer: std::vector<bool> packs bits");
        if (chunk == 0) chunk = 1;
        std::vector<Partial> parts(num_chunks(n, chunk));
        // Each result is built in the chunk's own locals and stored once: neighbouring slots share cache lines.
        parallel_for(n, chunk, [&](std::size_t begin, std::size_t end) { parts[begin / chunk] = map(begin, end); });
        return parts;
    }

    // map_chunks, then fold(accumulator, std::move(partial)) for every chunk's result in chunk order, on the
    // calling thread, starting from init; returns the accumulator. The fold order is fixed (chunk 0, 1, ...),
    // so a floating-point sum or a "first error" is the same for any thread count. An exception from the
    // fold propagates from here; for n == 0 this returns init.
    template <class T, class Map, class Fold>
    T map_fold(std::size_t n, std::size_t chunk, T init, Map &&map, Fold &&fold) {
        auto parts = map_chunks(n, chunk, std::forward<Map>(map));
        for (auto &part : parts) fold(init, std::move(part));
        return init;
    }

    // Stage bookkeeping: reports progress and throws Failure(Cancelled) if asked to stop.
    void checkpoint(Stage stage, double fraction);
    bool cancelled() const;

    void log(LogLevel level, const std::string &message) const;
    bool logs(LogLevel level) const {
        return hooks_.log && static_cast<int>(level) <= static_cast<int>(hooks_.log_level);
    }

private:
    int threads_;
    const std::atomic<int> *cancel_flag_;
    Hooks hooks_;
    ThreadPool *pool_ = nullptr;
};

KISSM_DETAIL_END

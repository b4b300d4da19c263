// SPDX-License-Identifier: MIT
// What every stage of one call shares: the worker threads, cancellation and the log sink.
//
// Parallel loops split [0, n) into fixed chunks whose size does not depend on the thread count, and every
// chunk writes only its own outputs; merges happen afterwards in chunk order on the calling thread. That is
// what makes results bitwise identical for any num_threads.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>

#include "detail_namespace.hpp"

KISSM_DETAIL_BEGIN

class ThreadPool;

enum class LogLevel { Error, Warn, Info, Debug };

// The stages, in the order a registration runs them (progress never goes back).
enum class Stage { Voxelize, Features, Matching, Pruning, Solver };

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

// SPDX-License-Identifier: MIT
#include "run_context.hpp"

#include <chrono>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

#include "failure.hpp"

#if defined(__x86_64__) || defined(_M_X64) || defined(__i386__)
#  include <immintrin.h>
#endif

KISSM_DETAIL_BEGIN

namespace {

// How long a thread spins for the next event before it sleeps. A registration runs about a hundred
// parallel loops (forty in the solver alone) with short serial stretches between them, and a sleep and a
// wake-up through the kernel cost more than most of those stretches (docs/design/performance.md, "Thread pool").
constexpr auto kSpin = std::chrono::microseconds(100);

inline void cpu_relax() {
#if defined(__x86_64__) || defined(_M_X64) || defined(__i386__)
    _mm_pause();
#endif
}

// Spins until done() or kSpin has passed; returns done().
template <class Done>
bool spin_until(Done done) {
    const auto deadline = std::chrono::steady_clock::now() + kSpin;
    for (;;) {
        for (int i = 0; i < 64; ++i) {
            if (done()) return true;
            cpu_relax();
        }
        if (std::chrono::steady_clock::now() >= deadline) return done();
    }
}

} // namespace

// A minimal pool: workers wait for a job, grab chunk indices from an atomic counter until none are left.
// Which thread runs which chunk varies; what each chunk computes does not. Waiting is a short spin, then
// a condition variable; every shared state change happens under the mutex as well, so a sleeper is never
// missed. A job is done when its chunks are: the caller waits for the workers that joined it, not for all of
// them, so a worker still starting (the pool lives for one call, and a thread's first wake-up is slow) holds
// up no loop; it joins whichever job is posted when it is ready.
class ThreadPool {
public:
    explicit ThreadPool(int workers) {
        threads_.reserve(static_cast<std::size_t>(workers));
        try {
            for (int i = 0; i < workers; ++i) threads_.emplace_back([this] { worker_loop(); });
        } catch (...) {
            shutdown();
            throw;
        }
    }
    ~ThreadPool() { shutdown(); }

    // Runs job(chunk_index) for every chunk in [0, num_chunks) on the workers and the calling thread.
    void run(std::size_t num_chunks, const std::function<void(std::size_t)> &job) {
        {
            std::lock_guard<std::mutex> lock(mutex_);
            job_ = &job;
            num_chunks_ = num_chunks;
            next_.store(0);
            pending_.store(num_chunks);
            generation_.fetch_add(1, std::memory_order_release);
        }
        cv_.notify_all();
        drain(job, num_chunks);
        if (!spin_until([this] { return pending_.load(std::memory_order_acquire) == 0; })) {
            std::unique_lock<std::mutex> lock(mutex_);
            done_cv_.wait(lock, [this] { return pending_.load() == 0; });
        }
        // Every chunk is done; a worker may still be between its last chunk and leaving the job (or have just
        // joined it and found nothing left). No worker can join once job_ is cleared under the mutex, so after
        // this wait none reads next_ again: the next job may reset it.
        std::unique_lock<std::mutex> lock(mutex_);
        done_cv_.wait(lock, [this] { return joined_ == 0; });
        job_ = nullptr;
    }

private:
    void drain(const std::function<void(std::size_t)> &job, std::size_t num_chunks) {
        for (;;) {
            std::size_t c = next_.fetch_add(1);
            if (c >= num_chunks) break;
            job(c);
            if (pending_.fetch_sub(1, std::memory_order_acq_rel) == 1) {
                std::lock_guard<std::mutex> lock(mutex_);
                done_cv_.notify_all();
            }
        }
    }

    void worker_loop() {
        std::uint64_t seen = 0;
        for (;;) {
            const auto ready = [&] {
                return stop_.load(std::memory_order_acquire) || generation_.load(std::memory_order_acquire) != seen;
            };
            const std::function<void(std::size_t)> *job = nullptr;
            std::size_t n = 0;
            spin_until(ready);
            {
                std::unique_lock<std::mutex> lock(mutex_);
                cv_.wait(lock, ready);
                if (stop_.load()) return;
                seen = generation_.load();
                if (job_ == nullptr) continue; // that job is over already: wait for the next
                job = job_;
                n = num_chunks_;
                ++joined_;
            }
            drain(*job, n);
            std::lock_guard<std::mutex> lock(mutex_);
            --joined_;
            done_cv_.notify_all();
        }
    }

    void shutdown() {
        {
            std::lock_guard<std::mutex> lock(mutex_);
            stop_.store(true);
        }
        cv_.notify_all();
        for (auto &t : threads_)
            if (t.joinable()) t.join();
        threads_.clear();
    }

    std::vector<std::thread> threads_;
    std::mutex mutex_;
    std::condition_variable cv_, done_cv_;
    const std::function<void(std::size_t)> *job_ = nullptr; // the posted job; null between jobs
    std::size_t num_chunks_ = 0;
    std::atomic<std::size_t> next_{0};    // the next chunk to take
    std::atomic<std::size_t> pending_{0}; // chunks of the posted job not finished yet
    int joined_ = 0;                      // workers inside the posted job (under the mutex)
    std::atomic<std::uint64_t> generation_{0};
    std::atomic<bool> stop_{false};
};

RunContext::RunContext(int num_threads, const std::atomic<int> *cancel_flag, Hooks hooks)
    : threads_(num_threads), cancel_flag_(cancel_flag), hooks_(std::move(hooks)) {
    if (threads_ <= 0) {
        unsigned hw = std::thread::hardware_concurrency();
        threads_ = hw == 0 ? 1 : static_cast<int>(hw);
    }
    if (threads_ > 1) {
        try {
            pool_ = new ThreadPool(threads_ - 1);
        } catch (const std::system_error &) {
            // Could not start threads (resource limits): run serially; results are identical anyway.
            pool_ = nullptr;
            threads_ = 1;
        }
    }
}

RunContext::~RunContext() { delete pool_; }

bool RunContext::cancelled() const { return cancel_flag_ && cancel_flag_->load(std::memory_order_relaxed) != 0; }

void RunContext::checkpoint(Stage stage, double fraction) {
    if (hooks_.progress && hooks_.progress(stage, fraction))
        fail(ErrorKind::Cancelled, "cancelled by the progress callback");
    if (cancelled()) fail(ErrorKind::Cancelled, "cancelled by kissm_cancel()");
}

void RunContext::log(LogLevel level, const std::string &message) const {
    if (logs(level)) hooks_.log(level, message);
}

void RunContext::parallel_for(std::size_t n, std::size_t chunk,
                              const std::function<void(std::size_t, std::size_t)> &body) {
    if (n == 0) return;
    if (chunk == 0) chunk = 1;
    const std::size_t num_chunks = (n + chunk - 1) / chunk;
    std::exception_ptr first_error;
    std::mutex error_mutex;
    std::atomic<bool> stop{false};
    auto job = [&](std::size_t c) {
        if (stop.load(std::memory_order_relaxed)) return;
        if (cancelled()) {
            stop.store(true);
            return;
        }
        const std::size_t begin = c * chunk;
        const std::size_t end = begin + chunk < n ? begin + chunk : n;
        try {
            body(begin, end);
        } catch (...) {
            std::lock_guard<std::mutex> lock(error_mutex);
            if (!first_error) first_error = std::current_exception();
            stop.store(true);
        }
    };
    if (pool_ == nullptr || num_chunks == 1) {
        for (std::size_t c = 0; c < num_chunks; ++c) job(c);
    } else {
        pool_->run(num_chunks, job);
    }
    if (first_error) std::rethrow_exception(first_error);
    if (cancelled()) fail(ErrorKind::Cancelled, "cancelled by kissm_cancel()");
}

KISSM_DETAIL_END

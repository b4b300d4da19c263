// SPDX-License-Identifier: MIT
#include "batch_progress.hpp"

#include <cstdio>
#include <utility>

#if defined(_WIN32)
#  include <io.h>
#  define KISSM_ISATTY(fd) _isatty(fd)
#  define KISSM_FILENO(f) _fileno(f)
#else
#  include <unistd.h>
#  define KISSM_ISATTY(fd) isatty(fd)
#  define KISSM_FILENO(f) fileno(f)
#endif

namespace kissm_cli {

namespace {

std::string duration_text(double s) {
    char buf[48];
    if (s < 90.0) {
        std::snprintf(buf, sizeof buf, "%.0f s", s);
    } else if (s < 5400.0) {
        std::snprintf(buf, sizeof buf, "%.0f min", s / 60.0);
    } else {
        std::snprintf(buf, sizeof buf, "%.1f h", s / 3600.0);
    }
    return buf;
}

} // namespace

std::string progress_text(size_t done, size_t total, double elapsed_s) {
    char buf[160];
    const double percent = total ? 100.0 * static_cast<double>(done) / static_cast<double>(total) : 100.0;
    if (done == 0 || elapsed_s <= 0.0) {
        std::snprintf(buf, sizeof buf, "%zu/%zu pairs (%.0f%%)", done, total, percent);
        return buf;
    }
    const double rate = static_cast<double>(done) / elapsed_s;
    std::snprintf(buf, sizeof buf, "%zu/%zu pairs (%.0f%%), %.3g pairs/s, ETA %s", done, total, percent, rate,
                  duration_text(static_cast<double>(total - done) / rate).c_str());
    return buf;
}

BatchProgress::BatchProgress(size_t total, bool enabled, std::string label)
    : total_(total), label_(std::move(label)), enabled_(enabled), tty_(enabled && KISSM_ISATTY(KISSM_FILENO(stderr))),
      start_(std::chrono::steady_clock::now()), last_print_(start_) {}

double BatchProgress::elapsed_s() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

void BatchProgress::pair_done() {
    ++done_;
    if (!enabled_) return;
    const auto now = std::chrono::steady_clock::now();
    const double since = std::chrono::duration<double>(now - last_print_).count();
    if (since < (tty_ ? 0.25 : 5.0)) return;
    last_print_ = now;
    print();
}

void BatchProgress::print() {
    const std::string text = label_ + ": " + progress_text(done_, total_, elapsed_s());
    if (tty_) {
        // Spaces over what is left of a longer previous line.
        const size_t pad = last_width_ > text.size() ? last_width_ - text.size() : 0;
        std::fprintf(stderr, "\r%s%*s", text.c_str(), static_cast<int>(pad), "");
        last_width_ = text.size();
    } else {
        std::fprintf(stderr, "%s\n", text.c_str());
    }
    std::fflush(stderr);
    printed_ = true;
}

void BatchProgress::finish() {
    if (!tty_) return;
    if (done_ > 0) print();
    if (printed_) std::fputc('\n', stderr);
}

} // namespace kissm_cli

// SPDX-License-Identifier: MIT
// Helpers shared by the reader tests: a scratch directory, byte builders for binary files, and checks that
// a read succeeds with exact coordinates or fails with one exact ErrorKind and a one-line message.
#pragma once

#include "harness.h"

#include "core/failure.hpp"
#include "io/read_points.hpp"

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <utility>
#include <vector>

namespace iotest {

using kissm::detail::ErrorKind;
using kissm::detail::FileFormat;

inline const char *kind_name(ErrorKind k) {
    switch (k) {
    case ErrorKind::Io: return "Io";
    case ErrorKind::Parse: return "Parse";
    case ErrorKind::UnsupportedFormat: return "UnsupportedFormat";
    case ErrorKind::Internal: return "Internal";
    default: return "other";
    }
}

// A fresh directory under the system temp dir, removed with everything in it on destruction.
class TempDir {
public:
    TempDir() {
        namespace fs = std::filesystem;
        std::random_device rd;
        const auto stamp = std::chrono::steady_clock::now().time_since_epoch().count();
        for (int attempt = 0; attempt < 100; ++attempt) {
            const fs::path p =
                fs::temp_directory_path() / ("kissm_io_test_" + std::to_string(stamp) + "_" + std::to_string(rd()));
            std::error_code ec;
            if (fs::create_directory(p, ec)) {
                path_ = p;
                return;
            }
        }
        fprintf(stderr, "cannot create a temporary directory\n");
        std::abort();
    }
    ~TempDir() {
        std::error_code ec;
        std::filesystem::remove_all(path_, ec);
    }
    TempDir(const TempDir &) = delete;
    TempDir &operator=(const TempDir &) = delete;

    std::string file(const std::string &name) const { return (path_ / name).string(); }
    std::string write(const std::string &name, const std::string &bytes) const {
        const std::string p = file(name);
        std::ofstream out(p, std::ios::binary | std::ios::trunc);
        out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
        if (!out) {
            fprintf(stderr, "cannot write %s\n", p.c_str());
            std::abort();
        }
        return p;
    }
    const std::filesystem::path &path() const { return path_; }

private:
    std::filesystem::path path_;
};

// Appends fixed-size values in a chosen byte order.
struct Bytes {
    std::string s;

    template <typename T>
    Bytes &put(T value, bool big_endian = false) {
        unsigned char b[sizeof(T)];
        std::memcpy(b, &value, sizeof(T));
        const std::uint16_t probe = 1;
        unsigned char first = 0;
        std::memcpy(&first, &probe, 1);
        const bool host_little = first == 1;
        if (big_endian == host_little) {
            for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
        }
        s.append(reinterpret_cast<const char *>(b), sizeof(T));
        return *this;
    }
    Bytes &text(const std::string &t) {
        s += t;
        return *this;
    }
};

struct Outcome {
    bool ok = false;
    ErrorKind kind = ErrorKind::Internal;
    std::string message;
    std::vector<double> points;
};

// Any exception other than Failure is reported as Internal so that the checks below flag it.
inline Outcome try_read(const std::string &path, FileFormat format) {
    Outcome o;
    try {
        o.points = kissm::detail::read_points_file(path, format);
        o.ok = true;
    } catch (const kissm::detail::Failure &f) {
        o.kind = f.kind();
        o.message = f.what();
    } catch (const std::exception &e) {
        o.kind = ErrorKind::Internal;
        o.message = std::string("unexpected exception: ") + e.what();
    }
    return o;
}

inline void record(bool ok, const char *file, int line, const std::string &what) {
    if (ok) {
        harness_passed++;
    } else {
        harness_failed++;
        fprintf(stderr, "%s:%d: %s\n", file, line, what.c_str());
    }
}

// The read fails with exactly `kind`; the message is one line, names the file, and contains `needle`.
inline Outcome expect_failure(const char *file, int line, const std::string &path, FileFormat format, ErrorKind kind,
                              const char *needle = nullptr) {
    Outcome o = try_read(path, format);
    if (o.ok) {
        record(false, file, line,
               "expected a " + std::string(kind_name(kind)) + " failure, read " + std::to_string(o.points.size() / 3) +
                   " points from " + path);
        return o;
    }
    record(o.kind == kind, file, line,
           "expected " + std::string(kind_name(kind)) + ", got " + kind_name(o.kind) + ": " + o.message);
    record(o.message.find('\n') == std::string::npos && o.message.find(path) != std::string::npos, file, line,
           "message is not one line naming the file: " + o.message);
    if (needle)
        record(o.message.find(needle) != std::string::npos, file, line,
               "message lacks '" + std::string(needle) + "': " + o.message);
    return o;
}

inline bool same_value(double a, double b) { return (std::isnan(a) && std::isnan(b)) || a == b; }

// The read succeeds with exactly these coordinates (NaN matches NaN).
inline Outcome expect_points(const char *file, int line, const std::string &path, FileFormat format,
                             const std::vector<double> &expected) {
    Outcome o = try_read(path, format);
    if (!o.ok) {
        record(false, file, line, "read failed: " + o.message);
        return o;
    }
    record(o.points.size() == expected.size(), file, line,
           "read " + std::to_string(o.points.size()) + " values, expected " + std::to_string(expected.size()) +
               " from " + path);
    if (o.points.size() != expected.size()) return o;
    for (std::size_t i = 0; i < expected.size(); ++i) {
        if (!same_value(o.points[i], expected[i])) {
            char buf[160];
            snprintf(buf, sizeof buf, "value %zu is %.17g, expected %.17g", i, o.points[i], expected[i]);
            record(false, file, line, buf);
            return o;
        }
    }
    record(true, file, line, "");
    return o;
}

#define EXPECT_FAILURE(...) iotest::expect_failure(__FILE__, __LINE__, __VA_ARGS__)
#define EXPECT_POINTS(...) iotest::expect_points(__FILE__, __LINE__, __VA_ARGS__)

// How a prefix of a valid file may be read.
enum class CutRule {
    ParseError,        // every proper prefix must fail with Parse
    ParseOrPrefix,     // fail with Parse, or return the first k points exactly (binary record formats)
    ParseOrTextPrefix, // like ParseOrPrefix, but the last point may differ (a number cut mid-digits)
};

// Reads every proper prefix of `bytes` (lengths 0 .. size-1) and checks each against `rule` and `full`.
// Prefixes of at least `complete_from` bytes must give the full result (data after the points is not needed).
inline void check_every_cut(const char *file, int line, const TempDir &dir, const std::string &name,
                            const std::string &bytes, FileFormat format, const std::vector<double> &full, CutRule rule,
                            std::size_t complete_from = SIZE_MAX) {
    int bad = 0;
    for (std::size_t cut = 0; cut < bytes.size() && bad < 5; ++cut) {
        const std::string path = dir.write(name, bytes.substr(0, cut));
        const Outcome o = try_read(path, format);
        std::string problem;
        if (cut >= complete_from) {
            if (!o.ok || o.points.size() != full.size())
                problem = "expected the full result";
            else
                for (std::size_t i = 0; i < full.size(); ++i)
                    if (!same_value(o.points[i], full[i])) problem = "wrong value";
        } else if (!o.ok) {
            if (o.kind != ErrorKind::Parse)
                problem = std::string("failed with ") + kind_name(o.kind) + ": " + o.message;
            else if (o.message.find('\n') != std::string::npos)
                problem = "multi-line message";
        } else if (rule == CutRule::ParseError || cut == 0) {
            problem = "succeeded";
        } else {
            const std::size_t n = o.points.size();
            std::size_t exact = n;
            if (rule == CutRule::ParseOrTextPrefix && n >= 3) exact = n - 3;
            if (n % 3 != 0 || n > full.size()) problem = "returned too many values";
            for (std::size_t i = 0; i < exact && problem.empty(); ++i)
                if (!same_value(o.points[i], full[i])) problem = "returned a wrong value";
        }
        if (!problem.empty()) {
            ++bad;
            record(false, file, line,
                   name + " cut at " + std::to_string(cut) + " of " + std::to_string(bytes.size()) + ": " + problem);
        }
    }
    record(bad == 0, file, line, name + ": some cuts misbehaved");
}

#define CHECK_EVERY_CUT(...) iotest::check_every_cut(__FILE__, __LINE__, __VA_ARGS__)

// Overwrites each of the first `span` bytes in turn with a few disruptive values; every read must either
// succeed or fail with Parse (never crash, never another kind). Returns how many variants were read.
// `also` is a second error kind some mutations may give (LAS: UnsupportedFormat for a format id that marks
// LAZ in a build without it).
inline int check_mutations(const char *file, int line, const TempDir &dir, const std::string &name,
                           const std::string &bytes, FileFormat format, std::size_t span,
                           ErrorKind also = ErrorKind::Parse) {
    static const char replacements[] = {'\0', '\n', ' ', '-', '9', '\x7f', '\xff', 'x', '.', '#'};
    int bad = 0, variants = 0;
    for (std::size_t i = 0; i < span && i < bytes.size() && bad < 5; ++i) {
        for (char r : replacements) {
            if (bytes[i] == r) continue;
            std::string m = bytes;
            m[i] = r;
            const Outcome o = try_read(dir.write(name, m), format);
            ++variants;
            if (!o.ok && o.kind != ErrorKind::Parse && o.kind != also) {
                ++bad;
                record(false, file, line,
                       name + " with byte " + std::to_string(i) + " changed: " + kind_name(o.kind) + ": " + o.message);
            }
        }
    }
    record(bad == 0, file, line, name + ": some mutations misbehaved");
    return variants;
}

#define CHECK_MUTATIONS(...) iotest::check_mutations(__FILE__, __LINE__, __VA_ARGS__)

} // namespace iotest

// SPDX-License-Identifier: MIT
#include "ply_writer.hpp"

#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>

namespace kissm_cli {
namespace {

struct FileCloser {
    void operator()(std::FILE *f) const { std::fclose(f); }
};

void put_le_double(unsigned char *out, double v) {
    uint64_t bits = 0;
    std::memcpy(&bits, &v, sizeof bits);
    for (int i = 0; i < 8; ++i) out[i] = static_cast<unsigned char>(bits >> (8 * i));
}

} // namespace

bool write_ply_xyz(const std::string &path, const double *xyz, size_t count, const double *transform,
                   const std::vector<std::string> &comments, std::string *error) {
    std::unique_ptr<std::FILE, FileCloser> file(std::fopen(path.c_str(), "wb"));
    const auto fail = [&](const char *what) {
        *error = std::string("cannot ") + what + " '" + path + "': " + std::strerror(errno);
        return false;
    };
    if (!file) return fail("create");
    std::string header = "ply\nformat binary_little_endian 1.0\n";
    for (const std::string &comment : comments) header += "comment " + comment + "\n";
    header += "element vertex " + std::to_string(count) + "\n";
    header += "property double x\nproperty double y\nproperty double z\nend_header\n";
    if (std::fwrite(header.data(), 1, header.size(), file.get()) != header.size()) return fail("write");

    constexpr size_t kChunk = 4096; // points per write
    std::vector<unsigned char> buffer(kChunk * 24);
    for (size_t begin = 0; begin < count; begin += kChunk) {
        const size_t n = count - begin < kChunk ? count - begin : kChunk;
        for (size_t i = 0; i < n; ++i) {
            const double *p = xyz + 3 * (begin + i);
            double q[3] = {p[0], p[1], p[2]};
            if (transform) {
                for (int r = 0; r < 3; ++r) {
                    q[r] = transform[4 * r] * p[0] + transform[4 * r + 1] * p[1] + transform[4 * r + 2] * p[2] +
                           transform[4 * r + 3];
                }
            }
            for (int k = 0; k < 3; ++k) put_le_double(&buffer[24 * i + 8 * static_cast<size_t>(k)], q[k]);
        }
        if (std::fwrite(buffer.data(), 24, n, file.get()) != n) return fail("write");
    }
    std::FILE *raw = file.release();
    if (std::fclose(raw) != 0) return fail("write");
    return true;
}

} // namespace kissm_cli

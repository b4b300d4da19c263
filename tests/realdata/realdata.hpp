// SPDX-License-Identifier: MIT
// What the real-data tests share: 3x3 rotations, the pair files of ../shared/data and reading a cloud.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "kissm.h"
#include "splitmix64.h"

namespace realdata {

struct Mat3 {
    double m[9];
};

inline Mat3 axis_angle(double ax, double ay, double az, double angle) {
    const double n = std::sqrt(ax * ax + ay * ay + az * az);
    ax /= n, ay /= n, az /= n;
    const double c = std::cos(angle), s = std::sin(angle), C = 1 - c;
    return Mat3{{c + ax * ax * C, ax * ay * C - az * s, ax * az * C + ay * s, ay * ax * C + az * s, c + ay * ay * C,
                 ay * az * C - ax * s, az * ax * C - ay * s, az * ay * C + ax * s, c + az * az * C}};
}

inline Mat3 mul(const Mat3 &a, const Mat3 &b) {
    Mat3 r{};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            for (int k = 0; k < 3; ++k) r.m[3 * i + j] += a.m[3 * i + k] * b.m[3 * k + j];
    return r;
}

inline Mat3 transpose(const Mat3 &a) {
    Mat3 r{};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) r.m[3 * i + j] = a.m[3 * j + i];
    return r;
}

inline double rotation_error_deg(const Mat3 &a, const Mat3 &b) {
    const Mat3 d = mul(transpose(a), b);
    const double c = (d.m[0] + d.m[4] + d.m[8] - 1.0) / 2.0;
    return std::acos(std::max(-1.0, std::min(1.0, c))) * 180.0 / 3.14159265358979323846;
}

struct Rng { // splitmix64 seeded with the seed itself: the same numbers on every platform
    std::uint64_t s;
    double uniform() { return splitmix64_uniform(&s); }
};

inline std::map<std::string, std::string> read_pair_txt(const std::string &path) {
    std::map<std::string, std::string> kv;
    std::ifstream f(path);
    std::string line;
    while (std::getline(f, line)) {
        const auto colon = line.find(':');
        if (colon == std::string::npos) continue;
        std::string value = line.substr(colon + 1);
        while (!value.empty() && (value[0] == ' ' || value[0] == '\t')) value.erase(0, 1);
        while (!value.empty() && (value.back() == '\r' || value.back() == ' ')) value.pop_back();
        kv[line.substr(0, colon)] = value;
    }
    return kv;
}

inline int32_t format_id(const std::string &name) {
    if (name == "ply") return KISSM_FORMAT_PLY;
    if (name == "kitti_bin_xyzi_f32") return KISSM_FORMAT_KITTI_BIN;
    if (name == "bin_xyz_f32") return KISSM_FORMAT_BIN_XYZ;
    if (name == "npy_xyz") return KISSM_FORMAT_NPY;
    return KISSM_FORMAT_AUTO;
}

inline std::vector<double> read_cloud(const std::string &path, int32_t format) {
    kissm_cloud *cloud = nullptr;
    std::vector<double> xyz;
    if (kissm_read_points(path.c_str(), format, &cloud) != KISSM_OK) {
        std::fprintf(stderr, "cannot read %s: %s\n", path.c_str(), kissm_last_error_message());
        return xyz;
    }
    xyz.assign(kissm_cloud_data(cloud), kissm_cloud_data(cloud) + 3 * kissm_cloud_count(cloud));
    kissm_cloud_destroy(cloud);
    return xyz;
}

// $KISSM_DATA_DIR when it holds index.tsv; otherwise "" after printing why the test is skipped (exit 77).
inline std::string data_root() {
    const char *dir = std::getenv("KISSM_DATA_DIR");
    const std::string root = dir ? dir : "";
    if (root.empty() || !std::ifstream(root + "/index.tsv")) {
        std::printf("SKIPPED: real data not found (KISSM_DATA_DIR=%s has no index.tsv); "
                    "these tests need ../shared/data\n",
                    root.c_str());
        return "";
    }
    return root;
}

} // namespace realdata

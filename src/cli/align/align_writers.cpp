// SPDX-License-Identifier: MIT
#include "align_writers.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "cli_args.hpp"
#include "json_writer.hpp"

namespace kissm_cli {
namespace {

// The poses table's numbers: the JSON writer's round-trip text, and "nan" (not "null") for a missing pose.
std::string table_number(double v) { return std::isnan(v) ? "nan" : JsonWriter::number(v); }

std::string g2o_pose(const double T[16]) {
    double q[4];
    rotation_quaternion(T, q);
    const double values[7] = {T[3], T[7], T[11], q[0], q[1], q[2], q[3]};
    std::string s;
    for (int i = 0; i < 7; ++i) s += (i ? " " : "") + python_float_text(values[i]);
    return s;
}

} // namespace

std::string python_float_text(double v) {
    if (std::isnan(v)) return "nan";
    if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
    if (v == 0.0) return std::signbit(v) ? "-0.0" : "0.0";
    // The fewest significant digits that read back (the correctly rounded ones, as repr's); then repr's layout.
    char buf[40];
    for (int digits = 1; digits <= 17; ++digits) {
        std::snprintf(buf, sizeof buf, "%.*e", digits - 1, v);
        if (std::strtod(buf, nullptr) == v) break;
    }
    std::string text(buf);
    std::string out;
    if (text[0] == '-') {
        out = "-";
        text.erase(0, 1);
    }
    const size_t e = text.find('e');
    const int exponent = std::atoi(text.c_str() + e + 1);
    std::string digits;
    for (size_t i = 0; i < e; ++i) {
        if (text[i] != '.') digits.push_back(text[i]);
    }
    while (digits.size() > 1 && digits.back() == '0') digits.pop_back();
    if (exponent >= -4 && exponent < 16) {
        if (exponent < 0) return out + "0." + std::string(static_cast<size_t>(-exponent - 1), '0') + digits;
        const size_t whole = static_cast<size_t>(exponent) + 1;
        if (digits.size() <= whole) return out + digits + std::string(whole - digits.size(), '0') + ".0";
        return out + digits.substr(0, whole) + "." + digits.substr(whole);
    }
    out += digits.substr(0, 1);
    if (digits.size() > 1) out += "." + digits.substr(1);
    char exp_text[16];
    std::snprintf(exp_text, sizeof exp_text, "e%c%02d", exponent < 0 ? '-' : '+', std::abs(exponent));
    return out + exp_text;
}

void rotation_quaternion(const double T[16], double q[4]) {
    const auto m = [T](int r, int c) { return T[4 * r + c]; };
    const double trace = (m(0, 0) + m(1, 1)) + m(2, 2);
    double x, y, z, w;
    if (trace > 0) {
        const double s = std::sqrt(trace + 1.0) * 2;
        x = (m(2, 1) - m(1, 2)) / s;
        y = (m(0, 2) - m(2, 0)) / s;
        z = (m(1, 0) - m(0, 1)) / s;
        w = 0.25 * s;
    } else if (m(0, 0) > m(1, 1) && m(0, 0) > m(2, 2)) {
        const double s = std::sqrt(((1.0 + m(0, 0)) - m(1, 1)) - m(2, 2)) * 2;
        x = 0.25 * s;
        y = (m(0, 1) + m(1, 0)) / s;
        z = (m(0, 2) + m(2, 0)) / s;
        w = (m(2, 1) - m(1, 2)) / s;
    } else if (m(1, 1) > m(2, 2)) {
        const double s = std::sqrt(((1.0 + m(1, 1)) - m(0, 0)) - m(2, 2)) * 2;
        x = (m(0, 1) + m(1, 0)) / s;
        y = 0.25 * s;
        z = (m(1, 2) + m(2, 1)) / s;
        w = (m(0, 2) - m(2, 0)) / s;
    } else {
        const double s = std::sqrt(((1.0 + m(2, 2)) - m(0, 0)) - m(1, 1)) * 2;
        x = (m(0, 2) + m(2, 0)) / s;
        y = (m(1, 2) + m(2, 1)) / s;
        z = 0.25 * s;
        w = (m(1, 0) - m(0, 1)) / s;
    }
    const double norm = std::sqrt(((x * x + y * y) + z * z) + w * w);
    const double sign = w < 0 ? -1.0 : 1.0;
    q[0] = sign * x / norm;
    q[1] = sign * y / norm;
    q[2] = sign * z / norm;
    q[3] = sign * w / norm;
}

std::string poses_table(const std::vector<Scan> &scans, const Alignment &alignment) {
    std::string s = "scan\tplaced\tcomponent";
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 4; ++c) s += "\tT" + std::to_string(r) + std::to_string(c);
    }
    s += "\n";
    for (size_t k = 0; k < scans.size(); ++k) {
        s += scans[k].name + "\t" + (alignment.placed[k] ? "1" : "0") + "\t" + std::to_string(alignment.components[k]);
        for (int i = 0; i < 12; ++i) s += "\t" + table_number(alignment.poses[16 * k + static_cast<size_t>(i)]);
        s += "\n";
    }
    return s;
}

std::string tum_text(const Alignment &alignment) {
    std::string s;
    for (size_t k = 0; k < alignment.placed.size(); ++k) {
        if (!alignment.placed[k]) continue;
        const double *T = &alignment.poses[16 * k];
        double q[4];
        rotation_quaternion(T, q);
        const double values[8] = {static_cast<double>(k), T[3], T[7], T[11], q[0], q[1], q[2], q[3]};
        for (int i = 0; i < 8; ++i) s += (i ? " " : "") + python_float_text(values[i]);
        s += "\n";
    }
    return s;
}

std::string kitti_text(const Alignment &alignment) {
    std::string s;
    for (size_t k = 0; k < alignment.placed.size(); ++k) {
        for (int i = 0; i < 12; ++i)
            s += (i ? " " : "") + python_float_text(alignment.poses[16 * k + static_cast<size_t>(i)]);
        s += "\n";
    }
    return s;
}

std::string g2o_text(const Alignment &alignment) {
    std::string s;
    for (size_t k = 0; k < alignment.placed.size(); ++k) {
        if (alignment.placed[k])
            s += "VERTEX_SE3:QUAT " + std::to_string(k) + " " + g2o_pose(&alignment.poses[16 * k]) + "\n";
    }
    static const int kOrder[6] = {3, 4, 5, 0, 1, 2};                // g2o: translation, then rotation
    static const double kScale[6] = {1.0, 1.0, 1.0, 2.0, 2.0, 2.0}; // d(rotation vector) = 2 d(quaternion vector)
    for (const AlignEdge &edge : alignment.edges) {
        if (!edge.accepted) continue;
        s += "EDGE_SE3:QUAT " + std::to_string(edge.target) + " " + std::to_string(edge.source) + " " +
             g2o_pose(edge.transform);
        for (int i = 0; i < 6; ++i) {
            for (int j = i; j < 6; ++j) {
                s += " " + python_float_text(edge.information[6 * kOrder[i] + kOrder[j]] * (kScale[i] * kScale[j]));
            }
        }
        s += "\n";
    }
    return s;
}

void write_text_file(const std::string &path, const std::string &text, const char *what) {
    std::FILE *file = std::fopen(path.c_str(), "wb");
    bool ok = file != nullptr;
    if (ok) ok = std::fwrite(text.data(), 1, text.size(), file) == text.size();
    if (file && std::fclose(file) != 0) ok = false;
    if (!ok) throw UsageError(std::string("cannot write ") + what + " '" + one_line(path) + "'");
}

} // namespace kissm_cli

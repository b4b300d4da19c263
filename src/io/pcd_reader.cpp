// SPDX-License-Identifier: MIT
// PCD (DATA ascii and binary): the x, y, z fields; every other field is skipped by its SIZE and COUNT.
#include "core/detail_namespace.hpp"
#include "io/binary_scalar.hpp"
#include "io/file_bytes.hpp"
#include "io/format_readers.hpp"
#include "io/text_scan.hpp"

#include <cstdint>
#include <string>
#include <vector>

KISSM_DETAIL_BEGIN

namespace {

struct PcdField {
    std::string name;
    std::uint64_t size = 0;
    char type = 'F';
    std::uint64_t count = 1;
};

enum class PcdData { Ascii, Binary };

struct PcdHeader {
    std::vector<PcdField> fields;
    std::uint64_t points = 0;
    PcdData data = PcdData::Ascii;
    std::size_t body_offset = 0;
    std::size_t body_first_line = 0;
};

bool pcd_scalar(char type, std::uint64_t size, Scalar &out) {
    switch (type) {
    case 'F':
        if (size == 4)
            out = Scalar::F32;
        else if (size == 8)
            out = Scalar::F64;
        else
            return false;
        return true;
    case 'I':
        if (size == 1)
            out = Scalar::I8;
        else if (size == 2)
            out = Scalar::I16;
        else if (size == 4)
            out = Scalar::I32;
        else if (size == 8)
            out = Scalar::I64;
        else
            return false;
        return true;
    case 'U':
        if (size == 1)
            out = Scalar::U8;
        else if (size == 2)
            out = Scalar::U16;
        else if (size == 4)
            out = Scalar::U32;
        else if (size == 8)
            out = Scalar::U64;
        else
            return false;
        return true;
    default: return false;
    }
}

PcdHeader parse_header(const std::string &path, std::string_view bytes) {
    LineCursor lines(bytes.data(), bytes.data() + bytes.size());
    auto bad_line = [&](const std::string &what) {
        fail_parse(path, "PCD header line " + std::to_string(lines.line_no) + ": " + what);
    };
    std::vector<std::string_view> names, sizes, types, counts;
    bool have_fields = false, have_size = false, have_type = false, have_count = false;
    bool have_width = false, have_height = false, have_points = false, have_data = false;
    std::uint64_t width = 0, height = 1, points = 0;
    PcdHeader header;

    auto one_number = [&](const std::vector<std::string_view> &w, bool &seen, std::uint64_t &value) {
        if (seen) bad_line("a second " + std::string(w[0]) + " line");
        if (w.size() != 2 || !parse_u64(w[1], value)) bad_line("expected '" + std::string(w[0]) + " <count>'");
        seen = true;
    };
    auto list = [&](const std::vector<std::string_view> &w, bool &seen, std::vector<std::string_view> &out) {
        if (seen) bad_line("a second " + std::string(w[0]) + " line");
        if (w.size() < 2) bad_line(std::string(w[0]) + " lists nothing");
        out.assign(w.begin() + 1, w.end());
        seen = true;
    };

    const char *lb = nullptr;
    const char *le = nullptr;
    while (!have_data) {
        if (!lines.next(lb, le)) fail_parse(path, "truncated: the PCD header has no DATA line");
        const std::vector<std::string_view> w = split_words(lb, le);
        if (w.empty() || w[0][0] == '#') continue;
        const std::string_view key = w[0];
        if (key == "VERSION" || key == "VIEWPOINT") {
            continue; // nothing here changes how x, y, z are read
        } else if (key == "FIELDS") {
            list(w, have_fields, names);
        } else if (key == "SIZE") {
            list(w, have_size, sizes);
        } else if (key == "TYPE") {
            list(w, have_type, types);
        } else if (key == "COUNT") {
            list(w, have_count, counts);
        } else if (key == "WIDTH") {
            one_number(w, have_width, width);
        } else if (key == "HEIGHT") {
            one_number(w, have_height, height);
        } else if (key == "POINTS") {
            one_number(w, have_points, points);
        } else if (key == "DATA") {
            if (w.size() != 2) bad_line("expected 'DATA ascii' or 'DATA binary'");
            if (w[1] == "ascii")
                header.data = PcdData::Ascii;
            else if (w[1] == "binary")
                header.data = PcdData::Binary;
            else if (w[1] == "binary_compressed")
                fail_parse(path, "binary_compressed PCD is not supported (re-save it as binary or ascii)");
            else
                bad_line("unknown DATA encoding " + quote_token(w[1]));
            have_data = true;
        } else {
            bad_line("unknown keyword " + quote_token(key));
        }
    }
    header.body_offset = static_cast<std::size_t>(lines.pos - bytes.data());
    header.body_first_line = lines.line_no + 1;

    if (!have_fields) fail_parse(path, "the PCD header has no FIELDS line");
    if (!have_size) fail_parse(path, "the PCD header has no SIZE line");
    auto same_length = [&](const std::vector<std::string_view> &v, const char *key) {
        if (v.size() != names.size())
            fail_parse(path, std::string("the PCD header's ") + key + " has " + std::to_string(v.size()) +
                                 " entries but FIELDS has " + std::to_string(names.size()));
    };
    same_length(sizes, "SIZE");
    if (have_type) same_length(types, "TYPE");
    if (have_count) same_length(counts, "COUNT");

    header.fields.resize(names.size());
    for (std::size_t i = 0; i < names.size(); ++i) {
        PcdField &f = header.fields[i];
        f.name = std::string(names[i]);
        if (!parse_u64(sizes[i], f.size) || f.size == 0)
            fail_parse(path, "PCD field '" + f.name + "' has a bad SIZE " + quote_token(sizes[i]));
        // Very old files omit TYPE; their fields were all floats.
        if (have_type) {
            if (types[i].size() != 1 || (types[i][0] != 'F' && types[i][0] != 'I' && types[i][0] != 'U'))
                fail_parse(path, "PCD field '" + f.name + "' has an unknown TYPE " + quote_token(types[i]));
            f.type = types[i][0];
        }
        if (have_count && (!parse_u64(counts[i], f.count) || f.count == 0))
            fail_parse(path, "PCD field '" + f.name + "' has a bad COUNT " + quote_token(counts[i]));
    }

    std::uint64_t grid = 0;
    if (have_width && !checked_mul(width, height, grid))
        fail_parse(path,
                   "PCD WIDTH * HEIGHT overflows (" + std::to_string(width) + " * " + std::to_string(height) + ")");
    if (have_points) {
        if (have_width && grid != points)
            fail_parse(path, "PCD POINTS " + std::to_string(points) +
                                 " disagrees with WIDTH * HEIGHT = " + std::to_string(grid));
        header.points = points;
    } else if (have_width) {
        header.points = grid;
    } else {
        fail_parse(path, "the PCD header has neither POINTS nor WIDTH");
    }
    return header;
}

struct XyzColumns {
    Scalar type[3] = {Scalar::F32, Scalar::F32, Scalar::F32};
    std::uint64_t byte_offset[3] = {0, 0, 0}; // within a binary record
    std::uint64_t value_index[3] = {0, 0, 0}; // within an ascii line
    std::uint64_t record_bytes = 0;
    std::uint64_t record_values = 0;
};

XyzColumns find_xyz(const std::string &path, const std::vector<PcdField> &fields) {
    XyzColumns c;
    const char *axes[3] = {"x", "y", "z"};
    bool found[3] = {false, false, false};
    for (std::size_t i = 0; i < fields.size(); ++i) {
        const PcdField &f = fields[i];
        for (int a = 0; a < 3; ++a) {
            if (f.name != axes[a]) continue;
            if (found[a]) fail_parse(path, "the PCD header has two '" + f.name + "' fields");
            if (f.count != 1)
                fail_parse(path, "PCD field '" + f.name + "' has COUNT " + std::to_string(f.count) + ", not 1");
            if (!pcd_scalar(f.type, f.size, c.type[a]))
                fail_parse(path, "PCD field '" + f.name + "' has an unsupported TYPE/SIZE " + std::string(1, f.type) +
                                     std::to_string(f.size));
            found[a] = true;
            c.byte_offset[a] = c.record_bytes;
            c.value_index[a] = c.record_values;
        }
        std::uint64_t bytes = 0;
        if (!checked_mul(f.size, f.count, bytes) || !checked_add(c.record_bytes, bytes, c.record_bytes) ||
            !checked_add(c.record_values, f.count, c.record_values))
            fail_parse(path, "PCD field '" + f.name + "' is too large (SIZE * COUNT overflows)");
    }
    for (int a = 0; a < 3; ++a)
        if (!found[a]) fail_parse(path, std::string("the PCD header has no '") + axes[a] + "' field");
    return c;
}

std::vector<double> read_binary(const std::string &path, std::string_view bytes, const PcdHeader &h,
                                const XyzColumns &c) {
    const std::size_t left = bytes.size() - h.body_offset;
    std::uint64_t need = 0;
    if (!checked_mul(h.points, c.record_bytes, need))
        fail_parse(path, "truncated: the PCD header declares " + std::to_string(h.points) + " points of " +
                             std::to_string(c.record_bytes) + " bytes, far more than the " + std::to_string(left) +
                             " bytes that follow");
    if (need > left)
        fail_parse(path, "truncated: expected " + std::to_string(need) + " bytes of point data, found " +
                             std::to_string(left));
    // PCL writes binary data in the writer's byte order, which in practice is always little-endian.
    const bool swap = !host_is_little_endian();
    const std::size_t n = static_cast<std::size_t>(h.points);
    const std::size_t record = static_cast<std::size_t>(c.record_bytes);
    std::vector<double> xyz(n * 3);
    const char *r = bytes.data() + h.body_offset;
    for (std::size_t i = 0; i < n; ++i, r += record) {
        for (int a = 0; a < 3; ++a)
            xyz[3 * i + static_cast<std::size_t>(a)] =
                load_scalar(r + static_cast<std::size_t>(c.byte_offset[a]), c.type[a], swap);
    }
    return xyz;
}

std::vector<double> read_ascii(const std::string &path, std::string_view bytes, const PcdHeader &h,
                               const XyzColumns &c) {
    const char *begin = bytes.data() + h.body_offset;
    const char *end = bytes.data() + bytes.size();
    const std::size_t left = static_cast<std::size_t>(end - begin);
    // Each value needs a character and a separator: refuse counts the data cannot hold before reserving.
    std::uint64_t values = 0;
    if (!checked_mul(h.points, c.record_values, values) || values > (left + 1) / 2)
        fail_parse(path, "truncated: the PCD header declares " + std::to_string(h.points) + " points but only " +
                             std::to_string(left) + " bytes of data follow");
    const std::size_t n = static_cast<std::size_t>(h.points);
    std::vector<double> xyz(n * 3);
    LineCursor lines(begin, end);
    lines.line_no = h.body_first_line - 1;
    std::size_t point = 0;
    const char *lb = nullptr;
    const char *le = nullptr;
    while (lines.next(lb, le)) {
        const char *p = lb;
        std::uint64_t k = 0;
        while (true) {
            while (p < le && is_space(*p)) ++p;
            if (p >= le) break;
            const char *tb = p;
            while (p < le && !is_space(*p)) ++p;
            if (k == 0 && point == n)
                fail_parse(path, "line " + std::to_string(lines.line_no) + ": more data than the header's " +
                                     std::to_string(n) + " points");
            for (int a = 0; a < 3; ++a) {
                if (c.value_index[a] != k) continue;
                if (!parse_double(tb, p, xyz[3 * point + static_cast<std::size_t>(a)]))
                    fail_parse(path, "line " + std::to_string(lines.line_no) + ": bad value " + quote_token(tb, p) +
                                         " for field '" + std::string(1, "xyz"[a]) + "'");
            }
            ++k;
        }
        if (k == 0) continue; // blank line
        if (k != c.record_values)
            fail_parse(path, "line " + std::to_string(lines.line_no) + ": expected " + std::to_string(c.record_values) +
                                 " values, found " + std::to_string(k));
        ++point;
    }
    if (point != n)
        fail_parse(path, "truncated: expected " + std::to_string(n) + " points, found " + std::to_string(point));
    return xyz;
}

} // namespace

std::vector<double> parse_pcd(const std::string &path, std::string_view bytes) {
    const PcdHeader header = parse_header(path, bytes);
    const XyzColumns columns = find_xyz(path, header.fields);
    if (header.data == PcdData::Binary) return read_binary(path, bytes, header, columns);
    return read_ascii(path, bytes, header, columns);
}

KISSM_DETAIL_END

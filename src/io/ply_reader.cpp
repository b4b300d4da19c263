// SPDX-License-Identifier: MIT
// PLY (ascii, binary_little_endian, binary_big_endian): the x, y, z properties of the `vertex` element.
//
// Elements after `vertex` are never read: they cannot change the points, and the Stanford scans carry a
// 200K-record range_grid list element after theirs. Elements before it are skipped record by record
// (list lengths vary), with every length checked against the bytes that are left.
#include "core/detail_namespace.hpp"
#include "core/failure.hpp"
#include "io/binary_scalar.hpp"
#include "io/file_bytes.hpp"
#include "io/format_readers.hpp"
#include "io/text_scan.hpp"

#include <cstdint>
#include <string>
#include <vector>

KISSM_DETAIL_BEGIN

namespace {

enum class PlyEncoding { Ascii, BinaryLittle, BinaryBig };

struct PlyProperty {
    std::string name;
    Scalar type = Scalar::F32; // the value type, or a list's item type
    bool is_list = false;
    Scalar count_type = Scalar::U8; // lists only
};

struct PlyElement {
    std::string name;
    std::uint64_t count = 0;
    std::vector<PlyProperty> properties;

    bool has_list() const {
        for (const PlyProperty &p : properties)
            if (p.is_list) return true;
        return false;
    }
    // Bytes of a record without lists; the smallest possible record (empty lists) otherwise.
    std::uint64_t min_record_bytes() const {
        std::uint64_t n = 0;
        for (const PlyProperty &p : properties) n += scalar_size(p.is_list ? p.count_type : p.type);
        return n;
    }
};

struct PlyHeader {
    PlyEncoding encoding = PlyEncoding::Ascii;
    std::vector<PlyElement> elements;
    std::size_t body_offset = 0;     // first byte after the end_header line
    std::size_t body_first_line = 0; // its line number, for ascii messages
};

bool ply_scalar(std::string_view name, Scalar &out) {
    struct Entry {
        const char *name;
        Scalar type;
    };
    static const Entry table[] = {
        {"char", Scalar::I8},   {"int8", Scalar::I8},     {"uchar", Scalar::U8},   {"uint8", Scalar::U8},
        {"short", Scalar::I16}, {"int16", Scalar::I16},   {"ushort", Scalar::U16}, {"uint16", Scalar::U16},
        {"int", Scalar::I32},   {"int32", Scalar::I32},   {"uint", Scalar::U32},   {"uint32", Scalar::U32},
        {"float", Scalar::F32}, {"float32", Scalar::F32}, {"double", Scalar::F64}, {"float64", Scalar::F64},
        {"int64", Scalar::I64}, {"uint64", Scalar::U64},
    };
    for (const Entry &e : table) {
        if (name == e.name) {
            out = e.type;
            return true;
        }
    }
    return false;
}

namespace {

// A keyword as the PLY header writes them: a letter, then letters, digits and underscores.
bool is_identifier(std::string_view w) {
    const auto letter = [](char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z'); };
    if (w.empty() || !letter(w[0])) return false;
    for (char c : w)
        if (!letter(c) && !(c >= '0' && c <= '9') && c != '_') return false;
    return true;
}

} // namespace

PlyHeader parse_header(const std::string &path, std::string_view bytes) {
    LineCursor lines(bytes.data(), bytes.data() + bytes.size());
    const char *lb = nullptr;
    const char *le = nullptr;
    if (!lines.next(lb, le) || std::string_view(lb, static_cast<std::size_t>(le - lb)) != "ply")
        fail_parse(path, "not a PLY file (the first line is not 'ply')");

    PlyHeader header;
    bool have_format = false;
    auto bad_line = [&](const std::string &what) {
        fail_parse(path, "PLY header line " + std::to_string(lines.line_no) + ": " + what);
    };
    for (;;) {
        if (!lines.next(lb, le)) fail_parse(path, "truncated: the PLY header has no end_header line");
        const std::vector<std::string_view> w = split_words(lb, le);
        if (w.empty()) continue;
        const std::string_view key = w[0];
        if (key == "comment" || key == "obj_info") continue;
        if (key == "end_header") {
            if (w.size() != 1) bad_line("unexpected text after end_header");
            break;
        }
        if (key == "format") {
            if (have_format) bad_line("a second format line");
            if (w.size() != 3) bad_line("expected 'format <encoding> 1.0'");
            if (w[1] == "ascii")
                header.encoding = PlyEncoding::Ascii;
            else if (w[1] == "binary_little_endian")
                header.encoding = PlyEncoding::BinaryLittle;
            else if (w[1] == "binary_big_endian")
                header.encoding = PlyEncoding::BinaryBig;
            else
                bad_line("unknown encoding " + quote_token(w[1]));
            have_format = true;
        } else if (key == "element") {
            if (w.size() != 3) bad_line("expected 'element <name> <count>'");
            PlyElement el;
            el.name = std::string(w[1]);
            if (!parse_u64(w[2], el.count)) bad_line("bad element count " + quote_token(w[2]));
            header.elements.push_back(std::move(el));
        } else if (key == "property") {
            if (header.elements.empty()) bad_line("property before any element");
            PlyProperty prop;
            if (w.size() >= 2 && w[1] == "list") {
                if (w.size() != 5) bad_line("expected 'property list <count type> <item type> <name>'");
                if (!ply_scalar(w[2], prop.count_type)) bad_line("unknown property type " + quote_token(w[2]));
                if (!scalar_is_integer(prop.count_type))
                    bad_line("list length type " + quote_token(w[2]) + " is not an integer type");
                if (!ply_scalar(w[3], prop.type)) bad_line("unknown property type " + quote_token(w[3]));
                prop.is_list = true;
                prop.name = std::string(w[4]);
            } else {
                if (w.size() != 3) bad_line("expected 'property <type> <name>'");
                if (!ply_scalar(w[1], prop.type)) bad_line("unknown property type " + quote_token(w[1]));
                prop.name = std::string(w[2]);
            }
            header.elements.back().properties.push_back(std::move(prop));
        } else if (header.elements.empty() && is_identifier(key)) {
            // Before the first element a line of an unknown keyword describes no data: some writers put their own
            // lines there (Stanford's Cyberware scans end their obj_info block with three "bye" lines). After it,
            // an unknown keyword may change what the elements mean, so it stays an error.
            continue;
        } else {
            bad_line("unknown keyword " + quote_token(key));
        }
    }
    if (!have_format) fail_parse(path, "the PLY header has no format line");
    header.body_offset = static_cast<std::size_t>(lines.pos - bytes.data());
    header.body_first_line = lines.line_no + 1;
    return header;
}

// Where x, y, z sit in a vertex record.
struct XyzSlots {
    std::size_t index[3] = {0, 0, 0}; // property indices

    // 0, 1, 2 for the x, y, z property; -1 for any other.
    int axis_of(std::size_t property) const {
        for (int a = 0; a < 3; ++a)
            if (index[a] == property) return a;
        return -1;
    }
};

XyzSlots find_xyz(const std::string &path, const PlyElement &vertex) {
    XyzSlots slots;
    const char *names[3] = {"x", "y", "z"};
    for (int a = 0; a < 3; ++a) {
        bool found = false;
        for (std::size_t i = 0; i < vertex.properties.size(); ++i) {
            if (vertex.properties[i].name != names[a]) continue;
            if (found) fail_parse(path, std::string("the vertex element has two '") + names[a] + "' properties");
            if (vertex.properties[i].is_list)
                fail_parse(path, std::string("vertex property '") + names[a] + "' is a list");
            slots.index[a] = i;
            found = true;
        }
        if (!found) fail_parse(path, std::string("the vertex element has no '") + names[a] + "' property");
    }
    return slots;
}

std::string truncated_bytes(const PlyElement &el, std::uint64_t expected, std::size_t found) {
    const std::string what = el.name == "vertex" ? "vertex data" : "element '" + el.name + "' data";
    return "truncated: expected " + std::to_string(expected) + " bytes of " + what + ", found " + std::to_string(found);
}

// ------------------------------------------------------------------------------------------------------
// Binary bodies
// ------------------------------------------------------------------------------------------------------

class BinaryBody {
public:
    BinaryBody(const std::string &path, std::string_view bytes, std::size_t offset, bool swap)
        : path_(path), p_(bytes.data() + offset), end_(bytes.data() + bytes.size()), swap_(swap) {}

    std::size_t left() const { return static_cast<std::size_t>(end_ - p_); }

    void skip_element(const PlyElement &el) {
        if (el.count == 0 || el.properties.empty()) return;
        if (!el.has_list()) {
            p_ += fixed_block(el);
            return;
        }
        for (std::uint64_t r = 0; r < el.count; ++r) {
            for (const PlyProperty &prop : el.properties) skip_property(el, r, prop);
        }
    }

    std::vector<double> read_vertices(const PlyElement &el, const XyzSlots &slots) {
        std::vector<double> xyz;
        if (el.count == 0) return xyz;
        if (!el.has_list()) {
            const std::size_t block = fixed_block(el);
            std::size_t offset[3] = {0, 0, 0};
            Scalar type[3] = {Scalar::F32, Scalar::F32, Scalar::F32};
            for (int a = 0; a < 3; ++a) {
                for (std::size_t i = 0; i < slots.index[a]; ++i) offset[a] += scalar_size(el.properties[i].type);
                type[a] = el.properties[slots.index[a]].type;
            }
            const std::size_t record = static_cast<std::size_t>(el.min_record_bytes());
            const std::size_t n = static_cast<std::size_t>(el.count);
            xyz.resize(n * 3);
            const char *r = p_;
            for (std::size_t i = 0; i < n; ++i, r += record) {
                xyz[3 * i + 0] = load_scalar(r + offset[0], type[0], swap_);
                xyz[3 * i + 1] = load_scalar(r + offset[1], type[1], swap_);
                xyz[3 * i + 2] = load_scalar(r + offset[2], type[2], swap_);
            }
            p_ += block;
            return xyz;
        }
        // Records vary in length: the smallest possible record bounds how many can fit.
        const std::uint64_t fit = left() / el.min_record_bytes();
        if (el.count > fit)
            fail_parse(path_, "truncated: the header declares " + std::to_string(el.count) + " vertices but only " +
                                  std::to_string(left()) + " bytes of data follow");
        xyz.reserve(static_cast<std::size_t>(el.count) * 3);
        for (std::uint64_t r = 0; r < el.count; ++r) {
            double v[3] = {0, 0, 0};
            for (std::size_t i = 0; i < el.properties.size(); ++i) {
                const PlyProperty &prop = el.properties[i];
                const int axis = slots.axis_of(i);
                if (axis < 0)
                    skip_property(el, r, prop);
                else
                    v[axis] = load_scalar(take(el, r, scalar_size(prop.type)), prop.type, swap_);
            }
            xyz.insert(xyz.end(), v, v + 3);
        }
        return xyz;
    }

private:
    // Checks that el.count records of a list-free element are all present; returns their byte count.
    std::size_t fixed_block(const PlyElement &el) {
        const std::uint64_t record = el.min_record_bytes();
        std::uint64_t need = 0;
        if (!checked_mul(el.count, record, need))
            fail_parse(path_, "truncated: element '" + el.name + "' declares " + std::to_string(el.count) +
                                  " records of " + std::to_string(record) + " bytes, far more than the " +
                                  std::to_string(left()) + " bytes that follow");
        if (need > left()) fail_parse(path_, truncated_bytes(el, need, left()));
        return static_cast<std::size_t>(need);
    }

    const char *take(const PlyElement &el, std::uint64_t record, std::uint64_t n) {
        if (n > left())
            fail_parse(path_, "truncated: record " + std::to_string(record) + " of element '" + el.name + "' (of " +
                                  std::to_string(el.count) + ") runs past the end of the file");
        const char *at = p_;
        p_ += n;
        return at;
    }

    void skip_property(const PlyElement &el, std::uint64_t record, const PlyProperty &prop) {
        if (!prop.is_list) {
            take(el, record, scalar_size(prop.type));
            return;
        }
        const char *at = take(el, record, scalar_size(prop.count_type));
        std::uint64_t items = 0;
        if (!load_count(at, prop.count_type, swap_, items))
            fail_parse(path_,
                       "negative list length in record " + std::to_string(record) + " of element '" + el.name + "'");
        std::uint64_t n = 0;
        if (!checked_mul(items, scalar_size(prop.type), n)) n = UINT64_MAX;
        take(el, record, n);
    }

    const std::string &path_;
    const char *p_;
    const char *end_;
    bool swap_;
};

// ------------------------------------------------------------------------------------------------------
// Ascii bodies
// ------------------------------------------------------------------------------------------------------

class AsciiBody {
public:
    AsciiBody(const std::string &path, std::string_view bytes, const PlyHeader &header)
        : path_(path), tokens_(bytes.data() + header.body_offset, bytes.data() + bytes.size(), header.body_first_line) {
    }

    void skip_element(const PlyElement &el) {
        if (el.properties.empty()) return;
        for (std::uint64_t r = 0; r < el.count; ++r) {
            for (const PlyProperty &prop : el.properties) skip_property(el, r, prop);
        }
    }

    std::vector<double> read_vertices(const PlyElement &el, const XyzSlots &slots) {
        std::vector<double> xyz;
        if (el.count == 0) return xyz;
        // Every value takes at least one character and one separator: refuse counts the data cannot hold
        // before reserving memory for them.
        const std::size_t left = static_cast<std::size_t>(tokens_.end - tokens_.pos);
        std::uint64_t values = 0;
        if (!checked_mul(el.count, el.properties.size(), values) || values > (left + 1) / 2)
            fail_parse(path_, "truncated: the header declares " + std::to_string(el.count) + " vertices but only " +
                                  std::to_string(left) + " bytes of data follow");
        xyz.resize(static_cast<std::size_t>(el.count) * 3);
        std::size_t first_line = 0;
        for (std::uint64_t r = 0; r < el.count; ++r) {
            for (std::size_t i = 0; i < el.properties.size(); ++i) {
                const PlyProperty &prop = el.properties[i];
                const int axis = slots.axis_of(i);
                if (axis < 0) {
                    skip_property(el, r, prop);
                } else {
                    const char *tb = nullptr;
                    const char *te = nullptr;
                    next(el, r, tb, te);
                    if (!parse_double(tb, te, xyz[3 * r + static_cast<std::size_t>(axis)]))
                        fail_parse(path_, "line " + std::to_string(tokens_.line_no) + ": bad vertex value " +
                                              quote_token(tb, te));
                }
                if (i == 0) first_line = tokens_.line_no;
            }
            // One record per line, as the format prescribes. Checking it catches a header that declares more
            // or fewer properties than the lines hold, which would otherwise shift values between axes.
            if (tokens_.line_no != first_line || !rest_of_line_blank())
                fail_parse(path_, "line " + std::to_string(tokens_.line_no) + ": vertex " + std::to_string(r) +
                                      " does not fill exactly one line: the lines hold a different number of"
                                      " values than the header's " +
                                      std::to_string(el.properties.size()) + " vertex properties");
        }
        return xyz;
    }

private:
    void next(const PlyElement &el, std::uint64_t record, const char *&tb, const char *&te) {
        if (tokens_.next(tb, te)) return;
        if (el.name == "vertex")
            fail_parse(path_, "truncated: expected " + std::to_string(el.count) + " vertices, found " +
                                  std::to_string(record));
        fail_parse(path_, "truncated: expected " + std::to_string(el.count) + " records of element '" + el.name +
                              "', found " + std::to_string(record));
    }

    void skip_property(const PlyElement &el, std::uint64_t record, const PlyProperty &prop) {
        const char *tb = nullptr;
        const char *te = nullptr;
        next(el, record, tb, te);
        if (!prop.is_list) return;
        std::uint64_t items = 0;
        if (!parse_u64(tb, te, items))
            fail_parse(path_, "line " + std::to_string(tokens_.line_no) + ": bad list length " + quote_token(tb, te));
        // Each item needs its own token, so a huge length simply runs out of tokens.
        for (std::uint64_t k = 0; k < items; ++k) next(el, record, tb, te);
    }

    bool rest_of_line_blank() {
        const char *p = tokens_.pos;
        while (p < tokens_.end && *p != '\n' && is_space(*p)) ++p;
        return p == tokens_.end || *p == '\n';
    }

    const std::string &path_;
    TokenCursor tokens_;
};

} // namespace

std::vector<double> parse_ply(const std::string &path, std::string_view bytes) {
    const PlyHeader header = parse_header(path, bytes);
    std::size_t vertex = header.elements.size();
    for (std::size_t i = 0; i < header.elements.size(); ++i) {
        if (header.elements[i].name != "vertex") continue;
        if (vertex != header.elements.size()) fail_parse(path, "the PLY header has two 'vertex' elements");
        vertex = i;
    }
    if (vertex == header.elements.size()) fail_parse(path, "the PLY header has no 'vertex' element");
    const XyzSlots slots = find_xyz(path, header.elements[vertex]);

    if (header.encoding == PlyEncoding::Ascii) {
        AsciiBody body(path, bytes, header);
        for (std::size_t i = 0; i < vertex; ++i) body.skip_element(header.elements[i]);
        return body.read_vertices(header.elements[vertex], slots);
    }
    const bool swap = (header.encoding == PlyEncoding::BinaryLittle) != host_is_little_endian();
    BinaryBody body(path, bytes, header.body_offset, swap);
    for (std::size_t i = 0; i < vertex; ++i) body.skip_element(header.elements[i]);
    return body.read_vertices(header.elements[vertex], slots);
}

KISSM_DETAIL_END

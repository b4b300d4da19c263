// SPDX-License-Identifier: MIT
// kissm_read_points(): load the file once, pick the format, hand the bytes to that format's parser.
#include "io/read_points.hpp"

#include "core/failure.hpp"
#include "io/file_bytes.hpp"
#include "io/format_readers.hpp"
#include "io/text_scan.hpp"

#include <cctype>
#include <cstring>
#include <string>
#include <string_view>

KISSM_DETAIL_BEGIN

namespace {

std::string lower_extension(const std::string &path) {
    const std::size_t slash = path.find_last_of("/\\");
    const std::size_t name = slash == std::string::npos ? 0 : slash + 1;
    const std::size_t dot = path.rfind('.');
    if (dot == std::string::npos || dot < name || dot + 1 == path.size()) return "";
    std::string ext = path.substr(dot + 1);
    for (char &c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return ext;
}

bool from_extension(const std::string &ext, FileFormat &format) {
    if (ext == "ply")
        format = FileFormat::Ply;
    else if (ext == "pcd")
        format = FileFormat::Pcd;
    else if (ext == "bin")
        format = FileFormat::KittiBin;
    else if (ext == "npy")
        format = FileFormat::Npy;
    else if (ext == "xyz" || ext == "txt" || ext == "pts" || ext == "asc")
        format = FileFormat::Xyz;
    else if (ext == "las" || ext == "laz") // the LAS reader names LAZ as such
        format = FileFormat::Las;
    else
        return false;
    return true;
}

bool starts_with(std::string_view s, std::string_view prefix) {
    return s.size() >= prefix.size() && s.compare(0, prefix.size(), prefix) == 0;
}

// The headerless formats (raw float32, xyz text) have no signature and are only chosen by extension.
bool from_content(std::string_view bytes, FileFormat &format) {
    if (starts_with(bytes, "ply\n") || starts_with(bytes, "ply\r\n")) {
        format = FileFormat::Ply;
        return true;
    }
    if (starts_with(bytes, "\x93NUMPY")) {
        format = FileFormat::Npy;
        return true;
    }
    if (starts_with(bytes, "LASF")) {
        format = FileFormat::Las;
        return true;
    }
    if (starts_with(bytes, "# .PCD")) {
        format = FileFormat::Pcd;
        return true;
    }
    // PCD files need not start with the "# .PCD" comment: look at the first line that is not a comment.
    LineCursor lines(bytes.data(), bytes.data() + std::min<std::size_t>(bytes.size(), 4096));
    const char *lb = nullptr;
    const char *le = nullptr;
    while (lines.next(lb, le)) {
        const std::string_view line(lb, static_cast<std::size_t>(le - lb));
        if (line.empty() || line[0] == '#') continue;
        if (starts_with(line, "VERSION") || starts_with(line, "FIELDS")) {
            format = FileFormat::Pcd;
            return true;
        }
        break;
    }
    return false;
}

} // namespace

std::vector<double> read_points_file(const std::string &path, FileFormat format, std::uint64_t *withheld) {
    if (withheld) *withheld = 0;
    switch (format) {
    case FileFormat::Auto:
    case FileFormat::Ply:
    case FileFormat::Pcd:
    case FileFormat::KittiBin:
    case FileFormat::Npy:
    case FileFormat::Xyz:
    case FileFormat::BinXyz:
    case FileFormat::Las: break;
    default:
        fail(ErrorKind::UnsupportedFormat,
             path + ": unknown file format code " + std::to_string(static_cast<int>(format)));
    }

    const std::string bytes = read_file_bytes(path);
    if (bytes.empty()) fail_parse(path, "the file is empty");

    if (format == FileFormat::Auto) {
        const std::string ext = lower_extension(path);
        if (!from_extension(ext, format) && !from_content(bytes, format))
            fail(ErrorKind::UnsupportedFormat,
                 path + ": unknown point file format: " +
                     (ext.empty() ? std::string("no extension") : "extension '." + ext + "' is not known") +
                     " and the content is not PLY, PCD, .npy or LAS (pass the format explicitly)");
    }

    switch (format) {
    case FileFormat::Ply: return parse_ply(path, bytes);
    case FileFormat::Pcd: return parse_pcd(path, bytes);
    case FileFormat::KittiBin: return parse_kitti_bin(path, bytes);
    case FileFormat::Npy: return parse_npy(path, bytes);
    case FileFormat::Xyz: return parse_xyz_text(path, bytes);
    case FileFormat::BinXyz: return parse_bin_xyz(path, bytes);
    case FileFormat::Las: return parse_las(path, bytes, withheld);
    case FileFormat::Auto: break;
    }
    fail(ErrorKind::Internal, path + ": format detection left no format");
}

KISSM_DETAIL_END

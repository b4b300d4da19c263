// SPDX-License-Identifier: MIT
#include "io/file_bytes.hpp"

#include "core/failure.hpp"

#include <cerrno>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <system_error>

KISSM_DETAIL_BEGIN

namespace {

[[noreturn]] void fail_io(const std::string &path, const char *action, const std::string &reason) {
    fail(ErrorKind::Io, path + ": cannot " + action + ": " + reason);
}

// std::generic_category().message() is the thread-safe spelling of strerror().
std::string errno_text(int err) { return std::generic_category().message(err != 0 ? err : EIO); }

struct FileCloser {
    void operator()(std::FILE *f) const { std::fclose(f); }
};

} // namespace

void fail_parse(const std::string &path, const std::string &what) { fail(ErrorKind::Parse, path + ": " + what); }

std::string read_file_bytes(const std::string &path) {
    namespace fs = std::filesystem;
    // fopen() succeeds on a directory on Linux and the failure only shows up as EISDIR on the first read;
    // checking up front gives the same clear message everywhere.
    std::error_code ec;
    const fs::file_status status = fs::status(path, ec);
    if (ec) fail_io(path, "open", ec.message());
    if (fs::is_directory(status)) fail_io(path, "open", errno_text(EISDIR));

    errno = 0;
    std::unique_ptr<std::FILE, FileCloser> file(std::fopen(path.c_str(), "rb"));
    if (!file) fail_io(path, "open", errno_text(errno));

    std::string bytes;
    // The size is only a hint (the file may change under us, or be a pipe): read until EOF regardless.
    std::uintmax_t hint = fs::is_regular_file(status) ? fs::file_size(path, ec) : 0;
    if (ec || hint > bytes.max_size()) hint = 0;
    if (hint > 0) {
        bytes.resize(static_cast<std::size_t>(hint));
        const std::size_t got = std::fread(&bytes[0], 1, bytes.size(), file.get());
        if (got < bytes.size()) {
            if (std::ferror(file.get())) fail_io(path, "read", errno_text(errno));
            bytes.resize(got);
            return bytes;
        }
    }
    char chunk[1 << 16];
    for (;;) {
        const std::size_t got = std::fread(chunk, 1, sizeof chunk, file.get());
        bytes.append(chunk, got);
        if (got < sizeof chunk) {
            if (std::ferror(file.get())) fail_io(path, "read", errno_text(errno));
            break;
        }
    }
    return bytes;
}

KISSM_DETAIL_END

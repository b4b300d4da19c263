// SPDX-License-Identifier: MIT
// Part of the abi_static_clash test: C++ code of a host program that links libkissm.a and happens to have
// its own kissm::detail namespace, with the names, signatures and class names kissm's internals use.
//
// kissm's internals live in the inline namespace kissm::v<major>_<minor>::detail (src/core), so their
// mangled names (_ZN5kissm4v0_16detail...) differ from these (_ZN5kissm6detail...). Before that namespace
// existed, this file broke the host in both ways a C++ name clash can:
//  - RunContext::cancelled() and voxelize() below are strong definitions of symbols libkissm.a also
//    defined strongly: "multiple definition" at link time;
//  - fail() below is a strong definition of a symbol libkissm.a defined weakly (an inline function): the
//    linker silently took the host's, so kissm's internal errors went through the host's code (here they
//    came back with the host's "host: " message; a host fail() that logs, aborts or throws another type
//    would do that inside kissm). main() checks the status codes and messages of kissm's own failures.
// Both were verified against libkissm.a of the commit before the versioned namespace (aa9dc24^): the
// link fails on RunContext::cancelled(), and without the strong clashes the test fails on the message.
// Two copies of the *same* kissm version (same v<major>_<minor>) still clash, as they must.
#include <stdexcept>
#include <string>

namespace kissm {
namespace detail {

enum class ErrorKind {
    InvalidArgument,
    NullArgument,
    EmptyInput,
    TooFewPoints,
    NonFinite,
    VoxelRange,
    StructSize,
    Cancelled,
    FeaturesMismatch,
    Io,
    Parse,
    UnsupportedFormat,
    Internal
};

class Failure : public std::runtime_error {
public:
    Failure(ErrorKind kind, const std::string &message) : std::runtime_error("host: " + message), kind_(kind) {}
    ErrorKind kind() const noexcept { return kind_; }

private:
    ErrorKind kind_;
};

// Same mangled name as kissm's internal (inline) fail() had without the versioned namespace.
[[noreturn]] void fail(ErrorKind kind, const std::string &message);
void fail(ErrorKind kind, const std::string &message) { throw Failure(kind, message); }

struct InputCloud {
    int points = 0;
};

class RunContext {
public:
    bool cancelled() const;
    int calls = 0;
};
bool RunContext::cancelled() const { return calls > 1; }

struct VoxelGrid {
    int voxels = 0;
};

// Same parameter types, by name, as kissm's internal voxelize(): the same mangled name without v0_1.
VoxelGrid voxelize(const InputCloud &cloud, double voxel_size, const std::string &what, RunContext &ctx);
VoxelGrid voxelize(const InputCloud &cloud, double voxel_size, const std::string &what, RunContext &ctx) {
    ++ctx.calls;
    if (voxel_size <= 0.0) fail(ErrorKind::VoxelRange, what + ": voxel size must be > 0");
    VoxelGrid g;
    g.voxels = cloud.points / 2;
    return g;
}

} // namespace detail
} // namespace kissm

// 0 when the host's own kissm::detail works as the host wrote it.
extern "C" int host_cpp_self_test(void) {
    using namespace kissm::detail;
    RunContext ctx;
    InputCloud cloud;
    cloud.points = 10;
    if (voxelize(cloud, 1.0, "host cloud", ctx).voxels != 5) return 1;
    try {
        voxelize(cloud, 0.0, "host cloud", ctx);
        return 2;
    } catch (const Failure &e) {
        if (e.kind() != ErrorKind::VoxelRange) return 3;
        if (std::string(e.what()).rfind("host: host cloud", 0) != 0) return 4;
    }
    if (!ctx.cancelled()) return 5;
    return 0;
}

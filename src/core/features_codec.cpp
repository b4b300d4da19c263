// SPDX-License-Identifier: MIT
// The features byte format, version 1 (docs/features-format.md has the layout). Every multi-byte value is
// written and read byte by byte in little-endian order, so the bytes are the same on every host and no
// unaligned load is ever made. The decoder trusts nothing: each read is bounds-checked, each count is checked
// against the bytes that remain before anything is allocated for it, and each value is checked against what
// the pipeline can produce, because a loaded cloud goes straight into matching and refinement.
#include "features_codec.hpp"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>

#include "failure.hpp"
#include "little_endian.hpp"
#include "setting_codes.hpp"
#include "setting_limits.hpp"

KISSM_DETAIL_BEGIN

namespace {

constexpr std::uint8_t kMagic[8] = {'K', 'I', 'S', 'S', 'M', 'F', 'T', 0};
// Magic, version, reserved, total size; the settings (6 + 3 + 3 doubles, an int32, 4 bytes of enums); the
// voxel and keypoint counts.
constexpr std::size_t kSettingsBytes = 12 * 8 + 4 + 4;
constexpr std::size_t kHeaderBytes = 8 + 4 + 4 + 8 + kSettingsBytes + 8 + 8;
constexpr std::size_t kOriginBytes = 3 * 8;
constexpr std::size_t kCountsBytes = 3 * 8;
constexpr std::size_t kChecksumBytes = 8;
constexpr std::size_t kPointBytes = 3 * 4;
constexpr std::size_t kDescriptorBytes = kDescriptorDim * 4;
// Nothing shorter can be features: one voxel, no valid normal, no keypoint.
constexpr std::size_t kMinBytes = kHeaderBytes + kOriginBytes + kPointBytes + 2 + kCountsBytes + kChecksumBytes;

// Limits the pipeline guarantees (see decode_features): a cloud needs 4 finite points; voxelize refuses more
// than 2^21 voxels per axis and recentres on the bounding-box centre, so a local coordinate is within
// 2^20 voxels of 0 (2^21 leaves room for the voxel's own width); each FPFH block of 11 bins is rescaled to
// sum to 100 (or is all 0), so no bin exceeds 100 but by rounding.
constexpr std::uint64_t kMinFinitePoints = 4;
constexpr double kMaxVoxelsFromOrigin = 2097152.0;
constexpr float kMaxDescriptorValue = 101.0f;

// ---- enums as the format's bytes (the same numbers as kissm.h's constants) ------------------------------

// setting_codes.hpp: one byte each.
template <class E>
std::uint8_t code_of(E v) {
    return static_cast<std::uint8_t>(setting_code(v));
}

// ---- writing ----------------------------------------------------------------------------------------------

class Writer {
public:
    explicit Writer(std::uint8_t *out) : p_(out) {}
    std::uint8_t *position() const { return p_; }
    void bytes(const std::uint8_t *b, std::size_t n) {
        std::memcpy(p_, b, n);
        p_ += n;
    }
    void u8(std::uint8_t v) { *p_++ = v; }
    void u32(std::uint32_t v) { store(v); }
    void u64(std::uint64_t v) { store(v); }
    void i32(std::int32_t v) { u32(static_cast<std::uint32_t>(v)); }
    void f32(float v) {
        store_le_f32(v, p_);
        p_ += 4;
    }
    void f64(double v) {
        store_le_f64(v, p_);
        p_ += 8;
    }
    void vec3(const Vec3f &v) { f32(v.x()), f32(v.y()), f32(v.z()); }

private:
    template <class U>
    void store(U v) {
        store_le(v, p_);
        p_ += sizeof(U);
    }
    std::uint8_t *p_;
};

std::size_t count_valid(const Normals &n) {
    std::size_t c = 0;
    for (const std::uint8_t v : n.valid) c += v != 0;
    return c;
}

// Flags for every voxel, then the vectors of the valid ones only: invalid normals are zero by construction
// (normals.cpp), so they carry nothing.
void write_normals(Writer &w, const Normals &n) {
    for (const std::uint8_t v : n.valid) w.u8(v != 0 ? 1 : 0);
    for (std::size_t i = 0; i < n.valid.size(); ++i)
        if (n.valid[i]) w.vec3(n.normal[i]);
}

// ---- reading ----------------------------------------------------------------------------------------------

[[noreturn]] void malformed(const std::string &what, std::size_t offset) {
    fail(ErrorKind::Parse, "features bytes: " + what + " (byte offset " + std::to_string(offset) + ")");
}

std::string text(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return buf;
}

class Reader {
public:
    Reader(const std::uint8_t *data, std::size_t size) : data_(data), size_(size) {}
    std::size_t offset() const { return pos_; }
    std::size_t left() const { return size_ - pos_; }

    // The next n bytes, which must exist.
    const std::uint8_t *take(std::size_t n, const char *what) {
        if (n > left())
            malformed(std::string("truncated: ") + what + " needs " + std::to_string(n) + " bytes, " +
                          std::to_string(left()) + " left",
                      pos_);
        const std::uint8_t *p = data_ + pos_;
        pos_ += n;
        return p;
    }
    std::uint8_t u8(const char *what) { return *take(1, what); }
    std::uint32_t u32(const char *what) { return load_le<std::uint32_t>(take(4, what)); }
    std::uint64_t u64(const char *what) { return load_le<std::uint64_t>(take(8, what)); }
    double f64(const char *what) { return load_le_f64(take(8, what)); }
    std::int32_t i32(const char *what) { return load_le_i32(take(4, what)); }

    // A count of elements of `element_bytes` each that follow: refused, before anything is allocated for it,
    // when the remaining bytes cannot hold them (a lying count never becomes a huge allocation).
    std::size_t count_that_fits(std::uint64_t count, std::size_t element_bytes, const char *what,
                                std::size_t count_offset) const {
        if (count > left() / element_bytes)
            malformed(std::string(what) + " is " + std::to_string(count) + ", more than the " + std::to_string(left()) +
                          " bytes left can hold",
                      count_offset);
        return static_cast<std::size_t>(count);
    }

private:
    const std::uint8_t *data_;
    std::size_t size_;
    std::size_t pos_ = 0;
};

double finite_in(Reader &r, const char *field, const RealLimits &range) {
    const std::size_t at = r.offset();
    const double v = r.f64(field);
    if (!range.contains(v))
        malformed(std::string(field) + " is " + text(v) + "; it must be in " + (range.lo_open ? "(" : "[") +
                      text(range.lo) + ", " + text(range.hi) + "]",
                  at);
    return v;
}

// The setting E stored as one byte, which must be one of its codes (setting_codes.hpp).
template <class E>
E setting_in(Reader &r, const char *field) {
    const std::size_t at = r.offset();
    const std::int32_t v = r.u8(field);
    constexpr std::int32_t max = max_setting_code<E>();
    if (v > max)
        malformed(std::string(field) + " is " + std::to_string(v) + "; it must be in [0, " + std::to_string(max) + "]",
                  at);
    return setting_of<E>(v);
}

void read_settings(Reader &r, Params &p) {
    p.voxel_size = finite_in(r, "voxel_size", limits::voxel_size);
    // Read before the normal radius, whose upper bound it is (as in kissm_config_validate).
    p.fpfh_radius_gain = finite_in(r, "fpfh_radius_gain", limits::fpfh_radius_gain);
    p.normal_radius_gain = finite_in(r, "normal_radius_gain", limits::normal_radius_gain_below(p.fpfh_radius_gain));
    p.max_linearity = finite_in(r, "max_linearity", limits::max_linearity);
    p.refine_normal_radius_gain = finite_in(r, "refine_normal_radius_gain", limits::refine_normal_radius_gain);
    p.sensor_height = finite_in(r, "sensor_height", limits::sensor_height);
    const char *viewpoint[3] = {"viewpoint[0]", "viewpoint[1]", "viewpoint[2]"};
    for (int i = 0; i < 3; ++i)
        p.viewpoint[static_cast<std::size_t>(i)] = finite_in(r, viewpoint[i], RealLimits{-HUGE_VAL, HUGE_VAL, false});
    const std::size_t up_at = r.offset();
    const char *up[3] = {"up[0]", "up[1]", "up[2]"};
    for (int i = 0; i < 3; ++i) p.up[static_cast<std::size_t>(i)] = finite_in(r, up[i], RealLimits{-1.0, 1.0, false});
    // The boundary normalises `up`: a stored one is a unit vector up to rounding.
    const double len = std::sqrt(p.up[0] * p.up[0] + p.up[1] * p.up[1] + p.up[2] * p.up[2]);
    if (!(std::fabs(len - 1.0) <= 1e-9)) malformed("up has length " + text(len) + "; it must be a unit vector", up_at);
    const std::size_t tau_at = r.offset();
    const std::int32_t tau = r.i32("min_normal_neighbors");
    if (!limits::min_normal_neighbors.contains(tau))
        malformed("min_normal_neighbors is " + std::to_string(tau) + "; it must be in [" +
                      std::to_string(limits::min_normal_neighbors.lo) + ", " +
                      std::to_string(limits::min_normal_neighbors.hi) + "]",
                  tau_at);
    p.min_normal_neighbors = tau;
    p.nonfinite = setting_in<NonFinitePolicy>(r, "nonfinite_policy");
    p.viewpoint_mode = setting_in<ViewpointMode>(r, "viewpoint_mode");
    p.refine_mode = setting_in<RefineMode>(r, "refine_mode");
    p.suppression = setting_in<Suppression>(r, "suppression");
}

void read_normals(Reader &r, std::size_t num_voxels, const char *flags_name, const char *vectors_name, Normals &n) {
    const std::size_t flags_at = r.offset();
    const std::uint8_t *flags = r.take(num_voxels, flags_name);
    std::size_t valid = 0;
    for (std::size_t i = 0; i < num_voxels; ++i) {
        if (flags[i] > 1)
            malformed(std::string(flags_name) + " of voxel " + std::to_string(i) + " is " + std::to_string(flags[i]) +
                          "; it must be 0 or 1",
                      flags_at + i);
        valid += flags[i];
    }
    const std::size_t at = r.offset();
    const std::uint8_t *p = r.take(valid * kPointBytes, vectors_name);
    n.valid.assign(flags, flags + num_voxels);
    n.normal.assign(num_voxels, Vec3f::Zero());
    for (std::size_t i = 0, k = 0; i < num_voxels; ++i) {
        if (!flags[i]) continue;
        const std::uint8_t *q = p + k * kPointBytes;
        const Vec3f v(load_le_f32(q), load_le_f32(q + 4), load_le_f32(q + 8));
        // Unit vectors from the eigen solver, rounded to float: anything else is not a normal the pipeline made.
        if (!(v.allFinite() && std::fabs(v.squaredNorm() - 1.0f) <= 1e-3f))
            malformed(std::string(vectors_name) + " of voxel " + std::to_string(i) + " is not a finite unit vector",
                      at + k * kPointBytes);
        n.normal[i] = v;
        ++k;
    }
}

} // namespace

std::uint64_t features_checksum(const std::uint8_t *data, std::size_t size) {
    // FNV-1a's step over 64-bit little-endian words, then over the last size % 8 bytes one by one. Each step is
    // a bijection of the state for a given word (or byte), so any change of one word (every single-bit flip in
    // particular) changes the result. By words, not bytes: a step is a multiply that waits for the one
    // before (docs/design/performance.md, "Features checksum").
    constexpr std::uint64_t kPrime = 1099511628211ull;
    std::uint64_t h = 14695981039346656037ull;
    std::size_t i = 0;
    for (; i + 8 <= size; i += 8) h = (h ^ load_le<std::uint64_t>(data + i)) * kPrime;
    for (; i < size; ++i) h = (h ^ data[i]) * kPrime;
    return h;
}

std::size_t encoded_features_size(const CloudFeatures &f) {
    const std::size_t v = f.voxels.points.size(), k = f.descriptors.keypoint.size();
    return kHeaderBytes + kOriginBytes + v * kPointBytes + 2 * v +
           (count_valid(f.normals) + count_valid(f.plane_normals)) * kPointBytes + k * (4 + kDescriptorBytes) +
           kCountsBytes + kChecksumBytes;
}

void encode_features_to(const CloudFeatures &f, std::uint8_t *out) {
    const Params &p = f.params;
    const std::size_t total = encoded_features_size(f);
    Writer w(out);
    w.bytes(kMagic, sizeof kMagic);
    w.u32(kFeaturesFormatVersion);
    w.u32(0); // reserved
    w.u64(total);
    w.f64(p.voxel_size);
    w.f64(p.fpfh_radius_gain);
    w.f64(p.normal_radius_gain);
    w.f64(p.max_linearity);
    w.f64(p.refine_normal_radius_gain);
    w.f64(p.sensor_height);
    for (const double v : p.viewpoint) w.f64(v);
    for (const double v : p.up) w.f64(v);
    w.i32(p.min_normal_neighbors);
    w.u8(code_of(p.nonfinite));
    w.u8(code_of(p.viewpoint_mode));
    w.u8(code_of(p.refine_mode));
    w.u8(code_of(p.suppression));
    w.u64(f.voxels.points.size());
    w.u64(f.descriptors.keypoint.size());

    for (int i = 0; i < 3; ++i) w.f64(f.voxels.origin[i]);
    for (const Vec3f &q : f.voxels.points) w.vec3(q);
    write_normals(w, f.normals);
    if (f.has_planes) {
        write_normals(w, f.plane_normals);
    } else {
        for (std::size_t i = 0; i < f.voxels.points.size(); ++i) w.u8(0); // described without the planes
    }
    for (const std::uint32_t k : f.descriptors.keypoint) w.u32(k);
    for (const float v : f.descriptors.values) w.f32(v);
    w.u64(f.num_points);
    w.u64(f.num_nonfinite);
    w.u64(f.num_suppressed);
    w.u64(features_checksum(out, total - kChecksumBytes));
}

std::vector<std::uint8_t> encode_features(const CloudFeatures &f) {
    std::vector<std::uint8_t> out(encoded_features_size(f));
    encode_features_to(f, out.data());
    return out;
}

CloudFeatures decode_features(const std::uint8_t *data, std::size_t size, RunContext &ctx) {
    // Magic and version first (another file, or a version whose checksum may differ, is named as such); then
    // the checksum over everything, so corruption anywhere is reported as corruption before any field is
    // interpreted; then the fields, each checked as if the checksum had been forged.
    if (size >= sizeof kMagic && std::memcmp(data, kMagic, sizeof kMagic) != 0)
        malformed("not kissm features (wrong magic)", 0);
    if (size >= 12 && load_le<std::uint32_t>(data + 8) != kFeaturesFormatVersion)
        malformed("format version " + std::to_string(load_le<std::uint32_t>(data + 8)) +
                      " is not known (this kissm reads " + std::to_string(kFeaturesFormatVersion) + ")",
                  8);
    if (size < kMinBytes)
        malformed("truncated: " + std::to_string(size) + " bytes given, features take at least " +
                      std::to_string(kMinBytes),
                  size);
    const std::uint64_t declared = load_le<std::uint64_t>(data + 16);
    const std::uint64_t stored = load_le<std::uint64_t>(data + size - kChecksumBytes);
    const std::uint64_t computed = features_checksum(data, size - kChecksumBytes);
    if (stored != computed)
        malformed("checksum mismatch: the bytes are corrupted or truncated (" + std::to_string(size) +
                      " bytes given, the header declares " + std::to_string(declared) + ")",
                  size - kChecksumBytes);
    if (declared != size)
        malformed("the header declares " + std::to_string(declared) + " bytes but " + std::to_string(size) +
                      " are given",
                  16);

    Reader r(data, size - kChecksumBytes);
    r.take(12, "magic and version");
    if (r.u32("reserved") != 0) malformed("the reserved field is not 0", 12);
    r.u64("size");
    CloudFeatures f;
    read_settings(r, f.params);
    const std::size_t voxels_at = r.offset();
    const std::uint64_t num_voxels64 = r.u64("num_voxels");
    const std::size_t keypoints_at = r.offset();
    const std::uint64_t num_keypoints64 = r.u64("num_keypoints");
    // Keypoints are 32-bit voxel numbers; a cloud has at least one voxel.
    if (num_voxels64 == 0 || num_voxels64 > 0xFFFFFFFFull)
        malformed("num_voxels is " + std::to_string(num_voxels64) + "; it must be in [1, 2^32 - 1]", voxels_at);
    if (num_keypoints64 > num_voxels64)
        malformed("num_keypoints " + std::to_string(num_keypoints64) + " exceeds num_voxels " +
                      std::to_string(num_voxels64),
                  keypoints_at);
    // Each voxel takes a point and two flags; each keypoint an index and a descriptor.
    const std::size_t num_voxels = r.count_that_fits(num_voxels64, kPointBytes + 2, "num_voxels", voxels_at);
    const std::size_t num_keypoints =
        r.count_that_fits(num_keypoints64, 4 + kDescriptorBytes, "num_keypoints", keypoints_at);

    const std::size_t origin_at = r.offset();
    const std::uint8_t *o = r.take(kOriginBytes, "origin");
    for (int i = 0; i < 3; ++i) {
        f.voxels.origin[i] = load_le_f64(o + 8 * i);
        if (!std::isfinite(f.voxels.origin[i])) malformed("origin[" + std::to_string(i) + "] is not finite", origin_at);
    }

    const std::size_t points_at = r.offset();
    const std::uint8_t *pts = r.take(num_voxels * kPointBytes, "voxel points");
    const float reach = static_cast<float>(kMaxVoxelsFromOrigin * f.params.voxel_size);
    f.voxels.points.resize(num_voxels);
    for (std::size_t i = 0; i < num_voxels; ++i) {
        const std::uint8_t *q = pts + i * kPointBytes;
        const Vec3f v(load_le_f32(q), load_le_f32(q + 4), load_le_f32(q + 8));
        if (!(v.allFinite() && v.cwiseAbs().maxCoeff() <= reach))
            malformed("voxel point " + std::to_string(i) + " is not finite or lies beyond 2^21 voxels of the origin",
                      points_at + i * kPointBytes);
        f.voxels.points[i] = v;
    }
    read_normals(r, num_voxels, "normal flag", "normal", f.normals);
    const std::size_t planes_at = r.offset();
    read_normals(r, num_voxels, "plane normal flag", "plane normal", f.plane_normals);
    // Features described without refinement carry no planes (refinement fits them on its call): their flags are 0.
    f.has_planes = f.params.refine_mode != RefineMode::None;
    if (!f.has_planes) {
        if (count_valid(f.plane_normals) != 0)
            malformed("plane normals are stored, but refine_mode is none (features described without them)", planes_at);
        f.plane_normals = Normals();
    }

    // Keypoints as select_keypoints() makes them: voxels with a valid normal, in increasing order.
    const std::size_t keys_at = r.offset();
    const std::uint8_t *keys = r.take(num_keypoints * 4, "keypoints");
    f.descriptors.keypoint.resize(num_keypoints);
    for (std::size_t i = 0; i < num_keypoints; ++i) {
        const std::uint32_t k = load_le<std::uint32_t>(keys + 4 * i);
        if (k >= num_voxels)
            malformed("keypoint " + std::to_string(i) + " is voxel " + std::to_string(k) + ", out of range (" +
                          std::to_string(num_voxels) + " voxels)",
                      keys_at + 4 * i);
        if (i > 0 && k <= f.descriptors.keypoint[i - 1])
            malformed("keypoint " + std::to_string(i) + " (voxel " + std::to_string(k) +
                          ") is not above the previous one",
                      keys_at + 4 * i);
        if (!f.normals.valid[k])
            malformed("keypoint " + std::to_string(i) + " (voxel " + std::to_string(k) + ") has no valid normal",
                      keys_at + 4 * i);
        f.descriptors.keypoint[i] = k;
    }
    const std::size_t values_at = r.offset();
    const std::uint8_t *vals = r.take(num_keypoints * kDescriptorBytes, "descriptors");
    f.descriptors.values.resize(num_keypoints * kDescriptorDim);
    for (std::size_t i = 0; i < f.descriptors.values.size(); ++i) {
        const float v = load_le_f32(vals + 4 * i);
        if (!(v >= 0.0f && v <= kMaxDescriptorValue))
            malformed("descriptor value " + std::to_string(i % kDescriptorDim) + " of keypoint " +
                          std::to_string(i / kDescriptorDim) + " is not in [0, 101]",
                      values_at + 4 * i);
        f.descriptors.values[i] = v;
    }

    const std::size_t counts_at = r.offset();
    f.num_points = r.u64("num_points");
    f.num_nonfinite = r.u64("num_nonfinite");
    f.num_suppressed = r.u64("num_suppressed");
    if (f.num_nonfinite > f.num_points || f.num_points - f.num_nonfinite < kMinFinitePoints ||
        f.num_points - f.num_nonfinite < num_voxels)
        malformed("num_points " + std::to_string(f.num_points) + " and num_nonfinite " +
                      std::to_string(f.num_nonfinite) + " leave fewer finite points than 4 or than the " +
                      std::to_string(num_voxels) + " voxels",
                  counts_at);
    if (f.params.nonfinite == NonFinitePolicy::Reject && f.num_nonfinite != 0)
        malformed("num_nonfinite is " + std::to_string(f.num_nonfinite) + " under the reject policy", counts_at + 8);
    if (f.num_suppressed > num_voxels || (f.params.suppression == Suppression::None && f.num_suppressed != 0))
        malformed("num_suppressed " + std::to_string(f.num_suppressed) + " is impossible for " +
                      std::to_string(num_voxels) + " voxels under this suppression",
                  counts_at + 16);
    if (r.left() != 0) malformed(std::to_string(r.left()) + " unexpected bytes before the checksum", r.offset());

    // The indexes, exactly as describe_cloud() builds them: a function of the descriptors and points alone.
    f.descriptor_index = std::move(DescriptorIndex::build({&f.descriptors}, ctx)[0]);
    f.keypoint_grid = keypoint_grid_of(f);
    if (f.params.refine_mode != RefineMode::None) f.index = RefineIndex(f.voxels.points, f.params.voxel_size);
    return f;
}

KISSM_DETAIL_END

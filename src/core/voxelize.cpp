#include "voxelize.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <vector>

#include "failure.hpp"
#include "radix_sort.hpp"

namespace kissm {
// Versioned so that two kissm versions linked statically into one program never share a symbol.
inline namespace v0_1 {
namespace detail {

namespace {

std::uint64_t cells_for(double extent, double voxel_size) {
    const double n = std::floor(extent / voxel_size) + 1.0;
    return n >= static_cast<double>(kMaxVoxelsPerAxis) + 1.0 ? kMaxVoxelsPerAxis + 1 : static_cast<std::uint64_t>(n);
}

// A point's offset inside its voxel, in units of 2^-30 voxels. Centroids come from integer sums of these:
// integer addition does not depend on order, so a permuted input (or another split into chunks) gives a
// bitwise identical cloud without sorting points. 2^30 per point times < 2^32 points fits in 64 bits.
constexpr double kFixedScale = 1073741824.0; // 2^30

// Open-addressing map from voxel key to its point count and offset sums. One pass over the points and no
// per-point sort: clouds have many points per voxel (e.g. 14 on average in a 70K-point scan at 0.3 m).
class VoxelTable {
public:
    struct Entry {
        std::uint64_t key = kEmpty;
        std::uint64_t sum[3] = {0, 0, 0};
        std::uint64_t count = 0;
    };

    void reserve(std::size_t voxels) {
        std::size_t cap = 16;
        while (cap < 2 * voxels) cap *= 2;
        if (cap > slots_.size()) rehash(cap);
    }

    void add(std::uint64_t key, const std::int64_t q[3]) {
        grow_for_one_more();
        Entry &e = find(key);
        if (e.key == kEmpty) e.key = key, ++used_;
        for (int a = 0; a < 3; ++a) e.sum[a] += static_cast<std::uint64_t>(q[a]);
        ++e.count;
    }

    void merge(const VoxelTable &other) {
        for (const Entry &o : other.slots_) {
            if (o.key == kEmpty) continue;
            grow_for_one_more();
            Entry &e = find(o.key);
            if (e.key == kEmpty) e.key = o.key, ++used_;
            for (int a = 0; a < 3; ++a) e.sum[a] += o.sum[a];
            e.count += o.count;
        }
    }

    // (key, slot) of every occupied slot.
    void collect(std::vector<KeyIndex> &out) const {
        out.clear();
        out.reserve(used_);
        for (std::size_t i = 0; i < slots_.size(); ++i)
            if (slots_[i].key != kEmpty) out.push_back({slots_[i].key, static_cast<std::uint32_t>(i)});
    }

    const Entry &entry(std::size_t slot) const { return slots_[slot]; }

    void release() {
        std::vector<Entry>().swap(slots_);
        used_ = 0;
    }

private:
    static constexpr std::uint64_t kEmpty = ~std::uint64_t(0); // keys use at most 63 bits

    // Load factor at most 1/2: probe runs stay short.
    void grow_for_one_more() {
        if (2 * (used_ + 1) > slots_.size()) rehash(slots_.empty() ? 1024 : 2 * slots_.size());
    }

    Entry &find(std::uint64_t key) {
        const std::size_t mask = slots_.size() - 1;
        std::size_t i = static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> 32) & mask;
        while (slots_[i].key != kEmpty && slots_[i].key != key) i = (i + 1) & mask;
        return slots_[i];
    }

    void rehash(std::size_t capacity) {
        std::vector<Entry> old(capacity);
        old.swap(slots_);
        for (const Entry &o : old)
            if (o.key != kEmpty) find(o.key) = o;
    }

    std::vector<Entry> slots_;
    std::size_t used_ = 0;
};

} // namespace

VoxelCloud voxelize(const InputCloud &input, double voxel_size, const std::string &name, RunContext &ctx) {
    VoxelCloud out;
    const std::size_t n = input.points.size();
    if (n == 0) return out;
    out.origin = 0.5 * (input.min + input.max);

    const Vec3d extent = input.max - input.min;
    std::uint64_t cells[3];
    for (int a = 0; a < 3; ++a) {
        cells[a] = cells_for(extent[a], voxel_size);
        if (cells[a] > kMaxVoxelsPerAxis) {
            std::ostringstream msg;
            msg.precision(6);
            msg << "voxel_size " << voxel_size << " is too small for the " << name << "'s extent of " << extent[a]
                << " along " << "xyz"[a] << " (at most " << kMaxVoxelsPerAxis
                << " voxels per axis; use a voxel size of at least "
                << extent[a] / static_cast<double>(kMaxVoxelsPerAxis - 1) << ")";
            fail(ErrorKind::VoxelRange, msg.str());
        }
    }

    const auto &pts = input.points;
    const double inv = 1.0 / voxel_size;
    // Fixed-chunk partial sums (a function of the input, not of the thread count), merged in chunk order.
    constexpr std::size_t kChunk = 65536;
    const std::size_t num_chunks = (n + kChunk - 1) / kChunk;
    std::vector<VoxelTable> partial(num_chunks);
    ctx.parallel_for(n, kChunk, [&](std::size_t b, std::size_t e) {
        VoxelTable &table = partial[b / kChunk];
        table.reserve(std::min<std::size_t>(e - b, 4096));
        for (std::size_t i = b; i < e; ++i) {
            const Vec3d rel = (pts[i] - input.min) * inv;
            std::uint64_t c[3];
            std::int64_t q[3];
            for (int a = 0; a < 3; ++a) {
                // rel >= 0 and below 2^22 (the extent check above), so truncation is floor; the clamp guards
                // the top face against rounding.
                const std::uint64_t ci = static_cast<std::uint64_t>(static_cast<std::int64_t>(rel[a]));
                c[a] = ci < cells[a] ? ci : cells[a] - 1;
                const double f = std::min(1.0, rel[a] - static_cast<double>(c[a]));
                q[a] = static_cast<std::int64_t>(f * kFixedScale + 0.5);
            }
            table.add((c[0] * cells[1] + c[1]) * cells[2] + c[2], q);
        }
    });
    VoxelTable &all = partial[0];
    for (std::size_t k = 1; k < num_chunks; ++k) {
        all.merge(partial[k]);
        partial[k].release();
    }

    // Output in key order: the table's slot order depends on its growth history, the key order does not.
    std::vector<KeyIndex> order;
    all.collect(order);
    radix_sort_by_key(order);
    out.points.resize(order.size());
    const Vec3d corner = input.min - out.origin;
    ctx.parallel_for(order.size(), 4096, [&](std::size_t b, std::size_t e) {
        for (std::size_t v = b; v < e; ++v) {
            const VoxelTable::Entry &s = all.entry(order[v].index);
            const std::uint64_t key = order[v].key;
            const std::uint64_t c[3] = {key / (cells[1] * cells[2]), (key / cells[2]) % cells[1], key % cells[2]};
            const double count = static_cast<double>(s.count);
            Vec3d centroid;
            for (int a = 0; a < 3; ++a)
                centroid[a] = corner[a] + (static_cast<double>(c[a]) + static_cast<double>(s.sum[a]) / kFixedScale / count) * voxel_size;
            out.points[v] = centroid.cast<float>();
        }
    });
    return out;
}

} // namespace detail
} // namespace v0_1
} // namespace kissm

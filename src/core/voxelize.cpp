// SPDX-License-Identifier: MIT
#include "voxelize.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <vector>

#include "failure.hpp"
#include "radix_sort.hpp"

KISSM_DETAIL_BEGIN

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
// per-point sort: clouds have many points per voxel (e.g. 14 on average in a 70K-point scan at 0.3 m). The slots
// hold a key and where its entry is; the entries lie packed in the order they came: the slots probed are 16
// bytes rather than 40, fewer to clear, and the entries are the table's contents with nothing to compact.
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
        entries_.reserve(voxels);
    }

    void add(const Entry &o) {
        grow_for_one_more();
        Slot &slot = find(o.key);
        if (slot.key == kEmpty) {
            slot = Slot{o.key, static_cast<std::uint32_t>(entries_.size())};
            entries_.push_back(o);
            return;
        }
        Entry &e = entries_[slot.entry];
        for (int a = 0; a < 3; ++a) e.sum[a] += o.sum[a];
        e.count += o.count;
    }

    std::size_t size() const { return entries_.size(); }

    // The entries, one per key, in the order their keys first came; the table is left empty.
    std::vector<Entry> take_entries() {
        std::vector<Slot>().swap(slots_);
        return std::move(entries_);
    }

private:
    static constexpr std::uint64_t kEmpty = ~std::uint64_t(0); // keys use at most 63 bits

    struct Slot {
        std::uint64_t key = kEmpty;
        std::uint32_t entry = 0;
    };

    // Load factor at most 1/2: probe runs stay short.
    void grow_for_one_more() {
        if (2 * (entries_.size() + 1) > slots_.size()) rehash(slots_.empty() ? 1024 : 2 * slots_.size());
    }

    Slot &find(std::uint64_t key) {
        const std::size_t mask = slots_.size() - 1;
        std::size_t i = static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> 32) & mask;
        while (slots_[i].key != kEmpty && slots_[i].key != key) i = (i + 1) & mask;
        return slots_[i];
    }

    void rehash(std::size_t capacity) {
        std::vector<Slot> old(capacity);
        old.swap(slots_);
        for (const Slot &o : old)
            if (o.key != kEmpty) find(o.key) = o;
    }

    std::vector<Slot> slots_;
    std::vector<Entry> entries_;
};

// Entries (a voxel may come several times, from several chunks) as one entry per voxel in key order: sorted by
// key (minus `base`: fewer radix passes), equal keys summed. Integer sums, so the order they are added in does not
// matter. Sorting the few entries of the chunks replaced adding them into a hash table and sorting its slots
// (docs/design/performance.md, "Voxel merge").
std::vector<VoxelTable::Entry> merged_in_key_order(const std::vector<VoxelTable::Entry> &entries, std::uint64_t base) {
    std::vector<KeyIndex> order(entries.size());
    for (std::size_t i = 0; i < entries.size(); ++i) order[i] = {entries[i].key - base, static_cast<std::uint32_t>(i)};
    radix_sort_by_key(order);
    std::vector<VoxelTable::Entry> out;
    out.reserve(entries.size());
    for (const KeyIndex &k : order) {
        const VoxelTable::Entry &e = entries[k.index];
        if (out.empty() || out.back().key != e.key) {
            out.push_back(e);
            continue;
        }
        VoxelTable::Entry &o = out.back();
        for (int a = 0; a < 3; ++a) o.sum[a] += e.sum[a];
        o.count += e.count;
    }
    return out;
}

// The grid: cells anchored at the finite points' minimum corner, x-major keys.
struct Grid {
    Vec3d min;
    double inv = 0.0;
    std::uint64_t cells[3] = {0, 0, 0};

    // The key of p's voxel; q its offset inside the voxel in units of 2^-30 voxels.
    std::uint64_t key(const Vec3d &p, std::int64_t q[3]) const {
        const Vec3d rel = (p - min) * inv;
        std::uint64_t c[3];
        for (int a = 0; a < 3; ++a) {
            // rel >= 0 and below 2^22 (the extent check of grid_for), so truncation is floor; the clamp guards
            // the top face against rounding.
            const std::uint64_t ci = static_cast<std::uint64_t>(static_cast<std::int64_t>(rel[a]));
            c[a] = ci < cells[a] ? ci : cells[a] - 1;
            const double f = std::min(1.0, rel[a] - static_cast<double>(c[a]));
            q[a] = static_cast<std::int64_t>(f * kFixedScale + 0.5);
        }
        return (c[0] * cells[1] + c[1]) * cells[2] + c[2];
    }
};

Grid grid_for(const InputCloud &input, double voxel_size, const std::string &name) {
    Grid g;
    g.min = input.min;
    g.inv = 1.0 / voxel_size;
    const Vec3d extent = input.max - input.min;
    for (int a = 0; a < 3; ++a) {
        g.cells[a] = cells_for(extent[a], voxel_size);
        if (g.cells[a] > kMaxVoxelsPerAxis) {
            std::ostringstream msg;
            msg.precision(6);
            msg << "voxel_size " << voxel_size << " is too small for the " << name << "'s extent of " << extent[a]
                << " along "
                << "xyz"[a] << " (at most " << kMaxVoxelsPerAxis << " voxels per axis; use a voxel size of at least "
                << extent[a] / static_cast<double>(kMaxVoxelsPerAxis - 1) << ")";
            fail(ErrorKind::VoxelRange, msg.str());
        }
    }
    return g;
}

} // namespace

VoxelCloud voxelize(const InputCloud &input, double voxel_size, const std::string &name, RunContext &ctx,
                    std::vector<std::uint64_t> *keys) {
    VoxelCloud out;
    const std::size_t n = static_cast<std::size_t>(input.num_given);
    if (input.num_finite() == 0) return out;
    out.origin = 0.5 * (input.min + input.max);
    const Grid grid = grid_for(input, voxel_size, name);
    const std::uint64_t *cells = grid.cells;

    // Fixed-chunk partial sums (a function of the input, not of the thread count), merged afterwards. A
    // chunk is small enough that a 70K-point scan still splits over a few threads.
    constexpr std::size_t kChunk = 16384;
    std::vector<VoxelTable> partial = ctx.map_chunks(n, kChunk, [&](std::size_t b, std::size_t e) {
        VoxelTable table; // built locally, stored once: neighbouring tables' counters share cache lines
        table.reserve(std::min<std::size_t>(e - b, 4096));
        const bool skip = input.skip_nonfinite;
        // Consecutive points of a scan often share a voxel: a run of them is summed here and enters the table
        // once (integer sums, so the same entry as point by point; docs/design/performance.md, "Voxel merge").
        VoxelTable::Entry run;
        input.for_each_point(b, e, [&](std::size_t, const Vec3d &p) {
            if (skip && !InputCloud::finite(p)) return;
            std::int64_t q[3];
            const std::uint64_t key = grid.key(p, q);
            if (key != run.key) {
                if (run.count != 0) table.add(run);
                run.key = key;
                run.sum[0] = run.sum[1] = run.sum[2] = 0;
                run.count = 0;
            }
            for (int a = 0; a < 3; ++a) run.sum[a] += static_cast<std::uint64_t>(q[a]);
            ++run.count;
        });
        if (run.count != 0) table.add(run);
        return table;
    });
    const std::size_t num_chunks = partial.size();
    // Each chunk's entries compacted (its table goes), then merged by key range: keys are x-major, so a range is
    // a slab of the scene. Each range is merged on its own, in parallel, from the chunks' entries in it; ranges
    // follow each other in key order, so the output is in key order. One table for the whole cloud was merged
    // serially, by random probes far out of cache, and that merge grew faster than the point count
    // (docs/design/performance.md, "What the profiles showed"). About 8K entries per range (a function of the data
    // alone), at most 256 ranges; a small cloud is one range.
    std::vector<std::vector<VoxelTable::Entry>> lists(num_chunks);
    ctx.parallel_for(num_chunks, 1, [&](std::size_t b, std::size_t e) {
        for (std::size_t c = b; c < e; ++c) {
            lists[c] = partial[c].take_entries();
        }
    });
    std::size_t all_entries = 0;
    for (const auto &list : lists) all_entries += list.size();
    const std::size_t kRanges = std::min<std::size_t>(256, all_entries / 8192 + 1);
    std::vector<std::vector<VoxelTable::Entry>> merged(kRanges);
    if (kRanges == 1) {
        std::vector<VoxelTable::Entry> all;
        all.reserve(all_entries);
        for (auto &list : lists) {
            all.insert(all.end(), list.begin(), list.end());
            std::vector<VoxelTable::Entry>().swap(list);
        }
        merged[0] = merged_in_key_order(all, 0);
    } else {
        const std::uint64_t width = cells[0] * cells[1] * cells[2] / kRanges + 1; // keys < 2^63 (extent check)
        // Per chunk: its entries grouped by range, and where each range starts among them.
        std::vector<std::vector<std::size_t>> range_begin(num_chunks);
        ctx.parallel_for(num_chunks, 1, [&](std::size_t b, std::size_t e) {
            for (std::size_t c = b; c < e; ++c) {
                std::vector<std::size_t> begin(kRanges + 1, 0);
                for (const VoxelTable::Entry &x : lists[c]) ++begin[x.key / width + 1];
                for (std::size_t r = 0; r < kRanges; ++r) begin[r + 1] += begin[r];
                std::vector<std::size_t> next(begin.begin(), begin.end() - 1);
                std::vector<VoxelTable::Entry> grouped(lists[c].size());
                for (const VoxelTable::Entry &x : lists[c]) grouped[next[x.key / width]++] = x;
                range_begin[c] = std::move(begin);
                lists[c] = std::move(grouped);
            }
        });
        ctx.parallel_for(kRanges, 1, [&](std::size_t b, std::size_t e) {
            std::vector<VoxelTable::Entry> entries;
            for (std::size_t r = b; r < e; ++r) {
                entries.clear();
                for (std::size_t c = 0; c < num_chunks; ++c)
                    entries.insert(entries.end(), lists[c].begin() + static_cast<std::ptrdiff_t>(range_begin[c][r]),
                                   lists[c].begin() + static_cast<std::ptrdiff_t>(range_begin[c][r + 1]));
                if (!entries.empty()) merged[r] = merged_in_key_order(entries, r * width);
            }
        });
    }

    std::vector<std::size_t> first_voxel(kRanges + 1, 0);
    for (std::size_t r = 0; r < kRanges; ++r) first_voxel[r + 1] = first_voxel[r] + merged[r].size();
    out.points.resize(first_voxel[kRanges]);
    if (keys != nullptr) keys->resize(first_voxel[kRanges]);
    const Vec3d corner = input.min - out.origin;
    ctx.parallel_for(kRanges, 1, [&](std::size_t b, std::size_t e) {
        for (std::size_t r = b; r < e; ++r) {
            const std::vector<VoxelTable::Entry> &m = merged[r];
            for (std::size_t v = 0; v < m.size(); ++v) {
                const VoxelTable::Entry &s = m[v];
                const std::uint64_t key = s.key;
                const std::uint64_t c[3] = {key / (cells[1] * cells[2]), (key / cells[2]) % cells[1], key % cells[2]};
                const double count = static_cast<double>(s.count);
                Vec3d centroid;
                for (int a = 0; a < 3; ++a)
                    centroid[a] =
                        corner[a] +
                        (static_cast<double>(c[a]) + static_cast<double>(s.sum[a]) / kFixedScale / count) * voxel_size;
                out.points[first_voxel[r] + v] = centroid.cast<float>();
                if (keys != nullptr) (*keys)[first_voxel[r] + v] = key;
            }
        }
    });
    return out;
}

std::vector<std::uint32_t> voxel_of_points(const InputCloud &input, double voxel_size, const std::string &name,
                                           const std::vector<std::uint64_t> &keys, RunContext &ctx) {
    const std::size_t n = static_cast<std::size_t>(input.num_given);
    std::vector<std::uint32_t> out(n, kNoVoxel);
    if (input.num_finite() == 0) return out;
    const Grid grid = grid_for(input, voxel_size, name);
    // Key -> voxel number in an open-addressing table (load at most 1/2): one probe or two per point, where a
    // binary search over the keys took 16 and was most of kissm_ground_mask (docs/design/performance.md, "Ground").
    constexpr std::uint64_t kEmpty = ~std::uint64_t(0); // keys use at most 63 bits
    std::size_t capacity = 16;
    while (capacity < 2 * keys.size()) capacity *= 2;
    const std::size_t mask = capacity - 1;
    const auto home = [mask](std::uint64_t key) {
        return static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> 32) & mask;
    };
    std::vector<std::uint64_t> slot_key(capacity, kEmpty);
    std::vector<std::uint32_t> slot_voxel(capacity, kNoVoxel);
    for (std::size_t v = 0; v < keys.size(); ++v) {
        std::size_t s = home(keys[v]);
        while (slot_key[s] != kEmpty) s = (s + 1) & mask;
        slot_key[s] = keys[v];
        slot_voxel[s] = static_cast<std::uint32_t>(v);
    }
    ctx.parallel_for(n, 16384, [&](std::size_t b, std::size_t e) {
        input.for_each_point(b, e, [&](std::size_t i, const Vec3d &p) {
            if (input.skip_nonfinite && !InputCloud::finite(p)) return;
            std::int64_t q[3];
            const std::uint64_t key = grid.key(p, q);
            for (std::size_t s = home(key); slot_key[s] != kEmpty; s = (s + 1) & mask)
                if (slot_key[s] == key) {
                    out[i] = slot_voxel[s];
                    break;
                }
        });
    });
    return out;
}

KISSM_DETAIL_END

// SPDX-License-Identifier: MIT
// The place gate against a planted answer: a map made of the scan's own place (moved and turned, descriptors
// perturbed) and far tiles of unrelated keypoints. The region must be exactly the planted place, the same for
// every thread count, and absent whenever the rules say the whole map must be searched.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "core/matching.hpp"
#include "core/place_gate.hpp"
#include "harness.h"
#include "test_rng.hpp"

using namespace kissm::detail;

namespace {

struct Cloud {
    Descriptors d;
    std::vector<Vec3f> points;
};

void add_random(Cloud &c, TestRng &rng, const Vec3f &centre, std::size_t n, float radius) {
    for (std::size_t i = 0; i < n; ++i) {
        const double a = rng.uniform(0.0, 6.283185307179586), r = radius * std::sqrt(rng.uniform());
        c.d.keypoint.push_back(static_cast<std::uint32_t>(c.points.size()));
        c.points.push_back(centre + Vec3f(static_cast<float>(r * std::cos(a)), static_cast<float>(r * std::sin(a)),
                                          static_cast<float>(rng.uniform(-2.0, 2.0))));
        for (int k = 0; k < kDescriptorDim; ++k) c.d.values.push_back(static_cast<float>(rng.uniform(0, 30)));
    }
}

// The scan's keypoints turned by `yaw`, moved to `centre`, descriptors perturbed, in a shuffled order.
// Returns the map keypoint indexes of the copy.
std::vector<std::uint32_t> add_copy(Cloud &map, const Cloud &scan, TestRng &rng, const Vec3f &centre, double yaw) {
    const std::size_t n = scan.points.size();
    const float c = static_cast<float>(std::cos(yaw)), s = static_cast<float>(std::sin(yaw));
    std::vector<std::uint32_t> added;
    for (std::size_t j = 0; j < n; ++j) {
        const std::size_t i = (j * 7919) % n; // n is not a multiple of 7919
        const Vec3f &p = scan.points[i];
        added.push_back(static_cast<std::uint32_t>(map.d.keypoint.size()));
        map.d.keypoint.push_back(static_cast<std::uint32_t>(map.points.size()));
        map.points.push_back(centre + Vec3f(c * p.x() - s * p.y(), s * p.x() + c * p.y(), p.z()));
        for (int k = 0; k < kDescriptorDim; ++k)
            map.d.values.push_back(scan.d.values[i * kDescriptorDim + k] + static_cast<float>(rng.uniform(-0.2, 0.2)));
    }
    std::sort(added.begin(), added.end());
    return added;
}

struct Indexed {
    std::vector<DescriptorIndex> index;
    KeypointGrid grid;
    // The view of `c`, which must be the cloud indexed (or one with the same descriptors, for bad positions).
    IndexedDescriptors view(const Cloud &c, bool with_points = true, bool with_grid = true) const {
        return IndexedDescriptors{&c.d, &index[0], with_points ? &c.points : nullptr, with_grid ? &grid : nullptr};
    }
};

Indexed index_of(const Cloud &c, RunContext &ctx) {
    return Indexed{DescriptorIndex::build({&c.d}, ctx), KeypointGrid(c.points, c.d.keypoint, 16.0)};
}

constexpr std::size_t kScan = 2000;

Cloud make_scan(TestRng &rng) {
    Cloud scan;
    add_random(scan, rng, Vec3f::Zero(), kScan, 50.0f);
    return scan;
}

} // namespace

static void test_region_is_the_planted_place_for_any_thread_count() {
    TestRng rng(5);
    const Cloud scan = make_scan(rng);
    Cloud map;
    const Vec3f far[] = {{0, 0, 0}, {-2000, 0, 0}, {0, 2000, 0}, {3000, 3000, 0}, {-3000, 1000, 0}};
    add_random(map, rng, far[0], kScan, 50.0f);
    add_random(map, rng, far[1], kScan, 50.0f);
    const std::vector<std::uint32_t> planted = add_copy(map, scan, rng, Vec3f(1000, -500, 10), 1.0);
    for (int t = 2; t < 5; ++t) add_random(map, rng, far[t], kScan, 50.0f);

    std::vector<std::uint32_t> first;
    std::vector<std::uint32_t> first_found;
    for (int threads : {1, 2, 4}) {
        RunContext ctx(threads, nullptr, Hooks());
        const Indexed si = index_of(scan, ctx), mi = index_of(map, ctx);
        const PlaceRegion region = PlaceRegion::find(si.view(scan), mi.view(map), ctx);
        REQUIRE(!region.empty());
        CHECK(region.keypoints() == planted);

        // A region's search finds its own keypoints exactly and never leaves the region.
        std::vector<std::uint32_t> found;
        std::size_t self = 0, outside = 0;
        for (std::uint32_t m = 0; m < map.d.keypoint.size(); m += 3) {
            const RankedNeighbours r = region.nearest(&map.d.values[static_cast<std::size_t>(m) * kDescriptorDim], 2);
            REQUIRE(r.found() == 2);
            found.push_back(r.index(0));
            outside += !std::binary_search(planted.begin(), planted.end(), r.index(0));
            outside += !std::binary_search(planted.begin(), planted.end(), r.index(1));
            const bool in_region = std::binary_search(planted.begin(), planted.end(), m);
            self += in_region && r.index(0) == m && r.dist(0) == 0.0f;
        }
        CHECK_EQ_INT(outside, 0);
        std::size_t planted_queried = 0;
        for (std::uint32_t m : planted) planted_queried += m % 3 == 0;
        CHECK_EQ_INT(self, planted_queried);

        // Matching the scan against the map goes through the region: every match lands in the planted place,
        // and nearly all on the planted partner.
        const auto matches = match_descriptors(si.view(scan), mi.view(map), MatchParams{0.9, 5000}, ctx);
        std::size_t right = 0, elsewhere = 0;
        for (const auto &c : matches) {
            elsewhere += !std::binary_search(planted.begin(), planted.end(), c.target);
            const std::size_t j = static_cast<std::size_t>(c.target - planted.front());
            right += j < kScan && (j * 7919) % kScan == c.source;
        }
        CHECK_EQ_INT(elsewhere, 0);
        CHECK_MSG(right >= kScan * 95 / 100, "%zu right of %zu", right, matches.size());
        if (first.empty()) {
            first = region.keypoints();
            first_found = found;
        }
        CHECK(region.keypoints() == first);
        CHECK(found == first_found);
    }
}

static void test_no_region_when_the_rules_say_search_it_all() {
    TestRng rng(9);
    const Cloud scan = make_scan(rng);
    RunContext ctx(2, nullptr, Hooks());
    const Indexed si = index_of(scan, ctx);

    // The scan's place twice, far apart: the votes split, neither window wins by the margin.
    {
        Cloud map;
        add_copy(map, scan, rng, Vec3f(1000, 0, 0), 0.5);
        add_copy(map, scan, rng, Vec3f(-1000, 0, 0), 2.0);
        add_random(map, rng, Vec3f(0, 2000, 0), kScan, 50.0f);
        const Indexed mi = index_of(map, ctx);
        CHECK(PlaceRegion::find(si.view(scan), mi.view(map), ctx).empty());
    }
    // A map not twice the scan's size.
    {
        Cloud map;
        add_copy(map, scan, rng, Vec3f(1000, 0, 0), 0.5);
        add_random(map, rng, Vec3f(0, 2000, 0), kScan - 1, 50.0f);
        const Indexed mi = index_of(map, ctx);
        CHECK(PlaceRegion::find(si.view(scan), mi.view(map), ctx).empty());
    }
    // The place holds most of the map: the region would save nothing.
    {
        Cloud map;
        add_copy(map, scan, rng, Vec3f(1000, 0, 0), 0.5);
        add_random(map, rng, Vec3f(1000, 0, 0), 2 * kScan, 50.0f);
        add_random(map, rng, Vec3f(0, 3000, 0), kScan, 50.0f);
        const Indexed mi = index_of(map, ctx);
        CHECK(PlaceRegion::find(si.view(scan), mi.view(map), ctx).empty());
    }
    // Without positions, or with a position that is not finite, or cells beyond the packed range.
    {
        Cloud map;
        const std::vector<std::uint32_t> planted = add_copy(map, scan, rng, Vec3f(1000, 0, 0), 0.5);
        for (int t = 0; t < 4; ++t)
            add_random(map, rng, Vec3f(-2000.0f * static_cast<float>(t + 1), 0, 0), kScan, 50.0f);
        Indexed mi = index_of(map, ctx);
        CHECK(!PlaceRegion::find(si.view(scan), mi.view(map), ctx).empty());
        CHECK(PlaceRegion::find(si.view(scan, false), mi.view(map), ctx).empty());
        CHECK(PlaceRegion::find(si.view(scan), mi.view(map, false), ctx).empty());
        CHECK(PlaceRegion::find(si.view(scan), mi.view(map, true, false), ctx).empty());
        // (every scan keypoint votes here, so every planted keypoint is some voter's nearest)
        Cloud bad = map;
        bad.points[map.d.keypoint[planted[5]]].y() = std::numeric_limits<float>::quiet_NaN();
        CHECK(PlaceRegion::find(si.view(scan), mi.view(bad), ctx).empty());
        bad = map;
        bad.points[map.d.keypoint[planted[7]]].x() = 3.0e8f; // 25 m cells: more than 2^20 cells out
        CHECK(PlaceRegion::find(si.view(scan), mi.view(bad), ctx).empty());
        // Matching without a region is matching against the whole map, as before the gate.
        const auto whole = match_descriptors(si.view(scan, false), mi.view(map), MatchParams{0.9, 5000}, ctx);
        const auto gated = match_descriptors(si.view(scan), mi.view(map), MatchParams{0.9, 5000}, ctx);
        CHECK(!whole.empty() && !gated.empty());
    }
}

int main() {
    RUN_TEST(test_region_is_the_planted_place_for_any_thread_count);
    RUN_TEST(test_no_region_when_the_rules_say_search_it_all);
    return TEST_SUMMARY();
}

// SPDX-License-Identifier: MIT
#include <algorithm>
#include <cstring>

#include "core/matching.hpp"
#include "harness.h"
#include "test_rng.hpp"

using namespace kissm::detail;

static Descriptors random_descriptors(TestRng &rng, std::size_t n) {
    Descriptors d;
    for (std::size_t i = 0; i < n; ++i) {
        d.keypoint.push_back(static_cast<std::uint32_t>(i));
        for (int c = 0; c < kDescriptorDim; ++c) d.values.push_back(static_cast<float>(rng.uniform(0, 30)));
    }
    return d;
}

// Both clouds indexed under `ctx`, then matched under it.
static std::vector<Correspondence> match(const Descriptors &src, const Descriptors &tgt, const MatchParams &mp,
                                         RunContext &ctx) {
    const std::vector<DescriptorIndex> idx = DescriptorIndex::build({&src, &tgt}, ctx);
    return match_descriptors(IndexedDescriptors{&src, &idx[0]}, IndexedDescriptors{&tgt, &idx[1]}, mp, ctx);
}

static void test_mutual_matches_found_and_threads_agree() {
    TestRng rng(14);
    const Descriptors src = random_descriptors(rng, 2000);
    // Target: the first 1000 source descriptors (slightly perturbed, in reverse order) plus 1500 others.
    Descriptors tgt;
    for (std::size_t i = 0; i < 1000; ++i) {
        const std::size_t s = 999 - i;
        tgt.keypoint.push_back(static_cast<std::uint32_t>(i));
        for (int c = 0; c < kDescriptorDim; ++c)
            tgt.values.push_back(src.values[s * kDescriptorDim + c] + static_cast<float>(rng.uniform(-0.2, 0.2)));
    }
    const Descriptors extra = random_descriptors(rng, 1500);
    for (std::size_t i = 0; i < 1500; ++i) {
        tgt.keypoint.push_back(static_cast<std::uint32_t>(1000 + i));
        tgt.values.insert(tgt.values.end(), extra.values.begin() + static_cast<std::ptrdiff_t>(i * kDescriptorDim),
                          extra.values.begin() + static_cast<std::ptrdiff_t>((i + 1) * kDescriptorDim));
    }
    RunContext one(1, nullptr, Hooks()), four(4, nullptr, Hooks());
    const MatchParams mp{0.9, 5000};
    const auto m1 = match(src, tgt, mp, one);
    const auto m4 = match(src, tgt, mp, four);
    REQUIRE(m1.size() == m4.size());
    CHECK(std::memcmp(m1.data(), m4.data(), m1.size() * sizeof(Correspondence)) == 0);
    std::size_t right = 0;
    for (const auto &c : m1) right += c.source < 1000 && c.target == 999 - c.source;
    CHECK_MSG(right >= 990, "%zu correct of %zu", right, m1.size());
    std::size_t wrong_among_planted = 0;
    for (const auto &c : m1) wrong_among_planted += c.source < 1000 && c.target != 999 - c.source;
    CHECK_EQ_INT(wrong_among_planted, 0);
    for (std::size_t i = 1; i < m1.size(); ++i) CHECK(m1[i - 1].source < m1[i].source);

    // The cap keeps the most distinctive matches.
    const auto capped = match(src, tgt, MatchParams{0.9, 100}, four);
    CHECK_EQ_INT(capped.size(), 100);
    float worst_kept = 0.0f;
    for (const auto &c : capped) worst_kept = std::max(worst_kept, c.score);
    std::size_t better_dropped = 0;
    for (const auto &c : m1) {
        bool kept = false;
        for (const auto &k : capped) kept = kept || (k.source == c.source && k.target == c.target);
        if (!kept && c.score < worst_kept) ++better_dropped;
    }
    CHECK_EQ_INT(better_dropped, 0);
}

static void test_identical_candidates_are_ambiguous() {
    // Two identical target descriptors: the ratio test must reject the match rather than pick one.
    Descriptors src, tgt;
    src.keypoint = {0};
    src.values.assign(kDescriptorDim, 1.0f);
    tgt.keypoint = {0, 1, 2};
    tgt.values.assign(3 * kDescriptorDim, 1.0f);
    for (int c = 0; c < kDescriptorDim; ++c) tgt.values[2 * kDescriptorDim + c] = 50.0f;
    RunContext ctx(1, nullptr, Hooks());
    CHECK(match(src, tgt, MatchParams{0.9, 10}, ctx).empty());
    // Without the ratio test the lower index wins the tie, deterministically.
    const auto m = match(src, tgt, MatchParams{1.0, 10}, ctx);
    REQUIRE(m.size() == 1);
    CHECK_EQ_INT(m[0].target, 0);
}

static void test_index_is_a_function_of_its_cloud() {
    // One large side indexed once (one thread) and matched by several small ones (four threads) gives what
    // indexing both fresh for every call gives, and the empty side matches nothing.
    TestRng rng(31);
    const Descriptors map = random_descriptors(rng, 20000);
    RunContext one(1, nullptr, Hooks()), four(4, nullptr, Hooks());
    const std::vector<DescriptorIndex> map_index = DescriptorIndex::build({&map}, one);
    REQUIRE(!map_index[0].empty());
    CHECK(map_index[0].bytes() > map.values.size() * sizeof(float));
    for (int scan = 0; scan < 3; ++scan) {
        Descriptors s;
        for (std::size_t i = 0; i < 500; ++i) {
            const std::size_t m = (static_cast<std::size_t>(scan) * 4001 + i * 37) % map.keypoint.size();
            s.keypoint.push_back(static_cast<std::uint32_t>(i));
            for (int c = 0; c < kDescriptorDim; ++c)
                s.values.push_back(map.values[m * kDescriptorDim + c] + static_cast<float>(rng.uniform(-0.1, 0.1)));
        }
        const std::vector<DescriptorIndex> s_index = DescriptorIndex::build({&s}, four);
        const auto reused = match_descriptors(IndexedDescriptors{&s, &s_index[0]},
                                              IndexedDescriptors{&map, &map_index[0]}, MatchParams{0.9, 5000}, four);
        const auto fresh = match(s, map, MatchParams{0.9, 5000}, one);
        REQUIRE(reused.size() == fresh.size());
        CHECK(std::memcmp(reused.data(), fresh.data(), fresh.size() * sizeof(Correspondence)) == 0);
        std::size_t right = 0;
        for (const auto &c : reused)
            right += c.target == (static_cast<std::size_t>(scan) * 4001 + c.source * 37) % map.keypoint.size();
        CHECK_MSG(right >= 490 && right == reused.size(), "%zu right of %zu", right, reused.size());
    }
    const Descriptors none;
    const std::vector<DescriptorIndex> empty = DescriptorIndex::build({&none}, one);
    CHECK(empty[0].empty());
    CHECK(match_descriptors(IndexedDescriptors{&none, &empty[0]}, IndexedDescriptors{&map, &map_index[0]},
                            MatchParams{0.9, 5000}, one)
              .empty());
}

static void test_automatic_cap() {
    // An explicit cap is the cap; automatic (0) is one match per 20 keypoints of the smaller cloud within
    // [5000, 100000]: every cloud of up to 100,000 keypoints keeps the fixed 5000.
    CHECK_EQ_INT(correspondence_cap(1234, 10), 1234);
    CHECK_EQ_INT(correspondence_cap(3, 5000000), 3);
    CHECK_EQ_INT(correspondence_cap(0, 0), 5000);
    CHECK_EQ_INT(correspondence_cap(0, 100019), 5000);
    CHECK_EQ_INT(correspondence_cap(0, 100020), 5001);
    CHECK_EQ_INT(correspondence_cap(0, 307616), 15380);
    CHECK_EQ_INT(correspondence_cap(0, 2000000), 100000);
    CHECK_EQ_INT(correspondence_cap(0, 3076906), 100000);

    // On small clouds automatic matching is the 5000 cap's, bit for bit; with more mutual matches than the
    // floor it keeps exactly the floor's most distinctive ones.
    TestRng rng(77);
    const Descriptors src = random_descriptors(rng, 6000);
    Descriptors tgt = src;
    for (float &v : tgt.values) v += static_cast<float>(rng.uniform(-0.05, 0.05));
    RunContext two(2, nullptr, Hooks());
    const auto fixed = match(src, tgt, MatchParams{1.0, 5000}, two);
    const auto automatic = match(src, tgt, MatchParams{1.0, 0}, two);
    CHECK_EQ_INT(fixed.size(), 5000);
    REQUIRE(automatic.size() == fixed.size());
    CHECK(std::memcmp(automatic.data(), fixed.data(), fixed.size() * sizeof(Correspondence)) == 0);
}

int main() {
    RUN_TEST(test_mutual_matches_found_and_threads_agree);
    RUN_TEST(test_automatic_cap);
    RUN_TEST(test_identical_candidates_are_ambiguous);
    RUN_TEST(test_index_is_a_function_of_its_cloud);
    return TEST_SUMMARY();
}

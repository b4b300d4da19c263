// SPDX-License-Identifier: MIT
// The block LDL^T of the pose graph's normal equations (src/core/block_ldlt.cpp) against a dense solve: random
// symmetric positive definite systems of 6x6 blocks on random sparse patterns (chains with loop closures, as pose
// graphs are, and scattered ones), refactorised with new values on the same analysis; a zero pivot reported, a
// negative one taken; the same bits on a second run and at both kernel widths; the fill of a drive's pattern.
#include <cstring>
#include <random>
#include <utility>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Dense>

#include "core/block_ldlt.hpp"
#include "harness.h"

using namespace kissm::detail;

namespace {

struct BlockSystem {
    long n = 0;
    std::vector<std::pair<long, long>> pairs;
    std::vector<Matrix6d> diagonal, off;
};

// A chain 0-1-...-(n-1) and `extra` more random pairs (each unordered pair once, in a random orientation).
std::vector<std::pair<long, long>> random_pattern(long n, long extra, std::mt19937 &rng) {
    std::vector<std::pair<long, long>> pairs;
    std::vector<std::vector<char>> used(n, std::vector<char>(n, 0));
    auto add = [&](long a, long b) {
        if (a == b || used[a][b]) return;
        used[a][b] = used[b][a] = 1;
        pairs.emplace_back(a, b);
    };
    for (long i = 0; i + 1 < n; ++i) add(i + 1, i);
    std::uniform_int_distribution<long> node(0, n - 1);
    for (long k = 0; k < extra; ++k) {
        const long a = node(rng), b = node(rng);
        if (rng() % 2)
            add(a, b);
        else
            add(b, a);
    }
    return pairs;
}

// Values on a pattern that make it positive definite: each pair a random J^T J coupling, as an edge adds it, and a
// little on every diagonal.
void random_values(BlockSystem &s, std::mt19937 &rng) {
    std::normal_distribution<double> normal(0.0, 1.0);
    s.diagonal.assign(s.n, Matrix6d::Zero());
    s.off.assign(s.pairs.size(), Matrix6d::Zero());
    for (std::size_t p = 0; p < s.pairs.size(); ++p) {
        Eigen::Matrix<double, 6, 12> j;
        for (int r = 0; r < 6; ++r)
            for (int c = 0; c < 12; ++c) j(r, c) = normal(rng);
        const Eigen::Matrix<double, 12, 12> h = j.transpose() * j;
        s.diagonal[s.pairs[p].first] += h.topLeftCorner<6, 6>();
        s.diagonal[s.pairs[p].second] += h.bottomRightCorner<6, 6>();
        s.off[p] = h.topRightCorner<6, 6>();
    }
    for (Matrix6d &d : s.diagonal) d += 0.01 * Matrix6d::Identity();
}

BlockSystem random_system(long n, long extra, unsigned seed) {
    std::mt19937 rng(seed);
    BlockSystem s;
    s.n = n;
    s.pairs = random_pattern(n, extra, rng);
    random_values(s, rng);
    return s;
}

Eigen::MatrixXd dense(const BlockSystem &s) {
    Eigen::MatrixXd a = Eigen::MatrixXd::Zero(6 * s.n, 6 * s.n);
    for (long i = 0; i < s.n; ++i) a.block<6, 6>(6 * i, 6 * i) = s.diagonal[i];
    for (std::size_t p = 0; p < s.pairs.size(); ++p) {
        const long i = s.pairs[p].first, j = s.pairs[p].second;
        a.block<6, 6>(6 * i, 6 * j) = s.off[p];
        a.block<6, 6>(6 * j, 6 * i) = s.off[p].transpose();
    }
    return a;
}

void check_against_dense(long n, long extra, unsigned seed) {
    std::mt19937 rng(seed);
    BlockSystem s;
    s.n = n;
    s.pairs = random_pattern(n, extra, rng);
    BlockLdlt ldlt;
    ldlt.analyse(n, s.pairs);
    CHECK(ldlt.size() == n);
    for (int refactor = 0; refactor < 3; ++refactor) { // new values on the same analysis
        random_values(s, rng);
        const Eigen::MatrixXd a = dense(s);
        Eigen::VectorXd b(6 * n);
        std::normal_distribution<double> normal(0.0, 1.0);
        for (Eigen::Index k = 0; k < b.size(); ++k) b[k] = normal(rng);
        REQUIRE(ldlt.factorize(s.diagonal, s.off));
        Eigen::VectorXd x = b;
        ldlt.solve(x);
        const Eigen::VectorXd expected = a.ldlt().solve(b);
        const double residual = (a * x - b).norm() / b.norm();
        const double error = (x - expected).norm() / expected.norm();
        CHECK_MSG(residual < 1e-10, "n %ld, extra %ld, seed %u: residual %g", n, extra, seed, residual);
        CHECK_MSG(error < 1e-8, "n %ld, extra %ld, seed %u: off the dense solve by %g", n, extra, seed, error);
        Eigen::VectorXd again = b; // a second solve on the same factors: the same bits
        ldlt.solve(again);
        CHECK(std::memcmp(again.data(), x.data(), sizeof(double) * x.size()) == 0);
    }
}

void test_matches_a_dense_solve() {
    check_against_dense(1, 0, 1);
    check_against_dense(2, 0, 2);
    check_against_dense(10, 0, 3);   // a chain: no fill
    check_against_dense(40, 8, 4);   // a chain with loop closures
    check_against_dense(60, 200, 5); // dense-ish: fronts of many blocks
    check_against_dense(120, 30, 6);
    for (unsigned seed = 10; seed < 20; ++seed) check_against_dense(30, static_cast<long>(seed), seed);
}

void test_disconnected_blocks() {
    // No pairs at all, and two components: every block its own system.
    std::mt19937 rng(7);
    BlockSystem s;
    s.n = 8;
    s.pairs = {{0, 1}, {2, 1}, {5, 6}};
    random_values(s, rng);
    BlockLdlt ldlt;
    ldlt.analyse(s.n, s.pairs);
    REQUIRE(ldlt.factorize(s.diagonal, s.off));
    const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(6 * s.n, -1.0, 1.0);
    Eigen::VectorXd x = b;
    ldlt.solve(x);
    CHECK((dense(s) * x - b).norm() < 1e-10 * b.norm());
}

void test_zero_pivot_fails() {
    BlockSystem s = random_system(5, 3, 8);
    BlockLdlt ldlt;
    ldlt.analyse(s.n, s.pairs);
    s.diagonal[3].setZero(); // row 3 of A all zero except its couplings: with them zeroed too, a zero pivot
    for (std::size_t p = 0; p < s.pairs.size(); ++p)
        if (s.pairs[p].first == 3 || s.pairs[p].second == 3) s.off[p].setZero();
    CHECK(!ldlt.factorize(s.diagonal, s.off));
    s.diagonal[3] = Matrix6d::Identity(); // and it recovers on the same analysis
    CHECK(ldlt.factorize(s.diagonal, s.off));
}

void test_negative_pivot_is_taken() {
    // As a scalar LDL^T (and Eigen's simplicial one) takes it: an indefinite system that is not singular is solved.
    BlockSystem s = random_system(8, 4, 13);
    s.diagonal[2] = -s.diagonal[2];
    for (std::size_t p = 0; p < s.pairs.size(); ++p)
        if (s.pairs[p].first == 2 || s.pairs[p].second == 2) s.off[p].setZero();
    BlockLdlt ldlt;
    ldlt.analyse(s.n, s.pairs);
    REQUIRE(ldlt.factorize(s.diagonal, s.off));
    const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(6 * s.n, 1.0, 2.0);
    Eigen::VectorXd x = b;
    ldlt.solve(x);
    CHECK((dense(s) * x - b).norm() < 1e-10 * b.norm());
}

void test_bitwise_repeatable() {
    const BlockSystem s = random_system(50, 40, 9);
    const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(300, -2.0, 3.0);
    Eigen::VectorXd x[2];
    for (Eigen::VectorXd &xi : x) {
        BlockLdlt ldlt;
        ldlt.analyse(s.n, s.pairs);
        REQUIRE(ldlt.factorize(s.diagonal, s.off));
        xi = b;
        ldlt.solve(xi);
    }
    CHECK(std::memcmp(x[0].data(), x[1].data(), sizeof(double) * 300) == 0);
}

// The bits of one solve, pinned: the test runs with the AVX2 kernels and again held to SSE2 (BOTH_WIDTHS), and both
// must give these (the pose graph's results are the same bits on every x86-64 CPU).
void test_same_bits_at_both_widths() {
    const BlockSystem s = random_system(60, 50, 12);
    BlockLdlt ldlt;
    ldlt.analyse(s.n, s.pairs);
    REQUIRE(ldlt.factorize(s.diagonal, s.off));
    Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(360, -1.0, 2.0);
    ldlt.solve(x);
    unsigned long long hash = 14695981039346656037ull; // FNV-1a over the solution's bytes
    const unsigned char *bytes = reinterpret_cast<const unsigned char *>(x.data());
    for (std::size_t k = 0; k < sizeof(double) * 360; ++k) hash = (hash ^ bytes[k]) * 1099511628211ull;
#if defined(__x86_64__)
    CHECK_MSG(hash == 0xefef00ec1a1a4110ull, "solution hash %016llx", hash);
#else
    (void)hash;
#endif
}

void test_fill_is_reduced() {
    // A long chain with a few closures: a good order keeps L close to A (a bad one fills whole bands).
    std::mt19937 rng(11);
    const long n = 2000;
    std::vector<std::pair<long, long>> pairs;
    for (long i = 0; i + 1 < n; ++i) pairs.emplace_back(i, i + 1);
    for (long i = 0; i + 100 < n; i += 7) pairs.emplace_back(i, i + 100);
    BlockLdlt ldlt;
    ldlt.analyse(n, pairs);
    CHECK_MSG(ldlt.lower_blocks() < 20 * static_cast<long>(pairs.size()), "%ld blocks below the diagonal for %zu pairs",
              ldlt.lower_blocks(), pairs.size());
}

} // namespace

int main() {
    RUN_TEST(test_matches_a_dense_solve);
    RUN_TEST(test_disconnected_blocks);
    RUN_TEST(test_zero_pivot_fails);
    RUN_TEST(test_negative_pivot_is_taken);
    RUN_TEST(test_bitwise_repeatable);
    RUN_TEST(test_same_bits_at_both_widths);
    RUN_TEST(test_fill_is_reduced);
    return TEST_SUMMARY();
}

// SPDX-License-Identifier: MIT
// Frames and maps on the KITTI 07 keyframes of $KISSM_DATA_DIR (issue 15), with frame-free normals
// (KISSM_VIEWPOINT_LOCAL): scan-to-map against leave-one-out maps in the world frame, directly and from
// features described once (bitwise the same, at 1 and 2 threads), map-to-map in world frames hundreds of
// metres apart, clouds in moved and turned frames, and an exact georeferenced shift (bitwise the same
// rotation); scan-to-map with other real places in the map, and with the scan's own place left out. No run may report a
// wrong pose as valid, the fixed viewpoint included.
#include <cstring>

#include "harness.h"
#include "kissm.h"
#include "realdata.hpp"

using namespace realdata;

namespace {

const double kPi = 3.14159265358979323846;

struct Pose {
    Mat3 r{{1, 0, 0, 0, 1, 0, 0, 0, 1}};
    double t[3] = {0, 0, 0};
};

Pose compose(const Pose &a, const Pose &b) { // a * b
    Pose c;
    c.r = mul(a.r, b.r);
    for (int i = 0; i < 3; ++i)
        c.t[i] = a.r.m[3 * i] * b.t[0] + a.r.m[3 * i + 1] * b.t[1] + a.r.m[3 * i + 2] * b.t[2] + a.t[i];
    return c;
}

Pose inverse(const Pose &a) {
    Pose b;
    b.r = transpose(a.r);
    for (int i = 0; i < 3; ++i)
        b.t[i] = -(b.r.m[3 * i] * a.t[0] + b.r.m[3 * i + 1] * a.t[1] + b.r.m[3 * i + 2] * a.t[2]);
    return b;
}

void apply(const Pose &p, const double *x, double *out) {
    for (int i = 0; i < 3; ++i)
        out[i] = p.r.m[3 * i] * x[0] + p.r.m[3 * i + 1] * x[1] + p.r.m[3 * i + 2] * x[2] + p.t[i];
}

// Appends `cloud` moved by `p` to `out`.
void append_moved(const Pose &p, const std::vector<double> &cloud, std::vector<double> &out) {
    const std::size_t at = out.size();
    out.resize(at + cloud.size());
    for (std::size_t i = 0; i < cloud.size(); i += 3) apply(p, &cloud[i], &out[at + i]);
}

Pose read_pose(const std::string &path) {
    double v[16] = {};
    std::ifstream f(path);
    for (double &x : v) f >> x;
    CHECK_MSG(static_cast<bool>(f), "cannot read %s", path.c_str());
    Pose p;
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) p.r.m[3 * i + j] = v[4 * i + j];
        p.t[i] = v[4 * i + 3];
    }
    return p;
}

// A frame turned by 0.5..pi about a random axis, its origin `distance` metres away in a random direction.
Pose random_frame(Rng &rng, double distance) {
    Pose p;
    p.r = axis_angle(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5, 0.5 + (kPi - 0.5) * rng.uniform());
    double d[3] = {rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5};
    const double n = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (int i = 0; i < 3; ++i) p.t[i] = d[i] / n * distance;
    return p;
}

kissm_points view(const std::vector<double> &xyz) { return {xyz.data(), xyz.size() / 3, 0, KISSM_SCALAR_FLOAT64, 0}; }

kissm_matcher *make_matcher(int32_t viewpoint_mode, int32_t threads) {
    kissm_config config;
    kissm_config_init(&config, sizeof(config));
    config.voxel_size = 0.5;
    config.num_threads = threads;
    config.viewpoint_mode = viewpoint_mode;
    kissm_matcher *m = nullptr;
    CHECK_MSG(kissm_create(&config, &m) == KISSM_OK, "kissm_create: %s", kissm_last_error_message());
    return m;
}

struct Errors {
    double rot_deg, trans_m;
};

// Rotation error, and how far apart the result and the truth put the source's centroid.
Errors errors(const kissm_result &r, const Pose &truth, const std::vector<double> &source) {
    if (!std::isfinite(r.rotation[0])) return {NAN, NAN};
    Pose got;
    std::memcpy(got.r.m, r.rotation, sizeof got.r.m);
    std::memcpy(got.t, r.translation, sizeof got.t);
    double c[3] = {0, 0, 0};
    for (std::size_t i = 0; i < source.size(); i += 3)
        for (int a = 0; a < 3; ++a) c[a] += source[i + a] / static_cast<double>(source.size() / 3);
    double pa[3], pb[3];
    apply(got, c, pa);
    apply(truth, c, pb);
    return {rotation_error_deg(got.r, truth.r),
            std::sqrt((pa[0] - pb[0]) * (pa[0] - pb[0]) + (pa[1] - pb[1]) * (pa[1] - pb[1]) +
                      (pa[2] - pb[2]) * (pa[2] - pb[2]))};
}

bool same_pose(const kissm_result &a, const kissm_result &b) {
    return std::memcmp(a.transform, b.transform, sizeof a.transform) == 0 && a.valid == b.valid &&
           a.num_final_inliers == b.num_final_inliers && a.num_initial_correspondences == b.num_initial_correspondences;
}

kissm_result new_result() {
    kissm_result r;
    std::memset(&r, 0, sizeof r);
    r.struct_size = sizeof r;
    return r;
}

struct Keyframes {
    std::vector<std::vector<double>> cloud; // sensor frames
    std::vector<Pose> world;                // each keyframe's pose in keyframe 0's frame
};

Keyframes read_keyframes(const std::string &root) {
    Keyframes kf;
    const std::string dir = root + "/kitti07_keyframes_gtsam_points";
    char name[64];
    for (int k = 0; k < 5; ++k) {
        std::snprintf(name, sizeof name, "/%06d/points.bin", k);
        kf.cloud.push_back(read_cloud(dir + name, KISSM_FORMAT_BIN_XYZ));
        if (k == 0) {
            kf.world.emplace_back();
        } else {
            std::snprintf(name, sizeof name, "/pairs/%06d__%06d/gt_T_target_source.txt", k - 1, k);
            kf.world.push_back(compose(kf.world.back(), read_pose(dir + name)));
        }
    }
    return kf;
}

void test_scan_to_map(const Keyframes &kf) {
    kissm_matcher *m = make_matcher(KISSM_VIEWPOINT_LOCAL, 2), *one = make_matcher(KISSM_VIEWPOINT_LOCAL, 1);
    for (int k = 0; k < 5; ++k) {
        std::vector<double> map;
        for (int j = 0; j < 5; ++j)
            if (j != k) append_moved(kf.world[j], kf.cloud[j], map);
        const kissm_points scan = view(kf.cloud[k]), map_points = view(map);
        kissm_result direct = new_result(), reused = new_result(), serial = new_result();
        CHECK(kissm_register(m, &scan, &map_points, &direct) == KISSM_OK);
        const Errors e = errors(direct, kf.world[k], kf.cloud[k]);
        std::printf("scan-to-map kf%d: valid %d, %.3f deg, %.3f m, %llu inliers\n", k, direct.valid, e.rot_deg,
                    e.trans_m, static_cast<unsigned long long>(direct.num_final_inliers));
        CHECK_MSG(direct.valid && e.rot_deg < 5.0 && e.trans_m < 2.0, "keyframe %d against the others' map", k);
        // The map described once: the same bits, at either thread count.
        kissm_features *map_features = nullptr, *scan_features = nullptr;
        REQUIRE(kissm_features_compute(one, &map_points, &map_features) == KISSM_OK);
        REQUIRE(kissm_features_compute(m, &scan, &scan_features) == KISSM_OK);
        CHECK(kissm_features_memory_bytes(map_features) > 264 * kissm_features_num_keypoints(map_features));
        CHECK(kissm_register_features(m, scan_features, map_features, &reused) == KISSM_OK);
        CHECK(kissm_register_features(one, scan_features, map_features, &serial) == KISSM_OK);
        CHECK_MSG(same_pose(direct, reused) && same_pose(direct, serial), "keyframe %d: features path differs", k);
        kissm_features_destroy(scan_features);
        kissm_features_destroy(map_features);
    }
    kissm_destroy(m);
    kissm_destroy(one);
}

// Other places: four real LiDAR scans, three times each, turned about z and set 700-1300 m from keyframe 0, so a
// map of them plus the leave-one-out map is several times the scan (the matching then searches only the place the
// scan's votes single out, src/core/place_gate.hpp).
std::vector<double> distractor_tiles(const std::string &root) {
    const std::pair<const char *, int32_t> files[] = {
        {"/kitti_demo_scans_unverified/000000.bin", KISSM_FORMAT_KITTI_BIN},
        {"/kitti_demo_scans_unverified/000015.bin", KISSM_FORMAT_KITTI_BIN},
        {"/small_gicp_lidar/target.ply", KISSM_FORMAT_PLY},
        {"/small_gicp_lidar/source.ply", KISSM_FORMAT_PLY}};
    std::vector<double> tiles;
    Rng rng{15};
    for (int t = 0; t < 4; ++t) {
        const std::vector<double> cloud = read_cloud(root + files[t].first, files[t].second);
        CHECK_MSG(!cloud.empty(), "cannot read %s", files[t].first);
        for (int copy = 0; copy < 3; ++copy) {
            Pose p;
            p.r = axis_angle(0, 0, 1, 2 * kPi * rng.uniform());
            const double bearing = kPi / 6 * (3 * t + copy) + 0.3, range = 700 + 600 * rng.uniform();
            p.t[0] = range * std::cos(bearing);
            p.t[1] = range * std::sin(bearing);
            append_moved(p, cloud, tiles);
        }
    }
    return tiles;
}

// Scan-to-map among other places: every keyframe right and valid (directly and from features described once,
// bitwise the same), and with its own place left out of the map every keyframe valid = 0.
void test_scan_to_map_among_other_places(const Keyframes &kf, const std::string &root) {
    const std::vector<double> tiles = distractor_tiles(root);
    if (harness_failed) return;
    kissm_matcher *m = make_matcher(KISSM_VIEWPOINT_LOCAL, 2), *one = make_matcher(KISSM_VIEWPOINT_LOCAL, 1);
    const kissm_points absent = view(tiles);
    kissm_features *absent_features = nullptr;
    REQUIRE(kissm_features_compute(m, &absent, &absent_features) == KISSM_OK);
    for (int k = 0; k < 5; ++k) {
        std::vector<double> map = tiles;
        for (int j = 0; j < 5; ++j)
            if (j != k) append_moved(kf.world[j], kf.cloud[j], map);
        const kissm_points scan = view(kf.cloud[k]), map_points = view(map);
        kissm_result direct = new_result(), reused = new_result(), serial = new_result(), away = new_result();
        CHECK(kissm_register(m, &scan, &map_points, &direct) == KISSM_OK);
        const Errors e = errors(direct, kf.world[k], kf.cloud[k]);
        std::printf(
            "scan-to-map among other places kf%d: valid %d, %.3f deg, %.3f m, %llu inliers, %llu map keypoints\n", k,
            direct.valid, e.rot_deg, e.trans_m, static_cast<unsigned long long>(direct.num_final_inliers),
            static_cast<unsigned long long>(direct.num_target_keypoints));
        CHECK_MSG(direct.valid && e.rot_deg < 2.0 && e.trans_m < 0.5, "keyframe %d among other places", k);
        kissm_features *map_features = nullptr, *scan_features = nullptr;
        REQUIRE(kissm_features_compute(m, &map_points, &map_features) == KISSM_OK);
        REQUIRE(kissm_features_compute(one, &scan, &scan_features) == KISSM_OK);
        CHECK(kissm_register_features(m, scan_features, map_features, &reused) == KISSM_OK);
        CHECK(kissm_register_features(one, scan_features, map_features, &serial) == KISSM_OK);
        CHECK_MSG(same_pose(direct, reused) && same_pose(direct, serial), "keyframe %d: reused map differs", k);
        // The scan's place left out: nothing may be reported valid.
        CHECK(kissm_register_features(m, scan_features, absent_features, &away) == KISSM_OK);
        std::printf("  its place left out: valid %d, %llu inliers\n", away.valid,
                    static_cast<unsigned long long>(away.num_final_inliers));
        CHECK_MSG(!away.valid, "keyframe %d valid against a map without its place", k);
        kissm_features_destroy(map_features);
        kissm_features_destroy(scan_features);
    }
    kissm_features_destroy(absent_features);
    kissm_destroy(m);
    kissm_destroy(one);
}

void test_map_to_map(const Keyframes &kf) {
    kissm_matcher *local = make_matcher(KISSM_VIEWPOINT_LOCAL, 2), *fixed = make_matcher(KISSM_VIEWPOINT_FIXED, 2);
    for (std::uint64_t seed = 1; seed <= 2; ++seed) {
        Rng rng{seed};
        const Pose frame_a = random_frame(rng, 300 + 500 * rng.uniform());
        const Pose frame_b = random_frame(rng, 300 + 500 * rng.uniform());
        std::vector<double> map_a, map_b;
        for (int j : {0, 1, 2}) append_moved(compose(frame_a, kf.world[j]), kf.cloud[j], map_a);
        for (int j : {3, 4}) append_moved(compose(frame_b, kf.world[j]), kf.cloud[j], map_b);
        const Pose truth = compose(frame_a, inverse(frame_b));
        const kissm_points a = view(map_a), b = view(map_b);
        kissm_result r = new_result(), f = new_result();
        CHECK(kissm_register(local, &b, &a, &r) == KISSM_OK);
        const Errors e = errors(r, truth, map_b);
        std::printf("map-to-map seed %llu: valid %d, %.3f deg, %.3f m, %llu inliers\n",
                    static_cast<unsigned long long>(seed), r.valid, e.rot_deg, e.trans_m,
                    static_cast<unsigned long long>(r.num_final_inliers));
        CHECK_MSG(r.valid && e.rot_deg < 2.0 && e.trans_m < 0.5, "map-to-map, seed %llu",
                  static_cast<unsigned long long>(seed));
        // The fixed viewpoint faces an origin hundreds of metres away: it may fail, never be wrong and valid.
        CHECK(kissm_register(fixed, &b, &a, &f) == KISSM_OK);
        const Errors ef = errors(f, truth, map_b);
        CHECK_MSG(!f.valid || (ef.rot_deg < 5.0 && ef.trans_m < 2.0), "fixed: valid but wrong (%.2f deg, %.2f m)",
                  ef.rot_deg, ef.trans_m);
    }
    kissm_destroy(local);
    kissm_destroy(fixed);
}

void test_moved_frames_and_shift(const Keyframes &kf) {
    kissm_matcher *m = make_matcher(KISSM_VIEWPOINT_LOCAL, 2);
    Rng rng{77};
    for (int k = 1; k < 5; ++k) {
        // Keyframe k against keyframe k-1, each in a frame of its own 40-80 m from its sensor.
        const Pose fs = random_frame(rng, 40 + 40 * rng.uniform()), ft = random_frame(rng, 40 + 40 * rng.uniform());
        const Pose step = compose(inverse(kf.world[k - 1]), kf.world[k]);
        std::vector<double> source, target;
        append_moved(fs, kf.cloud[k], source);
        append_moved(ft, kf.cloud[k - 1], target);
        const kissm_points s = view(source), t = view(target);
        kissm_result r = new_result();
        CHECK(kissm_register(m, &s, &t, &r) == KISSM_OK);
        const Errors e = errors(r, compose(ft, compose(step, inverse(fs))), source);
        CHECK_MSG(r.valid && e.rot_deg < 5.0 && e.trans_m < 2.0, "moved frames %d->%d: valid %d, %.2f deg, %.2f m", k,
                  k - 1, r.valid, e.rot_deg, e.trans_m);

        // The sensor frames shifted by whole metres up to 1e7 (exact for float32 data): the same rotation bits.
        const double shift[3] = {1e7, -3e6, 250.0};
        std::vector<double> s2 = kf.cloud[k], t2 = kf.cloud[k - 1];
        for (std::size_t i = 0; i < s2.size(); ++i) s2[i] += shift[i % 3];
        for (std::size_t i = 0; i < t2.size(); ++i) t2[i] += shift[i % 3];
        const kissm_points s0 = view(kf.cloud[k]), t0 = view(kf.cloud[k - 1]), s1 = view(s2), t1 = view(t2);
        kissm_result a = new_result(), b = new_result();
        CHECK(kissm_register(m, &s0, &t0, &a) == KISSM_OK);
        CHECK(kissm_register(m, &s1, &t1, &b) == KISSM_OK);
        CHECK_MSG(std::memcmp(a.rotation, b.rotation, sizeof a.rotation) == 0 &&
                      a.num_final_inliers == b.num_final_inliers,
                  "shift changed the rotation of %d->%d", k, k - 1);
        for (int i = 0; i < 3; ++i) { // t' = t + s - R s
            const double expect =
                a.translation[i] + shift[i] -
                (a.rotation[3 * i] * shift[0] + a.rotation[3 * i + 1] * shift[1] + a.rotation[3 * i + 2] * shift[2]);
            CHECK_MSG(std::fabs(b.translation[i] - expect) < 1e-6, "shifted translation %d: %.9f vs %.9f", i,
                      b.translation[i], expect);
        }
    }
    kissm_destroy(m);
}

} // namespace

int main() {
    const std::string root = data_root();
    if (root.empty()) return 77;
    const Keyframes kf = read_keyframes(root);
    for (const auto &c : kf.cloud) CHECK(!c.empty());
    if (harness_failed) return TEST_SUMMARY(); // a keyframe could not be read
    test_scan_to_map(kf);
    test_scan_to_map_among_other_places(kf, root);
    test_map_to_map(kf);
    test_moved_frames_and_shift(kf);
    return TEST_SUMMARY();
}

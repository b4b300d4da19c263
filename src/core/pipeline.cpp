// SPDX-License-Identifier: MIT
#include "pipeline.hpp"
#include "ambiguity.hpp"
#include "confidence.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <sstream>

#include "failure.hpp"
#include "fpfh.hpp"
#include "ground.hpp"
#include "input.hpp"
#include "matching.hpp"
#include "normals.hpp"
#include "place_gate.hpp"
#include "pose_solver.hpp"
#include "pruning.hpp"
#include "radius_search.hpp"
#include "voxel_suggest.hpp"
#include "voxelize.hpp"

KISSM_DETAIL_BEGIN

namespace {

// FPFH neighbours are weighted by (v / d)^2, not by 1/d as in the paper's Eq. (A5): it registered more pairs and
// reported no wrong pose as valid (docs/parameters.md, "FPFH weighting").
constexpr int kFpfhWeightPower = 2;

// Under ViewpointMode::Local a normal whose neighbours' mean offset along it is below this fraction of the normal
// radius keeps no sign: its pair features ignore it. Deciding those signs from noise cost a tenth of the
// coarse rotation accuracy of the sensor viewpoint on LiDAR pairs; leaving them open recovers it
// (docs/design/frames.md, "Open signs").
constexpr double kOpenSignGain = 0.1;

class Stopwatch {
public:
    Stopwatch() : last_(std::chrono::steady_clock::now()) {}
    // Milliseconds since the previous lap (or construction). Consecutive laps tile the time line, so the
    // stage times add up to the total exactly as measured.
    double lap() {
        const auto now = std::chrono::steady_clock::now();
        const auto ns = std::chrono::duration_cast<std::chrono::nanoseconds>(now - last_).count();
        last_ = now;
        return static_cast<double>(ns) * 1e-6;
    }

private:
    std::chrono::steady_clock::time_point last_;
};

// Params with voxel_size 0 (automatic) get the voxel suggested for `clouds` together; others are returned as given.
Params with_voxel_for(const Params &params, const std::vector<PointsView> &clouds,
                      const std::vector<const char *> &names) {
    if (params.voxel_size != 0.0) return params;
    Params p = params;
    p.voxel_size = suggest_voxel_size(clouds, names);
    return p;
}

} // namespace

bool same_descriptor_settings(const Params &a, const Params &b) {
    return a.voxel_size == b.voxel_size && a.normal_radius_gain == b.normal_radius_gain &&
           a.fpfh_radius_gain == b.fpfh_radius_gain && a.max_linearity == b.max_linearity &&
           a.min_normal_neighbors == b.min_normal_neighbors && a.nonfinite == b.nonfinite &&
           a.viewpoint_mode == b.viewpoint_mode && a.refine_normal_radius_gain == b.refine_normal_radius_gain &&
           (a.viewpoint_mode != ViewpointMode::Fixed || a.viewpoint == b.viewpoint) && a.suppression == b.suppression &&
           (a.suppression == Suppression::None ||
            (a.up == b.up && a.viewpoint == b.viewpoint && a.sensor_height == b.sensor_height));
}

namespace {

GroundParams ground_params(const Params &params, const Vec3d &cloud_origin) {
    GroundParams g;
    g.up = Vec3d(params.up[0], params.up[1], params.up[2]);
    // The voxels are offsets from cloud_origin; the sensor is at `viewpoint` in the cloud's own frame.
    g.sensor = Vec3d(params.viewpoint[0], params.viewpoint[1], params.viewpoint[2]) - cloud_origin;
    g.sensor_height = params.sensor_height;
    g.voxel_size = params.voxel_size;
    return g;
}

InputCloud gather_enough_points(const PointsView &view, const Params &params, const std::string &name,
                                RunContext &ctx) {
    InputCloud input = gather_points(view, params.nonfinite, name, ctx);
    if (input.num_finite() == 0)
        fail(ErrorKind::EmptyInput, name + " has no finite points (" + std::to_string(input.num_given) + " given)");
    if (input.num_finite() < 4)
        fail(ErrorKind::TooFewPoints,
             name + " has " + std::to_string(input.num_finite()) + " finite points; at least 4 are needed");
    return input;
}

void voxelize_cloud(const PointsView &view, const Params &params, const std::string &name, double progress,
                    CloudFeatures &f, RunContext &ctx) {
    f.params = params;
    Stopwatch clock;
    ctx.checkpoint(Stage::Voxelize, progress);
    InputCloud input = gather_enough_points(view, params, name, ctx);
    f.num_points = input.num_given;
    f.num_nonfinite = input.num_nonfinite;
    f.voxels = voxelize(input, params.voxel_size, name, ctx);
    f.time_voxelize_ms = clock.lap();
}

// Paper Sec. III-B: ground voxels give floods of look-alike descriptors, so they lose their keypoints; they
// keep their normals and stay in the cloud that refinement aligns.
void suppress_ground(const Params &params, std::vector<std::uint32_t> &keypoints, CloudFeatures &f, RunContext &ctx) {
    Stopwatch clock;
    const std::vector<std::uint8_t> ground =
        segment_ground(f.voxels.points, ground_params(params, f.voxels.origin), ctx);
    f.num_suppressed = static_cast<std::uint64_t>(std::count(ground.begin(), ground.end(), std::uint8_t(1)));
    keypoints.erase(std::remove_if(keypoints.begin(), keypoints.end(), [&](std::uint32_t k) { return ground[k] != 0; }),
                    keypoints.end());
    f.time_suppression_ms = clock.lap();
}

// What a normal and a plane need (radius, neighbours, linearity); the orientation is the caller's.
NormalParams normal_shape(const Params &params) {
    NormalParams np;
    np.normal_radius = static_cast<float>(params.normal_radius());
    np.min_neighbors = params.min_normal_neighbors;
    np.max_linearity = params.max_linearity;
    np.viewpoint = Vec3f::Zero();
    return np;
}

bool described_for_refinement(const Params &params, bool with_descriptors) {
    return params.refine_mode != RefineMode::None || !with_descriptors;
}

void describe_voxels(const Params &params, const std::string &name, double progress_from, double progress_to,
                     bool with_descriptors, CloudFeatures &f, RunContext &ctx) {
    Stopwatch clock;
    auto progress = [&](double part) {
        ctx.checkpoint(Stage::Features, progress_from + part * (progress_to - progress_from));
    };
    progress(0.0);
    const auto &pts = f.voxels.points;
    if (pts.size() > static_cast<std::size_t>(params.min_normal_neighbors)) {
        const Neighborhoods nb = radius_neighbors(pts, static_cast<float>(params.fpfh_radius()), ctx);
        progress(0.4);
        NormalParams np = normal_shape(params);
        const Vec3d vp =
            params.viewpoint_mode == ViewpointMode::Fixed
                ? Vec3d(Vec3d(params.viewpoint[0], params.viewpoint[1], params.viewpoint[2]) - f.voxels.origin)
                : Vec3d(Vec3d::Zero()); // the local origin is the bounding-box centre
        np.viewpoint = vp.cast<float>();
        np.orientation = params.viewpoint_mode == ViewpointMode::SignFree ? NormalOrientation::Unoriented
                         : params.viewpoint_mode == ViewpointMode::Local  ? NormalOrientation::AwayFromNeighbours
                                                                          : NormalOrientation::TowardViewpoint;
        if (params.viewpoint_mode == ViewpointMode::Local)
            np.open_sign_offset = static_cast<float>(kOpenSignGain * params.normal_radius());
        // The planes only where refinement will read them (refine_mode on, or kissm_refine's clouds): the default
        // path does not pay for them, and refining features described without them fits them then.
        f.has_planes = described_for_refinement(params, with_descriptors);
        const float plane_radius = f.has_planes ? static_cast<float>(params.refine_normal_radius()) : 0.0f;
        NormalSets sets = estimate_normal_sets(pts, nb, np, plane_radius, ctx);
        f.normals = std::move(sets.normals);
        f.plane_normals = std::move(sets.planes);
        progress(0.6);
        if (with_descriptors) {
            std::vector<std::uint32_t> keypoints = select_keypoints(nb, f.normals, params.min_normal_neighbors);
            if (params.suppression == Suppression::Ground) suppress_ground(params, keypoints, f, ctx);
            const NormalSigns signs = params.viewpoint_mode == ViewpointMode::SignFree ? NormalSigns::Ignored
                                      : params.viewpoint_mode == ViewpointMode::Local  ? NormalSigns::Mixed
                                                                                       : NormalSigns::Oriented;
            f.descriptors = compute_fpfh(pts, nb, f.normals, signs, std::move(keypoints),
                                         static_cast<float>(params.voxel_size), kFpfhWeightPower, ctx);
        }
        f.normals.open_sign = std::vector<std::uint8_t>(); // read by the descriptors only
    } else {
        f.normals.normal.assign(pts.size(), Vec3f::Zero());
        f.normals.valid.assign(pts.size(), 0);
        f.has_planes = described_for_refinement(params, with_descriptors);
        if (f.has_planes) f.plane_normals = f.normals;
    }
    // The index refinement searches, kept with the features so that a map is indexed once.
    if (params.refine_mode != RefineMode::None) f.index = RefineIndex(pts, params.voxel_size);
    f.time_features_ms = clock.lap();
    if (ctx.logs(LogLevel::Info)) {
        std::ostringstream msg;
        msg << name << ": " << f.num_points << " points, " << f.voxels.points.size() << " voxels, "
            << f.descriptors.keypoint.size() << " keypoints";
        ctx.log(LogLevel::Info, msg.str());
    }
}

// Whether the place gate could take cloud c of a pair as the map (PlaceRegion::find's size rule).
bool gate_may_read_grid(const std::vector<CloudFeatures *> &pair, std::size_t c) {
    const std::size_t mine = pair[c]->descriptors.keypoint.size();
    for (std::size_t o = 0; o < pair.size(); ++o)
        if (o != c && mine < PlaceRegion::kMinSizeRatio * pair[o]->descriptors.keypoint.size()) return false;
    return true;
}

// Which clouds get a keypoint grid: every one (features to keep), or only those the place gate could read.
enum class Grids { All, ForThePlaceGate };

// The descriptors' search indexes, built together (the trees side by side when there are threads); each
// cloud's feature time gains its share of the build by keypoints. A pair described for one registration
// needs a keypoint grid only on a side with kMinSizeRatio times the other's keypoints (the place gate reads no
// other), so similar clouds skip it; features kept for later always get theirs.
void index_descriptors(const std::vector<CloudFeatures *> &clouds, Grids grids, RunContext &ctx) {
    Stopwatch clock;
    std::vector<const Descriptors *> descriptors;
    double keypoints = 0.0;
    for (const CloudFeatures *f : clouds) {
        descriptors.push_back(&f->descriptors);
        keypoints += static_cast<double>(f->descriptors.keypoint.size());
    }
    std::vector<DescriptorIndex> built = DescriptorIndex::build(descriptors, ctx);
    ctx.parallel_for(clouds.size(), 1, [&](std::size_t b, std::size_t e) {
        for (std::size_t c = b; c < e; ++c)
            if (grids == Grids::All || gate_may_read_grid(clouds, c))
                clouds[c]->keypoint_grid = keypoint_grid_of(*clouds[c]);
    });
    const double ms = clock.lap();
    for (std::size_t c = 0; c < clouds.size(); ++c) {
        clouds[c]->descriptor_index = std::move(built[c]);
        if (keypoints > 0.0)
            clouds[c]->time_features_ms += ms * static_cast<double>(clouds[c]->descriptors.keypoint.size()) / keypoints;
    }
}

} // namespace

KeypointGrid keypoint_grid_of(const CloudFeatures &f) {
    return KeypointGrid(f.voxels.points, f.descriptors.keypoint, kKeypointColumnVoxels * f.params.voxel_size);
}

std::size_t features_bytes(const CloudFeatures &f) {
    return f.voxels.points.capacity() * sizeof(Vec3f) +
           (f.normals.normal.capacity() + f.plane_normals.normal.capacity()) * sizeof(Vec3f) +
           f.normals.valid.capacity() + f.plane_normals.valid.capacity() +
           f.descriptors.keypoint.capacity() * sizeof(std::uint32_t) + f.descriptors.values.capacity() * sizeof(float) +
           f.descriptor_index.bytes() + f.keypoint_grid.bytes() + f.index.bytes();
}

CloudFeatures describe_cloud(const PointsView &view, const Params &given, const std::string &name, RunContext &ctx) {
    CloudFeatures f;
    Stopwatch clock;
    const Params params = with_voxel_for(given, {view}, {name.c_str()}); // a cloud alone: its own suggestion
    const double suggest_ms = clock.lap();
    voxelize_cloud(view, params, name, 0.0, f, ctx);
    f.time_voxelize_ms += suggest_ms;
    describe_voxels(params, name, 0.0, 1.0, true, f, ctx);
    index_descriptors({&f}, Grids::All, ctx);
    return f;
}

namespace {

std::pair<CloudFeatures, CloudFeatures> describe_both(const PointsView &source, const PointsView &target,
                                                      const Params &params, bool with_descriptors, RunContext &ctx) {
    // Both clouds pass each stage before either enters the next, so progress never goes back.
    std::pair<CloudFeatures, CloudFeatures> p;
    voxelize_cloud(source, params, "source", 0.0, p.first, ctx);
    voxelize_cloud(target, params, "target", 0.5, p.second, ctx);
    describe_voxels(params, "source", 0.0, 0.5, with_descriptors, p.first, ctx);
    describe_voxels(params, "target", 0.5, 1.0, with_descriptors, p.second, ctx);
    if (with_descriptors) index_descriptors({&p.first, &p.second}, Grids::ForThePlaceGate, ctx);
    return p;
}

// The matcher's params for features described apart: under voxel_size 0 (automatic) the features' own voxel, which
// must then be one voxel for both (each cloud's own suggestion differs in general: the pair's is needed).
Params params_for_features(const CloudFeatures &source, const CloudFeatures &target, const Params &params) {
    if (params.voxel_size != 0.0) return params;
    if (source.params.voxel_size != target.params.voxel_size) {
        std::ostringstream msg;
        msg.precision(17);
        msg << "source features were computed with voxel size " << source.params.voxel_size << " and target features "
            << "with " << target.params.voxel_size << "; with an automatic voxel size both must use one voxel (compute "
            << "them with the voxel kissm_suggest_voxel_size gives for both clouds together)";
        fail(ErrorKind::FeaturesMismatch, msg.str());
    }
    Params p = params;
    p.voxel_size = source.params.voxel_size;
    return p;
}

void require_same_settings(const CloudFeatures &source, const CloudFeatures &target, const Params &params) {
    for (const auto *f : {&source, &target}) {
        if (!same_descriptor_settings(f->params, params))
            fail(ErrorKind::FeaturesMismatch, std::string(f == &source ? "source" : "target") +
                                                  " features were computed with descriptor settings (voxel size, "
                                                  "radii, tau, viewpoint) that differ from the matcher's");
    }
}

// sqrt of the largest eigenvalue of inv(information)'s rotation block; infinite for a singular information.
double rotation_sigma(const Matrix6d &information) {
    if (!information.allFinite()) return std::numeric_limits<double>::infinity();
    const Eigen::LDLT<Matrix6d> ldlt(information);
    if (ldlt.info() != Eigen::Success || !ldlt.isPositive() || !(ldlt.vectorD().minCoeff() > 0.0))
        return std::numeric_limits<double>::infinity();
    const Matrix6d cov = ldlt.solve(Matrix6d::Identity());
    const Eigen::Matrix3d rot = 0.5 * (cov.topLeftCorner<3, 3>() + cov.topLeftCorner<3, 3>().transpose());
    const double worst = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(rot, Eigen::EigenvaluesOnly).eigenvalues()[2];
    return worst >= 0.0 ? std::sqrt(worst) : std::numeric_limits<double>::infinity();
}

RefinedEvidence refined_evidence(const Registration &r) {
    RefinedEvidence e;
    e.num_correspondences = r.num_refine_correspondences;
    e.overlap = r.overlap;
    e.condition = r.refine_condition;
    e.inlier_coverage = r.inlier_coverage;
    e.converged = r.refine_converged;
    e.rmse = r.refine_rmse;
    e.degenerate = r.degenerate;
    e.rotation_sigma = rotation_sigma(r.information);
    return e;
}

RefinedRule refined_rule(const Params &params) {
    return RefinedRule{static_cast<std::uint64_t>(params.refine_min_inliers),
                       params.max_rotation_uncertainty,
                       params.min_overlap,
                       params.min_refine_condition,
                       params.min_inlier_coverage,
                       params.max_refine_rmse(),
                       kLooseRmseGain * params.voxel_size,
                       params.allow_degenerate != 0};
}

RefineParams refine_params(const Params &params) {
    RefineParams rp;
    rp.mode = params.refine_mode;
    rp.max_iterations = params.refine_max_iterations;
    rp.max_distance = params.refine_max_distance();
    rp.kernel_scale = params.refine_kernel_gain * params.voxel_size;
    rp.rotation_epsilon = params.refine_rotation_epsilon;
    rp.translation_epsilon = params.refine_translation_epsilon_gain * params.voxel_size;
    return rp;
}

// The planes of features described without them, as describing for refinement would have fitted them: the same
// neighbour rows (the FPFH-radius search), the same pass without the normals, so the same bits.
Normals planes_of(const CloudFeatures &f, RunContext &ctx) {
    const Params &params = f.params;
    const auto &pts = f.voxels.points;
    if (pts.size() <= static_cast<std::size_t>(params.min_normal_neighbors)) {
        Normals none;
        none.normal.assign(pts.size(), Vec3f::Zero());
        none.valid.assign(pts.size(), 0);
        return none;
    }
    const Neighborhoods nb = radius_neighbors(pts, static_cast<float>(params.fpfh_radius()), ctx);
    return estimate_planes(pts, nb, normal_shape(params), static_cast<float>(params.refine_normal_radius()), ctx);
}

// Stage 6 from (R, t) in the callers' frames: r's pose becomes the refined one, with its numbers.
void refine_registration(const CloudFeatures &source, const CloudFeatures &target, const Eigen::Matrix3d &R,
                         const Eigen::Vector3d &t, const Params &params, Registration &r, RunContext &ctx) {
    Stopwatch clock;
    ctx.checkpoint(Stage::Refine, 0.0);
    const Vec3d &os = source.voxels.origin, &ot = target.voxels.origin;
    // p_t - o_t = R (p_s - o_s) + (t + R o_s - o_t): the same pose between the local frames.
    const Eigen::Vector3d t_local = t + R * os - ot;
    RefineIndex built;
    const RefineIndex *index = &target.index;
    if (index->empty()) {
        built = RefineIndex(target.voxels.points, params.voxel_size);
        index = &built;
    }
    Normals source_fitted, target_fitted;
    const Normals &source_planes = source.has_planes ? source.plane_normals : (source_fitted = planes_of(source, ctx));
    const Normals &target_planes = target.has_planes ? target.plane_normals : (target_fitted = planes_of(target, ctx));
    const RefineOutput o =
        refine_pose(RefineCloud{&source.voxels.points, &source_planes},
                    RefineCloud{&target.voxels.points, &target_planes}, *index, R, t_local, refine_params(params), ctx);
    r.refined = true;
    r.rotation = o.rotation;
    r.translation = o.translation + ot - o.rotation * os;
    r.information = information_in_caller_frame(o, os, calibrated_variance(o, params.voxel_size));
    r.overlap = o.overlap;
    r.refine_rmse = o.num_correspondences > 0 ? o.rmse : std::numeric_limits<double>::quiet_NaN();
    r.refine_iterations = o.iterations;
    r.refine_converged = o.converged;
    r.num_refine_correspondences = o.num_correspondences;
    r.refine_condition = o.condition;
    r.weak_directions = weak_directions_in_caller_frame(o, os, params.min_refine_condition);
    r.degenerate = !r.weak_directions.empty();
    r.overlap_spread = o.overlap_spread;
    // The solver's inliers against the aligned overlap (principal standard deviations, both in the source frame).
    if (r.num_final_inliers > 0 && o.overlap_spread > 0.0) r.inlier_coverage = r.inlier_extent[0] / o.overlap_spread;
    r.time_refine_ms = clock.lap();
    ctx.checkpoint(Stage::Refine, 1.0);
}

} // namespace

std::pair<CloudFeatures, CloudFeatures> describe_pair(const PointsView &source, const PointsView &target,
                                                      const Params &params, RunContext &ctx) {
    return describe_both(source, target, params, true, ctx);
}

namespace {

// The counts of what describing found, and the solver's noise bound: reported whatever happens next.
Registration described_counts(const CloudFeatures &source, const CloudFeatures &target, const Params &params) {
    Registration r;
    r.num_source_points = source.num_points, r.num_target_points = target.num_points;
    r.num_source_nonfinite = source.num_nonfinite, r.num_target_nonfinite = target.num_nonfinite;
    r.num_source_voxels = source.voxels.points.size(), r.num_target_voxels = target.voxels.points.size();
    r.num_source_keypoints = source.descriptors.keypoint.size();
    r.num_target_keypoints = target.descriptors.keypoint.size();
    r.num_source_suppressed = source.num_suppressed, r.num_target_suppressed = target.num_suppressed;
    r.noise_bound = params.solver_noise_bound();
    r.voxel_size_used = params.voxel_size;
    return r;
}

IndexedDescriptors indexed(const CloudFeatures &f) {
    return IndexedDescriptors{&f.descriptors, &f.descriptor_index, &f.voxels.points, &f.keypoint_grid};
}

std::vector<Eigen::Vector3d> as_double(const std::vector<Vec3f> &points) {
    std::vector<Eigen::Vector3d> out(points.size());
    for (std::size_t k = 0; k < points.size(); ++k) out[k] = points[k].cast<double>();
    return out;
}

std::vector<Eigen::Vector3d> as_double(const std::vector<Vec3f> &points, const std::vector<std::uint32_t> &subset) {
    std::vector<Eigen::Vector3d> out(subset.size());
    for (std::size_t k = 0; k < subset.size(); ++k) out[k] = points[subset[k]].cast<double>();
    return out;
}

// The solver's pose, polished over all initial correspondences (pruning is conservative: matches it dropped
// but that agree with the pose both confirm it and sharpen the least squares), in the callers' frames, with the
// final inliers' residual and evidence.
InlierEvidence final_inliers(const std::vector<Eigen::Vector3d> &a, const std::vector<Eigen::Vector3d> &b,
                             const PoseSolver &solver, SolverOutput &sol, const CloudFeatures &source,
                             const CloudFeatures &target, Registration &r) {
    std::vector<std::uint8_t> inlier;
    r.num_final_inliers = solver.polish(a, b, sol.rotation, sol.translation, inlier);
    r.inlier_ratio = static_cast<double>(r.num_final_inliers) / static_cast<double>(r.num_initial_correspondences);
    // Back to the callers' frames: p_t = R (p_s - o_s) + t_local + o_t.
    r.rotation = sol.rotation;
    r.translation = sol.translation + target.voxels.origin - sol.rotation * source.voxels.origin;
    r.solved = true;
    std::vector<Eigen::Vector3d> inlier_points;
    double sq = 0.0;
    for (std::size_t k = 0; k < a.size(); ++k) {
        if (!inlier[k]) continue;
        inlier_points.push_back(a[k]);
        sq += (sol.rotation * a[k] + sol.translation - b[k]).squaredNorm();
    }
    if (!inlier_points.empty()) r.residual_rms = std::sqrt(sq / static_cast<double>(inlier_points.size()));
    const InlierEvidence inliers = inlier_evidence(inlier_points, r.noise_bound);
    r.inlier_extent = inliers.extent;
    r.rotation_uncertainty = inliers.rotation_uncertainty;
    return inliers;
}

// The result's confidence (confidence.hpp) from its own numbers; `solver`: the global solver estimated the pose.
double confidence_of(const Registration &r, const Params &params, bool solver) {
    ConfidenceInput in;
    in.has_pose = r.solved && r.rotation.allFinite() && r.translation.allFinite();
    in.solver = solver;
    in.refined = r.refined;
    in.inliers = r.num_final_inliers;
    in.ambiguity = r.ambiguity;
    in.overlap = r.overlap;
    in.refine_rmse_voxels = r.refine_rmse / params.voxel_size;
    return pose_confidence(in);
}

void log_counts(const Registration &r, RunContext &ctx) {
    if (!ctx.logs(LogLevel::Info)) return;
    std::ostringstream msg;
    msg << "matches " << r.num_initial_correspondences << ", max core " << r.num_pruned_correspondences
        << " (k=" << r.max_core_number << "), rotation inliers " << r.num_rotation_inliers << ", final inliers "
        << r.num_final_inliers;
    ctx.log(LogLevel::Info, msg.str());
}

} // namespace

Registration register_described(const CloudFeatures &source, const CloudFeatures &target, const Params &params,
                                RunContext &ctx) {
    Registration r = described_counts(source, target, params);
    r.reason = describable(r.num_source_voxels, r.num_target_voxels, r.num_source_keypoints, r.num_target_keypoints,
                           static_cast<std::uint64_t>(params.min_normal_neighbors) + 1);
    if (r.reason != Reason::None) return r;
    Stopwatch clock;

    // 3. Matching.
    ctx.checkpoint(Stage::Matching, 0.0);
    const MatchParams mp{params.ratio_test, params.max_correspondences};
    const std::vector<Correspondence> matches = match_descriptors(indexed(source), indexed(target), mp, ctx);
    const MatchedPoints matched = matched_points(indexed(source), indexed(target), matches);
    r.num_initial_correspondences = matched.source.size();
    r.time_matching_ms = clock.lap();
    if (matched.source.size() < 3) {
        r.reason = Reason::TooFewCorrespondences;
        return r;
    }

    // 4. Pruning.
    ctx.checkpoint(Stage::Pruning, 0.0);
    const PoseSolver solver(params);
    PrunedMatches pruned =
        prune_matches(matched.source, matched.target, params.prune_noise_bound(), solver.max_measurements(), ctx);
    r.max_core_number = pruned.max_core_number;
    r.num_pruned_correspondences = pruned.core.size();
    r.time_pruning_ms = clock.lap();
    if (pruned.core.size() < 3) {
        r.reason = Reason::TooFewCorrespondences;
        return r;
    }

    // 5. Solver, on the max core; then the final inliers over every match.
    ctx.checkpoint(Stage::Solver, 0.0);
    PoseSolution pose = solver.solve(as_double(matched.source, pruned.core), as_double(matched.target, pruned.core),
                                     pruned.measurements, ctx);
    r.tilt = pose.tilt;
    r.num_rotation_inliers = pose.solver.num_rotation_inliers;
    if (!pose.solver.solved) {
        r.reason = Reason::SolverFailed;
        r.time_solver_ms = clock.lap();
        return r;
    }
    const std::vector<Eigen::Vector3d> match_source = as_double(matched.source),
                                       match_target = as_double(matched.target);
    const InlierEvidence inliers = final_inliers(match_source, match_target, solver, pose.solver, source, target, r);

    // 5c. Ambiguity: the best competing pose's support (ambiguity.hpp), measured before the rules so that every
    // result with a pose carries it; the rule that reads it comes last (below).
    const AmbiguityInput competition{&match_source,        &match_target,         &pruned.core,
                                     &pruned.measurements, &pruned.second_core,   &pruned.second_measurements,
                                     r.num_final_inliers,  &source.voxels.points, &target.voxels.points,
                                     &source.normals,      params.voxel_size};
    r.ambiguity = measure_ambiguity(competition, solver, pose.solver.rotation, pose.solver.translation, ctx).value;

    // 5b. Validity without refinement.
    r.reason = r.rotation.allFinite() && r.translation.allFinite()
                   ? coarse_validity(
                         r.num_final_inliers, inliers,
                         CoarseRule{static_cast<std::uint64_t>(params.min_inliers), params.max_rotation_uncertainty})
                   : Reason::SolverFailed;
    const bool tilted =
        solver.yaw_only() && yaw_pose_refuted(YawEvidence{r.num_rotation_inliers, r.num_pruned_correspondences, r.tilt},
                                              params.max_rotation_uncertainty);
    if (tilted && r.reason == Reason::None) r.reason = Reason::Tilted;
    r.coarse_rotation = r.rotation;
    r.coarse_translation = r.translation;
    r.time_solver_ms = clock.lap();
    log_counts(r, ctx);
    ctx.checkpoint(Stage::Solver, 1.0);

    // 6. Refinement, and its validity (a yaw pose the data call tilted stays refused: the caller asked for zero
    // roll and pitch and the clouds disagree).
    if (params.refine_mode != RefineMode::None && r.reason != Reason::SolverFailed) {
        refine_registration(source, target, r.coarse_rotation, r.coarse_translation, params, r, ctx);
        r.reason = refined_validity(r.num_final_inliers, inliers, refined_evidence(r), refined_rule(params));
        if (tilted && r.reason == Reason::None) r.reason = Reason::Tilted;
    } else if ((r.reason == Reason::UncertainRotation ||
                (r.reason == Reason::TooFewInliers &&
                 r.num_final_inliers >= static_cast<std::uint64_t>(params.refine_min_inliers)) ||
                (r.reason == Reason::None &&
                 !(kCoarseConfirmSigmas * inliers.rotation_uncertainty <= params.max_rotation_uncertainty))) &&
               !tilted) {
        // Few inliers on a compact object leave the rotation uncertain by a few degrees whether the pose is right
        // or wrong, and a pair of low overlap (keyframes far apart, the ground suppressed) keeps fewer inliers than
        // min_inliers with the right pose, so the coarse evidence cannot decide; the dense alignment can. Refined with
        // GICP, the pose is reported when the refined rule accepts it (the rule of refine_mode GICP, inliers
        // included: refine_min_inliers), and the coarse result stands otherwise (docs/design/accuracy.md,
        // "Verifying uncertain rotations"). A valid pose whose rotation is known to the bound at one sigma but not
        // at two is refined the same way: reported refined when the refined rule accepts it, else not valid.
        Params verify = params;
        verify.refine_mode = RefineMode::Gicp;
        Registration refined = r;
        refine_registration(source, target, r.coarse_rotation, r.coarse_translation, verify, refined, ctx);
        refined.reason =
            refined_validity(refined.num_final_inliers, inliers, refined_evidence(refined), refined_rule(verify));
        if (refined.reason == Reason::None)
            r = std::move(refined);
        else if (r.reason == Reason::None)
            // A pose the dense alignment refuses is not valid, checked because its rotation was uncertain: the
            // wrong coarse poses of the simulated city and the Happy Buddha set (118-121 degrees off) left valid
            // otherwise; no right one measured was lost (docs/design/accuracy.md). The coarse pose stays.
            r.reason = refined.reason;
    }
    // Last, so that the reason names what else is wrong first: refinement cannot resolve ambiguity (the scene
    // aligns as well at the competitor), so a refined pose is refused for it too.
    if (r.reason == Reason::None && !(r.ambiguity <= params.max_ambiguity)) r.reason = Reason::Ambiguous;
    r.confidence = confidence_of(r, params, true);
    return r;
}

Registration register_points(const PointsView &source, const PointsView &target, const Params &given, RunContext &ctx) {
    Stopwatch clock;
    const Params params = with_voxel_for(given, {source, target}, {"source", "target"});
    const double suggest_ms = clock.lap();
    const auto clouds = describe_pair(source, target, params, ctx);
    Registration r = register_described(clouds.first, clouds.second, params, ctx);
    r.time_voxelize_ms = suggest_ms + clouds.first.time_voxelize_ms + clouds.second.time_voxelize_ms;
    r.time_features_ms = clouds.first.time_features_ms + clouds.second.time_features_ms;
    r.time_suppression_ms = clouds.first.time_suppression_ms + clouds.second.time_suppression_ms;
    return r;
}

Registration register_features(const CloudFeatures &source, const CloudFeatures &target, const Params &given,
                               RunContext &ctx) {
    const Params params = params_for_features(source, target, given);
    require_same_settings(source, target, params);
    return register_described(source, target, params, ctx);
}

namespace {

// A refinement from the caller's pose: no solver ran, so only the refined evidence decides.
Registration refine_described(const CloudFeatures &source, const CloudFeatures &target, const Eigen::Matrix3d &R,
                              const Eigen::Vector3d &t, const Params &params, RunContext &ctx) {
    Registration r;
    r.num_source_points = source.num_points, r.num_target_points = target.num_points;
    r.num_source_nonfinite = source.num_nonfinite, r.num_target_nonfinite = target.num_nonfinite;
    r.num_source_voxels = source.voxels.points.size(), r.num_target_voxels = target.voxels.points.size();
    r.noise_bound = params.solver_noise_bound(); // keypoints stay 0: refinement uses no descriptor
    r.voxel_size_used = params.voxel_size;
    r.coarse_rotation = R;
    r.coarse_translation = t;
    r.solved = true;
    Params p = params;
    if (p.refine_mode == RefineMode::None) p.refine_mode = RefineMode::Gicp;
    refine_registration(source, target, R, t, p, r, ctx);
    r.reason = prior_validity(refined_evidence(r), refined_rule(p));
    r.confidence = confidence_of(r, params, false);
    return r;
}

} // namespace

Registration refine_points(const PointsView &source, const PointsView &target, const Eigen::Matrix3d &initial_rotation,
                           const Eigen::Vector3d &initial_translation, const Params &given, RunContext &ctx) {
    Stopwatch clock;
    const Params params = with_voxel_for(given, {source, target}, {"source", "target"});
    const double suggest_ms = clock.lap();
    const auto clouds = describe_both(source, target, params, false, ctx);
    Registration r = refine_described(clouds.first, clouds.second, initial_rotation, initial_translation, params, ctx);
    r.time_voxelize_ms = suggest_ms + clouds.first.time_voxelize_ms + clouds.second.time_voxelize_ms;
    r.time_features_ms = clouds.first.time_features_ms + clouds.second.time_features_ms;
    return r;
}

Registration refine_features(const CloudFeatures &source, const CloudFeatures &target,
                             const Eigen::Matrix3d &initial_rotation, const Eigen::Vector3d &initial_translation,
                             const Params &given, RunContext &ctx) {
    const Params params = params_for_features(source, target, given);
    require_same_settings(source, target, params);
    return refine_described(source, target, initial_rotation, initial_translation, params, ctx);
}

std::vector<std::uint8_t> ground_mask(const PointsView &view, const Params &given, RunContext &ctx) {
    ctx.checkpoint(Stage::Voxelize, 0.0);
    const Params params = with_voxel_for(given, {view}, {"points"});
    const InputCloud input = gather_enough_points(view, params, "points", ctx);
    std::vector<std::uint64_t> keys;
    const VoxelCloud voxels = voxelize(input, params.voxel_size, "points", ctx, &keys);
    const std::vector<std::uint32_t> voxel = voxel_of_points(input, params.voxel_size, "points", keys, ctx);
    ctx.checkpoint(Stage::Features, 0.0);
    const std::vector<std::uint8_t> ground = segment_ground(voxels.points, ground_params(params, voxels.origin), ctx);
    std::vector<std::uint8_t> mask(voxel.size(), 0);
    for (std::size_t i = 0; i < voxel.size(); ++i)
        if (voxel[i] != kNoVoxel) mask[i] = ground[voxel[i]];
    ctx.checkpoint(Stage::Features, 1.0);
    return mask;
}

KISSM_DETAIL_END

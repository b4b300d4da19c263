// SPDX-License-Identifier: MIT
//! [`Registration`]: the pose and every number behind the decision to trust it.

use kissm_sys as sys;

use crate::error::static_str;

/// Why a registration gave no trustworthy pose ([`Registration::valid`] is `false`).
///
/// A well-formed input that gives no trustworthy pose is not an error: the call succeeds and says why.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Reason {
    /// The pose is valid.
    None,
    /// A cloud has too few occupied voxels to describe.
    TooFewVoxels,
    /// A cloud has too few points with a reliable descriptor.
    TooFewFeatures,
    /// Matching or pruning left too few correspondences.
    TooFewCorrespondences,
    /// The robust solver found no consistent rotation.
    SolverFailed,
    /// Final inliers below [`Config::min_inliers`](crate::Config::min_inliers) (with refinement:
    /// [`Config::refine_min_inliers`](crate::Config::refine_min_inliers)).
    TooFewInliers,
    /// The inliers are collinear or planar: the pose is ambiguous.
    Degenerate,
    /// Refinement ran and its pose lays too little of the source onto the target:
    /// [`Refinement::overlap`] below [`Config::min_overlap`](crate::Config::min_overlap), or fewer than 6
    /// correspondences.
    LowOverlap,
    /// Refinement ran and the aligned clouds leave a direction of the pose free (a plane, a corridor, a
    /// tunnel): [`Refinement::condition`] below [`Config::min_refine_condition`](crate::Config::min_refine_condition),
    /// so [`Refinement::degenerate`] is true and [`Refinement::weak_directions`] gives the free directions;
    /// see also [`Refinement::information`]. [`Config::allow_degenerate`](crate::Config::allow_degenerate)
    /// accepts such a pose.
    Unconstrained,
    /// Without refinement: the inliers pin the rotation down no better than
    /// [`Config::max_rotation_uncertainty`](crate::Config::max_rotation_uncertainty)
    /// ([`Registration::rotation_uncertainty`] above it): too few of them, or all on one compact object.
    UncertainRotation,
    /// With refinement: the solver's inliers cover less than
    /// [`Config::min_inlier_coverage`](crate::Config::min_inlier_coverage) of the aligned overlap
    /// ([`Refinement::inlier_coverage`] below it): one object may match itself in several poses.
    ClusteredInliers,
    /// With refinement (and in [`Matcher::refine`](crate::Matcher::refine)): refinement was still moving the
    /// pose at [`Config::refine_max_iterations`](crate::Config::refine_max_iterations)
    /// ([`Refinement::converged`] is false): it was crossing from one basin to another, as refinements from
    /// a wrong start do.
    NotConverged,
    /// With [`Config::rotation_dof`](crate::Config::rotation_dof) 1: the best unconstrained rotation on the
    /// yaw solution's inliers turns [`Config::up`](crate::Config::up) by more than
    /// [`Config::max_rotation_uncertainty`](crate::Config::max_rotation_uncertainty)
    /// ([`Registration::tilt`] above it): the clouds' relative roll or pitch is not zero, so the yaw-only
    /// pose would be off by at least that much.
    Tilted,
    /// With refinement (and in [`Matcher::refine`](crate::Matcher::refine)): the refined clouds stay farther
    /// apart than [`Config::max_refine_rmse_gain`](crate::Config::max_refine_rmse_gain) voxel sizes
    /// ([`Refinement::rmse`] above it): a local optimum beside the right pose, as a refinement from a prior
    /// outside its convergence basin reaches (a road shifted along itself, a scene turned onto its symmetry).
    LooseAlignment,
    /// The scene holds a second pose, distinct from the one returned, with nearly as much support
    /// ([`Registration::ambiguity`] above [`Config::max_ambiguity`](crate::Config::max_ambiguity)): a repetitive
    /// or symmetric scene (a street of identical facades, pillars at a regular spacing, a symmetric object) that
    /// matches as well one period along or turned onto its own symmetry. A prior or a check from elsewhere must
    /// choose.
    Ambiguous,
    /// With refinement: the refined clouds stay more than 0.37 voxel apart ([`Refinement::rmse`]) while the pose
    /// is weakly constrained ([`Refinement::condition`] below 0.09): a partial match of repeated structure (a
    /// street's ground and one facade lined up, the rest apart, the pose free to slide along it).
    LooseAndWeak,
    /// A reason this version of the crate does not know (from a newer library), with its code.
    Other(i32),
}

c_codes!(Reason, "KISSM_REASON_", "reason", Other {
    None => sys::KISSM_REASON_NONE,
    TooFewVoxels => sys::KISSM_REASON_TOO_FEW_VOXELS,
    TooFewFeatures => sys::KISSM_REASON_TOO_FEW_FEATURES,
    TooFewCorrespondences => sys::KISSM_REASON_TOO_FEW_CORRESPONDENCES,
    SolverFailed => sys::KISSM_REASON_SOLVER_FAILED,
    TooFewInliers => sys::KISSM_REASON_TOO_FEW_INLIERS,
    Degenerate => sys::KISSM_REASON_DEGENERATE,
    LowOverlap => sys::KISSM_REASON_LOW_OVERLAP,
    Unconstrained => sys::KISSM_REASON_UNCONSTRAINED,
    UncertainRotation => sys::KISSM_REASON_UNCERTAIN_ROTATION,
    ClusteredInliers => sys::KISSM_REASON_CLUSTERED_INLIERS,
    NotConverged => sys::KISSM_REASON_NOT_CONVERGED,
    Tilted => sys::KISSM_REASON_TILTED,
    Ambiguous => sys::KISSM_REASON_AMBIGUOUS,
    LooseAlignment => sys::KISSM_REASON_LOOSE_ALIGNMENT,
    LooseAndWeak => sys::KISSM_REASON_LOOSE_AND_WEAK,
});

impl Reason {
    /// The library's static description (`kissm_reason_string()`), such as `"none"`.
    pub fn as_str(self) -> &'static str {
        // SAFETY: no preconditions; returns a static string.
        static_str(unsafe { sys::kissm_reason_string(self.code()) }, "unknown reason")
    }
}

impl std::fmt::Display for Reason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Counts behind a registration, per stage.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
#[non_exhaustive]
pub struct Counts {
    /// Source points given.
    pub source_points: u64,
    /// Target points given.
    pub target_points: u64,
    /// Source points dropped as non-finite (under [`NonFinitePolicy::Drop`](crate::NonFinitePolicy::Drop)).
    pub source_nonfinite: u64,
    /// Target points dropped as non-finite.
    pub target_nonfinite: u64,
    /// Occupied source voxels.
    pub source_voxels: u64,
    /// Occupied target voxels.
    pub target_voxels: u64,
    /// Source voxels with a descriptor.
    pub source_keypoints: u64,
    /// Target voxels with a descriptor.
    pub target_keypoints: u64,
    /// Mutual, ratio-tested, capped matches.
    pub initial_correspondences: u64,
    /// Correspondences in the maximum k-core.
    pub pruned_correspondences: u64,
    /// The k of the maximum k-core.
    pub max_core_number: u64,
    /// Pruned correspondences the rotation solver kept.
    pub rotation_inliers: u64,
    /// Pruned correspondences within the solver bound after rotation and translation.
    pub final_inliers: u64,
    /// Source voxels [`Config::suppression`](crate::Config::suppression) kept from becoming keypoints (0
    /// when it is [`Suppression::None`](crate::Suppression::None)).
    pub source_suppressed: u64,
    /// Target voxels [`Config::suppression`](crate::Config::suppression) kept from becoming keypoints (0
    /// when it is off).
    pub target_suppressed: u64,
}

/// Wall-clock milliseconds per stage (stages not run are 0). The only values that differ between
/// identical calls.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[non_exhaustive]
pub struct Timings {
    /// Input checks, recentring and voxelisation.
    pub voxelize_ms: f64,
    /// Neighbour search, normals, FPFH descriptors (suppression included).
    pub features_ms: f64,
    /// Descriptor matching.
    pub matching_ms: f64,
    /// Compatibility graph and maximum k-core.
    pub pruning_ms: f64,
    /// GNC-TLS rotation, translation, inliers and validity.
    pub solver_ms: f64,
    /// Fine registration ([`Registration::refinement`]; 0 when it did not run).
    pub refine_ms: f64,
    /// Sum of the stages (refinement included).
    pub total_ms: f64,
    /// Suppression ([`Config::suppression`](crate::Config::suppression)), both clouds: part of
    /// [`features_ms`](Timings::features_ms); 0 when it is off.
    pub suppression_ms: f64,
}

/// What the fine registration found ([`Registration::refinement`]): present exactly when refinement ran,
/// after the solver ([`Config::refine_mode`](crate::Config::refine_mode)) or in
/// [`Matcher::refine`](crate::Matcher::refine).
#[derive(Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct Refinement {
    /// The 6 x 6 information matrix of the refined pose, `information[row][col]`, symmetric: the inverse
    /// covariance of the error `xi` in `T_true = T exp(xi)`, where `T` is
    /// [`Registration::transform`] and `xi = (rotation [rad], translation [clouds' unit])` is expressed in
    /// the source's frame (rotation first, then translation: the right perturbation GTSAM's `Pose3` uses;
    /// g2o orders translation first).
    ///
    /// It is the Gauss-Newton information of the refinement's point-to-plane cost over a calibrated
    /// variance (12 times the square of the residuals' robust spread: neighbouring voxels are not
    /// independent measurements), measured against the truth on simulated and real scans
    /// (`docs/design/accuracy.md`): use it in a pose graph as it is. A small eigenvalue shows a direction the
    /// data leaves free.
    pub information: [[f64; 6]; 6],
    /// Share of the source's voxels that the refined pose lays within the refinement's correspondence
    /// distance of a target voxel, in [0, 1].
    pub overlap: f64,
    /// Weighted RMS of the refinement's residuals at its final pose (point-to-plane distance, in the
    /// clouds' unit); NaN when it found no correspondence. A valid refined pose has it at most
    /// [`Config::max_refine_rmse_gain`](crate::Config::max_refine_rmse_gain) voxel sizes.
    pub rmse: f64,
    /// Weakest over strongest direction of the information, with rotations taken as displacements at the
    /// matched points' radius, in [0, 1]: near 0 the pose slides along some direction. A valid refined pose
    /// needs at least [`Config::min_refine_condition`](crate::Config::min_refine_condition) (below it:
    /// [`Reason::Unconstrained`]).
    pub condition: f64,
    /// Principal standard deviation of the solver's inliers over that of the source voxels the refined
    /// pose overlaps: how much of the overlap the global matches span (inliers on one compact object span
    /// little of it, whatever the pose). A valid refined registration needs at least
    /// [`Config::min_inlier_coverage`](crate::Config::min_inlier_coverage). NaN after
    /// [`Matcher::refine`](crate::Matcher::refine) (no solver, no inliers) and when there are no inliers.
    pub inlier_coverage: f64,
    /// Correspondences at the final pose.
    pub correspondences: u64,
    /// Iterations run.
    pub iterations: u32,
    /// Whether refinement stopped on its convergence test rather than its iteration cap; a refined pose
    /// that did not is not valid ([`Reason::NotConverged`]).
    pub converged: bool,
    /// Whether the aligned clouds leave directions of the pose free: directions whose share of the
    /// information (rotations taken as displacements at the matched points' radius) is below
    /// [`Config::min_refine_condition`](crate::Config::min_refine_condition) of the strongest direction's
    /// ([`condition`](Refinement::condition) is the weakest share). A corridor leaves one, a tunnel two, a
    /// plane three; [`weak_directions`](Refinement::weak_directions) gives them. Such a pose is not valid
    /// ([`Reason::Unconstrained`]) unless [`Config::allow_degenerate`](crate::Config::allow_degenerate).
    pub degenerate: bool,
    /// The first `num_weak` rows are the weak directions (the C result's rows beyond them are NaN; here 0,
    /// so that `==` compares what is in use).
    weak: [[f64; 6]; 6],
    /// Rows of `weak` in use, 0 to 6.
    num_weak: usize,
}

impl Refinement {
    /// The directions the aligned clouds leave free, weakest first: empty unless
    /// [`degenerate`](Refinement::degenerate), at most 6. Each is a unit 6-vector
    /// `xi = (rotation [rad], translation [clouds' unit])` in the order and frame of
    /// [`information`](Refinement::information) (`T exp(xi)` with `T` the
    /// [`Registration::transform`], `xi` in the source's frame), signed so that its largest-magnitude
    /// component is positive (the opposite direction is as free). A pose moved along one changes the
    /// alignment by almost nothing: along a corridor that runs along `d` in the target's frame, the
    /// direction is about `(0, 0, 0, R^T d)`.
    pub fn weak_directions(&self) -> &[[f64; 6]] {
        &self.weak[..self.num_weak]
    }
}

impl std::fmt::Debug for Refinement {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Refinement")
            .field("information", &self.information)
            .field("overlap", &self.overlap)
            .field("rmse", &self.rmse)
            .field("condition", &self.condition)
            .field("inlier_coverage", &self.inlier_coverage)
            .field("correspondences", &self.correspondences)
            .field("iterations", &self.iterations)
            .field("converged", &self.converged)
            .field("degenerate", &self.degenerate)
            .field("weak_directions", &self.weak_directions())
            .finish()
    }
}

/// The result of a registration: the rigid transform mapping source points into the target frame
/// (`p_target = R p_source + t`), whether it can be trusted, and the counts and timings behind it.
///
/// The transform is NaN when no pose was estimated; when [`valid`](Registration::valid) is `false` but a
/// pose was estimated, it is kept for inspection.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct Registration {
    /// Whether the pose can be trusted (see [`reason`](Registration::reason) and the counts).
    pub valid: bool,
    /// Why the pose is not valid ([`Reason::None`] when it is).
    pub reason: Reason,
    /// The 4 x 4 homogeneous transform, `transform[row][col]`.
    pub transform: [[f64; 4]; 4],
    /// The rotation `R`, `rotation[row][col]`.
    pub rotation: [[f64; 3]; 3],
    /// The translation `t`.
    pub translation: [f64; 3],
    /// The global solver's pose, `coarse_transform[row][col]`; for
    /// [`Matcher::refine`](crate::Matcher::refine) the initial transform (its rotation block made exactly
    /// rigid: the nearest rotation). [`transform`](Registration::transform) is the refined pose when
    /// refinement ran and equals this one otherwise. NaN when no pose was estimated.
    pub coarse_transform: [[f64; 4]; 4],
    /// What the fine registration found: `Some` exactly when refinement ran (see
    /// [`Config::refine_mode`](crate::Config::refine_mode) and [`Matcher::refine`](crate::Matcher::refine)).
    pub refinement: Option<Refinement>,
    /// Counts per stage.
    pub counts: Counts,
    /// Final inliers / initial correspondences (0 when there are none).
    pub inlier_ratio: f64,
    /// RMS of `|R a + t - b|` over the final inliers, in the clouds' unit (NaN when there are none).
    pub residual_rms: f64,
    /// The solver's inlier bound, in the clouds' unit.
    pub noise_bound: f64,
    /// Square roots of the eigenvalues (descending) of the inliers' source covariance: how well spread
    /// the inliers are.
    pub inlier_extent: [f64; 3],
    /// 1-sigma uncertainty (radians) of the solver's rotation about its worst axis if every inlier were off
    /// by [`noise_bound`](Registration::noise_bound): `noise_bound / sqrt(N (e1^2 + e2^2))`, with `N` the
    /// final inliers and `e1`, `e2` the two smaller [`inlier_extent`](Registration::inlier_extent) values.
    /// Without refinement a valid pose needs at most
    /// [`Config::max_rotation_uncertainty`](crate::Config::max_rotation_uncertainty). Infinite without
    /// inliers; NaN when no pose was estimated and after [`Matcher::refine`](crate::Matcher::refine) (no
    /// solver).
    pub rotation_uncertainty: f64,
    /// With [`Config::rotation_dof`](crate::Config::rotation_dof) 1: the angle (radians) by which the best
    /// unconstrained rotation on the yaw solution's inliers turns [`Config::up`](crate::Config::up), the
    /// evidence for [`Reason::Tilted`] (a valid pose needs it within
    /// [`Config::max_rotation_uncertainty`](crate::Config::max_rotation_uncertainty)). NaN otherwise.
    pub tilt: f64,
    /// When the solver found a pose: the support of the best competing pose, distinct from it (moving the
    /// matched points by more than 8 [`noise_bound`](Registration::noise_bound)s), over its own, in [0, 1]: the
    /// competitor's inliers among every match against this pose's, and from one half on the smaller of that and
    /// the same ratio of source voxels landing beside target voxels. Near 0 in a scene with one answer, near 1 in
    /// a repetitive or symmetric one. A valid pose needs at most
    /// [`Config::max_ambiguity`](crate::Config::max_ambiguity) ([`Reason::Ambiguous`] above it). NaN when the
    /// solver did not run and after [`Matcher::refine`](crate::Matcher::refine).
    pub ambiguity: f64,
    /// The probability that the pose is within the success tolerance (5 degrees, and 2 m for LiDAR, 0.3 m
    /// indoors, 1 cm on small objects: about 4 to 7 voxels at the suggested sizes), in [0, 1]: a fixed logistic
    /// function of the final inliers (with refinement also of the overlap and the residual) times a factor falling
    /// with the [`ambiguity`](Registration::ambiguity) (1 up to 0.6, a pick among equals from 0.8), and after
    /// [`Matcher::refine`](crate::Matcher::refine) of the overlap and the residual. 0 without a pose. It reads no
    /// [`Config`](crate::Config) threshold. Runs its fit did not see held no wrong pose at 0.95 or above.
    pub confidence: f64,
    /// The voxel size the clouds were described with: [`Config::voxel_size`](crate::Config::voxel_size), or
    /// under an automatic voxel size ([`ConfigBuilder::voxel_size_auto`](crate::ConfigBuilder::voxel_size_auto))
    /// the one [`suggest_voxel_size`](crate::suggest_voxel_size) gives for both clouds (from features, theirs).
    pub voxel_size_used: f64,
    /// Milliseconds per stage.
    pub timings: Timings,
}

/// A row-major C array as rows: `R` rows of `C` values.
fn rows<const R: usize, const C: usize>(flat: &[f64]) -> [[f64; C]; R] {
    let mut out = [[0.0; C]; R];
    for (row, values) in out.iter_mut().zip(flat.chunks_exact(C)) {
        row.copy_from_slice(values);
    }
    out
}

/// Whether two arrays of doubles (or of rows of them) hold the same bits.
fn bits<T: AsFlat + ?Sized>(a: &T, b: &T) -> bool {
    a.flat().eq(b.flat())
}

/// Arrays and matrices of doubles seen as the bits of their values, row by row.
trait AsFlat {
    fn flat(&self) -> impl Iterator<Item = u64> + '_;
}
impl<const N: usize> AsFlat for [f64; N] {
    fn flat(&self) -> impl Iterator<Item = u64> + '_ {
        self.iter().map(|v| v.to_bits())
    }
}
impl<const R: usize, const C: usize> AsFlat for [[f64; C]; R] {
    fn flat(&self) -> impl Iterator<Item = u64> + '_ {
        self.iter().flatten().map(|v| v.to_bits())
    }
}

impl Registration {
    pub(crate) fn from_raw(r: &sys::kissm_result) -> Registration {
        // The library writes NaN into overlap exactly when refinement did not run.
        let num_weak = usize::try_from(r.num_weak_directions).unwrap_or(0).min(6);
        let mut weak = [[0.0; 6]; 6];
        weak[..num_weak].copy_from_slice(&rows::<6, 6>(&r.weak_directions)[..num_weak]);
        let refinement = (!r.overlap.is_nan()).then(|| Refinement {
            information: rows(&r.information),
            overlap: r.overlap,
            rmse: r.refine_rmse,
            condition: r.refine_condition,
            inlier_coverage: r.inlier_coverage,
            correspondences: r.num_refine_correspondences,
            iterations: u32::try_from(r.refine_iterations).unwrap_or(0),
            converged: r.refine_converged != 0,
            degenerate: r.degenerate != 0,
            weak,
            num_weak,
        });
        Registration {
            valid: r.valid != 0,
            reason: Reason::from_code(r.reason),
            transform: rows(&r.transform),
            rotation: rows(&r.rotation),
            translation: r.translation,
            coarse_transform: rows(&r.coarse_transform),
            refinement,
            counts: Counts {
                source_points: r.num_source_points,
                target_points: r.num_target_points,
                source_nonfinite: r.num_source_nonfinite,
                target_nonfinite: r.num_target_nonfinite,
                source_voxels: r.num_source_voxels,
                target_voxels: r.num_target_voxels,
                source_keypoints: r.num_source_keypoints,
                target_keypoints: r.num_target_keypoints,
                initial_correspondences: r.num_initial_correspondences,
                pruned_correspondences: r.num_pruned_correspondences,
                max_core_number: r.max_core_number,
                rotation_inliers: r.num_rotation_inliers,
                final_inliers: r.num_final_inliers,
                source_suppressed: r.num_source_suppressed,
                target_suppressed: r.num_target_suppressed,
            },
            inlier_ratio: r.inlier_ratio,
            residual_rms: r.residual_rms,
            noise_bound: r.noise_bound,
            inlier_extent: r.inlier_extent,
            rotation_uncertainty: r.rotation_uncertainty,
            tilt: r.tilt,
            ambiguity: r.ambiguity,
            confidence: r.confidence,
            voxel_size_used: r.voxel_size_used,
            timings: Timings {
                voxelize_ms: r.time_voxelize_ms,
                features_ms: r.time_features_ms,
                matching_ms: r.time_matching_ms,
                pruning_ms: r.time_pruning_ms,
                solver_ms: r.time_solver_ms,
                refine_ms: r.time_refine_ms,
                total_ms: r.time_total_ms,
                suppression_ms: r.time_suppression_ms,
            },
        }
    }

    /// Final inliers (the same as `counts.final_inliers`).
    pub fn final_inliers(&self) -> u64 {
        self.counts.final_inliers
    }

    /// Whether the pose was refined ([`refinement`](Registration::refinement) is `Some`).
    pub fn is_refined(&self) -> bool {
        self.refinement.is_some()
    }

    /// Whether refinement ran and the aligned clouds leave directions of the pose free
    /// ([`Refinement::degenerate`]; `false` when refinement did not run: without it no dense information
    /// exists to tell). Such a pose is valid only with
    /// [`Config::allow_degenerate`](crate::Config::allow_degenerate), and even then it is to be trusted
    /// only across the directions [`weak_directions`](Registration::weak_directions) names, not along them.
    pub fn degenerate(&self) -> bool {
        self.refinement.is_some_and(|f| f.degenerate)
    }

    /// The directions the refined pose leaves free, weakest first ([`Refinement::weak_directions`]: unit
    /// 6-vectors, rotation then translation, in the order and frame of [`Refinement::information`]); empty
    /// when refinement did not run or the pose is not [`degenerate`](Registration::degenerate).
    pub fn weak_directions(&self) -> &[[f64; 6]] {
        self.refinement.as_ref().map_or(&[], Refinement::weak_directions)
    }

    /// Whether a pose was estimated (the transform is finite), valid or not.
    pub fn has_pose(&self) -> bool {
        self.transform.iter().flatten().all(|v| v.is_finite())
    }

    /// Maps a source point into the target frame: `R p + t`.
    pub fn transform_point(&self, p: [f64; 3]) -> [f64; 3] {
        let r = &self.rotation;
        let t = &self.translation;
        [
            r[0][0] * p[0] + r[0][1] * p[1] + r[0][2] * p[2] + t[0],
            r[1][0] * p[0] + r[1][1] * p[1] + r[1][2] * p[2] + t[1],
            r[2][0] * p[0] + r[2][1] * p[1] + r[2][2] * p[2] + t[2],
        ]
    }

    /// Whether two results are identical bit for bit in everything but the timings (the library's
    /// determinism promise: same input and config give the same bits, whatever the thread count).
    pub fn same_result(&self, other: &Registration) -> bool {
        let same_refinement = match (&self.refinement, &other.refinement) {
            (None, None) => true,
            (Some(a), Some(b)) => {
                a.correspondences == b.correspondences
                    && a.iterations == b.iterations
                    && a.converged == b.converged
                    && a.degenerate == b.degenerate
                    && a.num_weak == b.num_weak
                    && bits(&a.information, &b.information)
                    && bits(&a.weak, &b.weak)
                    && bits(
                        &[a.overlap, a.rmse, a.condition, a.inlier_coverage],
                        &[b.overlap, b.rmse, b.condition, b.inlier_coverage],
                    )
            }
            _ => false,
        };
        self.valid == other.valid
            && self.reason == other.reason
            && self.counts == other.counts
            && bits(&self.transform, &other.transform)
            && bits(&self.coarse_transform, &other.coarse_transform)
            && bits(&self.rotation, &other.rotation)
            && bits(&self.translation, &other.translation)
            && bits(
                &[
                    self.inlier_ratio,
                    self.residual_rms,
                    self.noise_bound,
                    self.rotation_uncertainty,
                    self.tilt,
                    self.ambiguity,
                    self.confidence,
                    self.voxel_size_used,
                ],
                &[
                    other.inlier_ratio,
                    other.residual_rms,
                    other.noise_bound,
                    other.rotation_uncertainty,
                    other.tilt,
                    other.ambiguity,
                    other.confidence,
                    other.voxel_size_used,
                ],
            )
            && bits(&self.inlier_extent, &other.inlier_extent)
            && same_refinement
    }
}

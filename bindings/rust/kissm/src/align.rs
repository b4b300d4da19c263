// SPDX-License-Identifier: MIT
//! Multiway alignment: [`Matcher::align_features`], [`AlignOptions`], [`Pairs`], [`Alignment`],
//! [`AlignedPair`], [`EdgeState`], and the loop-candidate rule alone, [`sequence_loops`] with
//! [`LoopPositions`].

use std::mem;
use std::ptr;

use kissm_sys as sys;

use crate::error::Error;
use crate::matcher::{Features, Matcher};
use crate::pose_graph::PoseGraph;
use crate::registration::Registration;

/// Which pairs of scans [`Matcher::align_features`] registers (`kissm_align_options.pairs`).
///
/// Scans are numbered by their position in the features slice; a pair `(source, target)` registers the source
/// against the target (the transform maps the source's points into the target's frame).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Pairs<'a> {
    /// Every pair once, the later scan the source: `(j, i)` for `i < j`, `i` outer (`KISSM_PAIRS_ALL`).
    /// Sensible up to some tens of scans.
    All,
    /// Scans in acquisition order (`KISSM_PAIRS_SEQUENCE`): each with the next, `(k + 1, k)`, then the loop
    /// candidates [`sequence_loops`] gives for those registrations (or for `priors`), so the work grows with the
    /// scans, not their square; without priors, where the chain breaks, also candidates by similarity
    /// ([`AlignOptions::similar_per_scan`]). [`Pairs::sequence`] gives the defaults.
    Sequence {
        /// `None`, or one world-from-scan pose per scan (GNSS, a SLAM run), `priors[scan][row][col]`, whose
        /// positions choose the loop candidates instead of the chained registrations; a pose with a non-finite
        /// translation marks a scan without one. Its length must be the number of scans.
        priors: Option<&'a [[[f64; 4]; 4]]>,
        /// A loop candidate's scans lie within this distance (the clouds' unit) of each other: finite, > 0.
        /// `None` for 30 voxels (the matcher's [`voxel_size`](crate::Config::voxel_size)).
        loop_radius: Option<f64>,
        /// A loop candidate's scans are at least this many apart in the sequence: 1 to 1,000,000
        /// ([`Pairs::DEFAULT_LOOP_GAP`] by default).
        loop_gap: usize,
        /// At most this many candidates per scan (the nearest): 0 (no loops) to 1,000,000
        /// ([`Pairs::DEFAULT_LOOPS_PER_SCAN`] by default).
        loops_per_scan: usize,
    },
    /// These pairs, `(source, target)`, in this order (`KISSM_PAIRS_LIST`): scans of the alignment, never a
    /// scan with itself.
    List(&'a [(usize, usize)]),
    /// Several sessions (drives, robots, survey days) merged (`KISSM_PAIRS_SESSIONS`, Python's
    /// `kissm.multiway.align_sessions`): the scans in session order, `sessions[scan]` its session (the first 0,
    /// each next equal or 1 above). Each session's consecutive pairs are trusted odometry, its loop candidates as
    /// [`Pairs::Sequence`] finds them, a grid of every `stride`-th scan of a later session with every `stride`-th
    /// of each earlier one; then, once placed, each scan of a later session with its `loops_per_scan` nearest
    /// placed scans of earlier sessions within `loop_radius`, and the graph again.
    Sessions {
        /// One session number per scan; its length must be the number of scans.
        sessions: &'a [u32],
        /// The grid across sessions takes every `stride`-th scan: 1 to 1,000,000 (10 in Python).
        stride: usize,
        /// As [`Pairs::Sequence`]'s, within sessions and across them; `None` for 30 voxels.
        loop_radius: Option<f64>,
        /// As [`Pairs::Sequence`]'s, within a session.
        loop_gap: usize,
        /// As [`Pairs::Sequence`]'s, within sessions and across them.
        loops_per_scan: usize,
    },
}

impl Pairs<'static> {
    /// The default `loop_gap` of [`Pairs::Sequence`] (`kissm_align_options_init`'s).
    pub const DEFAULT_LOOP_GAP: usize = 10;
    /// The default `loops_per_scan` of [`Pairs::Sequence`] (`kissm_align_options_init`'s).
    pub const DEFAULT_LOOPS_PER_SCAN: usize = 5;

    /// [`Pairs::Sequence`] with the defaults: no priors, a loop radius of 30 voxels,
    /// [`DEFAULT_LOOP_GAP`](Pairs::DEFAULT_LOOP_GAP) and [`DEFAULT_LOOPS_PER_SCAN`](Pairs::DEFAULT_LOOPS_PER_SCAN).
    pub fn sequence() -> Pairs<'static> {
        Pairs::Sequence {
            priors: None,
            loop_radius: None,
            loop_gap: Pairs::DEFAULT_LOOP_GAP,
            loops_per_scan: Pairs::DEFAULT_LOOPS_PER_SCAN,
        }
    }
}

/// Settings of [`Matcher::align_features`] (`kissm_align_options`). The default is [`Pairs::All`] with
/// [`PoseGraph::DEFAULT_BOUND`].
///
/// ```
/// use kissm::{AlignOptions, Pairs};
/// let options = AlignOptions { pairs: Pairs::sequence(), ..AlignOptions::default() };
/// assert_eq!(options.bound, kissm::PoseGraph::DEFAULT_BOUND);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AlignOptions<'a> {
    /// The pair policy and its settings.
    pub pairs: Pairs<'a>,
    /// The pose graph's bound on a robust edge's squared error (see [`PoseGraph::optimize`]): finite, > 0.
    pub bound: f64,
    /// [`Pairs::Sequence`] without priors: where the chained registrations break into pieces, each scan's loop
    /// candidates also include the `similar_per_scan` scans of other pieces, at least `loop_gap` back, whose
    /// [`Features::signature`]s are the nearest, and of the valid registrations between two pieces only the
    /// largest set that agrees joins the graph (Python's `align(pairs="sequence")`); 0 (none) to 1,000,000
    /// ([`AlignOptions::DEFAULT_SIMILAR_PER_SCAN`] by default). Read by [`Pairs::Sequence`] only.
    pub similar_per_scan: usize,
}

impl AlignOptions<'static> {
    /// The default `similar_per_scan` (`kissm_align_options_init`'s, Python's).
    pub const DEFAULT_SIMILAR_PER_SCAN: usize = 3;
}

impl Default for AlignOptions<'_> {
    fn default() -> Self {
        AlignOptions {
            pairs: Pairs::All,
            bound: PoseGraph::DEFAULT_BOUND,
            similar_per_scan: AlignOptions::DEFAULT_SIMILAR_PER_SCAN,
        }
    }
}

/// What became of a registration in the pose graph of an [`Alignment`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum EdgeState {
    /// The registration is not valid, so it is no edge.
    NotAnEdge,
    /// A robust edge the optimisation rejected (or one outside scan 0's component, or a registration between the
    /// pieces of a broken [`Pairs::Sequence`] chain that the others do not corroborate, held out of the graph).
    Rejected,
    /// An edge the optimisation accepted.
    Accepted,
}

/// One registration of an [`Alignment`] and its edge.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct AlignedPair {
    /// The source scan (the one the transform moves).
    pub source: usize,
    /// The target scan.
    pub target: usize,
    /// The registration, as [`Matcher::register_features`] gives it for these features.
    pub registration: Registration,
    /// Whether it became an edge and whether that edge was accepted.
    pub edge: EdgeState,
    /// The edge's 6 x 6 information as the graph weighed it, `information[row][col]`, rotation first: the
    /// refined information, or for a coarse pose an isotropic one from its rotation uncertainty (at least 1e-4
    /// rad) and a translation sigma of its noise bound. `None` when the registration is not an edge.
    pub information: Option<[[f64; 6]; 6]>,
    /// The edge's squared error `xi^T I xi` at the solution; NaN when it is not an edge or a scan of it is not
    /// placed.
    pub residual: f64,
}

impl AlignedPair {
    /// Whether two pairs are identical bit for bit in everything but the registrations' timings.
    pub fn same_result(&self, other: &AlignedPair) -> bool {
        let same_information = match (&self.information, &other.information) {
            (None, None) => true,
            (Some(a), Some(b)) => a.iter().flatten().zip(b.iter().flatten()).all(|(x, y)| x.to_bits() == y.to_bits()),
            _ => false,
        };
        self.source == other.source
            && self.target == other.target
            && self.edge == other.edge
            && self.residual.to_bits() == other.residual.to_bits()
            && same_information
            && self.registration.same_result(&other.registration)
    }
}

/// The outcome of [`Matcher::align_features`]: every scan's pose in scan 0's frame and every registration with
/// its edge. Owned Rust data (the C alignment is destroyed before it is returned).
#[derive(Clone, Debug, PartialEq)]
pub struct Alignment {
    poses: Vec<[[f64; 4]; 4]>,
    placed: Vec<bool>,
    components: Vec<usize>,
    registrations: Vec<AlignedPair>,
}

impl Alignment {
    /// The number of scans (the length of the features slice).
    pub fn num_scans(&self) -> usize {
        self.poses.len()
    }

    /// World-from-scan poses, `poses()[scan][row][col]`, the world being scan 0's frame (scan 0's pose is the
    /// identity). All NaN for a scan that is not [`placed`](Alignment::placed).
    pub fn poses(&self) -> &[[[f64; 4]; 4]] {
        &self.poses
    }

    /// The pose of `scan` when it is placed; `None` when it is not, or is not a scan of the alignment.
    pub fn pose(&self, scan: usize) -> Option<&[[f64; 4]; 4]> {
        self.poses.get(scan).filter(|_| self.placed.get(scan) == Some(&true))
    }

    /// Per scan: whether accepted edges join it to scan 0 (then its pose is estimated).
    pub fn placed(&self) -> &[bool] {
        &self.placed
    }

    /// Per scan: its component, the smallest scan joined to it by accepted edges (0 for the placed scans).
    pub fn components(&self) -> &[usize] {
        &self.components
    }

    /// The registrations that ran (the pairs with features on both sides), in the order they ran: the policy's
    /// pairs, then for [`Pairs::Sequence`] its loop candidates.
    pub fn registrations(&self) -> &[AlignedPair] {
        &self.registrations
    }

    /// Whether two alignments are identical bit for bit in everything but the registrations' timings (the
    /// library's promise: the same features, settings and pairs give the same bits, whatever the thread count).
    pub fn same_result(&self, other: &Alignment) -> bool {
        self.placed == other.placed
            && self.components == other.components
            && self.poses.len() == other.poses.len()
            && self
                .poses
                .iter()
                .flatten()
                .flatten()
                .zip(other.poses.iter().flatten().flatten())
                .all(|(a, b)| a.to_bits() == b.to_bits())
            && self.registrations.len() == other.registrations.len()
            && self.registrations.iter().zip(&other.registrations).all(|(a, b)| a.same_result(b))
    }
}

/// Owns a kissm_alignment for the time it is read; destroyed on drop.
struct RawAlignment(*mut sys::kissm_alignment);

impl Drop for RawAlignment {
    fn drop(&mut self) {
        // SAFETY: the pointer came from kissm_align_features (or is NULL, which the library accepts) and this is
        // its only owner, dropped once.
        unsafe { sys::kissm_alignment_destroy(self.0) }
    }
}

fn invalid(message: String) -> Error {
    Error::new(sys::KISSM_ERR_INVALID_ARGUMENT, message)
}

/// A loop setting as the `int32_t` of kissm_align_options; values the C range check would refuse anyway but that
/// do not fit are refused here with the same range.
fn loop_setting(value: usize, name: &str, range: &str) -> Result<i32, Error> {
    i32::try_from(value).map_err(|_| invalid(format!("{name} is {value}; {range}")))
}

/// A count or scan number from the library as a `usize`.
fn index(n: u64, what: &str) -> Result<usize, Error> {
    usize::try_from(n).map_err(|_| {
        Error::new(sys::KISSM_ERR_OUT_OF_MEMORY, format!("{what} {n} does not fit in this platform's usize"))
    })
}

/// `len` copies of `value`, or an out-of-memory error instead of an abort when they cannot be allocated.
fn filled<T: Clone>(len: usize, value: T, what: &str) -> Result<Vec<T>, Error> {
    let mut v = Vec::new();
    v.try_reserve_exact(len)
        .map_err(|_| Error::new(sys::KISSM_ERR_OUT_OF_MEMORY, format!("could not allocate {len} {what}")))?;
    v.resize(len, value);
    Ok(v)
}

/// Poses as the packed row-major doubles the C API takes.
fn flat_poses(poses: &[[[f64; 4]; 4]], what: &str) -> Result<Vec<f64>, Error> {
    let mut flat = Vec::new();
    flat.try_reserve_exact(poses.len().saturating_mul(16))
        .map_err(|_| Error::new(sys::KISSM_ERR_OUT_OF_MEMORY, format!("could not copy the {} {what}", poses.len())))?;
    flat.extend(poses.iter().flatten().flatten());
    Ok(flat)
}

impl Matcher {
    /// Aligns many scans into scan 0's frame with no initial guess (`kissm_align_features`): registers the pairs
    /// `options.pairs` chooses from the scans' features (with this matcher's settings, as
    /// [`register_features`](Matcher::register_features) does), makes each valid pose a robust edge of a pose
    /// graph and optimises it from scan 0. Every scan joined to scan 0 by accepted edges gets its pose in scan 0's
    /// frame; the others none (NaN poses, not [`placed`](Alignment::placed)), never a guess.
    ///
    /// `features[k]` describes scan `k`; `None` is a scan that could not be described: no pair with it is
    /// registered and it is not placed. With [`RefineMode::Gicp`](crate::RefineMode::Gicp) the edges are weighed
    /// by the refined information. The pairs run on the matcher's threads, one pair per thread; the result does
    /// not depend on their number, and is bitwise that of the C library, Python's `kissm.multiway.align` and
    /// `kissm align` on the same features, settings and pairs. A [`CancelHandle`](crate::CancelHandle) stops it.
    ///
    /// Fails with [`ErrorKind::InvalidArgument`](crate::ErrorKind::InvalidArgument), the message naming the
    /// argument, when `features` is empty or too long, a listed pair names a scan out of range or pairs a scan
    /// with itself, `priors` does not hold one pose per scan, or a setting is out of its range; with
    /// [`ErrorKind::FeaturesMismatch`](crate::ErrorKind::FeaturesMismatch) when some features were computed under
    /// other descriptor settings; with [`ErrorKind::Cancelled`](crate::ErrorKind::Cancelled) when cancelled.
    ///
    /// ```no_run
    /// use kissm::{AlignOptions, Config, Matcher, Pairs, RefineMode};
    /// # let scans: Vec<Vec<[f32; 3]>> = Vec::new();
    /// let mut matcher = Matcher::new(&Config::builder().voxel_size(0.3).refine_mode(RefineMode::Gicp).build()?)?;
    /// let features = scans.iter().map(|scan| matcher.compute_features(scan).ok()).collect::<Vec<_>>();
    /// let features: Vec<_> = features.iter().map(Option::as_ref).collect();
    /// let options = AlignOptions { pairs: Pairs::sequence(), ..AlignOptions::default() };
    /// let alignment = matcher.align_features(&features, &options)?;
    /// for (scan, pose) in alignment.poses().iter().enumerate() {
    ///     println!("scan {scan}: placed {}, pose {pose:?}", alignment.placed()[scan]);
    /// }
    /// # Ok::<(), kissm::Error>(())
    /// ```
    pub fn align_features(
        &mut self,
        features: &[Option<&Features>],
        options: &AlignOptions<'_>,
    ) -> Result<Alignment, Error> {
        let num_scans = features.len();
        if num_scans == 0 {
            return Err(invalid(format!("features is empty; 1 to {} scans", PoseGraph::MAX_NODES)));
        }
        let mut raw_options = sys::kissm_align_options::default();
        // SAFETY: raw_options is a writable kissm_align_options of exactly the size passed.
        Error::check(unsafe {
            sys::kissm_align_options_init(&mut raw_options, mem::size_of::<sys::kissm_align_options>() as u32)
        })?;
        raw_options.bound = options.bound;
        raw_options.similar_per_scan = loop_setting(options.similar_per_scan, "similar_per_scan", "0 to 1000000")?;
        // The arrays the options point to; they live until the end of this function.
        let mut pair_list: Vec<u64> = Vec::new();
        let mut priors_flat: Vec<f64> = Vec::new();
        match options.pairs {
            Pairs::All => raw_options.pairs = sys::KISSM_PAIRS_ALL,
            Pairs::Sequence { priors, loop_radius, loop_gap, loops_per_scan } => {
                raw_options.pairs = sys::KISSM_PAIRS_SEQUENCE;
                if let Some(priors) = priors {
                    if priors.len() != num_scans {
                        return Err(invalid(format!(
                            "priors holds {} poses; one per scan ({num_scans}, the length of features)",
                            priors.len()
                        )));
                    }
                    priors_flat = flat_poses(priors, "priors")?;
                }
                raw_options.loop_radius = loop_radius.unwrap_or(0.0);
                raw_options.loop_gap = loop_setting(loop_gap, "loop_gap", "1 to 1000000")?;
                raw_options.loops_per_scan = loop_setting(loops_per_scan, "loops_per_scan", "0 to 1000000")?;
            }
            Pairs::Sessions { sessions, stride, loop_radius, loop_gap, loops_per_scan } => {
                raw_options.pairs = sys::KISSM_PAIRS_SESSIONS;
                if sessions.len() != num_scans {
                    return Err(invalid(format!(
                        "sessions holds {} numbers; one per scan ({num_scans}, the length of features)",
                        sessions.len()
                    )));
                }
                raw_options.sessions = sessions.as_ptr();
                raw_options.stride = loop_setting(stride, "stride", "1 to 1000000")?;
                raw_options.loop_radius = loop_radius.unwrap_or(0.0);
                raw_options.loop_gap = loop_setting(loop_gap, "loop_gap", "1 to 1000000")?;
                raw_options.loops_per_scan = loop_setting(loops_per_scan, "loops_per_scan", "0 to 1000000")?;
            }
            Pairs::List(pairs) => {
                raw_options.pairs = sys::KISSM_PAIRS_LIST;
                pair_list.try_reserve_exact(pairs.len().saturating_mul(2)).map_err(|_| {
                    Error::new(sys::KISSM_ERR_OUT_OF_MEMORY, format!("could not copy the {} pairs", pairs.len()))
                })?;
                pair_list.extend(pairs.iter().flat_map(|&(s, t)| [s as u64, t as u64]));
                raw_options.num_pairs = pairs.len() as u64;
            }
        }
        if !pair_list.is_empty() {
            raw_options.pair_list = pair_list.as_ptr();
        }
        if !priors_flat.is_empty() {
            raw_options.priors = priors_flat.as_ptr();
        }
        let pointers: Vec<*const sys::kissm_features> =
            features.iter().map(|f| f.map_or(ptr::null(), |f| f.raw.as_ptr().cast_const())).collect();
        let mut raw: *mut sys::kissm_alignment = ptr::null_mut();
        // SAFETY: the matcher is live and used by this thread only (&mut self); pointers holds num_scans entries,
        // each NULL or live, immutable features borrowed for the call; raw_options has struct_size set and its
        // arrays (pair_list: 2 * num_pairs values, priors: 16 * num_scans values, or NULL) outlive the call;
        // raw is a valid out pointer.
        let status = unsafe {
            sys::kissm_align_features(self.ptr(), pointers.as_ptr(), num_scans as u64, &raw_options, &mut raw)
        };
        let raw = RawAlignment(raw);
        Error::check(status)?;
        if raw.0.is_null() {
            return Err(Error::new(
                sys::KISSM_ERR_INTERNAL,
                "kissm_align_features succeeded but returned no alignment",
            ));
        }
        read_alignment(&raw)
    }
}

/// Copies everything out of a C alignment.
fn read_alignment(raw: &RawAlignment) -> Result<Alignment, Error> {
    // SAFETY: raw.0 is a live alignment (from a successful kissm_align_features).
    let (num_scans, num_registrations) =
        unsafe { (sys::kissm_alignment_num_scans(raw.0), sys::kissm_alignment_num_registrations(raw.0)) };
    let num_scans = index(num_scans, "the number of scans")?;
    let num_registrations = index(num_registrations, "the number of registrations")?;
    let mut poses = filled(num_scans, [[0.0; 4]; 4], "poses")?;
    let mut placed = filled(num_scans, 0u8, "placed flags")?;
    let mut components = filled(num_scans, 0u64, "component labels")?;
    // SAFETY: the alignment is live; poses holds num_scans [[f64; 4]; 4], i.e. 16 * num_scans contiguous doubles
    // (arrays have no padding); placed and components hold num_scans elements.
    Error::check(unsafe {
        sys::kissm_alignment_poses(
            raw.0,
            poses.as_mut_ptr().cast::<f64>(),
            placed.as_mut_ptr(),
            components.as_mut_ptr(),
        )
    })?;
    let mut registrations = Vec::new();
    registrations.try_reserve_exact(num_registrations).map_err(|_| {
        Error::new(sys::KISSM_ERR_OUT_OF_MEMORY, format!("could not allocate {num_registrations} registrations"))
    })?;
    for k in 0..num_registrations {
        let mut result = sys::kissm_result::default();
        // SAFETY: result is a writable kissm_result of exactly the size passed.
        Error::check(unsafe { sys::kissm_result_init(&mut result, mem::size_of::<sys::kissm_result>() as u32) })?;
        let (mut source, mut target, mut edge, mut residual) = (0u64, 0u64, 0i32, 0.0f64);
        let mut information = [0.0f64; 36];
        // SAFETY: the alignment is live and k < num_registrations; every out pointer is valid and writable (result
        // with struct_size set, information 36 doubles).
        Error::check(unsafe {
            sys::kissm_alignment_registration(
                raw.0,
                k as u64,
                &mut source,
                &mut target,
                &mut result,
                &mut edge,
                information.as_mut_ptr(),
                &mut residual,
            )
        })?;
        let edge = match edge {
            -1 => EdgeState::NotAnEdge,
            0 => EdgeState::Rejected,
            1 => EdgeState::Accepted,
            other => {
                return Err(Error::new(
                    sys::KISSM_ERR_INTERNAL,
                    format!("kissm_alignment_registration gave edge state {other} for registration {k}"),
                ))
            }
        };
        let mut rows = [[0.0; 6]; 6];
        for (row, values) in rows.iter_mut().zip(information.chunks_exact(6)) {
            row.copy_from_slice(values);
        }
        registrations.push(AlignedPair {
            source: index(source, "scan")?,
            target: index(target, "scan")?,
            registration: Registration::from_raw(&result),
            edge,
            information: (edge != EdgeState::NotAnEdge).then_some(rows),
            residual,
        });
    }
    Ok(Alignment {
        poses,
        placed: placed.into_iter().map(|flag| flag != 0).collect(),
        components: components.into_iter().map(|c| index(c, "component")).collect::<Result<_, _>>()?,
        registrations,
    })
}

/// Where the scans of a sequence are, for [`sequence_loops`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LoopPositions<'a> {
    /// The consecutive registrations, one per step (so one fewer than the scans): `steps[k]` is `T_k_(k+1)`, the
    /// [`transform`](Registration::transform) of the pair `(k + 1, k)` (scan `k + 1` into scan `k`), or `None`
    /// for a step without a valid pose, which starts a new piece of the sequence in a frame of its own (no
    /// candidates across pieces). The radius then grows by 2% of the path between two scans (the odometry's
    /// drift).
    Steps(&'a [Option<[[f64; 4]; 4]>]),
    /// One world-from-scan pose per scan (GNSS, a SLAM run), `priors[scan][row][col]`; a pose with a non-finite
    /// translation marks a scan without a position. No drift allowance.
    Priors(&'a [[[f64; 4]; 4]]),
}

/// The loop candidates of a sequence of scans (`kissm_sequence_loops`): pairs far apart in the sequence but near
/// in space, the rule of [`Pairs::Sequence`] (and of Python's and the CLI's sequences), for a job of one's own.
///
/// For each scan `j` from `gap` on, the scans `i <= j - gap` within `radius` (the clouds' unit; grown by the
/// drift allowance with [`LoopPositions::Steps`]), the `per_scan` nearest (by distance, then `i`), are returned
/// as pairs `(j, i)` by increasing `i`; then `j + 1`.
///
/// Fails with [`ErrorKind::InvalidArgument`](crate::ErrorKind::InvalidArgument), the message naming the
/// argument, when `radius` is not finite and above 0, `gap` is not 1 to 1,000,000, `per_scan` is above
/// 1,000,000, `priors` is empty, or there are more scans than [`PoseGraph::MAX_NODES`].
///
/// ```
/// use kissm::{sequence_loops, LoopPositions};
/// // Out 1 m a step along x to x = 4 and back to x = 1: positions 0 1 2 3 4 3 2 1.
/// let step = |dx: f64| [[1.0, 0.0, 0.0, dx], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]];
/// let steps: Vec<_> = (0..7).map(|k| Some(step(if k < 4 { 1.0 } else { -1.0 }))).collect();
/// assert_eq!(sequence_loops(LoopPositions::Steps(&steps), 0.5, 3, 5)?, [(6, 2), (7, 1)]);
/// # Ok::<(), kissm::Error>(())
/// ```
pub fn sequence_loops(
    positions: LoopPositions<'_>,
    radius: f64,
    gap: usize,
    per_scan: usize,
) -> Result<Vec<(usize, usize)>, Error> {
    crate::check_library()?;
    let (num_scans, steps, step_valid, priors) = match positions {
        LoopPositions::Steps(steps) => {
            let mut flat = filled(steps.len().saturating_mul(16), 0.0f64, "step values")?;
            let mut valid = filled(steps.len(), 0u8, "step flags")?;
            for ((out, flag), step) in flat.chunks_exact_mut(16).zip(valid.iter_mut()).zip(steps) {
                if let Some(step) = step {
                    for (o, v) in out.iter_mut().zip(step.iter().flatten()) {
                        *o = *v;
                    }
                    *flag = 1;
                }
            }
            (steps.len() + 1, flat, valid, Vec::new())
        }
        LoopPositions::Priors(priors) => {
            if priors.is_empty() {
                return Err(invalid(format!("priors is empty; 1 to {} poses", PoseGraph::MAX_NODES)));
            }
            (priors.len(), Vec::new(), Vec::new(), flat_poses(priors, "priors")?)
        }
    };
    let from_steps = matches!(positions, LoopPositions::Steps(_));
    let (steps_ptr, valid_ptr, priors_ptr) = if from_steps {
        (steps.as_ptr(), step_valid.as_ptr(), ptr::null())
    } else {
        (ptr::null(), ptr::null(), priors.as_ptr())
    };
    let call = |out: *mut u64, capacity: u64, count: &mut u64| {
        // SAFETY: with steps, steps_ptr holds 16 * (num_scans - 1) doubles and valid_ptr num_scans - 1 flags of 0 or
        // 1 (non-NULL even when empty, and then not read); with priors, priors_ptr holds 16 * num_scans doubles;
        // the others are NULL. out is NULL or holds capacity pairs (2 * capacity u64); count is a valid out
        // pointer.
        Error::check(unsafe {
            sys::kissm_sequence_loops(
                num_scans as u64,
                steps_ptr,
                valid_ptr,
                priors_ptr,
                radius,
                gap as u64,
                per_scan as u64,
                out,
                capacity,
                count,
            )
        })
    };
    let mut count = 0u64;
    call(ptr::null_mut(), 0, &mut count)?;
    let len = index(count, "the number of loop candidates")?;
    let mut flat = filled(len.saturating_mul(2), 0u64, "loop candidate values")?;
    let mut written = 0u64;
    call(flat.as_mut_ptr(), count, &mut written)?;
    if written != count {
        return Err(Error::new(
            sys::KISSM_ERR_INTERNAL,
            format!("kissm_sequence_loops wrote {written} pairs after counting {count}"),
        ));
    }
    flat.chunks_exact(2).map(|pair| Ok((index(pair[0], "scan")?, index(pair[1], "scan")?))).collect()
}

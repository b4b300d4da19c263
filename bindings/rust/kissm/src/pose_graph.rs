// SPDX-License-Identifier: MIT
//! [`PoseGraph`], [`PoseGraphSolution`] and [`PoseGraphCancelHandle`].

use std::cell::Cell;
use std::fmt;
use std::marker::PhantomData;
use std::ptr::NonNull;
use std::sync::Arc;

use kissm_sys as sys;

use crate::error::Error;

/// Owns a kissm_pose_graph; destroyed when the PoseGraph and every PoseGraphCancelHandle are gone.
struct RawPoseGraph(NonNull<sys::kissm_pose_graph>);

// SAFETY: a kissm_pose_graph is not tied to a thread. Through a shared RawPoseGraph (the cancel handles) only
// kissm_pose_graph_cancel is called, which the C API documents as callable from any thread; every other call
// goes through the PoseGraph, whose mutating calls take `&mut self` and which is not Sync.
unsafe impl Send for RawPoseGraph {}
// SAFETY: as above.
unsafe impl Sync for RawPoseGraph {}

impl Drop for RawPoseGraph {
    fn drop(&mut self) {
        // SAFETY: the pointer came from kissm_pose_graph_create and this is its only owner, dropped once.
        unsafe { sys::kissm_pose_graph_destroy(self.0.as_ptr()) }
    }
}

/// A pose graph: the C library's `kissm_pose_graph`, destroyed on drop.
///
/// Nodes are scans (numbered `0` to `num_nodes - 1`), edges are relative poses between them: a registration's
/// transform and [`information`](crate::Refinement::information), an odometry step, a user's constraint.
/// [`optimize`](PoseGraph::optimize) finds every node's pose in the frame of an anchor node
/// (Levenberg-Marquardt on SE(3); the edges added as robust are weighed by graduated non-convexity with a
/// truncated least-squares cost, so that a wrong loop closure ends rejected instead of bending the map).
///
/// An edge from `source` s to `target` t with transform `T` states `T = inv(X_t) X_s` for the nodes'
/// world-from-node poses `X`: `T` maps the source's points into the target's frame, as
/// [`Registration::transform`](crate::Registration::transform) does. Its error is
/// `xi = Log(inv(T) inv(X_t) X_s)`, rotation first, in the source's frame, and its information is the inverse
/// covariance of `xi` (GTSAM's `BetweenFactor<Pose3>(t, s, T)`).
///
/// A graph may be moved between threads (`Send`) but is used by one thread at a time (not `Sync`); a running
/// optimisation can be stopped from another thread through a [`PoseGraphCancelHandle`]. The same graph gives
/// the same bits on every run.
///
/// ```
/// use kissm::PoseGraph;
///
/// let identity = [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]];
/// let step = [[1.0, 0.0, 0.0, 1.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]];
/// let mut information = [[0.0; 6]; 6];
/// (0..6).for_each(|i| information[i][i] = 100.0);
///
/// let mut graph = PoseGraph::new(3)?;
/// graph.add_edge(1, 0, &step, &information, false)?; // node 1 is 1 m ahead of node 0
/// graph.add_edge(2, 1, &step, &information, false)?;
/// graph.add_edge(2, 0, &identity, &information, true)?; // a wrong loop closure
/// let solution = graph.optimize(0, PoseGraph::DEFAULT_BOUND)?;
/// assert_eq!(solution.accepted, [true, true, false]);
/// assert!((solution.poses[2][0][3] - 2.0).abs() < 1e-9);
/// # Ok::<(), kissm::Error>(())
/// ```
pub struct PoseGraph {
    raw: Arc<RawPoseGraph>,
    _not_sync: PhantomData<Cell<()>>,
}

impl PoseGraph {
    /// The default bound on a robust edge's squared error `xi^T I xi` at which it is rejected
    /// (`KISSM_POSE_GRAPH_DEFAULT_BOUND`): the 99.9% quantile of a chi-square with 6 degrees of freedom, so a
    /// right edge with a calibrated information exceeds it once in a thousand.
    pub const DEFAULT_BOUND: f64 = sys::KISSM_POSE_GRAPH_DEFAULT_BOUND;

    /// The most nodes a graph may have (`KISSM_POSE_GRAPH_MAX_NODES`).
    pub const MAX_NODES: u64 = sys::KISSM_POSE_GRAPH_MAX_NODES as u64;

    /// Creates a graph of `num_nodes` nodes, numbered `0` to `num_nodes - 1`, with no edges. Fails with
    /// [`ErrorKind::InvalidArgument`](crate::ErrorKind::InvalidArgument) when `num_nodes` is 0 or above
    /// [`MAX_NODES`](PoseGraph::MAX_NODES).
    pub fn new(num_nodes: u64) -> Result<PoseGraph, Error> {
        crate::check_library()?;
        let mut raw: *mut sys::kissm_pose_graph = std::ptr::null_mut();
        // SAFETY: raw is a valid out pointer; no other preconditions.
        Error::check(unsafe { sys::kissm_pose_graph_create(num_nodes, &mut raw) })?;
        let raw = NonNull::new(raw).ok_or_else(|| {
            Error::new(sys::KISSM_ERR_INTERNAL, "kissm_pose_graph_create succeeded but returned no graph")
        })?;
        Ok(PoseGraph { raw: Arc::new(RawPoseGraph(raw)), _not_sync: PhantomData })
    }

    fn ptr(&self) -> *mut sys::kissm_pose_graph {
        self.raw.0.as_ptr()
    }

    /// The number of nodes.
    pub fn num_nodes(&self) -> u64 {
        // SAFETY: the graph is live; this only reads the node count, which no call changes.
        unsafe { sys::kissm_pose_graph_num_nodes(self.ptr()) }
    }

    /// The number of edges added so far.
    pub fn num_edges(&self) -> u64 {
        // SAFETY: the graph is live and not being changed (changes take `&mut self`, and the type is not Sync).
        unsafe { sys::kissm_pose_graph_num_edges(self.ptr()) }
    }

    /// Adds an edge and returns its number (edges are numbered in the order they are added, from 0).
    ///
    /// - `source`, `target`: two different nodes of the graph; `transform` moves the source's points into the
    ///   target's frame.
    /// - `transform`: `T_target_source`, 4 x 4, `transform[row][col]`; finite and rigid (as
    ///   [`Matcher::refine`](crate::Matcher::refine) checks its initial transform).
    /// - `information`: 6 x 6, `information[row][col]`, finite, symmetric (to 1e-9 of its largest entry) and
    ///   positive definite: the inverse covariance of the edge's error, rotation first, in the source's frame
    ///   ([`Refinement::information`](crate::Refinement::information) as it is).
    /// - `robust`: `true` for a candidate that may be wrong (a loop closure), which the optimisation may
    ///   reject; `false` for a trusted edge (odometry, a user's constraint), which is always kept.
    ///
    /// Fails with [`ErrorKind::InvalidArgument`](crate::ErrorKind::InvalidArgument), the message naming the
    /// argument, when any of these does not hold; the graph is then unchanged.
    pub fn add_edge(
        &mut self,
        source: u64,
        target: u64,
        transform: &[[f64; 4]; 4],
        information: &[[f64; 6]; 6],
        robust: bool,
    ) -> Result<u64, Error> {
        let transform: [f64; 16] = flatten(transform);
        let information: [f64; 36] = flatten(information);
        let mut edge = 0u64;
        // SAFETY: the graph is live and used by this thread only (&mut self); transform and information are
        // 16 and 36 doubles read during the call only; edge is a valid out pointer.
        let status = unsafe {
            sys::kissm_pose_graph_add_edge(
                self.ptr(),
                source,
                target,
                transform.as_ptr(),
                information.as_ptr(),
                i32::from(robust),
                &mut edge,
            )
        };
        Error::check(status)?;
        Ok(edge)
    }

    /// Optimises the graph and returns the solution: every node joined to `anchor` by accepted edges gets its
    /// pose in the anchor's frame (the anchor's own is the identity); the others get NaN poses, never a guess.
    ///
    /// The start is a spanning tree from the anchor (trusted edges first, then the most informative); the
    /// robust edges are then weighed by graduated non-convexity, and one whose squared error `xi^T I xi` ends
    /// above `bound` is rejected. Use [`DEFAULT_BOUND`](PoseGraph::DEFAULT_BOUND) for calibrated informations.
    /// The graph may be optimised again (with another anchor or bound, or after adding edges); the same graph
    /// gives the same bits on every run.
    ///
    /// Fails with [`ErrorKind::InvalidArgument`](crate::ErrorKind::InvalidArgument) when `anchor` is not a node
    /// of the graph or `bound` is not a finite number above 0, and with
    /// [`ErrorKind::Cancelled`](crate::ErrorKind::Cancelled) when a [`PoseGraphCancelHandle`] stopped it.
    pub fn optimize(&mut self, anchor: u64, bound: f64) -> Result<PoseGraphSolution, Error> {
        // SAFETY: the graph is live and used by this thread only (&mut self).
        Error::check(unsafe { sys::kissm_pose_graph_optimize(self.ptr(), anchor, bound) })?;
        self.solution()
    }

    /// Reads the solution of the optimisation that just succeeded.
    fn solution(&mut self) -> Result<PoseGraphSolution, Error> {
        let nodes = count(self.num_nodes(), "nodes")?;
        let edges = count(self.num_edges(), "edges")?;
        let mut poses = filled(nodes, [[0.0; 4]; 4], "poses")?;
        let mut placed = filled(nodes, 0u8, "placed flags")?;
        let mut components = filled(nodes, 0u64, "component labels")?;
        let mut accepted = filled(edges, 0u8, "accepted flags")?;
        let mut residuals = filled(edges, 0.0f64, "residuals")?;
        // SAFETY: the graph is live, exclusively borrowed and holds a solution (optimize just succeeded). poses
        // holds num_nodes [[f64; 4]; 4], i.e. 16 * num_nodes contiguous doubles (arrays have no padding); placed
        // and components hold num_nodes elements; accepted and residuals hold num_edges elements.
        let status = unsafe {
            sys::kissm_pose_graph_poses(
                self.ptr(),
                poses.as_mut_ptr().cast::<f64>(),
                placed.as_mut_ptr(),
                components.as_mut_ptr(),
            )
        };
        Error::check(status)?;
        // SAFETY: as above.
        Error::check(unsafe {
            sys::kissm_pose_graph_edges(self.ptr(), accepted.as_mut_ptr(), residuals.as_mut_ptr())
        })?;
        Ok(PoseGraphSolution {
            poses,
            placed: placed.into_iter().map(|flag| flag != 0).collect(),
            components,
            accepted: accepted.into_iter().map(|flag| flag != 0).collect(),
            residuals,
        })
    }

    /// A handle that stops this graph's running [`optimize`](PoseGraph::optimize) from another thread. The
    /// graph's C object lives on until the graph and all its handles are dropped.
    pub fn cancel_handle(&self) -> PoseGraphCancelHandle {
        PoseGraphCancelHandle { raw: Arc::clone(&self.raw) }
    }
}

/// A matrix as the `N = R * C` row-major doubles the C API takes.
fn flatten<const R: usize, const C: usize, const N: usize>(m: &[[f64; C]; R]) -> [f64; N] {
    let mut flat = [0.0; N];
    for (out, row) in flat.chunks_exact_mut(C).zip(m) {
        out.copy_from_slice(row);
    }
    flat
}

/// A count from the library as a length.
fn count(n: u64, what: &str) -> Result<usize, Error> {
    usize::try_from(n).map_err(|_| {
        Error::new(sys::KISSM_ERR_OUT_OF_MEMORY, format!("the graph's {n} {what} do not fit in this platform's memory"))
    })
}

/// `len` copies of `value`, or an out-of-memory error instead of an abort when they cannot be allocated.
fn filled<T: Clone>(len: usize, value: T, what: &str) -> Result<Vec<T>, Error> {
    let mut v = Vec::new();
    v.try_reserve_exact(len).map_err(|_| {
        Error::new(sys::KISSM_ERR_OUT_OF_MEMORY, format!("could not allocate the solution's {len} {what}"))
    })?;
    v.resize(len, value);
    Ok(v)
}

impl fmt::Debug for PoseGraph {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("PoseGraph").field("num_nodes", &self.num_nodes()).field("num_edges", &self.num_edges()).finish()
    }
}

/// The solution of [`PoseGraph::optimize`]: one entry per node in `poses`, `placed` and `components`, one per
/// edge (in the order they were added) in `accepted` and `residuals`.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct PoseGraphSolution {
    /// World-from-node poses, `poses[node][row][col]`, where the world is the anchor's frame (the anchor's pose
    /// is the identity). All NaN for a node that is not [`placed`](PoseGraphSolution::placed).
    pub poses: Vec<[[f64; 4]; 4]>,
    /// Whether accepted edges join the node to the anchor (then its pose is estimated).
    pub placed: Vec<bool>,
    /// The node's component: the smallest node joined to it by trusted and accepted edges. The anchor's
    /// component is the placed nodes.
    pub components: Vec<u64>,
    /// `true` for a trusted edge and an accepted robust one; `false` for a rejected robust edge and for any
    /// edge outside the anchor's component.
    pub accepted: Vec<bool>,
    /// The edge's squared error `xi^T I xi` at the solution; NaN where a node of the edge is not placed.
    pub residuals: Vec<f64>,
}

/// Stops a [`PoseGraph`]'s running [`optimize`](PoseGraph::optimize) from any thread: the call then fails with
/// [`ErrorKind::Cancelled`](crate::ErrorKind::Cancelled) and the graph keeps no solution (it may be optimised
/// again). A request made while no optimisation is running is dropped when the next one starts.
/// `Send + Sync + Clone`; it keeps the graph's C object alive, so it can never point to a destroyed graph.
///
/// ```no_run
/// # let mut graph = kissm::PoseGraph::new(2)?;
/// let cancel = graph.cancel_handle();
/// std::thread::spawn(move || {
///     std::thread::sleep(std::time::Duration::from_millis(100));
///     cancel.cancel();
/// });
/// match graph.optimize(0, kissm::PoseGraph::DEFAULT_BOUND) {
///     Err(e) if e.kind() == kissm::ErrorKind::Cancelled => println!("stopped"),
///     other => println!("{:?}", other.map(|s| s.placed)),
/// }
/// # Ok::<(), kissm::Error>(())
/// ```
#[derive(Clone)]
pub struct PoseGraphCancelHandle {
    raw: Arc<RawPoseGraph>,
}

impl PoseGraphCancelHandle {
    /// Requests that the optimisation running on the graph stop.
    pub fn cancel(&self) {
        // SAFETY: the graph is alive (this handle co-owns it); kissm_pose_graph_cancel is callable from any thread.
        unsafe { sys::kissm_pose_graph_cancel(self.raw.0.as_ptr()) }
    }
}

impl fmt::Debug for PoseGraphCancelHandle {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("PoseGraphCancelHandle").finish_non_exhaustive()
    }
}

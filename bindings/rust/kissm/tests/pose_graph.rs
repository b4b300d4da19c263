// SPDX-License-Identifier: MIT
//! The pose graph: the edge convention, a noise-free loop recovered exactly, wrong loop closures rejected,
//! bitwise repeatability, nodes that are not placed, every argument check with its code and message (and
//! the graph unchanged after a failed call), cancellation from another thread, and the Send/Sync contract.
#![allow(clippy::needless_range_loop)]

mod common;

use common::{assert_send, assert_sync, NotSync, Pose};
use kissm::{ErrorKind, PoseGraph, PoseGraphCancelHandle, PoseGraphSolution};
use kissm_sys as sys;

type Matrix4 = [[f64; 4]; 4];
type Matrix6 = [[f64; 6]; 6];

// ------------------------------------------------------------------------------------------------
// Helpers
// ------------------------------------------------------------------------------------------------

/// A deterministic generator (splitmix64), so that every run builds the same graphs.
struct Rng(u64);

impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in [lo, hi).
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * ((self.next_u64() >> 11) as f64 / (1u64 << 53) as f64)
    }

    /// A random rigid motion: a rotation of 20 to 180 degrees about a random axis and a translation of up to
    /// 5 in each coordinate.
    fn pose(&mut self) -> Pose {
        let axis = [self.uniform(-1.0, 1.0), self.uniform(-1.0, 1.0), self.uniform(0.1, 1.0)];
        let angle = self.uniform(20.0, 180.0);
        let t = [self.uniform(-5.0, 5.0), self.uniform(-5.0, 5.0), self.uniform(-5.0, 5.0)];
        Pose::axis_angle(axis, angle, t)
    }
}

/// The transform of an edge from `source` to `target`: `inv(X_target) X_source`.
fn relative(truth: &[Pose], source: usize, target: usize) -> Matrix4 {
    truth[target].inverse().compose(&truth[source]).to_matrix()
}

/// A confident, non-diagonal information (rotation first): 1e4 on the rotations, 1e2 on the translations,
/// and small couplings; symmetric and positive definite.
fn information() -> Matrix6 {
    let mut m = [[0.0; 6]; 6];
    for i in 0..6 {
        m[i][i] = if i < 3 { 1e4 } else { 1e2 };
    }
    for (i, j, v) in [(0, 3, 10.0), (1, 2, 50.0), (4, 5, -5.0), (2, 4, 3.0)] {
        m[i][j] = v;
        m[j][i] = v;
    }
    m
}

fn identity() -> Matrix4 {
    Pose::axis_angle([0.0, 0.0, 1.0], 0.0, [0.0; 3]).to_matrix()
}

/// Node count of the loop.
const LOOP: usize = 30;
/// Each loop closure joins node i to node i + CLOSURE_STEP (mod LOOP).
const CLOSURE_STEP: usize = 5;

/// The truth of the loop: 30 world-from-node poses on a circle of radius 10 (12 degrees apart) with a
/// vertical wobble, each facing along the circle and tilted a little, so that no coordinate is trivial.
fn loop_truth() -> Vec<Pose> {
    (0..LOOP)
        .map(|i| {
            let theta = (i as f64 * 12.0).to_radians();
            let t = [10.0 * theta.cos(), 10.0 * theta.sin(), 0.5 * (3.0 * theta).sin()];
            let heading = Pose::axis_angle([0.0, 0.0, 1.0], i as f64 * 12.0 + 90.0, t);
            let tilt = Pose::axis_angle([1.0, 0.3 * theta.sin(), 0.0], 5.0 * (2.0 * theta).cos(), [0.0; 3]);
            heading.compose(&tilt)
        })
        .collect()
}

/// The loop's graph: trusted odometry from node i + 1 to node i (edges 0 to 28), then robust loop closures
/// from node i to node i + 5 (edge 29 + i), the closures listed in `wrong` replaced by random poses (with
/// the same confident information). `extra_nodes` nodes with no edge follow the loop's.
fn loop_graph(truth: &[Pose], wrong: &[usize], extra_nodes: u64) -> PoseGraph {
    let info = information();
    let mut rng = Rng(7);
    let mut graph = PoseGraph::new(LOOP as u64 + extra_nodes).unwrap();
    for i in 0..LOOP - 1 {
        let edge = graph.add_edge(i as u64 + 1, i as u64, &relative(truth, i + 1, i), &info, false).unwrap();
        assert_eq!(edge, i as u64);
    }
    for i in 0..LOOP {
        let target = (i + CLOSURE_STEP) % LOOP;
        let transform = if wrong.contains(&i) { rng.pose().to_matrix() } else { relative(truth, i, target) };
        let edge = graph.add_edge(i as u64, target as u64, &transform, &info, true).unwrap();
        assert_eq!(edge, (LOOP - 1 + i) as u64);
    }
    assert_eq!(graph.num_edges(), (2 * LOOP - 1) as u64);
    graph
}

/// Nine of the thirty loop closures (30%), picked by a fixed seed.
fn wrong_closures() -> Vec<usize> {
    let mut rng = Rng(2024);
    let mut wrong = Vec::new();
    while wrong.len() < 9 {
        let i = (rng.next_u64() % LOOP as u64) as usize;
        if !wrong.contains(&i) {
            wrong.push(i);
        }
    }
    wrong.sort_unstable();
    wrong
}

/// The largest absolute difference between two matrices.
fn max_difference(a: &Matrix4, b: &Matrix4) -> f64 {
    a.iter().flatten().zip(b.iter().flatten()).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
}

/// Checks that the solution's poses of the first `LOOP` nodes are the truth in the frame of `anchor`.
fn assert_poses_are_the_truth(solution: &PoseGraphSolution, truth: &[Pose], anchor: usize, tolerance: f64) {
    let frame = truth[anchor].inverse();
    for i in 0..truth.len() {
        let expected = frame.compose(&truth[i]).to_matrix();
        let error = max_difference(&solution.poses[i], &expected);
        assert!(
            error <= tolerance,
            "node {i} (anchor {anchor}): off by {error}\n{:?}\n{expected:?}",
            solution.poses[i]
        );
    }
    assert_eq!(solution.poses[anchor], identity(), "the anchor's pose is the identity");
}

fn assert_same_bits(a: &PoseGraphSolution, b: &PoseGraphSolution) {
    assert_eq!(a.poses.len(), b.poses.len());
    for (i, (x, y)) in a.poses.iter().zip(&b.poses).enumerate() {
        assert!(common::same_bits_matrix(x, y), "node {i}: {x:?} vs {y:?}");
    }
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&a.residuals), bits(&b.residuals));
    assert_eq!(a.placed, b.placed);
    assert_eq!(a.components, b.components);
    assert_eq!(a.accepted, b.accepted);
}

// ------------------------------------------------------------------------------------------------
// Solutions
// ------------------------------------------------------------------------------------------------

#[test]
fn constants_are_the_headers() {
    assert_eq!(PoseGraph::DEFAULT_BOUND, 22.4577);
    assert_eq!(PoseGraph::MAX_NODES, 100_000_000);
}

#[test]
fn an_edge_maps_the_source_into_the_target_frame() {
    // One edge from node 0 to node 1 with transform T = inv(X_1) X_0: anchored at the target, the source's
    // pose is T; anchored at the source, the target's pose is inv(T).
    let t = Pose::axis_angle([0.3, -0.5, 1.0], 40.0, [1.0, -2.0, 0.5]);
    let mut graph = PoseGraph::new(2).unwrap();
    assert_eq!(graph.add_edge(0, 1, &t.to_matrix(), &information(), false).unwrap(), 0);
    let at_target = graph.optimize(1, PoseGraph::DEFAULT_BOUND).unwrap();
    assert!(max_difference(&at_target.poses[0], &t.to_matrix()) < 1e-12, "{:?}", at_target.poses[0]);
    assert_eq!(at_target.poses[1], identity());
    let at_source = graph.optimize(0, PoseGraph::DEFAULT_BOUND).unwrap();
    assert!(max_difference(&at_source.poses[1], &t.inverse().to_matrix()) < 1e-12, "{:?}", at_source.poses[1]);
    for s in [&at_target, &at_source] {
        assert_eq!(s.placed, [true, true]);
        assert_eq!(s.components, [0, 0]);
        assert_eq!(s.accepted, [true]);
        assert!(s.residuals[0] < 1e-20, "{}", s.residuals[0]);
    }
}

#[test]
fn a_noise_free_loop_is_the_truth() {
    let truth = loop_truth();
    let mut graph = loop_graph(&truth, &[], 0);
    for anchor in [0, 17] {
        let solution = graph.optimize(anchor as u64, PoseGraph::DEFAULT_BOUND).unwrap();
        assert_poses_are_the_truth(&solution, &truth, anchor, 1e-9);
        assert_eq!(solution.placed, vec![true; LOOP]);
        assert_eq!(solution.components, vec![0; LOOP]);
        assert_eq!(solution.accepted, vec![true; 2 * LOOP - 1]);
        assert_eq!(solution.residuals.len(), 2 * LOOP - 1);
        for (e, r) in solution.residuals.iter().enumerate() {
            assert!(*r >= 0.0 && *r < 1e-12, "edge {e}: residual {r}");
        }
    }
    // The graph is unchanged by optimising it.
    assert_eq!((graph.num_nodes(), graph.num_edges()), (LOOP as u64, (2 * LOOP - 1) as u64));
}

#[test]
fn wrong_loop_closures_are_rejected_and_the_right_ones_kept() {
    let truth = loop_truth();
    let wrong = wrong_closures();
    assert_eq!(wrong.len(), 9, "30% of the 30 closures");
    let mut graph = loop_graph(&truth, &wrong, 0);
    let solution = graph.optimize(0, PoseGraph::DEFAULT_BOUND).unwrap();
    for e in 0..LOOP - 1 {
        assert!(solution.accepted[e], "trusted edge {e} is always kept");
    }
    for i in 0..LOOP {
        let e = LOOP - 1 + i;
        let (accepted, residual) = (solution.accepted[e], solution.residuals[e]);
        if wrong.contains(&i) {
            assert!(!accepted, "wrong closure {i} -> {} accepted (residual {residual})", (i + CLOSURE_STEP) % LOOP);
            assert!(residual > PoseGraph::DEFAULT_BOUND, "wrong closure {i}: residual {residual}");
        } else {
            assert!(accepted, "right closure {i} -> {} rejected (residual {residual})", (i + CLOSURE_STEP) % LOOP);
            assert!(residual < 1e-12, "right closure {i}: residual {residual}");
        }
    }
    // The wrong closures do not bend the map: the accepted edges are noise-free.
    assert_poses_are_the_truth(&solution, &truth, 0, 1e-9);
    assert_eq!(solution.placed, vec![true; LOOP]);
    assert_eq!(solution.components, vec![0; LOOP]);
}

#[test]
fn the_same_graph_gives_the_same_bits() {
    let truth = loop_truth();
    let wrong = wrong_closures();
    let mut graph = loop_graph(&truth, &wrong, 2);
    let first = graph.optimize(3, PoseGraph::DEFAULT_BOUND).unwrap();
    // Again on the same graph, after another optimisation in between, and on a graph built anew.
    graph.optimize(0, 5.0).unwrap();
    let again = graph.optimize(3, PoseGraph::DEFAULT_BOUND).unwrap();
    let fresh = loop_graph(&truth, &wrong, 2).optimize(3, PoseGraph::DEFAULT_BOUND).unwrap();
    assert_same_bits(&first, &again);
    assert_same_bits(&first, &fresh);
    // (Compare bits: PartialEq is false for the NaN poses of the nodes that are not placed.)
    assert_same_bits(&first, &first.clone());
    // From another thread too.
    let other = std::thread::spawn(move || {
        let truth = loop_truth();
        loop_graph(&truth, &wrong_closures(), 2).optimize(3, PoseGraph::DEFAULT_BOUND).unwrap()
    })
    .join()
    .unwrap();
    assert_same_bits(&first, &other);
}

#[test]
fn nodes_not_joined_to_the_anchor_are_not_placed() {
    // The loop (nodes 0 to 29), an isolated node 30, and nodes 31 and 32 joined only to each other.
    let truth = loop_truth();
    let mut graph = loop_graph(&truth, &[], 3);
    let step = Pose::axis_angle([1.0, 0.0, 0.0], 30.0, [0.0, 1.0, 0.0]).to_matrix();
    let apart = graph.add_edge(32, 31, &step, &information(), false).unwrap();
    assert_eq!(apart, (2 * LOOP - 1) as u64);
    let solution = graph.optimize(0, PoseGraph::DEFAULT_BOUND).unwrap();
    assert_eq!(solution.poses.len(), LOOP + 3);
    assert_poses_are_the_truth(&solution, &truth, 0, 1e-9);
    for node in LOOP..LOOP + 3 {
        assert!(!solution.placed[node], "node {node} is placed");
        assert!(solution.poses[node].iter().flatten().all(|v| v.is_nan()), "node {node}: {:?}", solution.poses[node]);
    }
    assert!(solution.placed[..LOOP].iter().all(|&p| p));
    assert_eq!(solution.components[..LOOP], vec![0; LOOP]);
    assert_eq!(solution.components[LOOP..], [30, 31, 31]);
    // The edge between nodes 31 and 32 lies outside the anchor's component: not accepted, no residual.
    assert!(!solution.accepted[apart as usize]);
    assert!(solution.residuals[apart as usize].is_nan());

    // Anchored in the small component, only it is placed, and the edge from 32 to 31 holds.
    let small = graph.optimize(31, PoseGraph::DEFAULT_BOUND).unwrap();
    let placed: Vec<usize> = (0..LOOP + 3).filter(|&i| small.placed[i]).collect();
    assert_eq!(placed, [31, 32]);
    assert!(max_difference(&small.poses[32], &step) < 1e-12);
    assert!(small.poses[0].iter().flatten().all(|v| v.is_nan()));
    assert_eq!(small.accepted.iter().filter(|&&a| a).count(), 1);
    assert!(small.accepted[apart as usize]);
    assert!(small.residuals[..apart as usize].iter().all(|r| r.is_nan()));
}

#[test]
fn adding_an_edge_after_optimising_changes_the_next_solution() {
    let truth = loop_truth();
    let mut graph = PoseGraph::new(3).unwrap();
    let info = information();
    graph.add_edge(1, 0, &relative(&truth, 1, 0), &info, false).unwrap();
    let before = graph.optimize(0, PoseGraph::DEFAULT_BOUND).unwrap();
    assert_eq!(before.placed, [true, true, false]);
    assert_eq!(before.accepted.len(), 1);
    // A robust edge alone still places the node it reaches.
    assert_eq!(graph.add_edge(2, 1, &relative(&truth, 2, 1), &info, true).unwrap(), 1);
    let after = graph.optimize(0, PoseGraph::DEFAULT_BOUND).unwrap();
    assert_eq!(after.placed, [true, true, true]);
    assert_eq!(after.accepted, [true, true]);
    let expected = truth[0].inverse().compose(&truth[2]).to_matrix();
    assert!(max_difference(&after.poses[2], &expected) < 1e-9);
}

// ------------------------------------------------------------------------------------------------
// Errors
// ------------------------------------------------------------------------------------------------

#[track_caller]
fn assert_invalid<T: std::fmt::Debug>(result: Result<T, kissm::Error>, needle: &str) {
    let err = result.expect_err("an invalid argument");
    assert_eq!(err.kind(), ErrorKind::InvalidArgument, "{err}");
    assert_eq!(err.code(), sys::KISSM_ERR_INVALID_ARGUMENT, "{err}");
    assert!(err.message().contains(needle), "the message {:?} does not name {needle:?}", err.message());
}

#[test]
fn creating_a_graph_checks_the_node_count() {
    assert_invalid(PoseGraph::new(0), "num_nodes");
    assert_invalid(PoseGraph::new(PoseGraph::MAX_NODES + 1), "num_nodes");
    assert_invalid(PoseGraph::new(u64::MAX), "num_nodes");
    let graph = PoseGraph::new(1).unwrap();
    assert_eq!((graph.num_nodes(), graph.num_edges()), (1, 0));
    assert_eq!(format!("{graph:?}"), "PoseGraph { num_nodes: 1, num_edges: 0 }");
}

/// A graph of 4 nodes with one valid edge and a solution.
fn small_graph() -> PoseGraph {
    let mut graph = PoseGraph::new(4).unwrap();
    graph.add_edge(1, 0, &identity(), &information(), false).unwrap();
    graph
}

#[track_caller]
fn assert_edge_rejected(
    graph: &mut PoseGraph,
    (source, target): (u64, u64),
    transform: &Matrix4,
    information: &Matrix6,
    needle: &str,
) {
    let before = graph.num_edges();
    assert_invalid(graph.add_edge(source, target, transform, information, true), needle);
    assert_eq!(graph.num_edges(), before, "a failed add_edge leaves the graph unchanged");
}

#[test]
fn add_edge_checks_the_nodes() {
    let mut graph = small_graph();
    let (t, info) = (identity(), information());
    assert_edge_rejected(&mut graph, (4, 0), &t, &info, "source");
    assert_edge_rejected(&mut graph, (0, 4), &t, &info, "target");
    assert_edge_rejected(&mut graph, (u64::MAX, 0), &t, &info, "source");
    assert_edge_rejected(&mut graph, (0, u64::MAX), &t, &info, "target");
    assert_edge_rejected(&mut graph, (2, 2), &t, &info, "source and target");
    assert_eq!(graph.num_edges(), 1);
    // The graph is still usable, and its solution is that of its single edge.
    assert_eq!(graph.add_edge(2, 1, &t, &info, false).unwrap(), 1);
    assert_eq!(graph.optimize(0, PoseGraph::DEFAULT_BOUND).unwrap().placed, [true, true, true, false]);
}

#[test]
fn add_edge_checks_that_the_transform_is_rigid() {
    let mut graph = small_graph();
    let info = information();
    let rigid = Pose::axis_angle([1.0, 2.0, 3.0], 70.0, [1.0, 2.0, 3.0]).to_matrix();
    let mut scaled = rigid;
    (0..3).for_each(|i| (0..3).for_each(|j| scaled[i][j] *= 1.1));
    let mut reflected = rigid;
    (0..3).for_each(|i| reflected[i][0] = -reflected[i][0]);
    let mut sheared = rigid;
    sheared[0][1] += 0.05;
    let mut last_row = rigid;
    last_row[3][0] = 0.5;
    let mut homogeneous = rigid;
    homogeneous[3][3] = 2.0;
    let mut nan = rigid;
    nan[1][3] = f64::NAN;
    let mut infinite = rigid;
    infinite[2][2] = f64::INFINITY;
    for (what, t) in [
        ("scaled", scaled),
        ("reflected", reflected),
        ("sheared", sheared),
        ("last row", last_row),
        ("homogeneous", homogeneous),
        ("NaN", nan),
        ("infinite", infinite),
        ("zero", [[0.0; 4]; 4]),
    ] {
        let before = graph.num_edges();
        let err = graph.add_edge(0, 2, &t, &info, true).expect_err(what);
        assert_eq!((err.kind(), err.code()), (ErrorKind::InvalidArgument, sys::KISSM_ERR_INVALID_ARGUMENT), "{what}");
        assert!(err.message().contains("transform"), "{what}: {}", err.message());
        assert_eq!(graph.num_edges(), before, "{what}");
    }
    assert_eq!(graph.add_edge(0, 2, &rigid, &info, true).unwrap(), 1);
}

#[test]
fn add_edge_checks_the_information() {
    let mut graph = small_graph();
    let t = identity();
    let good = information();

    let mut asymmetric = good;
    asymmetric[0][4] = 1.0; // |I - I^T| = 1, above 1e-9 of the largest entry 1e4
    assert_edge_rejected(&mut graph, (0, 2), &t, &asymmetric, "symmetric");
    let mut indefinite = good;
    indefinite[5][5] = -1.0;
    assert_edge_rejected(&mut graph, (0, 2), &t, &indefinite, "positive definite");
    let mut singular = good;
    singular[3] = [0.0; 6];
    (0..6).for_each(|i| singular[i][3] = 0.0);
    assert_edge_rejected(&mut graph, (0, 2), &t, &singular, "positive definite");
    assert_edge_rejected(&mut graph, (0, 2), &t, &[[0.0; 6]; 6], "positive definite");
    assert_edge_rejected(&mut graph, (0, 2), &t, &[[1.0; 6]; 6], "positive definite"); // rank 1
    let mut negative = good;
    (0..6).for_each(|i| negative[i][i] = -negative[i][i]);
    assert_edge_rejected(&mut graph, (0, 2), &t, &negative, "positive definite");
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let mut m = good;
        m[2][2] = bad;
        assert_edge_rejected(&mut graph, (0, 2), &t, &m, "information[14]");
        let mut m = good;
        m[1][4] = bad;
        m[4][1] = bad;
        assert_edge_rejected(&mut graph, (0, 2), &t, &m, "information[10]");
    }
    assert_eq!(graph.num_edges(), 1);

    // Symmetric to within 1e-9 of the largest entry (as a matrix written out in decimal would be) is fine.
    let mut nearly = good;
    nearly[0][1] += 1e-9;
    assert_eq!(graph.add_edge(0, 2, &t, &nearly, true).unwrap(), 1);
}

#[test]
fn optimize_checks_the_anchor_and_the_bound() {
    let mut graph = small_graph();
    assert_invalid(graph.optimize(4, PoseGraph::DEFAULT_BOUND), "anchor");
    assert_invalid(graph.optimize(u64::MAX, PoseGraph::DEFAULT_BOUND), "anchor");
    for bound in [0.0, -0.0, -1.0, f64::NAN, f64::NEG_INFINITY, f64::INFINITY] {
        assert_invalid(graph.optimize(0, bound), "bound");
    }
    // A failed optimisation leaves the graph as it was, ready for a good one.
    assert_eq!((graph.num_nodes(), graph.num_edges()), (4, 1));
    let solution = graph.optimize(0, f64::MIN_POSITIVE).unwrap();
    assert_eq!(solution.placed, [true, true, false, false]);
}

// ------------------------------------------------------------------------------------------------
// Threads and cancellation
// ------------------------------------------------------------------------------------------------

/// A graph that takes a while to optimise (a few tenths of a second): a loop of `n` nodes with trusted odometry
/// and robust closures from every node to each of the three after the next, all right but a little noisy (up to
/// 0.05 degrees and 0.01 per axis), so that Levenberg-Marquardt iterates and nothing is rejected.
fn noisy_graph(n: usize) -> PoseGraph {
    let truth: Vec<Pose> = (0..n)
        .map(|i| {
            let theta = i as f64 / n as f64 * std::f64::consts::TAU;
            let t = [100.0 * theta.cos(), 100.0 * theta.sin(), (7.0 * theta).sin()];
            Pose::axis_angle([0.1, 0.2, 1.0], theta.to_degrees() + 90.0, t)
        })
        .collect();
    let info = information();
    let mut rng = Rng(5);
    let mut graph = PoseGraph::new(n as u64).unwrap();
    for i in 0..n - 1 {
        graph.add_edge(i as u64 + 1, i as u64, &relative(&truth, i + 1, i), &info, false).unwrap();
    }
    for i in 0..n {
        for k in 2..=4 {
            let target = (i + k) % n;
            let noise = Pose::axis_angle(
                [rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0), 1.0],
                rng.uniform(0.0, 0.05),
                [rng.uniform(-0.01, 0.01), rng.uniform(-0.01, 0.01), rng.uniform(-0.01, 0.01)],
            );
            let t = Pose::from_matrix(&relative(&truth, i, target)).compose(&noise).to_matrix();
            graph.add_edge(i as u64, target as u64, &t, &info, true).unwrap();
        }
    }
    graph
}

#[test]
fn cancel_stops_a_running_optimisation_and_the_graph_stays_usable() {
    let mut graph = noisy_graph(2000);
    // A request made while no optimisation runs is dropped when the next one starts.
    graph.cancel_handle().cancel();
    let reference = graph.optimize(0, PoseGraph::DEFAULT_BOUND).expect("a stale cancel request is dropped");
    assert!(reference.accepted.iter().all(|&a| a) && reference.placed.iter().all(|&p| p));

    let cancel = graph.cancel_handle();
    let outcome = common::while_cancelling(move || cancel.cancel(), || graph.optimize(0, PoseGraph::DEFAULT_BOUND));
    let err = outcome.expect_err("cancelled while running");
    assert_eq!((err.kind(), err.code()), (ErrorKind::Cancelled, sys::KISSM_ERR_CANCELLED), "{err}");

    // The graph is whole, and optimising it again gives the same bits as before.
    let after = graph.optimize(0, PoseGraph::DEFAULT_BOUND).unwrap();
    assert_same_bits(&reference, &after);
    // The handle keeps the graph's C object alive after the PoseGraph is dropped.
    let handle = graph.cancel_handle();
    drop(graph);
    handle.cancel();
    assert_eq!(format!("{handle:?}"), "PoseGraphCancelHandle { .. }");
}

#[test]
fn a_graph_moves_between_threads() {
    let truth = loop_truth();
    let mut graph = loop_graph(&truth, &[], 0);
    let here = graph.optimize(0, PoseGraph::DEFAULT_BOUND).unwrap();
    let (graph, there) = std::thread::spawn(move || {
        let solution = graph.optimize(0, PoseGraph::DEFAULT_BOUND).unwrap();
        (graph, solution)
    })
    .join()
    .unwrap();
    assert_same_bits(&here, &there);
    assert_eq!(graph.num_edges(), (2 * LOOP - 1) as u64);
}

#[test]
fn send_and_sync() {
    assert_send::<PoseGraph>();
    <PoseGraph as NotSync<_>>::check();
    assert_send::<PoseGraphCancelHandle>();
    assert_sync::<PoseGraphCancelHandle>();
    assert_send::<PoseGraphSolution>();
    assert_sync::<PoseGraphSolution>();
}

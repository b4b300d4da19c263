// SPDX-License-Identifier: MIT
//! Multiway alignment (`Matcher::align_features`, `sequence_loops`): four scans of the shared test scene, each
//! cropped to its own half and seen from its own sensor pose, placed in scan 0's frame within 2 degrees and 2
//! voxels of the truth by every pair policy; a scan without features not placed; the same bits at 1 and 2
//! threads; the registrations as `register_features` gives them; bad input with exact error kinds and messages
//! naming the argument; the loop-candidate rule against cases worked out by hand.

mod common;

use std::sync::OnceLock;

use common::{moved, scene, while_cancelling, Pose, SCENE_VOXEL};
use kissm::kissm_sys as sys;
use kissm::{
    sequence_loops, AlignOptions, Alignment, Config, EdgeState, ErrorKind, Features, LoopPositions, Matcher, Pairs,
    PoseGraph, RefineMode,
};

const SCANS: usize = 4;

type Matrix4 = [[f64; 4]; 4];

fn config(threads: usize) -> Config {
    Config::builder().voxel_size(SCENE_VOXEL).refine_mode(RefineMode::Gicp).num_threads(threads).build().unwrap()
}

/// The scans: their world-from-scan poses (the truth) and their features.
struct Scans {
    world_from_scan: Vec<Pose>,
    features: Vec<Features>,
}

/// Scan k: the scene's source cloud cropped to a half space whose normal turns by 90 degrees with k (about 3 units
/// past the scene's middle, so that any two scans share most of it), seen from a sensor turned by 40k degrees
/// about a tilted axis and moved by a metre or two. Computed once per test binary; `None` when the scene is absent.
fn scans() -> Option<&'static Scans> {
    static SCANS_ONCE: OnceLock<Option<Scans>> = OnceLock::new();
    SCANS_ONCE
        .get_or_init(|| {
            let pair = scene("align scans")?;
            let centre = [3.6, 1.4, -2.7];
            let mut matcher = Matcher::new(&config(2)).unwrap();
            let mut world_from_scan = Vec::new();
            let mut features = Vec::new();
            for k in 0..SCANS {
                let angle = (90.0 * k as f64).to_radians();
                let normal = [angle.cos(), angle.sin(), 0.0];
                let kept: Vec<[f64; 3]> = pair
                    .source
                    .iter()
                    .copied()
                    .filter(|p| (0..3).map(|i| normal[i] * (p[i] - centre[i])).sum::<f64>() > -3.0)
                    .collect();
                assert!(kept.len() > pair.source.len() / 2 && kept.len() < pair.source.len(), "crop {k}");
                let kf = k as f64;
                let pose = Pose::axis_angle([0.3, -0.2, 1.0], 40.0 * kf, [1.5 * kf, -0.7 * kf, 0.2 * kf]);
                world_from_scan.push(pose);
                features.push(matcher.compute_features(&moved(&kept, &pose.inverse())).unwrap());
            }
            Some(Scans { world_from_scan, features })
        })
        .as_ref()
}

fn all_features(scans: &Scans) -> Vec<Option<&Features>> {
    scans.features.iter().map(Some).collect()
}

fn align(scans: &Scans, features: &[Option<&Features>], pairs: Pairs<'_>, threads: usize) -> Alignment {
    let options = AlignOptions { pairs, ..AlignOptions::default() };
    let alignment = Matcher::new(&config(threads)).unwrap().align_features(features, &options).unwrap();
    check_consistent(&alignment, scans);
    alignment
}

/// Checks shared by every successful alignment: the lengths, and each registration's edge state, information
/// and residual.
fn check_consistent(alignment: &Alignment, scans: &Scans) {
    assert_eq!(alignment.num_scans(), scans.features.len());
    assert_eq!(alignment.poses().len(), alignment.num_scans());
    assert_eq!(alignment.placed().len(), alignment.num_scans());
    assert_eq!(alignment.components().len(), alignment.num_scans());
    for r in alignment.registrations() {
        assert!(r.source < alignment.num_scans() && r.target < alignment.num_scans() && r.source != r.target);
        match r.edge {
            EdgeState::NotAnEdge => {
                assert!(!r.registration.valid);
                assert!(r.information.is_none() && r.residual.is_nan());
            }
            EdgeState::Rejected | EdgeState::Accepted => {
                assert!(r.registration.valid);
                let information = r.information.expect("an edge has an information");
                // A refined pose's edge is weighed by its refined information.
                let refined = r.registration.refinement.expect("refined").information;
                assert!(common::same_bits_matrix(&information, &refined));
            }
        }
    }
}

/// Every scan placed within 2 degrees and 2 voxels of the truth relative to scan 0.
fn assert_placed_at_the_truth(alignment: &Alignment, scans: &Scans) {
    let origin = scans.world_from_scan[0].inverse();
    for k in 0..SCANS {
        assert!(alignment.placed()[k], "scan {k} not placed");
        assert_eq!(alignment.components()[k], 0);
        let pose = alignment.pose(k).expect("a placed scan has a pose");
        let truth = origin.compose(&scans.world_from_scan[k]);
        let (rot, trans) = truth.errors(&Pose::from_matrix(pose));
        assert!(rot < 2.0 && trans < 2.0 * SCENE_VOXEL, "scan {k}: rotation error {rot} deg, translation {trans}");
    }
    assert!(alignment.poses()[0].iter().flatten().zip(identity().iter().flatten()).all(|(a, b)| (a - b).abs() < 1e-12));
}

fn identity() -> Matrix4 {
    [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]]
}

fn pairs_of(alignment: &Alignment) -> Vec<(usize, usize)> {
    alignment.registrations().iter().map(|r| (r.source, r.target)).collect()
}

#[test]
fn all_pairs_place_every_scan_at_the_truth() {
    let Some(scans) = scans() else { return };
    let features = all_features(scans);
    let alignment = align(scans, &features, Pairs::All, 2);
    assert_eq!(pairs_of(&alignment), [(1, 0), (2, 0), (3, 0), (2, 1), (3, 1), (3, 2)]);
    assert_placed_at_the_truth(&alignment, scans);
    // A clean scene: every pair registers and every edge is accepted.
    assert!(alignment.registrations().iter().all(|r| r.registration.valid && r.edge == EdgeState::Accepted));
    for r in alignment.registrations().iter().filter(|r| r.edge == EdgeState::Accepted) {
        assert!(r.residual.is_finite() && r.residual >= 0.0);
    }
    // Each registration is register_features on its pair.
    let mut matcher = Matcher::new(&config(1)).unwrap();
    for r in alignment.registrations() {
        let direct = matcher.register_features(&scans.features[r.source], &scans.features[r.target]).unwrap();
        assert!(direct.same_result(&r.registration), "pair ({}, {})", r.source, r.target);
    }
    // The default options are All with the default bound.
    let default = Matcher::new(&config(2)).unwrap().align_features(&features, &AlignOptions::default()).unwrap();
    assert!(default.same_result(&alignment));
}

#[test]
fn a_sequence_registers_consecutive_pairs_then_its_loop_candidates() {
    let Some(scans) = scans() else { return };
    let features = all_features(scans);
    // The defaults: a gap of 10 leaves four scans no loop candidate.
    let plain = align(scans, &features, Pairs::sequence(), 2);
    assert_eq!(pairs_of(&plain), [(1, 0), (2, 1), (3, 2)]);
    assert_placed_at_the_truth(&plain, scans);

    // A gap of 2: the loop candidates are those of sequence_loops on the consecutive registrations, with the
    // default radius of 30 voxels.
    let pairs = Pairs::Sequence { priors: None, loop_radius: None, loop_gap: 2, loops_per_scan: 5 };
    let looped = align(scans, &features, pairs, 2);
    let steps: Vec<Option<Matrix4>> = looped.registrations()[..SCANS - 1]
        .iter()
        .map(|r| r.registration.valid.then_some(r.registration.transform))
        .collect();
    let loops = sequence_loops(LoopPositions::Steps(&steps), 30.0 * SCENE_VOXEL, 2, 5).unwrap();
    assert_eq!(loops, [(2, 0), (3, 0), (3, 1)]);
    assert_eq!(pairs_of(&looped)[SCANS - 1..], loops[..]);
    assert_placed_at_the_truth(&looped, scans);

    // Priors (the truth in the world frame) choose the candidates instead; a radius of 1 keeps none of these
    // scans, which are 1.7 to 5 apart.
    let priors: Vec<Matrix4> = scans.world_from_scan.iter().map(|p| p.to_matrix()).collect();
    let pairs = Pairs::Sequence { priors: Some(&priors), loop_radius: Some(1.0), loop_gap: 2, loops_per_scan: 5 };
    assert_eq!(pairs_of(&align(scans, &features, pairs, 2)), [(1, 0), (2, 1), (3, 2)]);
    let pairs = Pairs::Sequence { priors: Some(&priors), loop_radius: Some(4.0), loop_gap: 2, loops_per_scan: 5 };
    let with_priors = align(scans, &features, pairs, 2);
    let expected = sequence_loops(LoopPositions::Priors(&priors), 4.0, 2, 5).unwrap();
    assert_eq!(expected, [(2, 0), (3, 1)]);
    assert_eq!(pairs_of(&with_priors)[SCANS - 1..], expected[..]);
    assert_placed_at_the_truth(&with_priors, scans);
}

#[test]
fn a_list_registers_its_pairs_in_order() {
    let Some(scans) = scans() else { return };
    let features = all_features(scans);
    let list = [(0, 1), (2, 1), (3, 0)];
    let alignment = align(scans, &features, Pairs::List(&list), 2);
    assert_eq!(pairs_of(&alignment), list);
    assert_placed_at_the_truth(&alignment, scans);
    // A list that leaves scan 3 out: it is not placed, and gets NaN.
    let alignment = align(scans, &features, Pairs::List(&[(1, 0), (2, 1)]), 2);
    assert_eq!(alignment.placed(), [true, true, true, false]);
    assert_eq!(alignment.components()[3], 3);
    assert!(alignment.poses()[3].iter().flatten().all(|v| v.is_nan()));
    assert!(alignment.pose(3).is_none() && alignment.pose(4).is_none());
    // An empty list registers nothing: scan 0 alone is placed.
    let alignment = align(scans, &features, Pairs::List(&[]), 2);
    assert!(alignment.registrations().is_empty());
    assert_eq!(alignment.placed(), [true, false, false, false]);
    assert_eq!(alignment.pose(0), Some(&identity()));
}

#[test]
fn two_sessions_merge_into_one_frame() {
    let Some(scans) = scans() else { return };
    let features = all_features(scans);
    let sessions = [0, 0, 1, 1];
    let pairs = Pairs::Sessions { sessions: &sessions, stride: 2, loop_radius: None, loop_gap: 2, loops_per_scan: 1 };
    let alignment = align(scans, &features, pairs, 2);
    assert_placed_at_the_truth(&alignment, scans);
    // Odometry first, (1, 0) and (3, 2), trusted: valid ones are accepted edges; then the grid (2, 0).
    let pairs_run = pairs_of(&alignment);
    assert_eq!(pairs_run[..3], [(1, 0), (3, 2), (2, 0)]);
    for r in &alignment.registrations()[..2] {
        assert!(!r.registration.valid || r.edge == EdgeState::Accepted);
    }
    // Every later pair joins session 1 to session 0.
    assert!(pairs_run[3..].iter().all(|&(s, t)| sessions[s] == 1 && sessions[t] == 0));
    assert!(align(scans, &features, pairs, 1).same_result(&alignment));
}

#[test]
fn a_scan_without_features_is_not_placed() {
    let Some(scans) = scans() else { return };
    let mut features = all_features(scans);
    features[2] = None;
    let alignment = align(scans, &features, Pairs::All, 2);
    assert_eq!(pairs_of(&alignment), [(1, 0), (3, 0), (3, 1)]);
    assert_eq!(alignment.placed(), [true, true, false, true]);
    assert_eq!(alignment.components(), [0, 0, 2, 0]);
    assert!(alignment.poses()[2].iter().flatten().all(|v| v.is_nan()));
    assert!(alignment.pose(2).is_none());
    for k in [1, 3] {
        let truth = scans.world_from_scan[0].inverse().compose(&scans.world_from_scan[k]);
        let (rot, trans) = truth.errors(&Pose::from_matrix(alignment.pose(k).unwrap()));
        assert!(rot < 2.0 && trans < 2.0 * SCENE_VOXEL, "scan {k}: {rot} deg, {trans}");
    }
    // In a sequence the missing scan breaks the chain: 3 is joined to 0 through no pair.
    let alignment = align(scans, &features, Pairs::sequence(), 2);
    assert_eq!(pairs_of(&alignment), [(1, 0)]);
    assert_eq!(alignment.placed(), [true, true, false, false]);
}

#[test]
fn the_result_does_not_depend_on_the_thread_count() {
    let Some(scans) = scans() else { return };
    let features = all_features(scans);
    let list = [(1, 0), (2, 1), (3, 2), (3, 0)];
    for pairs in [
        Pairs::All,
        Pairs::Sequence { priors: None, loop_radius: None, loop_gap: 2, loops_per_scan: 5 },
        Pairs::List(&list),
    ] {
        let one = align(scans, &features, pairs, 1);
        let two = align(scans, &features, pairs, 2);
        assert!(one.same_result(&two), "{pairs:?}");
        for (a, b) in one.poses().iter().zip(two.poses()) {
            assert!(common::same_bits_matrix(a, b), "{pairs:?}");
        }
        assert!(one.registrations().iter().zip(two.registrations()).all(|(a, b)| a.same_result(b)));
        // And the same call again gives the same bits.
        assert!(align(scans, &features, pairs, 2).same_result(&two));
    }
}

#[test]
fn cancel_stops_an_alignment_and_the_matcher_stays_usable() {
    let Some(scans) = scans() else { return };
    let features = all_features(scans);
    let mut matcher = Matcher::new(&config(2)).unwrap();
    let cancel = matcher.cancel_handle();
    let result =
        while_cancelling(move || cancel.cancel(), || matcher.align_features(&features, &AlignOptions::default()));
    assert_error(result, ErrorKind::Cancelled, "");
    let alignment = matcher.align_features(&features, &AlignOptions::default()).unwrap();
    assert!(alignment.same_result(&align(scans, &features, Pairs::All, 1)));
}

fn assert_error<T: std::fmt::Debug>(result: Result<T, kissm::Error>, kind: ErrorKind, needle: &str) {
    let err = result.expect_err("an error");
    assert_eq!(err.kind(), kind, "{err}");
    assert!(err.message().contains(needle), "the message {:?} does not name {needle:?}", err.message());
}

#[test]
fn bad_input_fails_with_the_argument_named() {
    let Some(scans) = scans() else { return };
    let features = all_features(scans);
    let mut matcher = Matcher::new(&config(2)).unwrap();
    let mut run = |features: &[Option<&Features>], pairs: Pairs<'_>, bound: f64| {
        matcher.align_features(features, &AlignOptions { pairs, bound, ..AlignOptions::default() })
    };
    let bound = PoseGraph::DEFAULT_BOUND;
    let invalid = ErrorKind::InvalidArgument;
    assert_error(run(&features, Pairs::List(&[(1, 0), (0, 4)]), bound), invalid, "pair_list pair 1");
    assert_error(run(&features, Pairs::List(&[(1, 1)]), bound), invalid, "itself");
    let priors = vec![identity(); SCANS - 1];
    let sequence = |priors, loop_radius, loop_gap, loops_per_scan| Pairs::Sequence {
        priors,
        loop_radius,
        loop_gap,
        loops_per_scan,
    };
    assert_error(run(&features, sequence(Some(&priors[..]), None, 2, 5), bound), invalid, "priors");
    assert_error(run(&features, sequence(None, None, 0, 5), bound), invalid, "loop_gap");
    assert_error(run(&features, sequence(None, None, 1_000_001, 5), bound), invalid, "loop_gap");
    assert_error(run(&features, sequence(None, None, usize::MAX, 5), bound), invalid, "loop_gap");
    assert_error(run(&features, sequence(None, None, 2, usize::MAX), bound), invalid, "loops_per_scan");
    assert_error(run(&features, sequence(None, Some(-1.0), 2, 5), bound), invalid, "loop_radius");
    assert_error(run(&features, sequence(None, Some(f64::NAN), 2, 5), bound), invalid, "loop_radius");
    assert_error(run(&features, Pairs::All, 0.0), invalid, "bound");
    assert_error(run(&features, Pairs::All, f64::INFINITY), invalid, "bound");
    assert_error(run(&[], Pairs::All, bound), invalid, "features");
    let sessions =
        |sessions, stride| Pairs::Sessions { sessions, stride, loop_radius: None, loop_gap: 2, loops_per_scan: 1 };
    assert_error(run(&features, sessions(&[0, 0, 1], 2), bound), invalid, "sessions holds 3");
    assert_error(run(&features, sessions(&[0, 1, 0, 1], 2), bound), invalid, "options->sessions[2]");
    assert_error(run(&features, sessions(&[0, 0, 1, 1], 0), bound), invalid, "options->stride");
    // Features of other descriptor settings.
    let other = Matcher::with_voxel_size(0.5).unwrap().compute_features(&common::flat_plane()).unwrap();
    let mixed = [features[0], Some(&other)];
    assert_error(run(&mixed, Pairs::All, bound), ErrorKind::FeaturesMismatch, "features[1]");
    // The matcher is still usable.
    assert!(run(&features[..2], Pairs::All, bound).is_ok());
    let similar =
        |similar_per_scan| AlignOptions { pairs: Pairs::sequence(), similar_per_scan, ..AlignOptions::default() };
    assert_error(matcher.align_features(&features, &similar(1_000_001)), invalid, "options->similar_per_scan");
    assert_error(matcher.align_features(&features, &similar(usize::MAX)), invalid, "similar_per_scan");
}

#[test]
fn defaults_are_the_libraries() {
    let mut raw = sys::kissm_align_options::default();
    // SAFETY: raw is a writable kissm_align_options of exactly the size passed.
    let status =
        unsafe { sys::kissm_align_options_init(&mut raw, std::mem::size_of::<sys::kissm_align_options>() as u32) };
    assert_eq!(status, sys::KISSM_OK);
    assert_eq!(raw.pairs, sys::KISSM_PAIRS_ALL);
    assert_eq!(raw.loop_gap as usize, Pairs::DEFAULT_LOOP_GAP);
    assert_eq!(raw.loops_per_scan as usize, Pairs::DEFAULT_LOOPS_PER_SCAN);
    assert_eq!(raw.loop_radius, 0.0);
    assert_eq!(raw.bound, AlignOptions::default().bound);
    assert_eq!(raw.similar_per_scan as usize, AlignOptions::DEFAULT_SIMILAR_PER_SCAN);
    assert_eq!(AlignOptions::default().similar_per_scan, 3);
    assert_eq!(AlignOptions::default().pairs, Pairs::All);
    assert_eq!(Pairs::sequence(), Pairs::Sequence { priors: None, loop_radius: None, loop_gap: 10, loops_per_scan: 5 });
}

// ------------------------------------------------------------------------------------------------
// sequence_loops: worked out by hand
// ------------------------------------------------------------------------------------------------

fn along_x(x: f64) -> Matrix4 {
    let mut m = identity();
    m[0][3] = x;
    m
}

/// Eight scans out 1 m a step along x to x = 4 and back: positions 0 1 2 3 4 3 2 1.
fn out_and_back() -> Vec<Option<Matrix4>> {
    (0..7).map(|k| Some(along_x(if k < 4 { 1.0 } else { -1.0 }))).collect()
}

#[test]
fn sequence_loops_from_steps() {
    let steps = out_and_back();
    // Radius 0.5 (+2% of the path between): scan 5 (x 3) meets 3, but 5 - 3 < 3; scan 6 (x 2) meets 2, scan 7
    // (x 1) meets 1.
    assert_eq!(sequence_loops(LoopPositions::Steps(&steps), 0.5, 3, 5).unwrap(), [(6, 2), (7, 1)]);
    // Radius 0.95 and the drift: scan 5 meets 2 (1 m apart, allowed 1.01); 6 meets 1 (allowed 1.05), 2 and 3; 7
    // meets 0 (allowed 1.09), 1 and 2.
    assert_eq!(
        sequence_loops(LoopPositions::Steps(&steps), 0.95, 3, 5).unwrap(),
        [(5, 2), (6, 1), (6, 2), (6, 3), (7, 0), (7, 1), (7, 2)]
    );
    // per_scan 1 keeps the nearest; 0 none.
    assert_eq!(sequence_loops(LoopPositions::Steps(&steps), 0.95, 3, 1).unwrap(), [(5, 2), (6, 2), (7, 1)]);
    assert_eq!(sequence_loops(LoopPositions::Steps(&steps), 0.95, 3, 0).unwrap(), []);
    // A step without a pose (4 -> 5) starts a new piece: scans 5 to 7 get no candidates among 0 to 4.
    let mut broken = steps.clone();
    broken[4] = None;
    assert_eq!(sequence_loops(LoopPositions::Steps(&broken), 0.5, 3, 5).unwrap(), []);
    // One scan (no steps) has no candidates.
    assert_eq!(sequence_loops(LoopPositions::Steps(&[]), 0.5, 1, 5).unwrap(), []);
}

#[test]
fn sequence_loops_from_priors() {
    let mut priors: Vec<Matrix4> = [0.0, 1.0, 2.0, 3.0, 4.0, 3.0, 2.0, 1.0].into_iter().map(along_x).collect();
    // No drift allowance: at 0.95 only the scans at the same place.
    assert_eq!(sequence_loops(LoopPositions::Priors(&priors), 0.95, 3, 5).unwrap(), [(6, 2), (7, 1)]);
    // A scan without a position (NaN translation) gets and gives none.
    priors[1][0][3] = f64::NAN;
    assert_eq!(sequence_loops(LoopPositions::Priors(&priors), 0.5, 3, 5).unwrap(), [(6, 2)]);
}

#[test]
fn sequence_loops_checks_its_arguments() {
    let steps = out_and_back();
    let invalid = ErrorKind::InvalidArgument;
    assert_error(sequence_loops(LoopPositions::Steps(&steps), 0.0, 3, 5), invalid, "radius");
    assert_error(sequence_loops(LoopPositions::Steps(&steps), f64::INFINITY, 3, 5), invalid, "radius");
    assert_error(sequence_loops(LoopPositions::Steps(&steps), 0.5, 0, 5), invalid, "gap");
    assert_error(sequence_loops(LoopPositions::Steps(&steps), 0.5, 3, 2_000_000), invalid, "per_scan");
    assert_error(sequence_loops(LoopPositions::Priors(&[]), 0.5, 3, 5), invalid, "priors");
}

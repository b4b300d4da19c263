// SPDX-License-Identifier: MIT
//! Fine registration on the shared test scene (the committed pair of `tests/data`, or `KISSM_TEST_DATA`):
//! refinement after the solver lands closer to the ground truth than the solver's pose and leaves the
//! coarse result as it was; `Matcher::refine` from a perturbed ground truth converges; the information
//! matrix is symmetric positive definite; `refine_features` equals `refine` and one thread equals two, bit
//! for bit; the refined validity rule (overlap, conditioning); the directions a plane and a corridor leave
//! free (`degenerate`, `weak_directions`) and `allow_degenerate`; bad initial transforms are errors naming
//! `initial_transform`.
// Matrices are indexed by row and column, as in their formulas.
#![allow(clippy::needless_range_loop)]

mod common;

use common::{perturbed, scene, Pose, SCENE_VOXEL};
use kissm::{Config, ErrorKind, Matcher, Reason, RefineMode, Registration};

fn config(mode: RefineMode, threads: usize) -> Config {
    Config::builder().voxel_size(SCENE_VOXEL).num_threads(threads).refine_mode(mode).build().unwrap()
}

/// Pose error (degrees, units) of a 4 x 4 transform against the truth, as one number for comparisons:
/// degrees count as much as the scene's voxel size.
fn error(truth: &Pose, m: &[[f64; 4]; 4]) -> (f64, f64, f64) {
    let (rot, trans) = truth.errors(&Pose::from_matrix(m));
    (rot, trans, rot * SCENE_VOXEL + trans)
}

/// Cholesky factorisation succeeds exactly for symmetric positive definite matrices (after the symmetry
/// check below); returns the smallest pivot.
fn smallest_cholesky_pivot(a: &[[f64; 6]; 6]) -> f64 {
    let mut l = [[0.0; 6]; 6];
    let mut smallest = f64::INFINITY;
    for i in 0..6 {
        for j in 0..=i {
            let s: f64 = a[i][j] - (0..j).map(|k| l[i][k] * l[j][k]).sum::<f64>();
            if i == j {
                smallest = smallest.min(s);
                if s <= 0.0 {
                    return s;
                }
                l[i][i] = s.sqrt();
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    smallest
}

fn check_information(reg: &Registration) {
    let info = reg.refinement.expect("refined").information;
    for i in 0..6 {
        for j in 0..6 {
            assert!(info[i][j].is_finite(), "information[{i}][{j}] = {}", info[i][j]);
            let scale = info[i][i].abs().max(info[j][j].abs());
            assert!((info[i][j] - info[j][i]).abs() <= 1e-9 * scale, "information not symmetric at {i},{j}: {info:?}");
        }
    }
    assert!(smallest_cholesky_pivot(&info) > 0.0, "information not positive definite: {info:?}");
}

#[test]
fn refinement_after_the_solver_improves_the_pose() {
    let Some(pair) = scene("refinement_after_the_solver_improves_the_pose") else { return };
    let coarse = Matcher::new(&config(RefineMode::None, 2)).unwrap().register(&pair.source, &pair.target).unwrap();
    assert!(coarse.valid, "{}", coarse.reason);
    assert!(coarse.refinement.is_none() && !coarse.is_refined());
    // Without refinement there is no dense information to tell degeneracy by.
    assert!(!coarse.degenerate() && coarse.weak_directions().is_empty());
    assert_eq!(coarse.timings.refine_ms, 0.0);
    // Without refinement the coarse pose is the pose.
    assert!(common::same_bits_matrix(&coarse.coarse_transform, &coarse.transform));
    let (_, _, coarse_error) = error(&pair.truth, &coarse.transform);

    for mode in [RefineMode::Gicp, RefineMode::PointToPlane] {
        let reg = Matcher::new(&config(mode, 2)).unwrap().register(&pair.source, &pair.target).unwrap();
        assert!(reg.valid, "{mode:?}: {}", reg.reason);
        assert_eq!(reg.reason, Reason::None);
        let fine = reg.refinement.expect("refinement ran");
        // The solver's result is the same as without refinement: its pose is kept in coarse_transform.
        assert!(common::same_bits_matrix(&reg.coarse_transform, &coarse.transform), "{mode:?}");
        assert_eq!(reg.counts, coarse.counts, "{mode:?}");
        assert_eq!(reg.residual_rms.to_bits(), coarse.residual_rms.to_bits());
        let (rot, trans, refined_error) = error(&pair.truth, &reg.transform);
        assert!(
            refined_error < coarse_error,
            "{mode:?}: refined error {refined_error} (rot {rot} deg, trans {trans}) not below coarse {coarse_error}"
        );
        assert!(rot < 0.5 && trans < 0.1, "{mode:?}: rotation error {rot} deg, translation error {trans}");
        // The transform, rotation and translation agree.
        for i in 0..3 {
            assert_eq!(reg.transform[i][3], reg.translation[i]);
            assert_eq!(reg.transform[i][..3], reg.rotation[i]);
        }
        assert!(fine.overlap > 0.5 && fine.overlap <= 1.0, "{mode:?}: overlap {}", fine.overlap);
        assert!(fine.rmse > 0.0 && fine.rmse < SCENE_VOXEL, "{mode:?}: rmse {}", fine.rmse);
        assert!(fine.condition > 0.0 && fine.condition <= 1.0, "{mode:?}: condition {}", fine.condition);
        assert!(fine.correspondences >= 6 && fine.correspondences <= reg.counts.source_voxels);
        assert!(fine.iterations >= 1 && fine.iterations <= config(mode, 2).refine_max_iterations() as u32);
        assert!(fine.converged, "{mode:?}");
        // The scene constrains every direction.
        assert!(!fine.degenerate && fine.weak_directions().is_empty(), "{mode:?}: {fine:?}");
        assert!(!reg.degenerate() && reg.weak_directions().is_empty());
        check_information(&reg);
        assert!(reg.timings.refine_ms > 0.0);
        assert!(reg.timings.total_ms >= reg.timings.refine_ms);
    }
}

#[test]
fn refine_from_a_perturbed_ground_truth_converges() {
    let Some(pair) = scene("refine_from_a_perturbed_ground_truth_converges") else { return };
    let start = perturbed(&pair.truth).to_matrix();
    let (start_rot, start_trans, start_error) = error(&pair.truth, &start);
    assert!(start_rot > 2.9 && start_trans > 0.25, "the start is really off: {start_rot} deg, {start_trans}");
    for mode in [RefineMode::Gicp, RefineMode::PointToPlane] {
        let mut m = Matcher::new(&config(mode, 2)).unwrap();
        let reg = m.refine(&pair.source, &pair.target, &start).unwrap();
        assert!(reg.valid, "{mode:?}: {}", reg.reason);
        let fine = reg.refinement.expect("refine always refines");
        assert!(fine.converged, "{mode:?}: {} iterations", fine.iterations);
        let (rot, trans, refined_error) = error(&pair.truth, &reg.transform);
        assert!(rot < 0.5 && trans < 0.1, "{mode:?}: rotation error {rot} deg, translation error {trans}");
        assert!(refined_error < start_error / 5.0, "{mode:?}: {refined_error} vs start {start_error}");
        // The initial transform is reported as the coarse one: its translation as given, its rotation made
        // exactly rigid (the nearest rotation), which moves a computed rotation by rounding errors only.
        for i in 0..4 {
            assert_eq!(reg.coarse_transform[i][3].to_bits(), start[i][3].to_bits(), "{mode:?}: translation");
            for j in 0..3 {
                let d = (reg.coarse_transform[i][j] - start[i][j]).abs();
                assert!(d < 1e-14, "{mode:?}: coarse_transform[{i}][{j}] is {d} from the initial transform");
            }
        }
        check_information(&reg);
        // No descriptors, no global search.
        let c = &reg.counts;
        assert_eq!(c.source_points, pair.source.len() as u64);
        assert!(c.source_voxels > 0 && c.target_voxels > 0);
        assert_eq!((c.source_keypoints, c.initial_correspondences, c.final_inliers), (0, 0, 0));
        // (features_ms is the normals' time here.)
        assert_eq!((reg.timings.matching_ms, reg.timings.pruning_ms, reg.timings.solver_ms), (0.0, 0.0, 0.0));
        assert!(reg.timings.refine_ms > 0.0);
    }
}

#[test]
fn refine_with_mode_none_is_gicp() {
    let Some(pair) = scene("refine_with_mode_none_is_gicp") else { return };
    let start = perturbed(&pair.truth).to_matrix();
    let none = Matcher::new(&config(RefineMode::None, 2)).unwrap().refine(&pair.source, &pair.target, &start).unwrap();
    let gicp = Matcher::new(&config(RefineMode::Gicp, 2)).unwrap().refine(&pair.source, &pair.target, &start).unwrap();
    let p2pl =
        Matcher::new(&config(RefineMode::PointToPlane, 2)).unwrap().refine(&pair.source, &pair.target, &start).unwrap();
    assert!(none.same_result(&gicp), "{none:?}\nvs\n{gicp:?}");
    assert!(!p2pl.same_result(&gicp), "point-to-plane is another cost");
}

#[test]
fn refine_features_equals_refine_bitwise() {
    let Some(pair) = scene("refine_features_equals_refine_bitwise") else { return };
    let start = perturbed(&pair.truth).to_matrix();
    for mode in [RefineMode::None, RefineMode::Gicp, RefineMode::PointToPlane] {
        let mut m = Matcher::new(&config(mode, 2)).unwrap();
        let direct = m.refine(&pair.source, &pair.target, &start).unwrap();
        let source = m.compute_features(&pair.source).unwrap();
        let target = m.compute_features(&pair.target).unwrap();
        let described = m.refine_features(&source, &target, &start).unwrap();
        // Refinement uses no descriptor: no keypoints in either result, though the features have them.
        assert!(source.num_keypoints() > 0 && target.num_keypoints() > 0);
        assert_eq!((direct.counts.source_keypoints, direct.counts.target_keypoints), (0, 0));
        assert!(described.same_result(&direct), "{mode:?}: {described:?}\nvs\n{direct:?}");
        assert_eq!((described.timings.voxelize_ms, described.timings.features_ms), (0.0, 0.0));
        // The same features serve the global registration with refinement too.
        let registered = m.register_features(&source, &target).unwrap();
        assert_eq!(registered.is_refined(), mode != RefineMode::None, "{mode:?}");
        // Features of a matcher without refinement work for a refining matcher (the index is built then).
        let mut plain = Matcher::new(&config(RefineMode::None, 1)).unwrap();
        let (ps, pt) = (plain.compute_features(&pair.source).unwrap(), plain.compute_features(&pair.target).unwrap());
        let from_plain = m.refine_features(&ps, &pt, &start).unwrap();
        assert!(from_plain.same_result(&direct), "{mode:?}");
    }
}

#[test]
fn refinement_does_not_depend_on_the_thread_count() {
    let Some(pair) = scene("refinement_does_not_depend_on_the_thread_count") else { return };
    let start = perturbed(&pair.truth).to_matrix();
    for mode in [RefineMode::Gicp, RefineMode::PointToPlane] {
        let runs: Vec<(Registration, Registration)> = [1, 2]
            .into_iter()
            .map(|threads| {
                let mut m = Matcher::new(&config(mode, threads)).unwrap();
                (m.register(&pair.source, &pair.target).unwrap(), m.refine(&pair.source, &pair.target, &start).unwrap())
            })
            .collect();
        assert!(runs[0].0.is_refined() && runs[0].1.is_refined());
        assert!(runs[0].0.same_result(&runs[1].0), "{mode:?} register: 1 thread vs 2");
        assert!(runs[0].1.same_result(&runs[1].1), "{mode:?} refine: 1 thread vs 2");
        // A reused matcher gives the same bits again.
        let mut m = Matcher::new(&config(mode, 2)).unwrap();
        for _ in 0..2 {
            assert!(m.refine(&pair.source, &pair.target, &start).unwrap().same_result(&runs[0].1));
        }
    }
}

#[test]
fn low_overlap_makes_a_refined_pose_invalid() {
    let Some(pair) = scene("low_overlap_makes_a_refined_pose_invalid") else { return };
    let start = perturbed(&pair.truth).to_matrix();
    let base = Matcher::new(&config(RefineMode::Gicp, 2)).unwrap().refine(&pair.source, &pair.target, &start).unwrap();
    let overlap = base.refinement.unwrap().overlap;
    assert!(base.valid && overlap < 1.0, "overlap {overlap}");
    // Asking for more overlap than the pair has: the same pose, no longer valid.
    let strict = Config::builder()
        .voxel_size(SCENE_VOXEL)
        .num_threads(2)
        .refine_mode(RefineMode::Gicp)
        .min_overlap((overlap + 1.0) / 2.0)
        .build()
        .unwrap();
    let mut m = Matcher::new(&strict).unwrap();
    let reg = m.refine(&pair.source, &pair.target, &start).unwrap();
    assert!(!reg.valid);
    assert_eq!(reg.reason, Reason::LowOverlap);
    assert_eq!(reg.reason.code(), kissm_sys::KISSM_REASON_LOW_OVERLAP);
    assert!(common::same_bits_matrix(&reg.transform, &base.transform), "the refined pose is kept for inspection");
    let reg = m.register(&pair.source, &pair.target).unwrap();
    assert!(!reg.valid);
    assert_eq!(reg.reason, Reason::LowOverlap);
    // Exactly the overlap the pair has is enough.
    let exact = strict.to_builder().min_overlap(overlap).build().unwrap();
    assert!(Matcher::new(&exact).unwrap().refine(&pair.source, &pair.target, &start).unwrap().valid);
}

#[test]
fn a_plane_leaves_the_refined_pose_unconstrained() {
    // A flat plane against itself: the in-plane translations and the rotation about the normal are free.
    let plane = common::flat_plane();
    let identity = Pose::axis_angle([0.0, 0.0, 1.0], 0.0, [0.0; 3]).to_matrix();
    let config = Config::builder().voxel_size(0.3).num_threads(2).build().unwrap();
    let reg = Matcher::new(&config).unwrap().refine(&plane, &plane, &identity).unwrap();
    assert!(!reg.valid);
    assert_eq!(reg.reason, Reason::Unconstrained);
    let fine = reg.refinement.expect("refinement ran");
    assert!(fine.condition < 1e-3, "condition {}", fine.condition);
    // Three free directions: the two slides in the plane and the turn about its normal.
    assert!(fine.degenerate && reg.degenerate());
    let weak = reg.weak_directions();
    assert_eq!(weak.len(), 3, "{weak:?}");
    assert_eq!(weak, fine.weak_directions());
    for w in weak {
        check_unit_and_sign(w);
    }
    // They span the free directions (a turn about the normal through any point of the plane is a turn
    // about the origin plus a slide), and each of them is free.
    let free = [[0.0, 0.0, 1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0, 1.0, 0.0]];
    for v in &free {
        let off = degrees_to_span(v, weak);
        assert!(off < 10.0, "the free direction {v:?} is {off} deg off the weak directions {weak:?}");
    }
    for w in weak {
        let off = degrees_to_span(w, &free);
        assert!(off < 10.0, "the weak direction {w:?} is {off} deg off the free directions");
    }
}

/// A weak direction is a unit 6-vector whose largest-magnitude component is positive.
fn check_unit_and_sign(w: &[f64; 6]) {
    let norm = w.iter().map(|v| v * v).sum::<f64>().sqrt();
    assert!((norm - 1.0).abs() < 1e-12, "|w| = {norm}: {w:?}");
    let largest = w.iter().copied().fold(0.0f64, |a, v| if v.abs() > a.abs() { v } else { a });
    assert!(largest > 0.0, "the largest component of {w:?} is negative");
}

fn dot6(a: &[f64; 6], b: &[f64; 6]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// The angle (degrees) between `v` and the span of the rows `span` (linearly independent; weak directions
/// need not be orthogonal to each other in the source's frame).
fn degrees_to_span(v: &[f64; 6], span: &[[f64; 6]]) -> f64 {
    // Gram-Schmidt, then the length of v's projection.
    let mut basis: Vec<[f64; 6]> = Vec::new();
    for row in span {
        let mut u = *row;
        for b in &basis {
            let d = dot6(&u, b);
            u.iter_mut().zip(b).for_each(|(x, y)| *x -= d * y);
        }
        let n = dot6(&u, &u).sqrt();
        assert!(n > 1e-9, "dependent rows {span:?}");
        basis.push(u.map(|x| x / n));
    }
    let inside = basis.iter().map(|b| dot6(v, b).powi(2)).sum::<f64>().sqrt() / dot6(v, v).sqrt();
    inside.min(1.0).acos().to_degrees()
}

/// A corridor along x: a floor and two side walls, 20 long, 3 wide and 2.5 high, open at both ends, sampled on
/// a 0.1 grid (the points off the edges, so that none lies on two surfaces).
fn corridor() -> Vec<[f64; 3]> {
    const STEP: f64 = 0.1;
    let at = |i: usize| STEP * (i as f64 + 0.5);
    let mut points = Vec::new();
    for i in 0..200 {
        let x = -10.0 + at(i);
        points.extend((0..30).map(|j| [x, -1.5 + at(j), 0.0]));
        for k in 0..25 {
            points.push([x, -1.5, at(k)]);
            points.push([x, 1.5, at(k)]);
        }
    }
    points
}

#[test]
fn a_corridor_leaves_its_slide_free() {
    // The target is the corridor; the source the same surfaces seen from a pose turned by 7 degrees and
    // moved: target = R source + t.
    let truth = Pose::axis_angle([0.3, -1.0, 0.6], 7.0, [0.6, -0.4, 0.25]);
    let target = corridor();
    let source = common::moved(&target, &truth.inverse());
    // The free direction: a slide along the corridor (x in the target's frame) is, in the source's frame
    // of T exp(xi), no rotation and the translation R^T x.
    let r = &truth.r;
    let slide = [0.0, 0.0, 0.0, r[0][0], r[0][1], r[0][2]];
    let builder = Config::builder().voxel_size(0.2).num_threads(2).refine_mode(RefineMode::Gicp);
    let refine = |config: &Config| Matcher::new(config).unwrap().refine(&source, &target, &truth.to_matrix()).unwrap();

    // By default: not valid, Unconstrained, one weak direction, the slide.
    let default = builder.clone().build().unwrap();
    let reg = refine(&default);
    let fine = reg.refinement.expect("refinement ran");
    assert!(!reg.valid);
    assert_eq!(reg.reason, Reason::Unconstrained);
    assert!(fine.condition < default.min_refine_condition(), "condition {}", fine.condition);
    assert!(fine.converged && fine.overlap > 0.9, "{fine:?}");
    assert!(reg.degenerate() && fine.degenerate);
    let weak = reg.weak_directions();
    assert_eq!(weak.len(), 1, "{weak:?}");
    check_unit_and_sign(&weak[0]);
    let off = dot6(&weak[0], &slide).abs().min(1.0).acos().to_degrees();
    assert!(off < 10.0, "the weak direction {:?} is {off} deg off the slide {slide:?}", weak[0]);
    let rotation = weak[0][..3].iter().map(|v| v * v).sum::<f64>().sqrt();
    assert!(rotation < 0.01, "the slide turns by {rotation} rad per unit: {:?}", weak[0]);
    // The pose itself is right: refinement from the truth stays there (along the slide the data cannot say).
    let (deg, dist) = truth.errors(&Pose::from_matrix(&reg.transform));
    assert!(deg < 0.2 && dist < 0.2, "{deg} deg, {dist} from the truth");

    // allow_degenerate: the same refinement, now valid and still flagged, with the same direction bit for bit.
    let allowing = builder.allow_degenerate(true).build().unwrap();
    let accepted = refine(&allowing);
    assert!(accepted.valid, "{}", accepted.reason);
    assert_eq!(accepted.reason, Reason::None);
    assert!(accepted.degenerate());
    assert_eq!(accepted.weak_directions().len(), 1);
    assert!(common::same_bits_matrix(&[accepted.weak_directions()[0]], &[weak[0]]));
    let mut decided = accepted;
    decided.valid = reg.valid;
    decided.reason = reg.reason;
    assert!(decided.same_result(&reg), "more than the decision changed:\n{accepted:?}\nvs\n{reg:?}");
    // The other rules still apply: clouds asked to lie closer than they do are refused.
    let strict = allowing.to_builder().max_refine_rmse_gain(0.5 * fine.rmse / 0.2).build().unwrap();
    let refused = refine(&strict);
    assert!(!refused.valid && refused.degenerate());
    assert_eq!(refused.reason, Reason::LooseAlignment);
}

#[test]
fn bad_initial_transforms_are_invalid_arguments() {
    let Some(pair) = scene("bad_initial_transforms_are_invalid_arguments") else { return };
    let good = pair.truth.to_matrix();
    let mut bad = Vec::new();
    let mut with = |what: &str, f: &dyn Fn(&mut [[f64; 4]; 4])| {
        let mut m = good;
        f(&mut m);
        bad.push((what.to_string(), m));
    };
    with("NaN", &|m| m[1][2] = f64::NAN);
    with("infinite translation", &|m| m[0][3] = f64::INFINITY);
    with("last row", &|m| m[3] = [0.0, 0.0, 0.1, 1.0]);
    with("last row scale", &|m| m[3][3] = 2.0);
    with("scaled rotation", &|m| {
        for row in m.iter_mut().take(3) {
            for v in row.iter_mut().take(3) {
                *v *= 1.01;
            }
        }
    });
    with("reflection", &|m| {
        for row in m.iter_mut().take(3) {
            row[0] = -row[0];
        }
    });
    with("sheared rotation", &|m| m[0][1] += 0.01);
    with("huge translation", &|m| m[2][3] = 2e9);
    with("zero matrix", &|m| *m = [[0.0; 4]; 4]);

    let mut m = Matcher::new(&config(RefineMode::Gicp, 2)).unwrap();
    let (fs, ft) = (m.compute_features(&pair.source).unwrap(), m.compute_features(&pair.target).unwrap());
    for (what, initial) in &bad {
        for err in [
            m.refine(&pair.source, &pair.target, initial).unwrap_err(),
            m.refine_features(&fs, &ft, initial).unwrap_err(),
        ] {
            assert_eq!(err.kind(), ErrorKind::InvalidArgument, "{what}: {err}");
            assert_eq!(err.code(), kissm_sys::KISSM_ERR_INVALID_ARGUMENT);
            assert!(err.message().contains("initial_transform"), "{what}: {err}");
        }
    }
    // A translation just inside the bound and a rotation off by less than the tolerance are accepted.
    let mut edge = good;
    edge[0][3] = 1e9;
    assert!(m.refine(&pair.source, &pair.target, &edge).is_ok());
    let mut nearly = good;
    nearly[0][0] *= 1.0 + 1e-5;
    assert!(m.refine(&pair.source, &pair.target, &nearly).unwrap().is_refined());
    // The errors of the clouds stay those of register.
    let err = m.refine(&pair.source[..3], &pair.target, &good).unwrap_err();
    assert_eq!(err.kind(), ErrorKind::TooFewPoints, "{err}");
    let mut nan = pair.source.clone();
    nan[5][0] = f64::NAN;
    assert_eq!(m.refine(&nan, &pair.target, &good).unwrap_err().kind(), ErrorKind::NonFinite);
    // Features of another descriptor configuration are rejected, as by register_features.
    let mut other = Matcher::new(&Config::builder().voxel_size(0.5).build().unwrap()).unwrap();
    let foreign = other.compute_features(&pair.target).unwrap();
    assert_eq!(m.refine_features(&fs, &foreign, &good).unwrap_err().kind(), ErrorKind::FeaturesMismatch);
    // A failed call does not spoil the next one.
    assert!(m.refine(&pair.source, &pair.target, &good).unwrap().valid);
}

// SPDX-License-Identifier: MIT
//! The validity rules' settings on the shared test scene (the committed pair of `tests/data`, or
//! `KISSM_TEST_DATA`): each moves the decision exactly at the value the result reports, and only in its
//! own rule, never the pose. Without refinement `max_rotation_uncertainty` against
//! `Registration::rotation_uncertainty`; with refinement `refine_min_inliers` against the final inliers,
//! `min_inlier_coverage` against `Refinement::inlier_coverage` and `min_refine_condition` against
//! `Refinement::condition` (also in `Matcher::refine`'s rule; beyond it the pose is also `degenerate`, its
//! weakest direction reported, and `allow_degenerate` accepts it); `max_ambiguity` against
//! `Registration::ambiguity` with and without refinement; and a refinement stopped by its iteration cap
//! (`Reason::NotConverged`).

mod common;

use common::{perturbed, scene, Pose, Scene, SCENE_VOXEL};
use kissm::{Config, ConfigBuilder, Matcher, Reason, RefineMode, Registration};

fn builder(mode: RefineMode) -> ConfigBuilder {
    Config::builder().voxel_size(SCENE_VOXEL).num_threads(2).refine_mode(mode)
}

fn register(builder: ConfigBuilder, pair: &Scene) -> Registration {
    Matcher::new(&builder.build().unwrap()).unwrap().register(&pair.source, &pair.target).unwrap()
}

/// The next double toward 0 and away from it (for positive finite values).
fn just_below(v: f64) -> f64 {
    f64::from_bits(v.to_bits() - 1)
}
fn just_above(v: f64) -> f64 {
    f64::from_bits(v.to_bits() + 1)
}

/// Another decision on the same result: every bit but `valid` and `reason` is `base`'s.
fn same_but_decision(reg: &Registration, base: &Registration, what: &str) {
    let mut decided = *reg;
    decided.valid = base.valid;
    decided.reason = base.reason;
    assert!(decided.same_result(base), "{what}: more than the decision changed");
}

/// A threshold exactly at the measured value gives `base` itself; one just beyond it the same result with
/// `valid == false` and `reason`.
fn decision_flips(base: &Registration, at: &Registration, beyond: &Registration, reason: Reason, what: &str) {
    assert!(at.same_result(base), "{what}: at the measured value: {}", at.reason);
    assert!(!beyond.valid, "{what}: just beyond the measured value, still valid");
    assert_eq!(beyond.reason, reason, "{what}");
    same_but_decision(beyond, base, what);
}

/// `reg` is `base` but for the decision and the degeneracy that `min_refine_condition` also sets
/// ([`Refinement::degenerate`](kissm::Refinement::degenerate) and its weak directions): every other bit is
/// `base`'s.
fn same_but_degeneracy(reg: &Registration, base: &Registration, what: &str) {
    let mut decided = *reg;
    decided.valid = base.valid;
    decided.reason = base.reason;
    decided.refinement = base.refinement;
    assert!(decided.same_result(base), "{what}: more than the decision and the degeneracy changed");
    let (a, b) = (reg.refinement.expect("refined"), base.refinement.expect("refined"));
    assert!(common::same_bits_matrix(&a.information, &b.information), "{what}: information");
    let numbers = |f: &kissm::Refinement| [f.overlap, f.rmse, f.condition, f.inlier_coverage];
    assert!(common::same_bits_matrix(&[numbers(&a)], &[numbers(&b)]), "{what}: {a:?}\nvs\n{b:?}");
    assert_eq!((a.correspondences, a.iterations, a.converged), (b.correspondences, b.iterations, b.converged));
}

/// `min_refine_condition` exactly at the measured condition gives `base` itself; just above it the same pose,
/// not valid (`Unconstrained`) and degenerate, with the weakest direction alone reported; and that with
/// `allow_degenerate` (`allowed`) valid again, all else the same bit for bit.
fn condition_flips(base: &Registration, at: &Registration, beyond: &Registration, allowed: &Registration, what: &str) {
    assert!(at.same_result(base), "{what}: at the measured value: {}", at.reason);
    assert!(!base.degenerate() && base.weak_directions().is_empty(), "{what}: {base:?}");
    assert!(!beyond.valid, "{what}: just beyond the measured value, still valid");
    assert_eq!(beyond.reason, Reason::Unconstrained, "{what}");
    assert!(beyond.degenerate(), "{what}");
    assert_eq!(beyond.weak_directions().len(), 1, "{what}: {:?}", beyond.weak_directions());
    same_but_degeneracy(beyond, base, what);
    assert!(allowed.valid, "{what}: allow_degenerate: {}", allowed.reason);
    assert!(allowed.degenerate(), "{what}: allow_degenerate");
    same_but_decision(allowed, beyond, what);
}

/// The scene's pose is close to its ground truth, so the correct decision is "valid".
fn accurate(pair: &Scene, reg: &Registration, what: &str) {
    let (deg, dist) = pair.truth.errors(&Pose::from_matrix(&reg.transform));
    assert!(deg < 1.0 && dist < SCENE_VOXEL, "{what}: {deg} deg, {dist} from the truth");
    assert!(reg.valid, "{what}: an accurate pose is not valid: {}", reg.reason);
}

/// The shared scene and its GICP-refined registration under the default rules (accurate, so valid).
fn refined_scene(test: &str) -> Option<(&'static Scene, Registration)> {
    let pair = scene(test)?;
    let base = register(builder(RefineMode::Gicp), pair);
    accurate(pair, &base, "GICP");
    Some((pair, base))
}

#[test]
fn rotation_uncertainty_decides_an_unrefined_pose() {
    let Some(pair) = scene("rotation_uncertainty_decides_an_unrefined_pose") else { return };
    let base = register(builder(RefineMode::None), pair);
    accurate(pair, &base, "default");
    let u = base.rotation_uncertainty;
    assert!(u.is_finite() && u > 0.0 && u <= Config::default().max_rotation_uncertainty(), "{u}");
    // It is the formula kissm.h gives, from the result's own fields.
    let [_, e1, e2] = base.inlier_extent;
    let expected = base.noise_bound / (base.final_inliers() as f64 * (e1 * e1 + e2 * e2)).sqrt();
    assert!((u - expected).abs() <= 1e-12 * expected, "rotation_uncertainty {u}, formula {expected}");
    // As a 1-sigma bound it covers the solver's actual rotation error.
    let (deg, _) = pair.truth.errors(&Pose::from_matrix(&base.coarse_transform));
    assert!(deg.to_radians() <= 3.0 * u, "coarse rotation error {deg} deg, uncertainty {} deg", u.to_degrees());

    // A bound below twice the uncertainty (two sigmas) has the pose verified by refinement; held to a coverage no
    // inlier set reaches, the verification refuses it and the pose is not valid, for the verification's reason
    // (the coarse pose kept). One ulp below the uncertainty itself the coarse rule declines first.
    let at = register(builder(RefineMode::None).max_rotation_uncertainty(2.0 * u).min_inlier_coverage(1.0), pair);
    let below = register(
        builder(RefineMode::None).max_rotation_uncertainty(just_below(2.0 * u)).min_inlier_coverage(1.0),
        pair,
    );
    decision_flips(&base, &at, &below, Reason::ClusteredInliers, "max_rotation_uncertainty");
    let declined =
        register(builder(RefineMode::None).max_rotation_uncertainty(just_below(u)).min_inlier_coverage(1.0), pair);
    assert_eq!(declined.reason.code(), kissm_sys::KISSM_REASON_UNCERTAIN_ROTATION);
    assert!(common::same_bits_matrix(&declined.transform, &base.transform), "declined: the coarse pose");
    // Under the default refined rule the verification accepts it: the refined pose, valid, the solver's pose kept.
    let verified = register(builder(RefineMode::None).max_rotation_uncertainty(just_below(u)), pair);
    assert!(verified.valid && verified.is_refined(), "verified: {}", verified.reason);
    assert!(common::same_bits_matrix(&verified.coarse_transform, &base.coarse_transform), "verified: coarse pose");
    accurate(pair, &verified, "verified by refinement");

    // With refinement the solver's uncertainty is still reported, but the refined rule decides.
    let refined = register(builder(RefineMode::Gicp).max_rotation_uncertainty(just_below(u)), pair);
    assert!(refined.is_refined());
    assert_eq!(refined.rotation_uncertainty.to_bits(), u.to_bits());
    accurate(pair, &refined, "refined, with a rotation threshold below the uncertainty");
}

#[test]
fn ambiguity_decides_with_and_without_refinement() {
    let Some(pair) = scene("ambiguity_decides_with_and_without_refinement") else { return };
    for mode in [RefineMode::None, RefineMode::Gicp] {
        let base = register(builder(mode), pair);
        accurate(pair, &base, "default");
        // A scene with one answer: the best competitor has well under the pose's support.
        let a = base.ambiguity;
        assert!(a > 0.0 && a < Config::default().max_ambiguity(), "{a}");
        // Exactly the measured ambiguity is allowed; one ulp less is not, and nothing else changes.
        let at = register(builder(mode).max_ambiguity(a), pair);
        let below = register(builder(mode).max_ambiguity(just_below(a)), pair);
        decision_flips(&base, &at, &below, Reason::Ambiguous, "max_ambiguity");
        assert_eq!(below.reason.code(), kissm_sys::KISSM_REASON_AMBIGUOUS);
    }
    // A refinement from a prior runs no solver: no competitor either.
    let config = builder(RefineMode::Gicp).max_ambiguity(0.0).build().unwrap();
    let from_truth =
        Matcher::new(&config).unwrap().refine(&pair.source, &pair.target, &pair.truth.to_matrix()).unwrap();
    assert!(from_truth.ambiguity.is_nan());
    accurate(pair, &from_truth, "refine from the truth, max_ambiguity 0");
}

#[test]
fn the_refined_rule_needs_inliers_covering_the_overlap() {
    let Some((pair, base)) = refined_scene("the_refined_rule_needs_inliers_covering_the_overlap") else { return };
    let coverage = base.refinement.expect("refined").inlier_coverage;
    let inliers = base.final_inliers() as usize;
    assert!(coverage >= Config::default().min_inlier_coverage() && coverage < 1.0, "{coverage}");
    assert!(inliers >= Config::default().refine_min_inliers());

    // min_inlier_coverage: the measured coverage is enough, one ulp more is not.
    let at = register(builder(RefineMode::Gicp).min_inlier_coverage(coverage), pair);
    let above = register(builder(RefineMode::Gicp).min_inlier_coverage(just_above(coverage)), pair);
    decision_flips(&base, &at, &above, Reason::ClusteredInliers, "min_inlier_coverage");
    assert_eq!(above.reason.code(), kissm_sys::KISSM_REASON_CLUSTERED_INLIERS);

    // refine_min_inliers: the final inliers are enough, one more is not.
    let at = register(builder(RefineMode::Gicp).refine_min_inliers(inliers), pair);
    let short = register(builder(RefineMode::Gicp).refine_min_inliers(inliers + 1), pair);
    decision_flips(&base, &at, &short, Reason::TooFewInliers, "refine_min_inliers");

    // Without refinement neither setting applies, and there is no coverage to measure.
    let plain = register(builder(RefineMode::None).refine_min_inliers(inliers + 1).min_inlier_coverage(1.0), pair);
    assert!(plain.refinement.is_none());
    accurate(pair, &plain, "unrefined, with the refined rule's settings at their strictest");

    // A refinement from a prior has no solver: neither measure exists.
    let config = builder(RefineMode::Gicp).min_inlier_coverage(1.0).refine_min_inliers(100_000).build().unwrap();
    let from_truth =
        Matcher::new(&config).unwrap().refine(&pair.source, &pair.target, &pair.truth.to_matrix()).unwrap();
    assert!(from_truth.refinement.expect("refined").inlier_coverage.is_nan());
    assert!(from_truth.rotation_uncertainty.is_nan());
    accurate(pair, &from_truth, "refine from the truth, with the refined rule's settings at their strictest");
}

#[test]
fn the_refined_rules_need_a_conditioned_pose() {
    let Some((pair, base)) = refined_scene("the_refined_rules_need_a_conditioned_pose") else { return };
    let condition = base.refinement.expect("refined").condition;
    assert!(condition >= Config::default().min_refine_condition() && condition < 1.0, "{condition}");

    // The measured condition is enough, one ulp more is not.
    let at = register(builder(RefineMode::Gicp).min_refine_condition(condition), pair);
    let above = register(builder(RefineMode::Gicp).min_refine_condition(just_above(condition)), pair);
    let allowed =
        register(builder(RefineMode::Gicp).min_refine_condition(just_above(condition)).allow_degenerate(true), pair);
    condition_flips(&base, &at, &above, &allowed, "min_refine_condition");
    assert_eq!(above.reason.code(), kissm_sys::KISSM_REASON_UNCONSTRAINED);

    // Without refinement there is no condition to judge.
    let plain = register(builder(RefineMode::None).min_refine_condition(1.0), pair);
    assert!(plain.refinement.is_none());
    accurate(pair, &plain, "unrefined, with min_refine_condition 1");

    // A refinement from a prior is judged by it too.
    let refine = |b: ConfigBuilder| {
        Matcher::new(&b.build().unwrap()).unwrap().refine(&pair.source, &pair.target, &pair.truth.to_matrix()).unwrap()
    };
    let from_truth = refine(builder(RefineMode::Gicp));
    accurate(pair, &from_truth, "refine from the truth");
    let condition = from_truth.refinement.expect("refined").condition;
    let at = refine(builder(RefineMode::Gicp).min_refine_condition(condition));
    let above = refine(builder(RefineMode::Gicp).min_refine_condition(just_above(condition)));
    let allowed = refine(builder(RefineMode::Gicp).min_refine_condition(just_above(condition)).allow_degenerate(true));
    condition_flips(&from_truth, &at, &above, &allowed, "min_refine_condition, refine");
}

#[test]
fn a_refinement_stopped_by_its_cap_is_not_valid() {
    let Some(pair) = scene("a_refinement_stopped_by_its_cap_is_not_valid") else { return };
    let start = perturbed(&pair.truth);
    let (deg, dist) = pair.truth.errors(&start);
    assert!(deg > 2.0 && dist > SCENE_VOXEL, "the start is {deg} deg, {dist} off");
    let refine = |b: ConfigBuilder| {
        Matcher::new(&b.build().unwrap()).unwrap().refine(&pair.source, &pair.target, &start.to_matrix()).unwrap()
    };
    // One iteration from a few degrees off is still moving when it stops: the pose is kept, not trusted.
    let capped = refine(builder(RefineMode::Gicp).refine_max_iterations(1));
    let fine = capped.refinement.expect("refined");
    assert_eq!((fine.iterations, fine.converged), (1, false));
    assert!(!capped.valid);
    assert_eq!(capped.reason, Reason::NotConverged);
    assert_eq!(capped.reason.code(), kissm_sys::KISSM_REASON_NOT_CONVERGED);
    assert!(capped.has_pose() && capped.transform != start.to_matrix());
    // Only convergence failed: the same refinement passes every other refined test.
    assert!(fine.overlap >= Config::default().min_overlap(), "{}", fine.overlap);
    assert!(fine.condition >= Config::default().min_refine_condition(), "{}", fine.condition);
    // With the default cap the same start converges to the truth.
    let done = refine(builder(RefineMode::Gicp));
    assert!(done.refinement.expect("refined").converged);
    accurate(pair, &done, "refine from the perturbed start");
    // A registration refined for one iteration only is refused for the same reason when it was still moving.
    let reg = register(builder(RefineMode::Gicp).refine_max_iterations(1), pair);
    let fine = reg.refinement.expect("refined");
    assert_eq!(fine.iterations, 1);
    assert_eq!(reg.valid, fine.converged, "{}", reg.reason);
    assert_eq!(reg.reason == Reason::NotConverged, !fine.converged, "{}", reg.reason);
}

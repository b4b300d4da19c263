// SPDX-License-Identifier: MIT
//! Cross-language round trip, Rust side: the clouds of `tests/data` (or `KISSM_TEST_DATA`) registered
//! (`"call": "register"`) or refined from the case's `"initial_transform"` (`"call": "refine"`) with the
//! case's refine mode, viewpoint mode, suppression, rotational degrees of freedom and validity settings
//! (`max_refine_rmse_gain`, `min_refine_condition`, `allow_degenerate`, `max_ambiguity`), as listed in
//! `tests/data/golden.json` (written by the C library), give the same result bit for bit (the file writes
//! NaN as `null`; any NaN matches it). The C suite (`tests/roundtrip`) and the Python suite
//! (`tests/test_golden.py`) check the same file.

mod common;

use common::Json;
use kissm::{Config, Matcher, Reason, RefineMode, Registration, Suppression, Viewpoint};

fn viewpoint(name: &str) -> Viewpoint {
    match name {
        "fixed" => Viewpoint::Fixed([0.0; 3]),
        "cloud_center" => Viewpoint::CloudCenter,
        "sign_free" => Viewpoint::SignFree,
        "local" => Viewpoint::Local,
        other => panic!("golden.json: unknown viewpoint mode {other:?}"),
    }
}

fn refine_mode(name: &str) -> RefineMode {
    match name {
        "none" => RefineMode::None,
        "gicp" => RefineMode::Gicp,
        "point_to_plane" => RefineMode::PointToPlane,
        other => panic!("golden.json: unknown refine mode {other:?}"),
    }
}

fn suppression(name: &str) -> Suppression {
    match name {
        "none" => Suppression::None,
        "ground" => Suppression::Ground,
        other => panic!("golden.json: unknown suppression {other:?}"),
    }
}

/// 16 numbers as a 4 x 4 matrix, row-major.
fn matrix4(values: &[f64]) -> [[f64; 4]; 4] {
    assert_eq!(values.len(), 16, "16 numbers expected");
    let mut m = [[0.0; 4]; 4];
    for (i, v) in values.iter().enumerate() {
        m[i / 4][i % 4] = *v;
    }
    m
}

/// Every golden field of the case against the registration; returns the differences.
fn compare(case: &Json, reg: &Registration) -> Vec<String> {
    let mut failures = Vec::new();
    let mut same = |key: String, expect: f64, got: f64| {
        let equal = if expect.is_nan() { got.is_nan() } else { expect.to_bits() == got.to_bits() };
        if !equal {
            failures.push(format!("{key}: golden {expect:?} vs Rust {got:?}"));
        }
    };
    same("valid".into(), case.get("valid").num(), f64::from(u8::from(reg.valid)));
    same("reason".into(), case.get("reason").num(), f64::from(reg.reason.code()));
    let flat = |m: &[[f64; 4]; 4]| m.iter().flatten().copied().collect::<Vec<f64>>();
    let fine = reg.refinement;
    let information: Vec<f64> = match &fine {
        Some(f) => f.information.iter().flatten().copied().collect(),
        None => vec![f64::NAN; 36],
    };
    for (key, got) in [
        ("transform", flat(&reg.transform)),
        ("coarse_transform", flat(&reg.coarse_transform)),
        ("information", information),
    ] {
        let expect = case.get(key).nums();
        assert_eq!(expect.len(), got.len(), "{key}: length");
        for (i, (e, g)) in expect.into_iter().zip(got).enumerate() {
            same(format!("{key}[{i}]"), e, g);
        }
    }
    let c = &reg.counts;
    let counts = [
        ("num_source_points", c.source_points),
        ("num_target_points", c.target_points),
        ("num_source_voxels", c.source_voxels),
        ("num_target_voxels", c.target_voxels),
        ("num_source_keypoints", c.source_keypoints),
        ("num_target_keypoints", c.target_keypoints),
        ("num_initial_correspondences", c.initial_correspondences),
        ("num_pruned_correspondences", c.pruned_correspondences),
        ("num_rotation_inliers", c.rotation_inliers),
        ("num_final_inliers", c.final_inliers),
        ("max_core_number", c.max_core_number),
        ("num_refine_correspondences", fine.map_or(0, |f| f.correspondences)),
        ("refine_iterations", fine.map_or(0, |f| u64::from(f.iterations))),
        ("refine_converged", fine.map_or(0, |f| u64::from(f.converged))),
        ("num_source_suppressed", c.source_suppressed),
        ("num_target_suppressed", c.target_suppressed),
    ];
    for (key, got) in counts {
        same(key.into(), case.get(key).num(), got as f64);
    }
    let nan = f64::NAN;
    let doubles = [
        ("residual_rms", reg.residual_rms),
        ("overlap", fine.map_or(nan, |f| f.overlap)),
        ("refine_rmse", fine.map_or(nan, |f| f.rmse)),
        ("refine_condition", fine.map_or(nan, |f| f.condition)),
        ("rotation_uncertainty", reg.rotation_uncertainty),
        ("inlier_coverage", fine.map_or(nan, |f| f.inlier_coverage)),
        ("tilt", reg.tilt),
        ("ambiguity", reg.ambiguity),
        ("confidence", reg.confidence),
        ("voxel_size_used", reg.voxel_size_used),
    ];
    for (key, got) in doubles {
        same(key.into(), case.get(key).num(), got);
    }
    // The free directions: the flag, their count, and the rows in use bit for bit; the golden rows beyond
    // them are NaN (null), as the C result's.
    let weak = reg.weak_directions();
    same("degenerate".into(), case.get("degenerate").num(), f64::from(u8::from(reg.degenerate())));
    same("num_weak_directions".into(), case.get("num_weak_directions").num(), weak.len() as f64);
    let expect = case.get("weak_directions").nums();
    assert_eq!(expect.len(), 36, "weak_directions: length");
    let got = weak.iter().flatten().copied().chain(std::iter::repeat(f64::NAN)).take(36);
    for (i, (e, g)) in expect.into_iter().zip(got).enumerate() {
        same(format!("weak_directions[{i}]"), e, g);
    }
    failures
}

#[test]
fn golden_file_matches_bit_for_bit() {
    // The scene's folder (a SKIP line, or a failure under KISSM_REQUIRE_TEST_DATA=1, when it is absent).
    if common::scene("golden_file_matches_bit_for_bit").is_none() {
        return;
    }
    let dir = common::test_data_dir().expect("the scene was found");
    let text = std::fs::read_to_string(dir.join("golden.json")).expect("golden.json beside the scene");
    let golden = Json::parse(&text).expect("golden.json parses");
    let source = kissm::read_points(dir.join(golden.get("source").str())).unwrap();
    let target = kissm::read_points(dir.join(golden.get("target").str())).unwrap();
    let source32: Vec<[f32; 3]> = source.as_slice().iter().map(|p| [p[0] as f32, p[1] as f32, p[2] as f32]).collect();
    let target32: Vec<[f32; 3]> = target.as_slice().iter().map(|p| [p[0] as f32, p[1] as f32, p[2] as f32]).collect();
    let cases = golden.get("cases").arr();
    assert!(!cases.is_empty());
    let mut calls = std::collections::BTreeSet::new();
    let mut modes = std::collections::BTreeSet::new();
    let mut views = std::collections::BTreeSet::new();
    let mut suppressions = std::collections::BTreeSet::new();
    let mut dofs = std::collections::BTreeSet::new();
    let mut reasons = std::collections::BTreeSet::new();
    let mut accepted_degenerate = std::collections::BTreeSet::new();
    for case in cases {
        let name = case.get("name").str();
        let mode = refine_mode(case.get("refine").str());
        let call = case.get("call").str();
        let view = viewpoint(case.get("viewpoint").str());
        views.insert(format!("{view:?}"));
        let suppress = suppression(case.get("suppression").str());
        suppressions.insert(format!("{suppress:?}"));
        let dof = case.get("rotation_dof").u64() as usize;
        dofs.insert(dof);
        let rmse_gain = case.get("max_refine_rmse_gain").num();
        let min_condition = case.get("min_refine_condition").num();
        let max_ambiguity = case.get("max_ambiguity").num();
        let allow_degenerate = match case.get("allow_degenerate").u64() {
            0 => false,
            1 => true,
            other => panic!("{name}: allow_degenerate {other}"),
        };
        reasons.insert(case.get("reason").u64());
        if case.get("degenerate").u64() == 1 && case.get("valid").u64() == 1 {
            accepted_degenerate.insert(name.to_string());
        }
        calls.insert(call.to_string());
        modes.insert(format!("{mode:?}"));
        let float32 = match case.get("scalar").str() {
            "float32" => true,
            "float64" => false,
            other => panic!("{name}: unknown scalar {other:?}"),
        };
        for threads in [1, 2] {
            let config = Config::builder()
                .voxel_size(case.get("voxel_size").num())
                .num_threads(threads)
                .refine_mode(mode)
                .viewpoint(view)
                .suppression(suppress)
                .rotation_dof(dof)
                .max_refine_rmse_gain(rmse_gain)
                .min_refine_condition(min_condition)
                .allow_degenerate(allow_degenerate)
                .max_ambiguity(max_ambiguity)
                .build()
                .unwrap();
            let mut matcher = Matcher::new(&config).unwrap();
            let reg = match (call, float32) {
                ("register", true) => matcher.register(&source32, &target32).unwrap(),
                ("register", false) => matcher.register(&source, &target).unwrap(),
                ("refine", _) => {
                    let initial = matrix4(&case.get("initial_transform").nums());
                    if float32 {
                        matcher.refine(&source32, &target32, &initial).unwrap()
                    } else {
                        matcher.refine(&source, &target, &initial).unwrap()
                    }
                }
                (other, _) => panic!("{name}: unknown call {other:?}"),
            };
            // Refinement ran exactly in the cases whose golden overlap is a number.
            assert_eq!(reg.is_refined(), !case.get("overlap").num().is_nan(), "{name}: refinement");
            let failures = compare(case, &reg);
            assert!(
                failures.is_empty(),
                "{name} (threads {threads}) differs from golden.json:\n  {}",
                failures.join("\n  ")
            );
        }
    }
    // The file covers what it promises (a regenerated file with fewer kinds of cases fails here).
    assert!(calls.contains("register") && calls.contains("refine"), "calls {calls:?}");
    assert_eq!(modes.len(), 3, "refine modes {modes:?}");
    assert!(views.len() >= 3, "viewpoint modes {views:?}");
    assert_eq!(suppressions.len(), 2, "suppressions {suppressions:?}");
    assert!(dofs.contains(&1) && dofs.contains(&3), "rotation_dof {dofs:?}");
    let loose = Reason::LooseAlignment.code() as u64;
    assert!(reasons.contains(&loose), "no case ends LooseAlignment: reasons {reasons:?}");
    let ambiguous = Reason::Ambiguous.code() as u64;
    assert!(reasons.contains(&ambiguous), "no case ends Ambiguous: reasons {reasons:?}");
    assert!(!accepted_degenerate.is_empty(), "no case is a degenerate pose accepted by allow_degenerate");
}

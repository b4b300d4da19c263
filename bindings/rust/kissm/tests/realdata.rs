// SPDX-License-Identifier: MIT
//! Real scans with ground truth from `../shared/data` (or `KISSM_DATA_DIR`); skipped when absent.
//!
//! Every LiDAR and indoor pair of `index.tsv` that SPEC section 7 says must succeed, raw and with the
//! source turned by a large rotation (fixed axis and angle, ground truth composed accordingly):
//! rotation error < 5 degrees, translation error < 2 m (LiDAR) or 0.3 m (indoor), judged against the
//! ground truth. A valid pose must be accurate; an accurate pose should be valid, but the unrefined rule's
//! rotation-uncertainty threshold (tuned in the library) may turn down a few accurate poses backed by few
//! inliers: `Reason::UncertainRotation` on at most a fifth of the runs is tolerated and logged.
//!
//! Refinement: every LiDAR pair registered with GICP refinement after the solver, and refined from its
//! ground truth perturbed by a fixed small pose, gives a valid pose within the refined thresholds below
//! (which the coarse pose alone does not promise), with a finite, symmetric information matrix.

mod common;

use std::path::Path;

use common::{skip, Pose};
use kissm::{Config, Format, Matcher, Reason, RefineMode};

struct Kind {
    name: &'static str,
    voxel: f64,
    max_trans: f64,
}

const KINDS: [Kind; 3] = [
    Kind { name: "lidar_scan", voxel: 0.3, max_trans: 2.0 },
    Kind { name: "lidar_keyframe_downsampled", voxel: 0.5, max_trans: 2.0 },
    Kind { name: "indoor_rgbd_fragment", voxel: 0.05, max_trans: 0.3 },
];

fn read_matrix(path: &Path) -> [[f64; 4]; 4] {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let v: Vec<f64> = text.split_whitespace().map(|t| t.parse().expect("a number")).collect();
    assert_eq!(v.len(), 16, "{}: 16 numbers", path.display());
    let mut m = [[0.0; 4]; 4];
    for i in 0..4 {
        for j in 0..4 {
            m[i][j] = v[4 * i + j];
        }
    }
    m
}

/// One pair of `index.tsv`.
struct Pair {
    dir: String,
    kind: &'static Kind,
    source: kissm::Cloud,
    target: kissm::Cloud,
    truth: Pose,
}

/// The pairs of `index.tsv` of the kinds in `KINDS`; `None` (after a SKIP line naming `test`) without data.
fn pairs(test: &str) -> Option<Vec<Pair>> {
    let Some(data) = common::data_dir() else {
        skip(test, "no data (../shared/data or KISSM_DATA_DIR)");
        return None;
    };
    let Ok(index) = std::fs::read_to_string(data.join("index.tsv")) else {
        skip(test, "index.tsv is absent");
        return None;
    };
    let mut lines = index.lines();
    let header: Vec<&str> = lines.next().unwrap_or("").split('\t').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap_or_else(|| panic!("index.tsv has {name}"));
    let (c_dir, c_target, c_source, c_format, c_kind) =
        (col("pair_dir"), col("target"), col("source"), col("format"), col("kind"));
    let mut pairs = Vec::new();
    for line in lines.filter(|l| !l.trim().is_empty()) {
        let f: Vec<&str> = line.split('\t').collect();
        let Some(kind) = KINDS.iter().find(|k| k.name == f[c_kind]) else { continue };
        let format = Format::from_name(f[c_format]).unwrap_or_else(|| panic!("known format {}", f[c_format]));
        pairs.push(Pair {
            dir: f[c_dir].to_string(),
            kind,
            source: kissm::read_points_with_format(data.join(f[c_source]), format).unwrap(),
            target: kissm::read_points_with_format(data.join(f[c_target]), format).unwrap(),
            truth: Pose::from_matrix(&read_matrix(&data.join(f[c_dir]).join("gt_T_target_source.txt"))),
        });
    }
    assert!(!pairs.is_empty(), "index.tsv lists no LiDAR or indoor pair");
    Some(pairs)
}

fn log(line: String) {
    let _ = std::io::Write::write_all(&mut std::io::stderr(), (line + "\n").as_bytes());
}

#[test]
fn real_pairs_register_within_the_spec_thresholds() {
    let Some(pairs) = pairs("real_pairs_register_within_the_spec_thresholds") else { return };

    // A large extra rotation of the source (the pair is then "global" whatever its own motion).
    let turn = Pose::axis_angle([0.3, -0.5, 0.8], 150.0, [2.0, -1.0, 0.5]);
    let mut failures = Vec::new();
    let mut rejected = Vec::new();
    let mut tested = 0;
    for pair in &pairs {
        let kind = pair.kind;
        let config = Config::builder().voxel_size(kind.voxel).num_threads(2).build().unwrap();
        let mut matcher = Matcher::new(&config).unwrap();

        // Raw pair, then the turned source: p_t = T p_s = (T turn^-1) (turn p_s).
        let turned: Vec<[f64; 3]> = pair.source.as_slice().iter().map(|&p| turn.apply(p)).collect();
        let variants =
            [("raw", pair.source.to_vec(), pair.truth), ("turned", turned, pair.truth.compose(&turn.inverse()))];
        for (variant, src, gt) in variants {
            let reg = matcher.register(&src, &pair.target).unwrap();
            let (rot, trans) = gt.errors(&Pose::from_matrix(&reg.transform));
            let accurate = rot < 5.0 && trans < kind.max_trans;
            let ok = reg.valid && accurate;
            // The library turning an accurate pose down for the tunable rule, not for a wrong pose.
            let conservative = accurate && !reg.valid && reg.reason == Reason::UncertainRotation;
            log(format!(
                "{} {variant}: valid {} ({}) rre {rot:.3} deg rte {trans:.3} inliers {} rotation uncertainty {:.3} deg \
                 {:.0} ms {}",
                pair.dir,
                reg.valid,
                reg.reason,
                reg.final_inliers(),
                reg.rotation_uncertainty.to_degrees(),
                reg.timings.total_ms,
                if ok {
                    "OK"
                } else if conservative {
                    "ACCURATE BUT NOT VALID"
                } else {
                    "FAIL"
                }
            ));
            if conservative {
                rejected.push(format!(
                    "{} {variant}: rre {rot} rte {trans}, rotation uncertainty {} deg, {} inliers",
                    pair.dir,
                    reg.rotation_uncertainty.to_degrees(),
                    reg.final_inliers()
                ));
            } else if !ok {
                failures.push(format!(
                    "{} {variant}: valid {} ({}) rre {rot} rte {trans}",
                    pair.dir, reg.valid, reg.reason
                ));
            }
            tested += 1;
        }
    }
    assert!(tested > 0, "index.tsv lists no LiDAR or indoor pair");
    assert!(failures.is_empty(), "failed pairs:\n  {}", failures.join("\n  "));
    assert!(
        5 * rejected.len() <= tested,
        "{} of {tested} accurate poses turned down as uncertain:\n  {}",
        rejected.len(),
        rejected.join("\n  ")
    );
}

/// Refined poses of the LiDAR pairs: rotation error below this (degrees) ... The worst measured at this
/// change was 0.15 degrees (small_gicp_lidar, whose reference pose is itself about 0.06 degrees from an ICP
/// optimum), and the coarse poses alone reach 0.49 degrees and 0.14 m on these pairs.
const REFINED_MAX_ROT_DEG: f64 = 0.25;
/// ... and translation error below this (metres); the worst measured was 0.027 m.
const REFINED_MAX_TRANS_M: f64 = 0.06;

#[test]
fn lidar_pairs_refine_within_the_refined_thresholds() {
    let test = "lidar_pairs_refine_within_the_refined_thresholds";
    let Some(pairs) = pairs(test) else { return };
    // A prior that is off by about 2 degrees and half a metre, as odometry can be.
    let nudge = Pose::axis_angle([0.1, 0.2, 1.0], 2.0, [0.4, -0.3, 0.1]);
    let mut failures = Vec::new();
    let mut tested = 0;
    for pair in pairs.iter().filter(|p| p.kind.name.starts_with("lidar")) {
        let config =
            Config::builder().voxel_size(pair.kind.voxel).num_threads(2).refine_mode(RefineMode::Gicp).build().unwrap();
        let mut matcher = Matcher::new(&config).unwrap();
        let start = nudge.compose(&pair.truth);
        let runs = [
            ("register+gicp", matcher.register(&pair.source, &pair.target).unwrap()),
            ("refine from a nudged truth", matcher.refine(&pair.source, &pair.target, &start.to_matrix()).unwrap()),
        ];
        for (what, reg) in runs {
            let (coarse_rot, coarse_trans) = pair.truth.errors(&Pose::from_matrix(&reg.coarse_transform));
            let (rot, trans) = pair.truth.errors(&Pose::from_matrix(&reg.transform));
            let fine = reg.refinement.expect("refinement ran");
            let symmetric = (0..6).all(|i| {
                (0..6).all(|j| {
                    let (a, b) = (fine.information[i][j], fine.information[j][i]);
                    a.is_finite() && (a - b).abs() <= 1e-9 * a.abs().max(b.abs()).max(1.0)
                })
            });
            let ok = reg.valid && rot < REFINED_MAX_ROT_DEG && trans < REFINED_MAX_TRANS_M && symmetric;
            log(format!(
                "{} {what}: valid {} ({}) coarse {coarse_rot:.3} deg {coarse_trans:.3} m -> refined {rot:.3} deg \
                 {trans:.3} m, overlap {:.3} inlier coverage {:.3} condition {:.3} {} iterations {:.0} ms {}",
                pair.dir,
                reg.valid,
                reg.reason,
                fine.overlap,
                fine.inlier_coverage,
                fine.condition,
                fine.iterations,
                reg.timings.refine_ms,
                if ok { "OK" } else { "FAIL" }
            ));
            if !ok {
                failures.push(format!(
                    "{} {what}: valid {} rre {rot} rte {trans} symmetric {symmetric}",
                    pair.dir, reg.valid
                ));
            }
            tested += 1;
        }
    }
    assert!(tested > 0, "index.tsv lists no LiDAR pair");
    assert!(failures.is_empty(), "failed refinements:\n  {}", failures.join("\n  "));
}

// SPDX-License-Identifier: MIT
//! Real scans with ground truth from `../shared/data` (or `KISSM_DATA_DIR`); skipped when absent.
//!
//! Every LiDAR and indoor pair of `index.tsv` that SPEC section 7 says must succeed, raw and with the
//! source turned by a large rotation (fixed axis and angle, ground truth composed accordingly):
//! rotation error < 5 degrees, translation error < 2 m (LiDAR) or 0.3 m (indoor), and a valid pose.

mod common;

use std::path::Path;

use common::{skip, Pose};
use kissm::{Config, Format, Matcher};

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

#[test]
fn real_pairs_register_within_the_spec_thresholds() {
    let Some(data) = common::data_dir() else {
        skip("real_pairs_register_within_the_spec_thresholds", "no data (../shared/data or KISSM_DATA_DIR)");
        return;
    };
    let Ok(index) = std::fs::read_to_string(data.join("index.tsv")) else {
        skip("real_pairs_register_within_the_spec_thresholds", "index.tsv is absent");
        return;
    };
    let mut lines = index.lines();
    let header: Vec<&str> = lines.next().unwrap_or("").split('\t').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap_or_else(|| panic!("index.tsv has {name}"));
    let (c_dir, c_target, c_source, c_format, c_kind) =
        (col("pair_dir"), col("target"), col("source"), col("format"), col("kind"));

    // A large extra rotation of the source (the pair is then "global" whatever its own motion).
    let turn = Pose::axis_angle([0.3, -0.5, 0.8], 150.0, [2.0, -1.0, 0.5]);
    let mut failures = Vec::new();
    let mut tested = 0;
    for line in lines.filter(|l| !l.trim().is_empty()) {
        let f: Vec<&str> = line.split('\t').collect();
        let Some(kind) = KINDS.iter().find(|k| k.name == f[c_kind]) else { continue };
        let format = Format::from_name(f[c_format]).unwrap_or_else(|| panic!("known format {}", f[c_format]));
        let source = kissm::read_points_with_format(data.join(f[c_source]), format).unwrap();
        let target = kissm::read_points_with_format(data.join(f[c_target]), format).unwrap();
        let truth = Pose::from_matrix(&read_matrix(&data.join(f[c_dir]).join("gt_T_target_source.txt")));
        let config = Config::builder().voxel_size(kind.voxel).num_threads(2).build().unwrap();
        let mut matcher = Matcher::new(&config).unwrap();

        // Raw pair, then the turned source: p_t = T p_s = (T turn^-1) (turn p_s).
        let turned: Vec<[f64; 3]> = source.as_slice().iter().map(|&p| turn.apply(p)).collect();
        let variants = [("raw", source.to_vec(), truth), ("turned", turned, truth.compose(&turn.inverse()))];
        for (variant, src, gt) in variants {
            let reg = matcher.register(&src, &target).unwrap();
            let (rot, trans) = gt.errors(&Pose::from_matrix(&reg.transform));
            let ok = reg.valid && rot < 5.0 && trans < kind.max_trans;
            let _ = std::io::Write::write_all(
                &mut std::io::stderr(),
                format!(
                    "{} {variant}: valid {} rre {rot:.3} deg rte {trans:.3} inliers {} {:.0} ms {}\n",
                    f[c_dir],
                    reg.valid,
                    reg.final_inliers(),
                    reg.timings.total_ms,
                    if ok { "OK" } else { "FAIL" }
                )
                .as_bytes(),
            );
            if !ok {
                failures.push(format!("{} {variant}: valid {} rre {rot} rte {trans}", f[c_dir], reg.valid));
            }
            tested += 1;
        }
    }
    assert!(tested > 0, "index.tsv lists no LiDAR or indoor pair");
    assert!(failures.is_empty(), "failed pairs:\n  {}", failures.join("\n  "));
}

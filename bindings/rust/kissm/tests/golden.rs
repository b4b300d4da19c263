// SPDX-License-Identifier: MIT
//! Cross-language round trip, Rust side: the clouds of `tests/data` (or `KISSM_TEST_DATA`) registered as
//! listed in `tests/data/golden.json` (written by the C library) give the same result bit for bit. The C
//! suite (`tests/roundtrip`) and the Python suite (`tests/test_golden.py`) check the same file.

mod common;

use common::Json;
use kissm::{Config, Matcher};

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
    let cases = golden.get("cases").arr();
    assert!(!cases.is_empty());
    for case in cases {
        let name = case.get("name").str();
        let source32: Vec<[f32; 3]> =
            source.as_slice().iter().map(|p| [p[0] as f32, p[1] as f32, p[2] as f32]).collect();
        let target32: Vec<[f32; 3]> =
            target.as_slice().iter().map(|p| [p[0] as f32, p[1] as f32, p[2] as f32]).collect();
        for threads in [1, 2] {
            let config =
                Config::builder().voxel_size(case.get("voxel_size").num()).num_threads(threads).build().unwrap();
            let mut matcher = Matcher::new(&config).unwrap();
            let reg = if case.get("scalar").str() == "float32" {
                matcher.register(&source32, &target32).unwrap()
            } else {
                matcher.register(&source, &target).unwrap()
            };
            assert_eq!(reg.valid, case.get("valid").u64() == 1, "{name}: valid");
            assert_eq!(i64::from(reg.reason.code()), case.get("reason").num() as i64, "{name}: reason");
            let expect = case.get("transform").nums();
            for (i, value) in expect.iter().enumerate() {
                let got = reg.transform[i / 4][i % 4];
                assert_eq!(got.to_bits(), value.to_bits(), "{name} threads {threads}: transform[{i}] {got} vs {value}");
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
            ];
            for (key, got) in counts {
                assert_eq!(got, case.get(key).u64(), "{name} threads {threads}: {key}");
            }
            assert_eq!(reg.residual_rms.to_bits(), case.get("residual_rms").num().to_bits(), "{name}: residual_rms");
        }
    }
}

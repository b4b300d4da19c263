// SPDX-License-Identifier: MIT
//! Rust results bit for bit equal to the C library's on the same input: the `kissm` tool's
//! `register --json` output (which prints every double so that it reads back exactly) against this
//! crate's registration of the same files read with `kissm::read_points`.
//!
//! The demo's clouds (`kissm demo --out DIR`, float64 PLY) and the shared test scene of `tests/data`
//! (or `KISSM_TEST_DATA`). Real data: KITTI 07 keyframes
//! 000001 -> 000000 (raw float32 xyz, voxel 0.5), skipped when `../shared/data` is absent. Both need
//! the tool: `KISSM_CLI`, `KISSM_BUILD_DIR/kissm` or the repository's `build/kissm` (skipped otherwise).

mod common;

use std::ffi::OsStr;
use std::path::Path;

use common::{compare_with_cli_json, run_cli_json, skip, Json};
use kissm::{Config, Format, Matcher};

fn check_against_cli(cli: &Path, source: &Path, target: &Path, format: Format, format_name: &str, voxel: f64) {
    let voxel_text = voxel.to_string();
    let mut args: Vec<&OsStr> = vec![
        OsStr::new("register"),
        source.as_os_str(),
        target.as_os_str(),
        OsStr::new("--voxel"),
        OsStr::new(&voxel_text),
        OsStr::new("--threads"),
        OsStr::new("1"),
        OsStr::new("--json"),
    ];
    if format != Format::Auto {
        args.extend([OsStr::new("--format"), OsStr::new(format_name)]);
    }
    let json: Json = run_cli_json(cli, &args);
    for key in ["valid", "transform", "final_inliers", "time_ms"] {
        assert!(json.has(key), "the tool's JSON has {key}");
    }

    let source_cloud = kissm::read_points_with_format(source, format).unwrap();
    let target_cloud = kissm::read_points_with_format(target, format).unwrap();
    // Thread counts do not change results: compare 1 (as the tool ran) and 2.
    for threads in [1, 2] {
        let config = Config::builder().voxel_size(voxel).num_threads(threads).build().unwrap();
        let reg = Matcher::new(&config).unwrap().register(&source_cloud, &target_cloud).unwrap();
        let failures = compare_with_cli_json(&json, &reg);
        assert!(failures.is_empty(), "Rust (threads {threads}) differs from C:\n  {}", failures.join("\n  "));
    }
}

#[test]
fn demo_clouds_match_the_c_tool_bitwise() {
    let Some(cli) = common::cli() else {
        skip("demo_clouds_match_the_c_tool_bitwise", "the kissm tool was not found (set KISSM_CLI)");
        return;
    };
    let dir = common::temp_dir("demo");
    let out = std::process::Command::new(&cli)
        .args([OsStr::new("demo"), OsStr::new("--out"), dir.as_os_str(), OsStr::new("--threads"), OsStr::new("2")])
        .output()
        .expect("run kissm demo");
    assert!(
        out.status.success() || out.status.code() == Some(1),
        "kissm demo failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    check_against_cli(&cli, &dir.join("source.ply"), &dir.join("target.ply"), Format::Auto, "auto", 0.3);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn shared_scene_matches_the_c_tool_bitwise() {
    let Some(cli) = common::cli() else {
        skip("shared_scene_matches_the_c_tool_bitwise", "the kissm tool was not found (set KISSM_CLI)");
        return;
    };
    if common::scene("shared_scene_matches_the_c_tool_bitwise").is_none() {
        return;
    }
    let dir = common::test_data_dir().expect("the scene was found");
    let (source, target) = (dir.join("roundtrip_source.ply"), dir.join("roundtrip_target.ply"));
    check_against_cli(&cli, &source, &target, Format::Auto, "auto", common::SCENE_VOXEL);
}

#[test]
fn kitti_keyframes_match_the_c_tool_bitwise() {
    let Some(cli) = common::cli() else {
        skip("kitti_keyframes_match_the_c_tool_bitwise", "the kissm tool was not found (set KISSM_CLI)");
        return;
    };
    let Some(data) = common::data_dir() else {
        skip("kitti_keyframes_match_the_c_tool_bitwise", "no data (../shared/data or KISSM_DATA_DIR)");
        return;
    };
    let dir = data.join("kitti07_keyframes_gtsam_points");
    let (source, target) = (dir.join("000001/points.bin"), dir.join("000000/points.bin"));
    if !source.is_file() || !target.is_file() {
        skip("kitti_keyframes_match_the_c_tool_bitwise", "kitti07_keyframes_gtsam_points is absent");
        return;
    }
    check_against_cli(&cli, &source, &target, Format::BinXyz, "bin_xyz", 0.5);
}

#[test]
fn in_memory_points_match_file_points() {
    // The same coordinates given as Rust slices instead of a library-read cloud: the same bits.
    let Some(data) = common::data_dir() else {
        skip("in_memory_points_match_file_points", "no data (../shared/data or KISSM_DATA_DIR)");
        return;
    };
    let dir = data.join("kitti07_keyframes_gtsam_points");
    let (source, target) = (dir.join("000001/points.bin"), dir.join("000000/points.bin"));
    if !source.is_file() || !target.is_file() {
        skip("in_memory_points_match_file_points", "kitti07_keyframes_gtsam_points is absent");
        return;
    }
    let read_f32 = |path: &Path| -> Vec<f32> {
        std::fs::read(path).unwrap().chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect()
    };
    let (src32, tgt32) = (read_f32(&source), read_f32(&target));
    let src_view = kissm::PointsView::strided_f32(&src32, 3).unwrap();
    let tgt_view = kissm::PointsView::strided_f32(&tgt32, 3).unwrap();
    let config = Config::builder().voxel_size(0.5).num_threads(2).build().unwrap();
    let mut m = Matcher::new(&config).unwrap();
    let from_f32 = m.register(&src_view, &tgt_view).unwrap();
    let source_cloud = kissm::read_points_with_format(&source, Format::BinXyz).unwrap();
    let target_cloud = kissm::read_points_with_format(&target, Format::BinXyz).unwrap();
    let from_files = m.register(&source_cloud, &target_cloud).unwrap();
    assert!(from_f32.valid);
    // float32 values widened to float64 are the same numbers.
    assert!(from_f32.same_result(&from_files), "{from_f32:?} vs {from_files:?}");
}

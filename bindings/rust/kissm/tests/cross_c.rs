// SPDX-License-Identifier: MIT
//! Rust results bit for bit equal to the C library's on the same input: the `kissm` tool's
//! `register --json` and `refine --json` output (which prints every double so that it reads back exactly)
//! against this crate's registration or refinement of the same files read with `kissm::read_points`.
//!
//! The demo's clouds (`kissm demo --out DIR`, float64 PLY) and the shared test scene of `tests/data`
//! (or `KISSM_TEST_DATA`), without refinement, with GICP or point-to-plane refinement after the solver,
//! and refined from a perturbed ground truth (`kissm refine --initial`). Real data: KITTI 07 keyframes
//! 000001 -> 000000 (raw float32 xyz, voxel 0.5), skipped when `../shared/data` is absent. All need
//! the tool: `KISSM_CLI`, `KISSM_BUILD_DIR/kissm` or the repository's `build/kissm` (skipped otherwise).

mod common;

use std::ffi::OsStr;
use std::path::{Path, PathBuf};

use common::{compare_with_cli_json, run_cli_json, skip, Json};
use kissm::{Config, Format, Matcher, RefineMode};

/// What the tool and the crate run.
#[derive(Clone, Copy)]
enum Call<'a> {
    /// `kissm register ... --refine MODE` and `Matcher::register` with that refine mode.
    Register(RefineMode),
    /// `kissm refine ... --initial FILE --refine MODE` and `Matcher::refine` from the same transform.
    Refine(RefineMode, &'a [[f64; 4]; 4]),
}

fn refine_name(mode: RefineMode) -> &'static str {
    match mode {
        RefineMode::None => "none",
        RefineMode::Gicp => "gicp",
        RefineMode::PointToPlane => "point-to-plane",
    }
}

/// The initial transform as a file for the tool, in a folder of its own (only the shared-scene test
/// refines, once per mode, so the folder's name is unique).
fn write_initial(initial: &[[f64; 4]; 4], mode: RefineMode) -> PathBuf {
    let file = common::temp_dir(&format!("cross-refine-{}", refine_name(mode))).join("initial.txt");
    // Rust's shortest round-trip form reads back to the same doubles in C.
    let rows: Vec<String> =
        initial.iter().map(|r| r.iter().map(|v| format!("{v:?}")).collect::<Vec<_>>().join(" ")).collect();
    std::fs::write(&file, format!("# the initial transform\n{}\n", rows.join("\n"))).unwrap();
    file
}

fn check_against_cli(
    cli: &Path,
    source: &Path,
    target: &Path,
    format: Format,
    format_name: &str,
    voxel: f64,
    call: Call,
) {
    let voxel_text = voxel.to_string();
    let (command, mode) = match call {
        Call::Register(mode) => ("register", mode),
        Call::Refine(mode, _) => ("refine", mode),
    };
    let mut args: Vec<&OsStr> = vec![
        OsStr::new(command),
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
    if mode != RefineMode::None {
        args.extend([OsStr::new("--refine"), OsStr::new(refine_name(mode))]);
    }
    let initial_file = match call {
        Call::Refine(_, initial) => Some(write_initial(initial, mode)),
        Call::Register(_) => None,
    };
    if let Some(file) = &initial_file {
        args.extend([OsStr::new("--initial"), file.as_os_str()]);
    }
    let json: Json = run_cli_json(cli, &args);
    if let Some(folder) = initial_file.as_deref().and_then(Path::parent) {
        let _ = std::fs::remove_dir_all(folder);
    }
    for key in ["valid", "transform", "final_inliers", "time_ms"] {
        assert!(json.has(key), "the tool's JSON has {key}");
    }
    if mode != RefineMode::None || matches!(call, Call::Refine(..)) {
        assert_eq!(json.get("refine").str(), refine_name(mode), "the tool's refine mode");
        assert!(!matches!(json.get("information"), Json::Null), "the tool refined");
    }
    if let Call::Refine(_, initial) = call {
        let printed = json.get("initial_transform").arr();
        let printed: Vec<f64> = printed.iter().flat_map(Json::nums).collect();
        let given: Vec<f64> = initial.iter().flatten().copied().collect();
        assert_eq!(printed, given, "the tool's initial_transform");
    }

    let source_cloud = kissm::read_points_with_format(source, format).unwrap();
    let target_cloud = kissm::read_points_with_format(target, format).unwrap();
    // Thread counts do not change results: compare 1 (as the tool ran) and 2.
    for threads in [1, 2] {
        let config = Config::builder().voxel_size(voxel).num_threads(threads).refine_mode(mode).build().unwrap();
        let mut matcher = Matcher::new(&config).unwrap();
        let reg = match call {
            Call::Register(_) => matcher.register(&source_cloud, &target_cloud).unwrap(),
            Call::Refine(_, initial) => matcher.refine(&source_cloud, &target_cloud, initial).unwrap(),
        };
        assert_eq!(reg.is_refined(), mode != RefineMode::None || matches!(call, Call::Refine(..)));
        let failures = compare_with_cli_json(&json, &reg);
        assert!(
            failures.is_empty(),
            "Rust (threads {threads}, {command}, refine {mode:?}) differs from C:\n  {}",
            failures.join("\n  ")
        );
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
    let (source, target) = (dir.join("source.ply"), dir.join("target.ply"));
    for mode in [RefineMode::None, RefineMode::Gicp] {
        check_against_cli(&cli, &source, &target, Format::Auto, "auto", 0.3, Call::Register(mode));
    }
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
    let truth = common::read_ground_truth(&dir.join("roundtrip_ground_truth.txt"));
    let initial = common::perturbed(&truth).to_matrix();
    for call in [
        Call::Register(RefineMode::None),
        Call::Register(RefineMode::Gicp),
        Call::Register(RefineMode::PointToPlane),
        Call::Refine(RefineMode::Gicp, &initial),
        Call::Refine(RefineMode::PointToPlane, &initial),
    ] {
        check_against_cli(&cli, &source, &target, Format::Auto, "auto", common::SCENE_VOXEL, call);
    }
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
    for mode in [RefineMode::None, RefineMode::Gicp] {
        check_against_cli(&cli, &source, &target, Format::BinXyz, "bin_xyz", 0.5, Call::Register(mode));
    }
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

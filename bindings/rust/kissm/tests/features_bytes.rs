// SPDX-License-Identifier: MIT
//! `Features::to_bytes` / `Features::from_bytes`: byte round trips, registrations and refinements from loaded
//! features bitwise equal to the originals', truncated and bit-flipped input refused with `ErrorKind::Parse`,
//! loaded features of another configuration refused on use, and the signature (the same bits when loaded or at
//! other thread counts, nearly the same for a moved cloud); on the shared test scene and, when the real
//! data is there, a KITTI 07 keyframe pair.

mod common;

use common::{scene, skip, SCENE_VOXEL};
use kissm::{Config, ErrorKind, Features, Format, Matcher, RefineMode, SIGNATURE_SIZE};

const IDENTITY: [[f64; 4]; 4] =
    [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]];

fn scene_config(refine: RefineMode) -> Config {
    Config::builder().voxel_size(SCENE_VOXEL).refine_mode(refine).build().unwrap()
}

/// Loads features from their bytes and checks what can be checked without registering.
fn reload(features: &Features) -> Features {
    let bytes = features.to_bytes().unwrap();
    assert_eq!(&bytes[..8], b"KISSMFT\0");
    assert_eq!(features.to_bytes().unwrap(), bytes, "the same features give the same bytes");
    let loaded = Features::from_bytes(&bytes).unwrap();
    assert_eq!(loaded.to_bytes().unwrap(), bytes, "serialise, deserialise, serialise: the same bytes");
    assert_eq!(
        (loaded.num_points(), loaded.num_voxels(), loaded.num_keypoints()),
        (features.num_points(), features.num_voxels(), features.num_keypoints())
    );
    // memory_bytes counts the vectors' capacities: the original's may hold the slack of their growth, which
    // the exactly sized loaded vectors do not have.
    assert!(loaded.memory_bytes() <= features.memory_bytes());
    assert!(loaded.memory_bytes() as f64 >= 0.99 * features.memory_bytes() as f64);
    assert_eq!(bits(&loaded.signature().unwrap()), bits(&features.signature().unwrap()), "loaded signature");
    loaded
}

fn bits(signature: &[f64; SIGNATURE_SIZE]) -> Vec<u64> {
    signature.iter().map(|v| v.to_bits()).collect()
}

fn distance(a: &[f64; SIGNATURE_SIZE], b: &[f64; SIGNATURE_SIZE]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum::<f64>().sqrt()
}

/// The signature: three unit-length blocks, the same bits at 1 and 4 threads, nearly the same for the cloud
/// moved rigidly (the voxel grid differs), farther for the other scan of the scene, zeros without keypoints.
#[test]
fn signature_is_frame_and_thread_free() {
    let Some(scene) = scene("signature_is_frame_and_thread_free") else { return };
    let config = |threads: usize| Config::builder().voxel_size(SCENE_VOXEL).num_threads(threads).build().unwrap();
    let (mut one, mut four) = (Matcher::new(&config(1)).unwrap(), Matcher::new(&config(4)).unwrap());
    let here = one.compute_features(&scene.source).unwrap().signature().unwrap();
    assert_eq!(bits(&here), bits(&four.compute_features(&scene.source).unwrap().signature().unwrap()));
    for block in [0..33, 33..66, 66..SIGNATURE_SIZE] {
        let squares: f64 = here[block.clone()].iter().map(|v| v * v).sum();
        assert!((squares - 1.0).abs() < 1e-12, "{block:?}: {squares}");
    }
    let pose = common::Pose::axis_angle([1.0, -2.0, 3.0], 150.0, [40.0, -25.0, 3.0]);
    let moved = one.compute_features(&common::moved(&scene.source, &pose)).unwrap().signature().unwrap();
    let other = one.compute_features(&scene.target).unwrap().signature().unwrap();
    let (near, far) = (distance(&here, &moved), distance(&here, &other));
    assert!(near < 0.1 && far > near, "moved {near}, the other scan {far}");
    let flat = one.compute_features(&common::flat_plane()).unwrap();
    if flat.num_keypoints() == 0 {
        assert!(flat.signature().unwrap().iter().all(|v| *v == 0.0));
    }
}

#[test]
fn scene_features_round_trip_and_register_bitwise() {
    let Some(scene) = scene("scene_features_round_trip_and_register_bitwise") else { return };
    for refine in [RefineMode::None, RefineMode::Gicp] {
        let mut m = Matcher::new(&scene_config(refine)).unwrap();
        let (fs, ft) = (m.compute_features(&scene.source).unwrap(), m.compute_features(&scene.target).unwrap());
        let (ls, lt) = (reload(&fs), reload(&ft));
        let expected = m.register_features(&fs, &ft).unwrap();
        assert!(expected.valid, "{refine:?}: {expected:?}");
        assert_eq!(expected.is_refined(), refine != RefineMode::None);
        let got = m.register_features(&ls, &lt).unwrap();
        assert!(got.same_result(&expected), "{refine:?}: {got:?} vs {expected:?}");
        assert!(m.register_features(&fs, &lt).unwrap().same_result(&expected), "{refine:?}: mixed");
        let initial = common::perturbed(&scene.truth).to_matrix();
        let refined = m.refine_features(&ls, &lt, &initial).unwrap();
        assert!(refined.same_result(&m.refine_features(&fs, &ft, &initial).unwrap()), "{refine:?}: refine");
        // Loaded features are Features like any other: shared between threads, used by another matcher.
        let other = std::thread::spawn(move || {
            Matcher::new(&scene_config(refine)).unwrap().register_features(&ls, &lt).unwrap()
        });
        assert!(other.join().unwrap().same_result(&expected), "{refine:?}: another thread");
    }
}

#[test]
fn kitti_keyframe_features_round_trip_and_register_bitwise() {
    const TEST: &str = "kitti_keyframe_features_round_trip_and_register_bitwise";
    let Some(data) = common::data_dir() else {
        skip(TEST, "no data (../shared/data or KISSM_DATA_DIR)");
        return;
    };
    let dir = data.join("kitti07_keyframes_gtsam_points");
    let (source, target) = (dir.join("000001/points.bin"), dir.join("000000/points.bin"));
    if !source.is_file() || !target.is_file() {
        skip(TEST, "kitti07_keyframes_gtsam_points is absent");
        return;
    }
    let source = kissm::read_points_with_format(&source, Format::BinXyz).unwrap();
    let target = kissm::read_points_with_format(&target, Format::BinXyz).unwrap();
    let mut m = Matcher::new(&Config::builder().voxel_size(0.5).num_threads(2).build().unwrap()).unwrap();
    let (fs, ft) = (m.compute_features(&source).unwrap(), m.compute_features(&target).unwrap());
    let expected = m.register_features(&fs, &ft).unwrap();
    assert!(expected.valid, "{expected:?}");
    let (ls, lt) = (reload(&fs), reload(&ft));
    let got = m.register_features(&ls, &lt).unwrap();
    assert!(got.same_result(&expected), "{got:?} vs {expected:?}");
}

fn small_features_bytes(test: &str) -> Option<Vec<u8>> {
    let scene = scene(test)?;
    let mut m = Matcher::new(&scene_config(RefineMode::None)).unwrap();
    Some(m.compute_features(&scene.source).unwrap().to_bytes().unwrap())
}

fn parse_error(bytes: &[u8], what: &str) -> String {
    let err = Features::from_bytes(bytes).expect_err(what);
    assert_eq!(err.kind(), ErrorKind::Parse, "{what}: {err}");
    assert_eq!(err.code(), kissm_sys::KISSM_ERR_PARSE);
    assert!(err.message().contains("features bytes"), "{what}: {err}");
    err.message().to_string()
}

#[test]
fn truncated_bytes_are_parse_errors() {
    let Some(bytes) = small_features_bytes("truncated_bytes_are_parse_errors") else { return };
    let n = bytes.len();
    for size in [0, 1, 7, 8, 12, 100, 213, 214, n / 2, n - 8, n - 1] {
        let message = parse_error(&bytes[..size], &format!("{size} of {n} bytes"));
        assert!(message.contains("truncated"), "{size} of {n} bytes: {message}");
    }
    let mut longer = bytes.clone();
    longer.push(0);
    parse_error(&longer, "a trailing byte");
    let mut not_features = bytes.clone();
    not_features[..4].copy_from_slice(b"PLY\n");
    assert!(parse_error(&not_features, "another magic").contains("not kissm features"));
}

#[test]
fn flipped_bits_are_parse_errors() {
    let Some(bytes) = small_features_bytes("flipped_bits_are_parse_errors") else { return };
    let n = bytes.len();
    // The magic is checked first, then the version, then the checksum over everything else.
    let cases = [
        (0, "not kissm features"),
        (8, "version"),
        (24, "checksum mismatch"),
        (200, "checksum mismatch"),
        (n / 2, "checksum mismatch"),
        (n - 9, "checksum mismatch"),
        (n - 1, "checksum mismatch"),
    ];
    for (offset, expected) in cases {
        for bit in [0, 7] {
            let mut flipped = bytes.clone();
            flipped[offset] ^= 1 << bit;
            let message = parse_error(&flipped, &format!("bit {bit} of byte {offset} flipped"));
            assert!(message.contains(expected), "bit {bit} of byte {offset}: {message}");
        }
    }
    assert!(Features::from_bytes(&bytes).is_ok());
}

#[test]
fn loaded_features_of_another_config_mismatch_on_use() {
    let Some(scene) = scene("loaded_features_of_another_config_mismatch_on_use") else { return };
    let mut a = Matcher::with_voxel_size(SCENE_VOXEL).unwrap();
    let mut b = Matcher::with_voxel_size(2.0 * SCENE_VOXEL).unwrap();
    let fa = Features::from_bytes(&a.compute_features(&scene.source).unwrap().to_bytes().unwrap()).unwrap();
    let fb = Features::from_bytes(&b.compute_features(&scene.target).unwrap().to_bytes().unwrap()).unwrap();
    let err = a.register_features(&fa, &fb).unwrap_err();
    assert_eq!(err.kind(), ErrorKind::FeaturesMismatch, "{err}");
    assert!(!err.message().is_empty());
    assert_eq!(a.refine_features(&fb, &fa, &IDENTITY).unwrap_err().kind(), ErrorKind::FeaturesMismatch);
    assert_eq!(b.register_features(&fb, &fb).unwrap().counts.source_voxels, fb.num_voxels());
}

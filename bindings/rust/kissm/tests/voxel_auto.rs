// SPDX-License-Identifier: MIT
//! The automatic voxel size: `suggest_voxel_size` (symmetric, order-free, exactly scaled) and
//! `ConfigBuilder::voxel_size_auto`, which registers as the pair's suggestion does, bit for bit.

mod common;

use common::{permuted, scene, Pose};
use kissm::{suggest_voxel_size, Config, ErrorKind, Matcher};

#[test]
fn suggestion_is_symmetric_order_free_and_scaled() {
    let Some(pair) = scene("suggestion_is_symmetric_order_free_and_scaled") else { return };
    let (s, t) = (&pair.source[..], &pair.target[..]);
    let v = suggest_voxel_size(&[&s, &t]).unwrap();
    assert_eq!(v, suggest_voxel_size(&[&t, &s]).unwrap());
    let own = [suggest_voxel_size(&[&s]).unwrap(), suggest_voxel_size(&[&t]).unwrap()];
    assert_eq!(v, own[0].min(own[1]));
    let shuffled = permuted(s, 3);
    assert_eq!(suggest_voxel_size(&[&shuffled]).unwrap(), own[0]);
    let scaled: Vec<[f64; 3]> = s.iter().map(|p| [p[0] * 2.0, p[1] * 2.0 + 5.0, p[2] * 2.0]).collect();
    assert_eq!(suggest_voxel_size(&[&scaled]).unwrap(), 2.0 * own[0]);
    let k = 8.0 * v.log2();
    assert!((k - k.round()).abs() < 1e-9, "{v} is not 2^(k/8)");
}

#[test]
fn suggestion_refuses_clouds_without_a_length() {
    let same = vec![[1.0, 2.0, 3.0]; 50];
    let err = suggest_voxel_size(&[&same]).unwrap_err();
    assert_eq!(err.kind(), ErrorKind::TooFewPoints);
    assert!(err.message().contains("clouds[0]") && err.message().contains("coincide"), "{err}");
    let err = suggest_voxel_size(&[]).unwrap_err();
    assert_eq!(err.kind(), ErrorKind::InvalidArgument);
    assert!(err.message().contains("num_clouds"), "{err}");
}

#[test]
fn auto_registers_as_the_suggested_voxel() {
    let Some(pair) = scene("auto_registers_as_the_suggested_voxel") else { return };
    let (s, t) = (&pair.source[..], &pair.target[..]);
    let v = suggest_voxel_size(&[&s, &t]).unwrap();
    let auto = Config::builder().voxel_size_auto().num_threads(1).build().unwrap();
    assert_eq!(auto.voxel_size(), 0.0);
    let fixed = Config::builder().voxel_size(v).num_threads(2).build().unwrap();
    let a = Matcher::new(&auto).unwrap().register(s, t).unwrap();
    let f = Matcher::new(&fixed).unwrap().register(s, t).unwrap();
    assert_eq!(a.voxel_size_used, v);
    assert!(a.same_result(&f));
    assert!(a.valid);
    let (rot, _) = pair.truth.errors(&Pose::from_matrix(&a.transform));
    assert!(rot < 2.0, "rotation error {rot} deg");
}

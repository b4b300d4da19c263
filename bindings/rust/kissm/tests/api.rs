// SPDX-License-Identifier: MIT
//! API surface without registrations of real size: versions, config defaults and validation, error
//! mapping for every reachable status code, point views, file reading, and the Send/Sync contract.

mod common;

use std::io::Write as _;

use common::{assert_send, assert_sync, moved, scene, NotSync, Pose};
use kissm::{
    AsPoints, CancelHandle, Cloud, Config, Error, ErrorKind, Features, Format, Matcher, NonFinitePolicy, PointsView,
    Preset, Reason, RefineMode, Refinement, Registration, Suppression, Viewpoint,
};
use kissm_sys as sys;

#[test]
fn version_matches_header() {
    kissm::check_library().expect("the linked library matches the bindings");
    assert_eq!(kissm::version_number(), sys::KISSM_VERSION_NUMBER as u32);
    assert_eq!(kissm::version().as_bytes(), &sys::KISSM_VERSION_STRING[..sys::KISSM_VERSION_STRING.len() - 1]);
    assert_eq!(kissm::MIN_POINTS, 4);
}

#[test]
fn struct_layouts_match_the_library() {
    // SAFETY: no preconditions.
    let sizes = unsafe {
        [
            sys::kissm_abi_sizeof(sys::KISSM_STRUCT_CONFIG),
            sys::kissm_abi_sizeof(sys::KISSM_STRUCT_POINTS),
            sys::kissm_abi_sizeof(sys::KISSM_STRUCT_RESULT),
        ]
    };
    assert_eq!(sizes[0] as usize, std::mem::size_of::<sys::kissm_config>());
    assert_eq!(sizes[1] as usize, std::mem::size_of::<sys::kissm_points>());
    assert_eq!(sizes[2] as usize, std::mem::size_of::<sys::kissm_result>());
}

#[test]
fn config_defaults_are_the_documented_ones() {
    let c = Config::default();
    assert_eq!(c.num_threads(), 0);
    assert_eq!(c.voxel_size(), 0.3);
    assert_eq!(c.normal_radius_gain(), 3.5);
    assert_eq!(c.fpfh_radius_gain(), 5.0);
    assert_eq!(c.max_linearity(), 0.99);
    assert_eq!(c.ratio_test(), 0.9);
    assert_eq!(c.prune_noise_bound_gain(), 1.0);
    assert_eq!(c.solver_noise_bound_gain(), 0.75);
    assert_eq!(c.noise_bound_max(), 0.0);
    assert_eq!(c.viewpoint(), Viewpoint::Local);
    assert_eq!(c.viewpoint(), Viewpoint::default());
    assert_eq!(c.min_normal_neighbors(), 3);
    assert_eq!(c.max_correspondences(), 0);
    assert_eq!(c.min_inliers(), 15);
    assert_eq!(c.nonfinite_policy(), NonFinitePolicy::Reject);
    // The former spelling still names the same type.
    #[allow(deprecated)]
    let former: kissm::NonfinitePolicy = NonFinitePolicy::Drop;
    assert_eq!(Config::builder().nonfinite_policy(former).build().unwrap().nonfinite_policy(), NonFinitePolicy::Drop);
    c.validate().expect("defaults are valid");
    // The builder starts from the same values.
    let built = Config::builder().build().unwrap();
    assert_eq!(format!("{built:?}"), format!("{c:?}"));
    assert!(c.as_raw().log_fn.is_none() && c.as_raw().progress_fn.is_none());
}

/// The library's own defaults (`kissm_config_init`), read without this crate's wrapper.
fn library_defaults() -> sys::kissm_config {
    let mut raw = sys::kissm_config::default();
    // SAFETY: raw is a writable kissm_config of exactly the size passed.
    let status = unsafe { sys::kissm_config_init(&mut raw, std::mem::size_of::<sys::kissm_config>() as u32) };
    assert_eq!(status, sys::KISSM_OK);
    raw
}

#[test]
fn refine_defaults_are_the_library_ones() {
    // The library may tune these values: the crate reads them, so compare with kissm_config_init's.
    let lib = library_defaults();
    for c in [Config::default(), Config::builder().build().unwrap()] {
        assert_eq!(c.refine_mode(), RefineMode::None);
        assert_eq!(c.refine_mode().code(), lib.refine_mode);
        assert_eq!(c.refine_max_iterations(), lib.refine_max_iterations as usize);
        assert_eq!(c.refine_max_distance_gain().to_bits(), lib.refine_max_distance_gain.to_bits());
        assert_eq!(c.refine_kernel_gain().to_bits(), lib.refine_kernel_gain.to_bits());
        assert_eq!(c.refine_rotation_epsilon().to_bits(), lib.refine_rotation_epsilon.to_bits());
        assert_eq!(c.refine_translation_epsilon_gain().to_bits(), lib.refine_translation_epsilon_gain.to_bits());
        assert_eq!(c.min_overlap().to_bits(), lib.min_overlap.to_bits());
        assert_eq!(c.refine_normal_radius_gain().to_bits(), lib.refine_normal_radius_gain.to_bits());
        // Every default is inside the range the builder documents (and the library validates).
        assert!((1..=1000).contains(&c.refine_max_iterations()));
        assert!(c.refine_normal_radius_gain() > 0.0 && c.refine_normal_radius_gain() <= 50.0);
        assert!(c.refine_max_distance_gain() > 0.0 && c.refine_max_distance_gain() <= 100.0);
        assert!(c.refine_kernel_gain() > 0.0 && c.refine_kernel_gain() <= 100.0);
        for v in [c.refine_rotation_epsilon(), c.refine_translation_epsilon_gain(), c.min_overlap()] {
            assert!((0.0..=1.0).contains(&v), "{v}");
        }
    }
    assert_eq!(RefineMode::default(), RefineMode::None);
}

#[test]
fn validity_settings_are_the_library_ones() {
    // The lead may tune these defaults: the crate reads them from kissm_config_init.
    let lib = library_defaults();
    for c in [Config::default(), Config::builder().build().unwrap()] {
        assert_eq!(c.max_rotation_uncertainty().to_bits(), lib.max_rotation_uncertainty.to_bits());
        assert_eq!(c.min_inlier_coverage().to_bits(), lib.min_inlier_coverage.to_bits());
        assert_eq!(c.refine_min_inliers(), lib.refine_min_inliers as usize);
        assert_eq!(c.min_overlap().to_bits(), lib.min_overlap.to_bits());
        assert_eq!(c.min_refine_condition().to_bits(), lib.min_refine_condition.to_bits());
        assert_eq!(c.max_refine_rmse_gain().to_bits(), lib.max_refine_rmse_gain.to_bits());
        assert_eq!(c.max_ambiguity().to_bits(), lib.max_ambiguity.to_bits());
        assert!((0.0..=1.0).contains(&c.max_ambiguity()));
        // Inside the documented ranges.
        assert!(c.max_rotation_uncertainty() > 0.0 && c.max_rotation_uncertainty() <= 3.15);
        assert!((0.0..=1.0).contains(&c.min_inlier_coverage()));
        assert!((0.0..=1.0).contains(&c.min_refine_condition()));
        assert!(c.max_refine_rmse_gain() > 0.0 && c.max_refine_rmse_gain() <= 100.0);
        assert!((3..=100_000).contains(&c.refine_min_inliers()));
        // A degenerate refined pose is not valid unless asked for.
        assert_eq!(c.allow_degenerate(), lib.allow_degenerate != 0);
        assert!(!c.allow_degenerate());
        assert_eq!(c.as_raw().allow_degenerate, 0);
        // The reserved fields are zero and not settings.
        assert_eq!((c.as_raw().reserved1, c.as_raw().reserved2), (0, 0));
        assert!(!format!("{c:?}").contains("reserved"), "{c:?}");
        assert!(format!("{c:?}").contains("allow_degenerate: false"), "{c:?}");
    }
    assert_eq!((lib.reserved1, lib.reserved2, lib.allow_degenerate), (0, 0, 0));
}

#[test]
fn builder_sets_every_validity_field() {
    let c = Config::builder()
        .max_rotation_uncertainty(0.01)
        .min_inlier_coverage(0.6)
        .refine_min_inliers(25)
        .min_refine_condition(0.05)
        .max_refine_rmse_gain(0.7)
        .allow_degenerate(true)
        .max_ambiguity(0.9)
        .build();
    let c = c.unwrap();
    assert_eq!((c.max_ambiguity(), c.as_raw().max_ambiguity), (0.9, 0.9));
    assert_eq!(c.max_refine_rmse_gain(), 0.7);
    assert_eq!(c.as_raw().max_refine_rmse_gain, 0.7);
    assert!(c.allow_degenerate());
    assert_eq!((c.as_raw().allow_degenerate, c.as_raw().reserved2), (1, 0));
    assert_eq!(c.max_rotation_uncertainty(), 0.01);
    assert_eq!(c.min_inlier_coverage(), 0.6);
    assert_eq!(c.refine_min_inliers(), 25);
    assert_eq!(c.min_refine_condition(), 0.05);
    // Under their C names in the raw struct, next to a zero reserved field; the Debug output names them.
    let raw = c.as_raw();
    assert_eq!((raw.max_rotation_uncertainty, raw.min_inlier_coverage), (0.01, 0.6));
    assert_eq!((raw.refine_min_inliers, raw.reserved1, raw.min_refine_condition), (25, 0, 0.05));
    let debug = format!("{c:?}");
    for field in [
        "max_rotation_uncertainty: 0.01",
        "min_inlier_coverage: 0.6",
        "refine_min_inliers: 25",
        "min_refine_condition: 0.05",
        "max_refine_rmse_gain: 0.7",
        "allow_degenerate: true",
        "max_ambiguity: 0.9",
    ] {
        assert!(debug.contains(field), "{debug}");
    }
    // Every other field keeps the library's default.
    let back = c
        .to_builder()
        .max_rotation_uncertainty(Config::default().max_rotation_uncertainty())
        .min_inlier_coverage(Config::default().min_inlier_coverage())
        .refine_min_inliers(Config::default().refine_min_inliers())
        .min_refine_condition(Config::default().min_refine_condition())
        .max_refine_rmse_gain(Config::default().max_refine_rmse_gain())
        .allow_degenerate(Config::default().allow_degenerate())
        .max_ambiguity(Config::default().max_ambiguity())
        .build()
        .unwrap();
    assert_eq!(format!("{back:?}"), format!("{:?}", Config::default()));
    assert_eq!(back.as_raw().allow_degenerate, 0);
    // A matcher keeps them.
    assert_eq!(format!("{:?}", Matcher::new(&c).unwrap().config()), debug);
    // The range ends are accepted.
    let ends = Config::builder().max_rotation_uncertainty(3.15).min_inlier_coverage(0.0).refine_min_inliers(3);
    let ends = ends.min_refine_condition(0.0).build().unwrap();
    assert_eq!((ends.max_rotation_uncertainty(), ends.refine_min_inliers()), (3.15, 3));
    let ends = ends.to_builder().max_rotation_uncertainty(1e-300).min_inlier_coverage(1.0).refine_min_inliers(100_000);
    let ends = ends.min_refine_condition(1.0).build().unwrap();
    assert_eq!((ends.refine_min_inliers(), ends.min_refine_condition()), (100_000, 1.0));
    for gain in [1e-300, 100.0] {
        assert_eq!(Config::builder().max_refine_rmse_gain(gain).build().unwrap().max_refine_rmse_gain(), gain);
    }
    for gain in [0.0, -1.0, 100.5, f64::NAN] {
        let err = Config::builder().max_refine_rmse_gain(gain).build().unwrap_err();
        assert_eq!(err.kind(), kissm::ErrorKind::InvalidArgument);
        assert!(err.message().contains("config.max_refine_rmse_gain"), "{err}");
    }
    for bound in [0.0, 1.0] {
        assert_eq!(Config::builder().max_ambiguity(bound).build().unwrap().max_ambiguity(), bound);
    }
    for bound in [-0.01, 1.01, f64::NAN, f64::INFINITY] {
        let err = Config::builder().max_ambiguity(bound).build().unwrap_err();
        assert_eq!(err.kind(), kissm::ErrorKind::InvalidArgument);
        assert!(err.message().contains("config.max_ambiguity"), "{err}");
    }
}

#[test]
fn refine_modes_map_their_codes() {
    for (mode, code) in [
        (RefineMode::None, sys::KISSM_REFINE_NONE),
        (RefineMode::Gicp, sys::KISSM_REFINE_GICP),
        (RefineMode::PointToPlane, sys::KISSM_REFINE_POINT_TO_PLANE),
    ] {
        assert_eq!(mode.code(), code);
        assert_eq!(RefineMode::from_code(code), Some(mode));
        let c = Config::builder().refine_mode(mode).build().unwrap();
        assert_eq!(c.refine_mode(), mode);
        assert_eq!(c.as_raw().refine_mode, code);
    }
    assert_eq!(RefineMode::from_code(3), None);
    assert_eq!(RefineMode::from_code(-1), None);
}

#[test]
fn builder_sets_every_refine_field() {
    let c = Config::builder()
        .refine_mode(RefineMode::PointToPlane)
        .refine_max_iterations(7)
        .refine_max_distance_gain(2.5)
        .refine_kernel_gain(0.75)
        .refine_rotation_epsilon(2e-4)
        .refine_translation_epsilon_gain(5e-3)
        .min_overlap(0.4)
        .refine_normal_radius_gain(1.25)
        .build()
        .unwrap();
    assert_eq!(c.refine_mode(), RefineMode::PointToPlane);
    assert_eq!(c.refine_max_iterations(), 7);
    assert_eq!(c.refine_max_distance_gain(), 2.5);
    assert_eq!(c.refine_kernel_gain(), 0.75);
    assert_eq!(c.refine_rotation_epsilon(), 2e-4);
    assert_eq!(c.refine_translation_epsilon_gain(), 5e-3);
    assert_eq!(c.min_overlap(), 0.4);
    assert_eq!(c.refine_normal_radius_gain(), 1.25);
    // The raw struct holds them under the C names, and a matcher keeps them.
    let raw = c.as_raw();
    assert_eq!((raw.refine_mode, raw.refine_max_iterations), (sys::KISSM_REFINE_POINT_TO_PLANE, 7));
    assert_eq!((raw.refine_max_distance_gain, raw.refine_kernel_gain), (2.5, 0.75));
    assert_eq!((raw.refine_rotation_epsilon, raw.refine_translation_epsilon_gain, raw.min_overlap), (2e-4, 5e-3, 0.4));
    assert_eq!(raw.refine_normal_radius_gain, 1.25);
    let m = Matcher::new(&c).unwrap();
    assert_eq!(format!("{:?}", m.config()), format!("{c:?}"));
    assert!(format!("{c:?}").contains("refine_mode: PointToPlane"), "{c:?}");
    assert!(format!("{c:?}").contains("refine_normal_radius_gain: 1.25"), "{c:?}");
    // The range ends are accepted.
    let ends = Config::builder()
        .refine_max_iterations(1)
        .refine_max_distance_gain(100.0)
        .refine_kernel_gain(100.0)
        .refine_rotation_epsilon(0.0)
        .refine_translation_epsilon_gain(1.0)
        .min_overlap(1.0)
        .refine_normal_radius_gain(50.0)
        .build()
        .unwrap();
    assert_eq!(ends.refine_max_iterations(), 1);
    let ends = ends.to_builder().refine_max_iterations(1000).refine_rotation_epsilon(1.0).min_overlap(0.0);
    let ends = ends.refine_normal_radius_gain(1e-300).build().unwrap();
    assert_eq!((ends.refine_max_iterations(), ends.refine_normal_radius_gain()), (1000, 1e-300));
}

#[test]
fn builder_sets_every_field() {
    let c = Config::builder()
        .num_threads(3)
        .voxel_size(0.25)
        .normal_radius_gain(3.0)
        .fpfh_radius_gain(6.0)
        .max_linearity(0.9)
        .ratio_test(0.8)
        .prune_noise_bound_gain(1.5)
        .solver_noise_bound_gain(0.5)
        .noise_bound_max(0.2)
        .viewpoint(Viewpoint::Fixed([1.0, 2.0, 3.0]))
        .min_normal_neighbors(5)
        .max_correspondences(1000)
        .min_inliers(12)
        .nonfinite_policy(NonFinitePolicy::Drop)
        .build()
        .unwrap();
    assert_eq!(c.num_threads(), 3);
    assert_eq!(c.voxel_size(), 0.25);
    assert_eq!(c.normal_radius_gain(), 3.0);
    assert_eq!(c.fpfh_radius_gain(), 6.0);
    assert_eq!(c.max_linearity(), 0.9);
    assert_eq!(c.ratio_test(), 0.8);
    assert_eq!(c.prune_noise_bound_gain(), 1.5);
    assert_eq!(c.solver_noise_bound_gain(), 0.5);
    assert_eq!(c.noise_bound_max(), 0.2);
    assert_eq!(c.viewpoint(), Viewpoint::Fixed([1.0, 2.0, 3.0]));
    assert_eq!(c.min_normal_neighbors(), 5);
    assert_eq!(c.max_correspondences(), 1000);
    assert_eq!(c.min_inliers(), 12);
    assert_eq!(c.nonfinite_policy(), NonFinitePolicy::Drop);
    let center = c.to_builder().viewpoint(Viewpoint::CloudCenter).build().unwrap();
    assert_eq!(center.viewpoint(), Viewpoint::CloudCenter);
    assert_eq!(center.min_inliers(), 12);
    for v in [Viewpoint::SignFree, Viewpoint::Local] {
        assert_eq!(c.to_builder().viewpoint(v).build().unwrap().viewpoint(), v);
    }
    // The matcher keeps the config it was created with.
    let m = Matcher::new(&center).unwrap();
    assert_eq!(format!("{:?}", m.config()), format!("{center:?}"));
}

fn invalid(builder: kissm::ConfigBuilder, field: &str) {
    let err = builder.build().expect_err(field);
    assert_eq!(err.kind(), ErrorKind::InvalidArgument, "{field}: {err}");
    assert_eq!(err.code(), sys::KISSM_ERR_INVALID_ARGUMENT);
    assert!(err.message().contains(field), "the message names {field}: {err}");
    assert!(err.to_string().contains(err.message()));
}

#[test]
fn invalid_config_values_are_errors_not_panics() {
    let b = Config::builder;
    invalid(b().voxel_size(-1e-300), "voxel_size"); // 0 is the automatic voxel size (tests/voxel_auto.rs)
    invalid(b().voxel_size(-0.5), "voxel_size");
    invalid(b().voxel_size(f64::NAN), "voxel_size");
    invalid(b().voxel_size(f64::INFINITY), "voxel_size");
    invalid(b().num_threads(1025), "num_threads");
    invalid(b().num_threads(usize::MAX), "num_threads");
    invalid(b().fpfh_radius_gain(1.0), "fpfh_radius_gain");
    invalid(b().fpfh_radius_gain(51.0), "fpfh_radius_gain");
    invalid(b().normal_radius_gain(0.0), "normal_radius_gain");
    invalid(b().normal_radius_gain(6.0), "normal_radius_gain");
    invalid(b().max_linearity(0.0), "max_linearity");
    invalid(b().ratio_test(1.5), "ratio_test");
    invalid(b().prune_noise_bound_gain(0.0), "prune_noise_bound_gain");
    invalid(b().solver_noise_bound_gain(-1.0), "solver_noise_bound_gain");
    invalid(b().noise_bound_max(f64::NAN), "noise_bound_max");
    invalid(b().viewpoint(Viewpoint::Fixed([0.0, f64::INFINITY, 0.0])), "viewpoint");
    invalid(b().min_normal_neighbors(2), "min_normal_neighbors");
    invalid(b().max_correspondences(usize::MAX), "max_correspondences");
    invalid(b().max_correspondences(2), "max_correspondences");
    assert_eq!(b().max_correspondences(0).build().unwrap().max_correspondences(), 0); // automatic
    invalid(b().min_inliers(2), "min_inliers");
    invalid(b().refine_max_iterations(0), "refine_max_iterations");
    invalid(b().refine_max_iterations(1001), "refine_max_iterations");
    invalid(b().refine_max_iterations(usize::MAX), "refine_max_iterations");
    invalid(b().refine_max_distance_gain(0.0), "refine_max_distance_gain");
    invalid(b().refine_max_distance_gain(100.5), "refine_max_distance_gain");
    invalid(b().refine_max_distance_gain(f64::NAN), "refine_max_distance_gain");
    invalid(b().refine_kernel_gain(0.0), "refine_kernel_gain");
    invalid(b().refine_kernel_gain(f64::INFINITY), "refine_kernel_gain");
    invalid(b().refine_rotation_epsilon(-1e-9), "refine_rotation_epsilon");
    invalid(b().refine_rotation_epsilon(1.5), "refine_rotation_epsilon");
    invalid(b().refine_translation_epsilon_gain(-0.1), "refine_translation_epsilon_gain");
    invalid(b().refine_translation_epsilon_gain(f64::NAN), "refine_translation_epsilon_gain");
    invalid(b().min_overlap(-0.01), "min_overlap");
    invalid(b().min_overlap(1.01), "min_overlap");
    invalid(b().min_overlap(f64::NAN), "min_overlap");
    invalid(b().max_rotation_uncertainty(0.0), "config.max_rotation_uncertainty");
    invalid(b().max_rotation_uncertainty(-0.1), "config.max_rotation_uncertainty");
    invalid(b().max_rotation_uncertainty(3.16), "config.max_rotation_uncertainty");
    invalid(b().max_rotation_uncertainty(f64::NAN), "config.max_rotation_uncertainty");
    invalid(b().max_rotation_uncertainty(f64::INFINITY), "config.max_rotation_uncertainty");
    invalid(b().min_inlier_coverage(-0.01), "config.min_inlier_coverage");
    invalid(b().min_inlier_coverage(1.01), "config.min_inlier_coverage");
    invalid(b().min_inlier_coverage(f64::NAN), "config.min_inlier_coverage");
    invalid(b().refine_min_inliers(2), "config.refine_min_inliers");
    invalid(b().refine_min_inliers(100_001), "config.refine_min_inliers");
    invalid(b().refine_min_inliers(usize::MAX), "config.refine_min_inliers");
    invalid(b().min_refine_condition(-0.01), "config.min_refine_condition");
    invalid(b().min_refine_condition(1.01), "config.min_refine_condition");
    invalid(b().min_refine_condition(f64::NAN), "config.min_refine_condition");
    invalid(b().min_refine_condition(f64::INFINITY), "config.min_refine_condition");
    invalid(b().refine_normal_radius_gain(0.0), "config.refine_normal_radius_gain");
    invalid(b().refine_normal_radius_gain(-1.0), "config.refine_normal_radius_gain");
    invalid(b().refine_normal_radius_gain(50.5), "config.refine_normal_radius_gain");
    invalid(b().refine_normal_radius_gain(f64::NAN), "config.refine_normal_radius_gain");
    invalid(b().refine_normal_radius_gain(f64::INFINITY), "config.refine_normal_radius_gain");
    // The reserved field is no setting; a raw config holding anything but 0 there is rejected.
    let mut raw = *Config::default().as_raw();
    raw.reserved1 = 1;
    let err = Matcher::new(&Config::from_raw(raw)).unwrap_err();
    assert_eq!(err.kind(), ErrorKind::InvalidArgument);
    assert!(err.message().contains("reserved1"), "{err}");
    let mut raw = *Config::default().as_raw();
    raw.reserved2 = 1;
    let err = Matcher::new(&Config::from_raw(raw)).unwrap_err();
    assert_eq!(err.kind(), ErrorKind::InvalidArgument);
    assert!(err.message().contains("reserved2"), "{err}");
    // allow_degenerate is a bool here; a raw config can hold any i32, and only 0 and 1 are valid.
    for flag in [2, -1, i32::MAX] {
        let mut raw = *Config::default().as_raw();
        raw.allow_degenerate = flag;
        let config = Config::from_raw(raw);
        assert!(config.allow_degenerate(), "{flag} reads as true");
        let err = config.validate().unwrap_err();
        assert_eq!(err.kind(), ErrorKind::InvalidArgument, "{err}");
        assert!(err.message().contains("config.allow_degenerate"), "{err}");
        let err = Matcher::new(&config).unwrap_err();
        assert!(err.message().contains("config.allow_degenerate"), "{err}");
        let err = config.to_builder().build().unwrap_err();
        assert!(err.message().contains("config.allow_degenerate"), "{err}");
        // The builder's setter writes a valid value over it.
        assert_eq!(config.to_builder().allow_degenerate(false).build().unwrap().as_raw().allow_degenerate, 0);
    }
    // refine_mode cannot be out of range through the enum; a raw config can hold any code.
    for code in [3, -1] {
        let mut raw = *Config::default().as_raw();
        raw.refine_mode = code;
        let config = Config::from_raw(raw);
        assert_eq!(config.refine_mode(), RefineMode::None);
        let err = config.validate().unwrap_err();
        assert_eq!(err.kind(), ErrorKind::InvalidArgument, "{err}");
        assert!(err.message().contains("refine_mode"), "{err}");
        let err = Matcher::new(&config).unwrap_err();
        assert!(err.message().contains("refine_mode"), "{err}");
    }
    // An unvalidated raw config is checked again by Matcher::new.
    let mut raw = *Config::default().as_raw();
    raw.voxel_size = -1.0;
    let err = Matcher::new(&Config::from_raw(raw)).unwrap_err();
    assert_eq!(err.kind(), ErrorKind::InvalidArgument);
    assert!(err.message().contains("voxel_size"), "{err}");
    assert!(Matcher::with_voxel_size(-0.1).is_err());
    assert!(Matcher::with_voxel_size(0.0).is_ok()); // automatic
}

#[test]
fn error_kinds_map_every_code() {
    let codes = [
        (sys::KISSM_ERR_INVALID_ARGUMENT, ErrorKind::InvalidArgument),
        (sys::KISSM_ERR_NULL_ARGUMENT, ErrorKind::NullArgument),
        (sys::KISSM_ERR_EMPTY_INPUT, ErrorKind::EmptyInput),
        (sys::KISSM_ERR_TOO_FEW_POINTS, ErrorKind::TooFewPoints),
        (sys::KISSM_ERR_NONFINITE, ErrorKind::NonFinite),
        (sys::KISSM_ERR_VOXEL_RANGE, ErrorKind::VoxelRange),
        (sys::KISSM_ERR_STRUCT_SIZE, ErrorKind::StructSize),
        (sys::KISSM_ERR_OUT_OF_MEMORY, ErrorKind::OutOfMemory),
        (sys::KISSM_ERR_CANCELLED, ErrorKind::Cancelled),
        (sys::KISSM_ERR_FEATURES_MISMATCH, ErrorKind::FeaturesMismatch),
        (sys::KISSM_ERR_IO, ErrorKind::Io),
        (sys::KISSM_ERR_PARSE, ErrorKind::Parse),
        (sys::KISSM_ERR_UNSUPPORTED_FORMAT, ErrorKind::UnsupportedFormat),
        (sys::KISSM_ERR_INTERNAL, ErrorKind::Internal),
    ];
    let mut descriptions = std::collections::HashSet::new();
    for (code, kind) in codes {
        assert_eq!(ErrorKind::from_code(code), kind);
        assert!(descriptions.insert(kissm::status_string(code)), "distinct description for {code}");
    }
    assert_eq!(ErrorKind::from_code(-1000), ErrorKind::Unknown);
    assert_eq!(ErrorKind::from_code(0), ErrorKind::Unknown);
    assert_eq!(kissm::status_string(-1000), "unknown status");
}

#[test]
fn reasons_round_trip() {
    let mut descriptions = std::collections::HashSet::new();
    for code in 0..=13 {
        let reason = Reason::from_code(code);
        assert_eq!(reason.code(), code);
        assert!(!matches!(reason, Reason::Other(_)));
        assert!(!reason.as_str().is_empty());
        assert_ne!(reason.as_str(), "unknown reason");
        assert!(descriptions.insert(reason.as_str()), "distinct description for {code}");
    }
    assert_eq!(Reason::from_code(sys::KISSM_REASON_LOW_OVERLAP), Reason::LowOverlap);
    assert_eq!(Reason::from_code(sys::KISSM_REASON_UNCONSTRAINED), Reason::Unconstrained);
    assert_eq!(Reason::LowOverlap.code(), 7);
    assert_eq!(Reason::Unconstrained.code(), 8);
    assert_eq!(Reason::from_code(sys::KISSM_REASON_UNCERTAIN_ROTATION), Reason::UncertainRotation);
    assert_eq!(Reason::from_code(sys::KISSM_REASON_CLUSTERED_INLIERS), Reason::ClusteredInliers);
    assert_eq!(Reason::UncertainRotation.code(), 9);
    assert_eq!(Reason::ClusteredInliers.code(), 10);
    assert_eq!(Reason::from_code(sys::KISSM_REASON_NOT_CONVERGED), Reason::NotConverged);
    assert_eq!(Reason::NotConverged.code(), 11);
    assert_eq!(Reason::NotConverged.to_string(), "refinement did not converge");
    assert_eq!(Reason::from_code(sys::KISSM_REASON_TILTED), Reason::Tilted);
    assert_eq!(Reason::Tilted.code(), 12);
    assert_eq!(Reason::Tilted.to_string(), "the clouds' relative roll or pitch is not zero (rotation_dof = 1)");
    assert_eq!(Reason::from_code(sys::KISSM_REASON_LOOSE_ALIGNMENT), Reason::LooseAlignment);
    assert_eq!(Reason::LooseAlignment.code(), 13);
    assert_eq!(
        Reason::LooseAlignment.to_string(),
        "the refined clouds stay apart (a local optimum beside the right pose)"
    );
    assert_eq!(Reason::from_code(sys::KISSM_REASON_AMBIGUOUS), Reason::Ambiguous);
    assert_eq!(Reason::Ambiguous.code(), 14);
    assert_eq!(
        Reason::Ambiguous.to_string(),
        "a second, distinct pose has nearly as much support (a repetitive or symmetric scene)"
    );
    assert_eq!(Reason::from_code(sys::KISSM_REASON_LOOSE_AND_WEAK), Reason::LooseAndWeak);
    assert_eq!(Reason::LooseAndWeak.code(), 15);
    assert_eq!(
        Reason::LooseAndWeak.to_string(),
        "the refined clouds stay loosely apart and the pose can slide (a partial match of repeated structure)"
    );
    assert_eq!(Reason::from_code(16), Reason::Other(16));
    assert_eq!(Reason::from_code(0), Reason::None);
    assert_eq!(Reason::from_code(99), Reason::Other(99));
    assert_eq!(Reason::Other(99).code(), 99);
    assert_eq!(Reason::None.to_string(), "none");
}

#[test]
fn ground_defaults_are_the_library_ones() {
    let lib = library_defaults();
    for c in [Config::default(), Config::builder().build().unwrap()] {
        assert_eq!(c.suppression(), Suppression::None);
        assert_eq!(c.suppression().code(), lib.suppression);
        assert_eq!(c.rotation_dof(), lib.rotation_dof as usize);
        assert_eq!(c.rotation_dof(), 3);
        assert_eq!(c.up(), lib.up);
        assert_eq!(c.up(), [0.0, 0.0, 1.0]);
        assert_eq!(c.sensor_height().to_bits(), lib.sensor_height.to_bits());
        assert_eq!(c.sensor_height(), 0.0);
        let debug = format!("{c:?}");
        for field in ["suppression: None", "rotation_dof: 3", "up: [0.0, 0.0, 1.0]", "sensor_height: 0.0"] {
            assert!(debug.contains(field), "{debug}");
        }
    }
    assert_eq!(Suppression::default(), Suppression::None);
}

#[test]
fn suppressions_map_their_codes() {
    for (suppression, code) in
        [(Suppression::None, sys::KISSM_SUPPRESS_NONE), (Suppression::Ground, sys::KISSM_SUPPRESS_GROUND)]
    {
        assert_eq!(suppression.code(), code);
        assert_eq!(Suppression::from_code(code), Some(suppression));
        let c = Config::builder().suppression(suppression).build().unwrap();
        assert_eq!(c.suppression(), suppression);
        assert_eq!(c.as_raw().suppression, code);
    }
    assert_eq!(Suppression::from_code(2), None);
    assert_eq!(Suppression::from_code(-1), None);
}

#[test]
fn builder_sets_every_ground_field() {
    let c = Config::builder()
        .suppression(Suppression::Ground)
        .rotation_dof(1)
        .up([0.0, 0.5, 2.0])
        .sensor_height(1.73)
        .build()
        .unwrap();
    assert_eq!(c.suppression(), Suppression::Ground);
    assert_eq!(c.rotation_dof(), 1);
    assert_eq!(c.up(), [0.0, 0.5, 2.0]); // as given: the library normalises its own copy
    assert_eq!(c.sensor_height(), 1.73);
    let raw = c.as_raw();
    assert_eq!((raw.suppression, raw.rotation_dof, raw.up, raw.sensor_height), (1, 1, [0.0, 0.5, 2.0], 1.73));
    let debug = format!("{c:?}");
    for field in ["suppression: Ground", "rotation_dof: 1", "up: [0.0, 0.5, 2.0]", "sensor_height: 1.73"] {
        assert!(debug.contains(field), "{debug}");
    }
    // A matcher keeps them; every other field keeps the library's default.
    assert_eq!(format!("{:?}", Matcher::new(&c).unwrap().config()), debug);
    let back = c
        .to_builder()
        .suppression(Suppression::None)
        .rotation_dof(3)
        .up([0.0, 0.0, 1.0])
        .sensor_height(0.0)
        .build()
        .unwrap();
    assert_eq!(format!("{back:?}"), format!("{:?}", Config::default()));
    // The range ends are accepted.
    let ends = Config::builder().sensor_height(1000.0).up([1e-9, 1e-9, 0.0]).build().unwrap();
    assert_eq!((ends.sensor_height(), ends.up()), (1000.0, [1e-9, 1e-9, 0.0]));
    let ends = Config::builder().up([-1e300, 0.0, 0.0]).build().unwrap();
    assert_eq!(ends.up(), [-1e300, 0.0, 0.0]);
}

#[test]
fn invalid_ground_values_are_errors_not_panics() {
    let b = Config::builder;
    invalid(b().up([0.0, 0.0, 0.0]), "config.up");
    invalid(b().up([1e-10, 0.0, 0.0]), "config.up");
    invalid(b().up([f64::NAN, 0.0, 1.0]), "config.up[0]");
    invalid(b().up([0.0, 0.0, f64::INFINITY]), "config.up[2]");
    invalid(b().rotation_dof(2), "config.rotation_dof");
    invalid(b().rotation_dof(0), "config.rotation_dof");
    invalid(b().rotation_dof(6), "config.rotation_dof");
    invalid(b().rotation_dof(usize::MAX), "config.rotation_dof");
    invalid(b().sensor_height(-1.0), "config.sensor_height");
    invalid(b().sensor_height(1000.5), "config.sensor_height");
    invalid(b().sensor_height(f64::NAN), "config.sensor_height");
    invalid(b().sensor_height(f64::INFINITY), "config.sensor_height");
    // suppression cannot be out of range through the enum; a raw config can hold any code.
    for code in [7, 2, -1] {
        let mut raw = *Config::default().as_raw();
        raw.suppression = code;
        let config = Config::from_raw(raw);
        assert_eq!(config.suppression(), Suppression::None);
        let err = config.validate().unwrap_err();
        assert_eq!(err.kind(), ErrorKind::InvalidArgument, "{err}");
        assert_eq!(err.code(), sys::KISSM_ERR_INVALID_ARGUMENT);
        assert!(err.message().contains("config.suppression"), "{err}");
        let err = Matcher::new(&config).unwrap_err();
        assert!(err.message().contains("config.suppression"), "{err}");
        let err = config.to_builder().build().unwrap_err();
        assert!(err.message().contains("config.suppression"), "{err}");
    }
}

#[test]
fn presets_set_the_library_values() {
    let vehicle = Config::preset(Preset::LidarVehicle).build().unwrap();
    assert_eq!(vehicle.voxel_size(), 0.3);
    assert_eq!(vehicle.suppression(), Suppression::Ground);
    assert_eq!(vehicle.up(), [0.0, 0.0, 1.0]);
    assert_eq!(vehicle.viewpoint(), Viewpoint::Fixed([0.0; 3]));
    assert_eq!(vehicle.rotation_dof(), 3);
    let handheld = Config::preset(Preset::LidarHandheld).build().unwrap();
    assert_eq!((handheld.voxel_size(), handheld.suppression()), (0.3, Suppression::None));
    assert_eq!(handheld.viewpoint(), Viewpoint::Local);
    let rgbd = Config::preset(Preset::IndoorRgbd).build().unwrap();
    assert_eq!((rgbd.voxel_size(), rgbd.suppression(), rgbd.rotation_dof()), (0.05, Suppression::None, 3));
    let object = Config::preset(Preset::Object).build().unwrap();
    assert_eq!((object.voxel_size(), object.suppression(), object.rotation_dof()), (0.006, Suppression::None, 3));

    for (preset, code, name) in [
        (Preset::LidarVehicle, sys::KISSM_PRESET_LIDAR_VEHICLE, "lidar-vehicle"),
        (Preset::LidarHandheld, sys::KISSM_PRESET_LIDAR_HANDHELD, "lidar-handheld"),
        (Preset::IndoorRgbd, sys::KISSM_PRESET_INDOOR_RGBD, "indoor-rgbd"),
        (Preset::Object, sys::KISSM_PRESET_OBJECT, "object"),
    ] {
        assert_eq!(preset.code(), code);
        assert_eq!(Preset::from_code(code), Some(preset));
        assert_eq!((preset.name(), preset.to_string()), (name, name.to_string()));
        assert_eq!(Preset::from_name(name), Some(preset));
        // Exactly what kissm_config_preset writes on top of kissm_config_init's defaults.
        let mut lib = library_defaults();
        // SAFETY: lib is a complete kissm_config with struct_size set.
        assert_eq!(unsafe { sys::kissm_config_preset(&mut lib, code) }, sys::KISSM_OK);
        let config = Config::preset(preset).build().unwrap();
        assert_eq!(format!("{config:?}"), format!("{:?}", Config::from_raw(lib)), "{name}");
        // Config::preset is the builder step from the defaults; later setters win.
        let step = Config::builder().preset(preset).build().unwrap();
        assert_eq!(format!("{step:?}"), format!("{config:?}"));
        let changed = Config::preset(preset).voxel_size(0.7).num_threads(2).build().unwrap();
        assert_eq!((changed.voxel_size(), changed.num_threads()), (0.7, 2));
        assert_eq!(changed.suppression(), config.suppression());
    }
    assert_eq!(Preset::ALL.map(Preset::code), [1, 2, 3, 4]);
    assert_eq!(Preset::from_code(0), None);
    assert_eq!(Preset::from_code(5), None);
    assert_eq!(Preset::from_name("Lidar-Vehicle"), None);
    // On top of a builder's values: the preset's fields are overwritten, every other field kept.
    let on_top = Config::builder()
        .num_threads(3)
        .min_inliers(21)
        .voxel_size(2.0)
        .sensor_height(1.8)
        .suppression(Suppression::None)
        .preset(Preset::LidarVehicle)
        .build()
        .unwrap();
    assert_eq!((on_top.num_threads(), on_top.min_inliers(), on_top.sensor_height()), (3, 21, 1.8));
    assert_eq!((on_top.voxel_size(), on_top.suppression()), (0.3, Suppression::Ground));
    // A raw config's bad field is still reported after a preset that does not touch it.
    let err = Config::builder().min_inliers(2).preset(Preset::Object).build().unwrap_err();
    assert!(err.message().contains("min_inliers"), "{err}");
}

/// A street-like cloud in the sensor's frame: a flat ground plane at z = -1.7 (the sensor 1.7 above it at
/// the origin), a 161 x 161 grid 0.25 apart nudged within the plane, and four boxes of different sizes
/// standing on it, their surfaces sampled every 0.1. Returns the points and how many of the first are the
/// plane's.
fn ground_scene() -> (Vec<[f64; 3]>, usize) {
    const GROUND: f64 = -1.7;
    let mut points: Vec<[f64; 3]> = (0..161 * 161)
        .map(|i| {
            let (x, y) = ((i % 161) as f64, (i / 161) as f64);
            [-20.0 + 0.25 * x + 0.04 * (1.3 * y).sin(), -20.0 + 0.25 * y + 0.04 * (2.1 * x).cos(), GROUND]
        })
        .collect();
    let plane = points.len();
    // (centre x, centre y, size x, size y, height)
    for (cx, cy, sx, sy, h) in [
        (8.0, 5.0, 2.0, 3.0, 1.5),
        (-10.0, 4.0, 4.0, 1.6, 2.5),
        (4.0, -12.0, 1.2, 1.2, 3.0),
        (-7.0, -9.0, 3.0, 2.0, 1.0),
    ] {
        let steps = |len: f64| (len / 0.1).round() as usize;
        let (x0, y0, top) = (cx - sx / 2.0, cy - sy / 2.0, GROUND + h);
        for i in 0..=steps(sx) {
            for j in 0..=steps(sy) {
                points.push([x0 + 0.1 * i as f64, y0 + 0.1 * j as f64, top]);
            }
        }
        for k in 1..steps(h) {
            let z = GROUND + 0.1 * k as f64;
            for i in 0..=steps(sx) {
                let x = x0 + 0.1 * i as f64;
                points.push([x, y0, z]);
                points.push([x, y0 + sy, z]);
            }
            for j in 1..steps(sy) {
                let y = y0 + 0.1 * j as f64;
                points.push([x0, y, z]);
                points.push([x0 + sx, y, z]);
            }
        }
    }
    (points, plane)
}

#[test]
fn ground_mask_labels_the_plane_not_the_boxes() {
    let (points, plane) = ground_scene();
    let config = Config::preset(Preset::LidarVehicle).num_threads(1).build().unwrap();
    let mask = Matcher::new(&config).unwrap().ground_mask(&points).unwrap();
    assert_eq!(mask.len(), points.len());
    // The model covers 2.7 m and more from the sensor: most of the plane is ground.
    let ground = mask[..plane].iter().filter(|&&g| g).count();
    assert!(ground as f64 > 0.9 * plane as f64, "{ground} of {plane} plane points are ground");
    // No box point clear of the voxels that touch the plane is ground.
    let mut boxes_above = 0;
    for (p, &g) in points[plane..].iter().zip(&mask[plane..]) {
        if p[2] > -1.7 + 2.0 * config.voxel_size() {
            boxes_above += 1;
            assert!(!g, "box point {p:?} labelled ground");
        }
    }
    assert!(boxes_above > 1000, "{boxes_above}");
    let box_ground = mask[plane..].iter().filter(|&&g| g).count();
    assert!(box_ground * 10 < points.len() - plane, "{box_ground} of {} box points are ground", points.len() - plane);

    // The same mask for 2 threads, for float32 input, and whatever the matcher's suppression.
    let two = config.to_builder().num_threads(2).build().unwrap();
    assert_eq!(Matcher::new(&two).unwrap().ground_mask(&points).unwrap(), mask);
    let off = config.to_builder().suppression(Suppression::None).build().unwrap();
    assert_eq!(Matcher::new(&off).unwrap().ground_mask(&points).unwrap(), mask);
    // Without ground in the cloud: all false.
    let boxes = &points[plane..];
    let none = Matcher::new(&config).unwrap().ground_mask(boxes).unwrap();
    assert_eq!(none.len(), boxes.len());
    // A matcher whose up is sideways sees no horizontal ground in the plane.
    let sideways = config.to_builder().up([1.0, 0.0, 0.0]).build().unwrap();
    let side = Matcher::new(&sideways).unwrap().ground_mask(&points).unwrap();
    assert!(side[..plane].iter().filter(|&&g| g).count() < ground / 2);

    // Bad clouds fail as registration does, and the matcher stays usable.
    let mut m = Matcher::new(&config).unwrap();
    let err = m.ground_mask(&Vec::<[f64; 3]>::new()).unwrap_err();
    assert_eq!(err.kind(), ErrorKind::EmptyInput, "{err}");
    let err = m.ground_mask(&[[0.0f32; 3]; 3]).unwrap_err();
    assert_eq!(err.kind(), ErrorKind::TooFewPoints, "{err}");
    let mut bad = points.clone();
    bad[7][1] = f64::NAN;
    assert_eq!(m.ground_mask(&bad).unwrap_err().kind(), ErrorKind::NonFinite);
    let drop = config.to_builder().nonfinite_policy(NonFinitePolicy::Drop).build().unwrap();
    let dropped = Matcher::new(&drop).unwrap().ground_mask(&bad).unwrap();
    assert!(!dropped[7]);
    assert_eq!(m.ground_mask(&points).unwrap(), mask);
}

#[test]
fn ground_suppression_counts_suppressed_voxels() {
    let (points, _) = ground_scene();
    // The target: the scene seen from a sensor turned by 35 degrees about the vertical and moved along the
    // ground, so its ground is still 1.7 below the sensor.
    let turn = Pose::axis_angle([0.0, 0.0, 1.0], 35.0, [1.5, -0.8, 0.0]);
    let target = moved(&points, &turn);
    let config = Config::preset(Preset::LidarVehicle).num_threads(2).build().unwrap();
    let reg = Matcher::new(&config).unwrap().register(&points, &target).unwrap();
    assert!(reg.counts.source_suppressed > 0, "{:?}", reg.counts);
    assert!(reg.counts.target_suppressed > 0, "{:?}", reg.counts);
    assert!(reg.counts.source_suppressed + reg.counts.source_keypoints <= reg.counts.source_voxels);
    assert!(reg.timings.suppression_ms >= 0.0 && reg.timings.suppression_ms <= reg.timings.features_ms);
    assert!(reg.tilt.is_nan(), "tilt {} without rotation_dof 1", reg.tilt);
    // Without suppression: nothing suppressed, and more keypoints.
    let off = config.to_builder().suppression(Suppression::None).build().unwrap();
    let plain = Matcher::new(&off).unwrap().register(&points, &target).unwrap();
    assert_eq!((plain.counts.source_suppressed, plain.counts.target_suppressed), (0, 0));
    assert_eq!(plain.timings.suppression_ms, 0.0);
    assert!(plain.counts.source_keypoints > reg.counts.source_keypoints);
    // Deterministic: the same result with 1 thread.
    let one = config.to_builder().num_threads(1).build().unwrap();
    assert!(Matcher::new(&one).unwrap().register(&points, &target).unwrap().same_result(&reg));
}

#[test]
fn yaw_only_registration_turns_about_up_only() {
    let Some(pair) = scene("yaw_only_registration_turns_about_up_only") else { return };
    let truth = Pose::axis_angle([0.0, 0.0, 1.0], 70.0, [2.0, -1.0, 0.3]);
    let target = moved(&pair.source, &truth);
    let config = Config::builder().voxel_size(common::SCENE_VOXEL).num_threads(2).rotation_dof(1).build().unwrap();
    let reg = Matcher::new(&config).unwrap().register(&pair.source, &target).unwrap();
    assert!(reg.has_pose(), "{}", reg.reason);
    for i in 0..3 {
        let expected = if i == 2 { 1.0 } else { 0.0 };
        assert!((reg.rotation[2][i] - expected).abs() < 1e-9, "row 3: {:?}", reg.rotation);
        assert!((reg.rotation[i][2] - expected).abs() < 1e-9, "column 3: {:?}", reg.rotation);
    }
    assert!(reg.valid, "{} (tilt {})", reg.reason, reg.tilt);
    let (rot, trans) = truth.errors(&Pose::from_matrix(&reg.transform));
    assert!(rot < 1.0 && trans < 0.2, "rotation error {rot} deg, translation error {trans}");
    assert!(reg.tilt.is_finite() && reg.tilt >= 0.0 && reg.tilt <= config.max_rotation_uncertainty(), "{}", reg.tilt);
    // With 3 degrees of freedom there is no tilt.
    let free = config.to_builder().rotation_dof(3).build().unwrap();
    assert!(Matcher::new(&free).unwrap().register(&pair.source, &target).unwrap().tilt.is_nan());
    // A pair whose relative pitch is 5 degrees is not valid under rotation_dof 1: Reason::Tilted, with the
    // tilt as evidence; at 20 degrees it is not valid either, and the tilt measures the pitch.
    for (degrees, reason) in [(5.0, Some(Reason::Tilted)), (20.0, None)] {
        let tilted = Pose::axis_angle([1.0, 0.0, 0.0], degrees, [0.0; 3]).compose(&truth);
        let reg = Matcher::new(&config).unwrap().register(&pair.source, &moved(&pair.source, &tilted)).unwrap();
        assert!(!reg.valid, "a pair tilted by {degrees} degrees is valid under rotation_dof 1");
        if let Some(reason) = reason {
            assert_eq!(reg.reason, reason, "tilt {}", reg.tilt);
        }
        assert!(reg.tilt > config.max_rotation_uncertainty(), "{}", reg.tilt);
        assert!((reg.tilt.to_degrees() - degrees).abs() < 0.2 * degrees, "tilt {} deg", reg.tilt.to_degrees());
    }
}

fn line(n: usize) -> Vec<[f64; 3]> {
    (0..n).map(|i| [i as f64 * 0.1, (i % 7) as f64 * 0.13, (i % 3) as f64 * 0.2]).collect()
}

fn register_err(source: &dyn Fn() -> Vec<[f64; 3]>, config: &Config, good: &[[f64; 3]]) -> Error {
    let mut m = Matcher::new(config).unwrap();
    m.register(&source(), good).expect_err("the registration fails")
}

#[test]
fn registration_errors_carry_code_and_message() {
    let Some(scene) = common::scene("registration_errors_carry_code_and_message") else { return };
    let good = &scene.target;
    let config = Config::default();
    let empty = register_err(&Vec::new, &config, good);
    assert_eq!(empty.kind(), ErrorKind::EmptyInput, "{empty}");
    assert!(!empty.message().is_empty());

    let few = register_err(&|| line(3), &config, good);
    assert_eq!(few.kind(), ErrorKind::TooFewPoints, "{few}");
    assert_eq!(few.code(), sys::KISSM_ERR_TOO_FEW_POINTS);

    let nan = register_err(
        &|| {
            let mut p = line(100);
            p[42][1] = f64::NAN;
            p
        },
        &config,
        good,
    );
    assert_eq!(nan.kind(), ErrorKind::NonFinite, "{nan}");

    let all_nan = register_err(
        &|| vec![[f64::NAN; 3]; 50],
        &config.to_builder().nonfinite_policy(NonFinitePolicy::Drop).build().unwrap(),
        good,
    );
    assert_eq!(all_nan.kind(), ErrorKind::EmptyInput, "{all_nan}");

    let huge = register_err(
        &|| vec![[0.0, 0.0, 0.0], [1e4, 0.0, 0.0], [0.0, 1e4, 0.0], [0.0, 0.0, 1e4], [5.0, 5.0, 5.0]],
        &Config::builder().voxel_size(0.001).build().unwrap(),
        good,
    );
    assert_eq!(huge.kind(), ErrorKind::VoxelRange, "{huge}");

    // The error belongs to the failing call, and the next successful call is not affected.
    let mut m = Matcher::new(&config).unwrap();
    let pts = &scene.source;
    assert!(m.register(&line(2), pts).is_err());
    let ok = m.register(pts, pts).expect("a good call after a failed one");
    assert!(ok.counts.source_points > 0);
}

#[test]
fn nonfinite_points_are_dropped_and_counted() {
    let Some(scene) = common::scene("nonfinite_points_are_dropped_and_counted") else { return };
    let config = Config::builder().nonfinite_policy(NonFinitePolicy::Drop).build().unwrap();
    let mut m = Matcher::new(&config).unwrap();
    let mut source = scene.source.clone();
    source[3] = [f64::NAN, 0.0, 0.0];
    source[10] = [0.0, f64::INFINITY, 0.0];
    let mut target = scene.target.clone();
    target[0][2] = f64::NEG_INFINITY;
    let reg = m.register(&source, &target).unwrap();
    assert_eq!(reg.counts.source_nonfinite, 2);
    assert_eq!(reg.counts.target_nonfinite, 1);
    assert_eq!(reg.counts.source_points, source.len() as u64);
    assert!(reg.valid, "two dropped points do not spoil the scene: {}", reg.reason);
    // Under the default policy the same input is an error.
    let err = Matcher::new(&Config::default()).unwrap().register(&source, &scene.target).unwrap_err();
    assert_eq!(err.kind(), ErrorKind::NonFinite, "{err}");
    assert_eq!(err.code(), sys::KISSM_ERR_NONFINITE);
}

#[test]
fn degenerate_input_is_invalid_not_an_error() {
    // A flat, featureless plane: accepted, but no trustworthy pose.
    let plane = common::flat_plane();
    let mut m = Matcher::with_voxel_size(0.3).unwrap();
    let reg = m.register(&plane, &plane).expect("well-formed input is not an error");
    assert!(!reg.valid);
    assert_ne!(reg.reason, Reason::None);
}

#[test]
fn features_from_another_config_are_rejected() {
    let Some(scene) = common::scene("features_from_another_config_are_rejected") else { return };
    let cloud = &scene.source;
    let mut a = Matcher::with_voxel_size(0.3).unwrap();
    let mut b = Matcher::with_voxel_size(0.5).unwrap();
    let fa = a.compute_features(cloud).unwrap();
    let fb = b.compute_features(cloud).unwrap();
    assert_eq!(fa.num_points(), cloud.len() as u64);
    assert!(fa.num_keypoints() > 0 && fa.num_keypoints() <= fa.num_voxels());
    let err = a.register_features(&fa, &fb).unwrap_err();
    assert_eq!(err.kind(), ErrorKind::FeaturesMismatch, "{err}");
    assert!(!err.message().is_empty());
    // The refinement's planes are computed with the features: another refine_normal_radius_gain (at the same
    // voxel size) gives features this matcher cannot use, for a registration and a refinement alike.
    let gain = 0.5 * Config::default().refine_normal_radius_gain();
    let mut c =
        Matcher::new(&Config::builder().voxel_size(0.3).refine_normal_radius_gain(gain).build().unwrap()).unwrap();
    let fc = c.compute_features(cloud).unwrap();
    let err = a.register_features(&fa, &fc).unwrap_err();
    assert_eq!(err.kind(), ErrorKind::FeaturesMismatch, "{err}");
    assert_eq!(err.code(), sys::KISSM_ERR_FEATURES_MISMATCH);
    let identity = [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]];
    assert_eq!(a.refine_features(&fc, &fa, &identity).unwrap_err().kind(), ErrorKind::FeaturesMismatch);
    assert!(c.register_features(&fc, &fc).is_ok());
    let err = a.compute_features(&line(2)).unwrap_err();
    assert_eq!(err.kind(), ErrorKind::TooFewPoints);
}

#[test]
fn points_views() {
    let packed32: Vec<[f32; 3]> = vec![[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]];
    assert_eq!(packed32.as_points().len(), 2);
    assert_eq!(packed32.as_points().as_raw().scalar_type, sys::KISSM_SCALAR_FLOAT32);
    assert_eq!(packed32.as_points().as_raw().stride_bytes, 0);
    let arr = [[0.0f64; 3]; 5];
    assert_eq!(arr.as_points().len(), 5);
    assert_eq!(arr.as_points().as_raw().scalar_type, sys::KISSM_SCALAR_FLOAT64);
    assert!(Vec::<[f64; 3]>::new().as_points().is_empty());

    let xyzi = [0.0f32; 12];
    let v = PointsView::strided_f32(&xyzi, 4).unwrap();
    assert_eq!((v.len(), v.as_raw().stride_bytes), (3, 16));
    // Sliced from a column offset, the last row's padding is missing: still 3 points.
    assert_eq!(PointsView::strided_f32(&xyzi[1..], 4).unwrap().len(), 3);
    assert_eq!(PointsView::strided_f64(&[0.0; 7], 5).unwrap().len(), 1);
    assert_eq!(PointsView::strided_f64(&[0.0; 2], 3).unwrap().len(), 0);
    assert_eq!(PointsView::strided_f64(&[0.0; 9], 3).unwrap().len(), 3);
    assert_eq!(PointsView::strided_f32(&xyzi, usize::MAX).unwrap().len(), 1);
    let err = PointsView::strided_f32(&xyzi, 2).unwrap_err();
    assert_eq!(err.kind(), ErrorKind::InvalidArgument);
    assert!(err.message().contains("stride"));
    let view: PointsView = packed32.as_slice().into();
    assert_eq!(format!("{view:?}"), "PointsView { len: 2, scalar: \"f32\", stride_bytes: 0 }");
}

#[test]
fn read_points_formats_and_errors() {
    let dir = common::temp_dir("read");
    let xyz = dir.join("cloud.xyz");
    std::fs::write(&xyz, "0 0 0\n1.5 2 3\n-4 5.25 6\n").unwrap();
    let cloud = kissm::read_points(&xyz).unwrap();
    assert_eq!(cloud.len(), 3);
    assert_eq!(cloud.as_slice()[1], [1.5, 2.0, 3.0]);
    assert_eq!(cloud.to_vec()[2], [-4.0, 5.25, 6.0]);
    assert_eq!(cloud.as_points().len(), 3);

    // Raw float32 xyz needs the explicit format: by extension .bin is KITTI x y z intensity.
    let bin = dir.join("cloud.bin");
    let mut f = std::fs::File::create(&bin).unwrap();
    for v in [1.0f32, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0, 11.0, 12.0] {
        f.write_all(&v.to_le_bytes()).unwrap();
    }
    drop(f);
    let as_xyz = kissm::read_points_with_format(&bin, Format::BinXyz).unwrap();
    assert_eq!(as_xyz.len(), 4);
    assert_eq!(as_xyz.as_slice()[3], [10.0, 11.0, 12.0]);
    let as_kitti = kissm::read_points(&bin).unwrap();
    assert_eq!(as_kitti.len(), 3);
    assert_eq!(as_kitti.as_slice()[1], [5.0, 6.0, 7.0]);

    let missing = kissm::read_points(dir.join("missing.ply")).unwrap_err();
    assert_eq!(missing.kind(), ErrorKind::Io, "{missing}");
    assert!(missing.message().contains("missing.ply"), "{missing}");

    let bad_ply = dir.join("bad.ply");
    std::fs::write(&bad_ply, "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header\n1\n").unwrap();
    let parse = kissm::read_points(&bad_ply).unwrap_err();
    assert_eq!(parse.kind(), ErrorKind::Parse, "{parse}");

    let unknown = dir.join("cloud.unknown");
    std::fs::write(&unknown, "something that is no point file").unwrap();
    let unsupported = kissm::read_points(&unknown).unwrap_err();
    assert_eq!(unsupported.kind(), ErrorKind::UnsupportedFormat, "{unsupported}");

    // LAS 1.2, point format 0, scale 1, offset 0: three points, the middle one withheld (bit 7 of byte 15).
    let mut las = vec![0u8; 227];
    las[..4].copy_from_slice(b"LASF");
    las[24] = 1;
    las[25] = 2;
    las[94..96].copy_from_slice(&227u16.to_le_bytes());
    las[96..100].copy_from_slice(&227u32.to_le_bytes());
    las[105..107].copy_from_slice(&20u16.to_le_bytes());
    las[107..111].copy_from_slice(&3u32.to_le_bytes());
    for k in 0..3 {
        las[131 + 8 * k..139 + 8 * k].copy_from_slice(&1.0f64.to_le_bytes());
    }
    for i in 0..3i32 {
        let mut record = [0u8; 20];
        for k in 0..3 {
            record[4 * k..4 * k + 4].copy_from_slice(&(i * 10).to_le_bytes());
        }
        if i == 1 {
            record[15] = 0x80;
        }
        las.extend_from_slice(&record);
    }
    let las_path = dir.join("withheld.las");
    std::fs::write(&las_path, &las).unwrap();
    let las_cloud = kissm::read_points(&las_path).unwrap();
    assert_eq!(las_cloud.to_vec(), vec![[0.0, 0.0, 0.0], [20.0, 20.0, 20.0]]);
    assert_eq!(las_cloud.num_withheld(), 1);
    assert_eq!(cloud.num_withheld(), 0);
    // The library this crate builds has no LAZ support: a compressed format id is refused as such.
    las[104] = 0x80;
    std::fs::write(dir.join("c.laz"), &las).unwrap();
    let laz = kissm::read_points(dir.join("c.laz")).unwrap_err();
    assert_eq!(laz.kind(), ErrorKind::UnsupportedFormat, "{laz}");
    assert!(laz.message().contains("LAZ support was not built in"), "{laz}");

    let nul = kissm::read_points("bad\0name.ply").unwrap_err();
    assert_eq!(nul.kind(), ErrorKind::InvalidArgument);

    assert_eq!(Format::from_name("BIN_XYZ"), Some(Format::BinXyz));
    assert_eq!(Format::from_name("bin_xyz_f32"), Some(Format::BinXyz));
    assert_eq!(Format::from_name("kitti_bin_xyzi_f32"), Some(Format::KittiBin));
    assert_eq!(Format::from_name("npy_xyz"), Some(Format::Npy));
    assert_eq!(Format::from_name("ply").map(Format::code), Some(sys::KISSM_FORMAT_PLY));
    assert_eq!(Format::from_name("LAS"), Some(Format::Las));
    assert_eq!(Format::from_name("las").map(Format::code), Some(sys::KISSM_FORMAT_LAS));
    assert_eq!(Format::from_name("laz"), None);
    let _ = std::fs::remove_dir_all(&dir);
}

// Compile-time thread-safety contract: common::{assert_send, assert_sync, NotSync}.

#[test]
fn thread_safety_contract() {
    assert_send::<Matcher>();
    <Matcher as NotSync<_>>::check();
    assert_send::<Features>();
    assert_sync::<Features>();
    assert_send::<CancelHandle>();
    assert_sync::<CancelHandle>();
    assert_send::<Cloud>();
    assert_sync::<Cloud>();
    assert_send::<Config>();
    assert_sync::<Config>();
    assert_send::<Error>();
    assert_sync::<Error>();
    assert_send::<PointsView<'static>>();
    assert_sync::<PointsView<'static>>();
    assert_send::<Registration>();
    assert_sync::<Registration>();
    assert_send::<Refinement>();
    assert_sync::<Refinement>();
    assert_send::<Preset>();
    assert_sync::<Preset>();
    assert_send::<Suppression>();
    assert_sync::<Suppression>();
}

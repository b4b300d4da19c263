// SPDX-License-Identifier: MIT
//! The Rust declarations' struct layout equals the C ABI's committed layout (`tests/abi/layout.json`,
//! checked against the compiled header by the C suite; or the file `KISSM_ABI_LAYOUT` names) and the linked
//! library's `kissm_abi_sizeof`.

mod common;

use std::mem::{offset_of, size_of};
use std::path::PathBuf;

use common::{skip, Json};
use kissm::kissm_sys as sys;

fn field_offset(strukt: &str, field: &str) -> Option<usize> {
    macro_rules! fields {
        ($t:ty; $($f:ident),*) => {
            match field { $(stringify!($f) => Some(offset_of!($t, $f)),)* _ => None }
        };
    }
    match strukt {
        "kissm_config" => fields!(sys::kissm_config; struct_size, num_threads, voxel_size, normal_radius_gain,
            fpfh_radius_gain, max_linearity, ratio_test, prune_noise_bound_gain, solver_noise_bound_gain,
            noise_bound_max, viewpoint, min_normal_neighbors, max_correspondences, min_inliers, nonfinite_policy,
            viewpoint_mode, log_level, log_fn, log_user_data, progress_fn, progress_user_data, refine_mode,
            refine_max_iterations, refine_max_distance_gain, refine_kernel_gain, refine_rotation_epsilon,
            refine_translation_epsilon_gain, max_rotation_uncertainty, min_overlap, min_inlier_coverage,
            refine_min_inliers, reserved1, min_refine_condition, refine_normal_radius_gain, suppression, rotation_dof,
            up, sensor_height, max_refine_rmse_gain, allow_degenerate, reserved2, max_ambiguity),
        "kissm_points" => fields!(sys::kissm_points; data, count, stride_bytes, scalar_type, reserved),
        "kissm_result" => fields!(sys::kissm_result; struct_size, valid, reason, reserved0, transform, rotation,
            translation, num_source_points, num_target_points, num_source_nonfinite, num_target_nonfinite,
            num_source_voxels, num_target_voxels, num_source_keypoints, num_target_keypoints,
            num_initial_correspondences, num_pruned_correspondences, num_rotation_inliers, num_final_inliers,
            max_core_number, inlier_ratio, residual_rms, noise_bound, inlier_extent, time_voxelize_ms,
            time_features_ms, time_matching_ms, time_pruning_ms, time_solver_ms, time_total_ms, coarse_transform,
            information, overlap, refine_rmse, refine_condition, rotation_uncertainty, inlier_coverage,
            time_refine_ms, num_refine_correspondences, refine_iterations, refine_converged, num_source_suppressed,
            num_target_suppressed, time_suppression_ms, tilt, degenerate, num_weak_directions, weak_directions,
            ambiguity, confidence, voxel_size_used),
        _ => None,
    }
}

fn struct_size(strukt: &str) -> Option<usize> {
    match strukt {
        "kissm_config" => Some(size_of::<sys::kissm_config>()),
        "kissm_points" => Some(size_of::<sys::kissm_points>()),
        "kissm_result" => Some(size_of::<sys::kissm_result>()),
        _ => None,
    }
}

#[test]
fn layout_matches_c_abi() {
    // KISSM_ABI_LAYOUT names the file outside a source checkout (package_test.sh sets it).
    let path = match std::env::var_os("KISSM_ABI_LAYOUT") {
        Some(path) if !path.is_empty() => PathBuf::from(path),
        _ => PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../tests/abi/layout.json"),
    };
    let Ok(text) = std::fs::read_to_string(&path) else {
        let why = "tests/abi/layout.json not found (not a source checkout; set KISSM_ABI_LAYOUT)";
        assert!(!common::test_data_required(), "layout_matches_c_abi: {why}, and KISSM_REQUIRE_TEST_DATA=1");
        skip("layout_matches_c_abi", why);
        return;
    };
    if size_of::<usize>() != 8 {
        skip("layout_matches_c_abi", "layout.json describes 64-bit targets");
        return;
    }
    let layout = Json::parse(&text).expect("layout.json parses");
    for name in ["kissm_config", "kissm_points", "kissm_result"] {
        let s = layout.get("structs").get(name);
        let size = s.get("size").u64() as usize;
        assert_eq!(struct_size(name), Some(size), "{name}: size");
        // SAFETY: a plain query of the linked library.
        let lib_size = unsafe { sys::kissm_abi_sizeof(s.get("id").num() as i32) };
        assert_eq!(lib_size as usize, size, "{name}: kissm_abi_sizeof");
        let fields = s.get("fields").arr();
        assert!(!fields.is_empty());
        for f in fields {
            let field = f.get("name").str();
            assert_eq!(field_offset(name, field), Some(f.get("offset").u64() as usize), "{name}.{field}: offset");
        }
    }
}

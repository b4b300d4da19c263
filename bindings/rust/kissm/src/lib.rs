// SPDX-License-Identifier: MIT
//! Fast, robust, deterministic global 3D point cloud registration.
//!
//! `kissm` registers two point clouds that overlap in an unknown relative pose (no initial guess, large
//! rotations welcome) and returns the rigid transform that maps the source into the target frame,
//! whether that pose can be trusted, and every number behind that decision. This crate is the safe Rust
//! API over the kissm C library (through [`kissm_sys`]).
//!
//! # Example
//!
//! This is the example of the repository's README (`tests/readme.rs` fails when the two differ), run as a
//! doc test on the shared test scene: `source.ply` is `tests/data/roundtrip_source.ply` and `target.bin`
//! the target of that pair as raw float32 xyz (the hidden lines set them up in a temporary folder).
//!
//! ```
//! # // Setup: the committed pair of tests/data (or KISSM_TEST_DATA) as source.ply and target.bin.
//! # use std::path::PathBuf;
//! # let data = match std::env::var_os("KISSM_TEST_DATA") {
//! #     Some(dir) if !dir.is_empty() => PathBuf::from(dir),
//! #     _ => PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../tests/data"),
//! # };
//! # if !data.join("roundtrip_source.ply").is_file() {
//! #     let why = "SKIP README example: the test scene was not found (set KISSM_TEST_DATA)";
//! #     assert!(!matches!(std::env::var("KISSM_REQUIRE_TEST_DATA").as_deref(), Ok("1")), "{why}");
//! #     eprintln!("{why}");
//! #     return Ok(());
//! # }
//! # let work = std::env::temp_dir().join(format!("kissm-readme-example-{}", std::process::id()));
//! # std::fs::create_dir_all(&work)?;
//! # std::fs::copy(data.join("roundtrip_source.ply"), work.join("source.ply"))?;
//! # let target_xyz: Vec<u8> = kissm::read_points(data.join("roundtrip_target.ply"))?
//! #     .as_slice()
//! #     .iter()
//! #     .flat_map(|p| p.iter().flat_map(|&v| (v as f32).to_le_bytes()))
//! #     .collect();
//! # std::fs::write(work.join("target.bin"), target_xyz)?;
//! # std::env::set_current_dir(&work)?;
//! use kissm::{Config, Format, Matcher};
//!
//! let source = kissm::read_points("source.ply")?;
//! let target = kissm::read_points_with_format("target.bin", Format::BinXyz)?; // or &[[f32; 3]], &[[f64; 3]]
//! let mut matcher = Matcher::new(&Config::builder().voxel_size(0.3).num_threads(2).build()?)?;
//! let reg = matcher.register(&source, &target)?;        // Err(kissm::Error { code, message }) on bad input
//! if reg.valid {
//!     println!("{:?}", reg.transform);                  // [[f64; 4]; 4], maps source into target
//! } else {
//!     println!("no trustworthy pose: {}", reg.reason);
//! }
//! # // Checks: the pose is the ground truth's (rotation within 2 degrees, translation within 0.3).
//! # let truth: Vec<f64> = std::fs::read_to_string(data.join("roundtrip_ground_truth.txt"))?
//! #     .lines()
//! #     .filter(|l| !l.starts_with('#'))
//! #     .flat_map(str::split_whitespace)
//! #     .map(|v| v.parse::<f64>())
//! #     .collect::<Result<_, _>>()?;
//! # assert!(reg.valid, "{}", reg.reason);
//! # let trace: f64 = (0..3).flat_map(|i| (0..3).map(move |k| (i, k))).map(|(i, k)| truth[4 * k + i] * reg.transform[k][i]).sum();
//! # let angle = ((trace - 1.0) / 2.0).clamp(-1.0, 1.0).acos().to_degrees();
//! # let shift = (0..3).map(|i| (reg.transform[i][3] - truth[4 * i + 3]).powi(2)).sum::<f64>().sqrt();
//! # assert!(angle < 2.0 && shift < 0.3, "rotation error {angle} deg, translation error {shift}");
//! # std::env::set_current_dir(std::env::temp_dir())?;
//! # std::fs::remove_dir_all(&work)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! - **Input**: `&[[f32; 3]]`, `&[[f64; 3]]`, their `Vec`s, strided flat slices ([`PointsView`]) and
//!   files ([`read_points`]), without copies; anything implementing [`AsPoints`].
//! - **Refinement**: [`Config::refine_mode`] refines the global pose with GICP or point-to-plane ICP in
//!   the same call, and [`Matcher::refine`] refines a known pose; [`Registration::refinement`] then holds
//!   the overlap, residual, conditioning and 6 x 6 information matrix of the refined pose, the directions
//!   it leaves free ([`Registration::degenerate`], [`Registration::weak_directions`]: a corridor's slide),
//!   and how much of the overlap the solver's inliers cover.
//! - **LiDAR on vehicles**: [`Config::preset`] with [`Preset::LidarVehicle`] sets the voxel size and
//!   [`Suppression::Ground`] (ground voxels get no keypoint; [`Matcher::ground_mask`] shows them);
//!   [`ConfigBuilder::rotation_dof`] 1 estimates the yaw about [`Config::up`] only, and a clearly tilted
//!   pair is then not valid ([`Reason::Tilted`], [`Registration::tilt`]).
//! - **Results** are bitwise identical to the C library's (and the `kissm` tool's) on the same input,
//!   whatever the thread count and whether the matcher is fresh or reused.
//! - **Errors**: every failure is an [`Error`] with the C status code and the library's message naming
//!   the offending argument. A well-formed input that gives no trustworthy pose is not an error:
//!   [`Registration::valid`] is `false` and [`Registration::reason`] says why.
//! - **Threads**: a [`Matcher`] is `Send` (one thread at a time); [`Features`] are `Send + Sync` and can be
//!   shared by matchers on several threads; a [`CancelHandle`] stops a running call from any thread.
//! - **Pose graphs**: a [`PoseGraph`] joins many relative poses (registrations, odometry) into one consistent
//!   set of absolute poses, and rejects the wrong loop closures among its robust edges.
//! - **Multiway alignment**: [`Matcher::align_features`] places many scans in the first one's frame with no
//!   initial guess (the pairs of a [`Pairs`] policy registered from their [`Features`], then one pose graph);
//!   [`sequence_loops`] is its loop-candidate rule alone.
//! - **Portable features**: [`Features::to_bytes`] and [`Features::from_bytes`] move described clouds
//!   between processes and machines; registration from loaded features is bitwise the original's.
//! - Nothing here panics, and no Rust code is ever called back from C.
//!
//! # Refinement
//!
//! With [`Config::refine_mode`] the global pose is refined in the same call (GICP or point-to-plane ICP on
//! the voxelised clouds), and [`Matcher::refine`] refines a known pose without any global search
//! (tracking, re-localisation from a prior). [`Registration::refinement`] then holds what the refined pose
//! rests on; [`Registration::coarse_transform`] keeps the solver's (or the initial) pose. This example runs
//! as a doc test on the shared test scene (`source` and `target` are its clouds) and is the refinement
//! example of the READMEs (`tests/readme.rs`).
//!
//! ```
//! # // Setup: the committed pair of tests/data (or KISSM_TEST_DATA).
//! # use std::path::PathBuf;
//! # let data = match std::env::var_os("KISSM_TEST_DATA") {
//! #     Some(dir) if !dir.is_empty() => PathBuf::from(dir),
//! #     _ => PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../tests/data"),
//! # };
//! # if !data.join("roundtrip_source.ply").is_file() {
//! #     let why = "SKIP README refinement example: the test scene was not found (set KISSM_TEST_DATA)";
//! #     assert!(!matches!(std::env::var("KISSM_REQUIRE_TEST_DATA").as_deref(), Ok("1")), "{why}");
//! #     eprintln!("{why}");
//! #     return Ok(());
//! # }
//! # let source = kissm::read_points(data.join("roundtrip_source.ply"))?;
//! # let target = kissm::read_points(data.join("roundtrip_target.ply"))?;
//! # let next_scan = kissm::read_points(data.join("roundtrip_source.ply"))?;
//! use kissm::{Config, Matcher, RefineMode};
//!
//! let config = Config::builder().voxel_size(0.25).refine_mode(RefineMode::Gicp).build()?;
//! let mut matcher = Matcher::new(&config)?;
//! let reg = matcher.register(&source, &target)?;           // global pose, then GICP
//! if let (true, Some(fine)) = (reg.valid, reg.refinement) {
//!     println!("overlap {:.2}, rmse {:.3}", fine.overlap, fine.rmse);
//!     println!("{:?}", fine.information);                  // 6x6, rotation then translation (GTSAM)
//! }
//! let tracked = matcher.refine(&next_scan, &target, &reg.transform)?; // from a known pose
//! # // Checks: refined, valid, and refining the refined pose again stays put.
//! # let fine = reg.refinement.expect("refined");
//! # assert!(reg.valid && tracked.valid, "{} {}", reg.reason, tracked.reason);
//! # assert!(fine.overlap > 0.5 && fine.converged);
//! # let moved = (0..3).map(|i| (tracked.transform[i][3] - reg.transform[i][3]).abs()).fold(0.0, f64::max);
//! # assert!(moved < 0.01, "refining the refined pose moved it by {moved}");
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! # Pose graphs
//!
//! A [`PoseGraph`] turns many relative poses (registrations, odometry, loop closures) into one consistent
//! set of absolute poses in the frame of an anchor node. An edge from `source` to `target` holds the
//! transform that maps the source's points into the target's frame (a [`Registration::transform`]) and
//! the 6 x 6 information of its error ([`Refinement::information`]); robust edges (loop closures) may be
//! rejected by the optimisation, trusted ones (odometry) never are. This example is the pose graph
//! example of the crate's README (`tests/readme.rs`).
//!
//! ```
//! use kissm::PoseGraph;
//!
//! // Four scans around a 1 m square: each is 1 m ahead of the last and turned left by 90 degrees.
//! let step = [[0.0, -1.0, 0.0, 1.0], [1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]];
//! let identity = [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]];
//! let mut information = [[0.0; 6]; 6];                        // rotation then translation, as reg.refinement's
//! (0..6).for_each(|i| information[i][i] = 1e4);
//!
//! let mut graph = PoseGraph::new(4)?;
//! for i in 0..3 {
//!     graph.add_edge(i + 1, i, &step, &information, false)?; // odometry, trusted: maps scan i + 1 into scan i
//! }
//! graph.add_edge(0, 3, &step, &information, true)?;          // a right loop closure
//! graph.add_edge(2, 0, &identity, &information, true)?;      // a wrong one
//! let solution = graph.optimize(0, PoseGraph::DEFAULT_BOUND)?; // Err(kissm::Error) on bad input
//! assert_eq!(solution.accepted, [true, true, true, true, false]);
//! println!("{:?}", solution.poses[2]);                        // [[f64; 4]; 4] in scan 0's frame
//! # // Checks: scan 2 is at (1, 1, 0), turned by 180 degrees.
//! # let truth = [[-1.0, 0.0, 0.0, 1.0], [0.0, -1.0, 0.0, 1.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]];
//! # let error = solution.poses[2].iter().flatten().zip(truth.iter().flatten()).map(|(a, b)| (a - b).abs());
//! # assert!(error.fold(0.0, f64::max) < 1e-9, "{:?}", solution.poses[2]);
//! # assert!(solution.placed.iter().all(|&p| p));
//! # Ok::<(), kissm::Error>(())
//! ```
#![deny(missing_docs)]
#![warn(unsafe_op_in_unsafe_fn)]

#[macro_use]
mod codes; // first: its macro serves the modules below
mod align;
mod config;
mod error;
mod matcher;
mod points;
mod pose_graph;
mod registration;

use std::mem;
use std::sync::OnceLock;

pub use kissm_sys;
use kissm_sys as sys;

pub use align::{sequence_loops, AlignOptions, AlignedPair, Alignment, EdgeState, LoopPositions, Pairs};
#[allow(deprecated)] // the former name, kept as an alias
pub use config::NonfinitePolicy;
pub use config::{Config, ConfigBuilder, NonFinitePolicy, Preset, RefineMode, Suppression, Viewpoint};
pub use error::{status_string, Error, ErrorKind};
pub use matcher::{CancelHandle, Features, Matcher, SIGNATURE_SIZE};
pub use points::{read_points, read_points_with_format, suggest_voxel_size, AsPoints, Cloud, Format, PointsView};
pub use pose_graph::{PoseGraph, PoseGraphCancelHandle, PoseGraphSolution};
pub use registration::{Counts, Reason, Refinement, Registration, Timings};

/// Fewest points a cloud may have; smaller clouds fail with [`ErrorKind::TooFewPoints`].
pub const MIN_POINTS: usize = sys::KISSM_MIN_POINTS as usize;

/// The version of the linked C library, such as `"0.1.0"` (`kissm_version_string()`).
pub fn version() -> &'static str {
    // SAFETY: no preconditions; returns a static string.
    error::static_str(unsafe { sys::kissm_version_string() }, "unknown")
}

/// The version of the linked C library as `major * 10000 + minor * 100 + patch`.
pub fn version_number() -> u32 {
    // SAFETY: no preconditions.
    unsafe { sys::kissm_version_number() }
}

/// One-shot registration: creates a [`Matcher`] with `config`, registers `source` against `target` and
/// drops the matcher. Use a [`Matcher`] directly for several registrations.
///
/// ```no_run
/// let (source, target): (Vec<[f32; 3]>, Vec<[f32; 3]>) = (Vec::new(), Vec::new());
/// let config = kissm::Config::builder().voxel_size(0.3).build()?;
/// let reg = kissm::register(&config, &source, &target)?;
/// # Ok::<(), kissm::Error>(())
/// ```
pub fn register<S, T>(config: &Config, source: &S, target: &T) -> Result<Registration, Error>
where
    S: AsPoints + ?Sized,
    T: AsPoints + ?Sized,
{
    Matcher::new(config)?.register(source, target)
}

fn check_library_uncached() -> Result<(), Error> {
    // SAFETY: these calls have no preconditions.
    let (abi, points_size, config_size, result_size) = unsafe {
        (
            sys::kissm_abi_version(),
            sys::kissm_abi_sizeof(sys::KISSM_STRUCT_POINTS),
            sys::kissm_abi_sizeof(sys::KISSM_STRUCT_CONFIG),
            sys::kissm_abi_sizeof(sys::KISSM_STRUCT_RESULT),
        )
    };
    let mismatch = |what: String| {
        Err(Error::new(
            sys::KISSM_ERR_STRUCT_SIZE,
            format!(
                "the linked kissm library ({}) does not match the bindings (built from kissm.h {}): {}",
                version(),
                std::str::from_utf8(&sys::KISSM_VERSION_STRING[..sys::KISSM_VERSION_STRING.len() - 1]).unwrap_or("?"),
                what
            ),
        ))
    };
    if abi != sys::KISSM_ABI_VERSION as u32 {
        return mismatch(format!("ABI version {abi}, expected {}", sys::KISSM_ABI_VERSION));
    }
    // kissm_points has no struct_size: its layout must be the same. The other structs carry their size,
    // and the library accepts any published prefix, so they only need to be non-zero.
    if points_size as usize != mem::size_of::<sys::kissm_points>() {
        return mismatch(format!(
            "sizeof(kissm_points) {points_size}, expected {}",
            mem::size_of::<sys::kissm_points>()
        ));
    }
    if config_size == 0 || result_size == 0 {
        return mismatch("kissm_abi_sizeof does not know kissm_config or kissm_result".to_string());
    }
    Ok(())
}

/// Checks once per process that the linked C library matches the header these bindings were generated
/// from (ABI version and struct layouts). Called by every constructor of this crate, so a mismatched
/// installed library gives an [`ErrorKind::StructSize`] error instead of undefined behaviour.
pub fn check_library() -> Result<(), Error> {
    static CHECK: OnceLock<Result<(), Error>> = OnceLock::new();
    CHECK.get_or_init(check_library_uncached).clone()
}

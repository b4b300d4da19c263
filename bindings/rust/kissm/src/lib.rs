//! Fast, robust, deterministic global 3D point cloud registration.
//!
//! `kissm` registers two point clouds that overlap in an unknown relative pose (no initial guess, large
//! rotations welcome) and returns the rigid transform that maps the source into the target frame,
//! whether that pose can be trusted, and every number behind that decision. This crate is the safe Rust
//! API over the kissm C library (through [`kissm_sys`]).
//!
//! ```no_run
//! use kissm::{Config, Format, Matcher};
//!
//! let source = kissm::read_points("source.ply")?;
//! let target = kissm::read_points_with_format("target.bin", Format::BinXyz)?;
//!
//! let config = Config::builder().voxel_size(0.5).num_threads(2).build()?;
//! let mut matcher = Matcher::new(&config)?;
//! let reg = matcher.register(&source, &target)?;
//! if reg.valid {
//!     println!("p_target = R p_source + t: {:?}", reg.transform);
//! } else {
//!     println!("no trustworthy pose: {}", reg.reason);
//! }
//! # Ok::<(), kissm::Error>(())
//! ```
//!
//! - **Input**: `&[[f32; 3]]`, `&[[f64; 3]]`, their `Vec`s, strided flat slices ([`PointsView`]) and
//!   files ([`read_points`]), without copies; anything implementing [`AsPoints`].
//! - **Results** are bitwise identical to the C library's (and the `kissm` tool's) on the same input,
//!   whatever the thread count and whether the matcher is fresh or reused.
//! - **Errors**: every failure is an [`Error`] with the C status code and the library's message naming
//!   the offending argument. A well-formed input that gives no trustworthy pose is not an error:
//!   [`Registration::valid`] is `false` and [`Registration::reason`] says why.
//! - **Threads**: a [`Matcher`] is `Send` (one thread at a time); [`Features`] are `Send + Sync` and can be
//!   shared by matchers on several threads; a [`CancelHandle`] stops a running call from any thread.
//! - Nothing here panics, and no Rust code is ever called back from C.
#![deny(missing_docs)]
#![warn(unsafe_op_in_unsafe_fn)]

mod config;
mod error;
mod matcher;
mod points;
mod registration;

use std::mem;
use std::sync::OnceLock;

pub use kissm_sys;
use kissm_sys as sys;

#[allow(deprecated)] // the former name, kept as an alias
pub use config::NonfinitePolicy;
pub use config::{Config, ConfigBuilder, NonFinitePolicy, Viewpoint};
pub use error::{status_string, Error, ErrorKind};
pub use matcher::{CancelHandle, Features, Matcher};
pub use points::{read_points, read_points_with_format, AsPoints, Cloud, Format, PointsView};
pub use registration::{Counts, Reason, Registration, Timings};

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

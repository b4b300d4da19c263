// SPDX-License-Identifier: MIT
//! [`Config`] and its [`ConfigBuilder`].

use std::fmt;
use std::mem;

use kissm_sys as sys;

use crate::error::Error;

/// What a registration does with NaN or infinite coordinates.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum NonFinitePolicy {
    /// Such a point fails the call with [`ErrorKind::NonFinite`](crate::ErrorKind::NonFinite) (the default).
    #[default]
    Reject,
    /// Such points are skipped and counted in [`Counts::source_nonfinite`](crate::Counts::source_nonfinite)
    /// and [`Counts::target_nonfinite`](crate::Counts::target_nonfinite).
    Drop,
}

/// The former name of [`NonFinitePolicy`] ("non-finite" is spelt `NonFinite` in type names, as in
/// [`ErrorKind::NonFinite`](crate::ErrorKind::NonFinite)).
#[deprecated(since = "0.1.0", note = "renamed to `NonFinitePolicy`")]
pub type NonfinitePolicy = NonFinitePolicy;

/// The fine registration that refines a pose on the voxelised clouds (`kissm_config.refine_mode`): after
/// the global solver in [`Matcher::register`](crate::Matcher::register), and the cost that
/// [`Matcher::refine`](crate::Matcher::refine) minimises.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum RefineMode {
    /// No refinement: [`Matcher::register`](crate::Matcher::register) returns the solver's pose as it is
    /// (the default). [`Matcher::refine`](crate::Matcher::refine) uses [`RefineMode::Gicp`] then.
    #[default]
    None,
    /// Generalized ICP (plane-to-plane).
    Gicp,
    /// Point-to-plane ICP.
    PointToPlane,
}

c_codes!(RefineMode, "KISSM_REFINE_", "mode" {
    None => sys::KISSM_REFINE_NONE,
    Gicp => sys::KISSM_REFINE_GICP,
    PointToPlane => sys::KISSM_REFINE_POINT_TO_PLANE,
});

/// Where surface normals are oriented toward.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum Viewpoint {
    /// A fixed sensor position, in each cloud's own input frame (single scans in their sensor frame, when the
    /// sensor position is known).
    Fixed([f64; 3]),
    /// Each cloud's bounding-box centre.
    CloudCenter,
    /// No viewpoint: descriptors that do not depend on the normals' signs, so on no cloud's frame
    /// (`docs/design/frames.md`).
    SignFree,
    /// No viewpoint (the default): each normal turned away from the centroid of its neighbours, a rule of the
    /// local shape alone, its sign ignored where that centroid is too close to the surface to say, so features
    /// depend on no cloud's frame (`docs/design/frames.md`).
    #[default]
    Local,
}

/// Geometric suppression before keypoints (`kissm_config.suppression`): voxels it picks get no descriptor, so
/// they cannot flood the matching with look-alike correspondences. They stay in the clouds refinement
/// aligns.
///
/// It is computed with the features, so [`Features`](crate::Features) of a matcher with another value do not
/// match this one's ([`ErrorKind::FeaturesMismatch`](crate::ErrorKind::FeaturesMismatch)).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum Suppression {
    /// Every voxel may become a keypoint (the default).
    #[default]
    None,
    /// Ground voxels get no keypoint: a region-wise ground model around the sensor (the
    /// [`Viewpoint::Fixed`] position), perpendicular to [`Config::up`], with the sensor
    /// [`Config::sensor_height`] above the ground. [`Matcher::ground_mask`](crate::Matcher::ground_mask)
    /// shows what it labels ground. For scans of a LiDAR on a vehicle, in the sensor's frame.
    Ground,
}

c_codes!(Suppression, "KISSM_SUPPRESS_", "suppression" {
    None => sys::KISSM_SUPPRESS_NONE,
    Ground => sys::KISSM_SUPPRESS_GROUND,
});

/// The settings for a common kind of data (`kissm_config_preset`, `docs/parameters.md`, "Presets"): the
/// voxel size and the options that kind wants; every other field keeps its value.
///
/// [`Config::preset`] starts a builder from the library's defaults with a preset applied (as Python's
/// `Config.preset(name)` does); [`ConfigBuilder::preset`] applies one on top of a builder's current values
/// (as the C function does), so call it before your own changes:
///
/// ```
/// use kissm::{Config, Preset, Suppression};
/// let config = Config::preset(Preset::LidarVehicle).num_threads(2).build()?;
/// assert_eq!((config.voxel_size(), config.suppression()), (0.3, Suppression::Ground));
/// // The same as a builder step.
/// let same = Config::builder().preset(Preset::LidarVehicle).num_threads(2).build()?;
/// assert_eq!(format!("{config:?}"), format!("{same:?}"));
/// # Ok::<(), kissm::Error>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Preset {
    /// `"lidar-vehicle"`: outdoor LiDAR on a car or ground robot, scans in the sensor frame: 0.3 m voxels,
    /// ground suppression ([`Suppression::Ground`], up +z, a fixed viewpoint).
    LidarVehicle,
    /// `"lidar-handheld"`: handheld, backpack or drone LiDAR (no ground assumption, any orientation): 0.3 m
    /// voxels, frame-free normals ([`Viewpoint::Local`]), no suppression, 3 rotational degrees of freedom.
    LidarHandheld,
    /// `"indoor-rgbd"`: indoor RGB-D fragments (rooms, metres across): 0.05 m voxels, no suppression, 3
    /// rotational degrees of freedom.
    IndoorRgbd,
    /// `"object"`: objects on a turntable or scanned by hand (decimetres across): 0.006 m voxels, no
    /// suppression, 3 rotational degrees of freedom.
    Object,
}

c_codes!(Preset, "KISSM_PRESET_", "preset" {
    LidarVehicle => sys::KISSM_PRESET_LIDAR_VEHICLE,
    LidarHandheld => sys::KISSM_PRESET_LIDAR_HANDHELD,
    IndoorRgbd => sys::KISSM_PRESET_INDOOR_RGBD,
    Object => sys::KISSM_PRESET_OBJECT,
});

impl Preset {
    /// Every preset, in the order of their codes.
    pub const ALL: [Preset; 4] = [Preset::LidarVehicle, Preset::LidarHandheld, Preset::IndoorRgbd, Preset::Object];

    /// The name the Python binding and the documentation use, such as `"lidar-vehicle"`.
    pub fn name(self) -> &'static str {
        match self {
            Preset::LidarVehicle => "lidar-vehicle",
            Preset::LidarHandheld => "lidar-handheld",
            Preset::IndoorRgbd => "indoor-rgbd",
            Preset::Object => "object",
        }
    }

    /// The preset of a [`name`](Preset::name) (`None` for any other text).
    pub fn from_name(name: &str) -> Option<Preset> {
        Preset::ALL.into_iter().find(|p| p.name() == name)
    }
}

impl fmt::Display for Preset {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A validated registration configuration.
///
/// Built with [`Config::builder`], whose defaults are the C library's (`kissm_config_init`; each builder
/// method states its range and default, checked against `docs/parameters.md`, "Ranges"). Every length
/// scales with the voxel size, so it is usually the only value to set; [`Config::preset`] sets it and the
/// options a common kind of data wants.
///
/// ```
/// let config = kissm::Config::builder().voxel_size(0.5).num_threads(2).build()?;
/// assert_eq!(config.voxel_size(), 0.5);
/// assert_eq!(config.min_inliers(), 15);
/// # Ok::<(), kissm::Error>(())
/// ```
#[derive(Clone)]
pub struct Config {
    raw: sys::kissm_config,
}

// SAFETY: the only pointers in the raw config are the log and progress callbacks and their user data,
// which this crate always leaves NULL; everything else is plain data.
unsafe impl Send for Config {}
// SAFETY: as above; a shared Config is never mutated.
unsafe impl Sync for Config {}

/// The documented defaults, as written by `kissm_config_init`. On the impossible failure of that call (it
/// only rejects a struct size below the first published layout) the config is left zeroed, which every
/// later validation rejects with a proper error: this never panics.
fn raw_defaults() -> (sys::kissm_config, i32) {
    let mut raw = sys::kissm_config::default();
    let size = mem::size_of::<sys::kissm_config>() as u32;
    // SAFETY: raw is a valid, writable kissm_config of exactly `size` bytes.
    let status = unsafe { sys::kissm_config_init(&mut raw, size) };
    if status != sys::KISSM_OK {
        raw = sys::kissm_config::default();
        raw.struct_size = size;
    }
    (raw, status)
}

/// `Config`'s read accessors that return one field of the raw struct: `f64` and `vec3` as stored, `count` (an `i32`
/// in C) as a `usize`, negative as 0, `bool` (an `i32` flag in C) as whether it is not 0.
macro_rules! config_getters {
    ($($(#[$doc:meta])* $name:ident: $kind:ident,)*) => { $(config_getter!($(#[$doc])* $name $kind);)* };
}
macro_rules! config_getter {
    ($(#[$doc:meta])* $name:ident f64) => {
        $(#[$doc])*
        pub fn $name(&self) -> f64 {
            self.raw.$name
        }
    };
    ($(#[$doc:meta])* $name:ident vec3) => {
        $(#[$doc])*
        pub fn $name(&self) -> [f64; 3] {
            self.raw.$name
        }
    };
    ($(#[$doc:meta])* $name:ident count) => {
        $(#[$doc])*
        pub fn $name(&self) -> usize {
            usize::try_from(self.raw.$name).unwrap_or(0)
        }
    };
    ($(#[$doc:meta])* $name:ident bool) => {
        $(#[$doc])*
        pub fn $name(&self) -> bool {
            self.raw.$name != 0
        }
    };
}

/// `ConfigBuilder`'s setters that store their argument in one field of the raw struct: `f64` and `vec3` as given,
/// `count` as an `i32` (saturated; `build` then names the field out of range), `bool` as the `i32` 1 or 0.
macro_rules! builder_setters {
    ($($(#[$doc:meta])* $name:ident: $kind:ident,)*) => { $(builder_setter!($(#[$doc])* $name $kind);)* };
}
macro_rules! builder_setter {
    ($(#[$doc:meta])* $name:ident f64) => {
        $(#[$doc])*
        pub fn $name(mut self, value: f64) -> Self {
            self.raw.$name = value;
            self
        }
    };
    ($(#[$doc:meta])* $name:ident vec3) => {
        $(#[$doc])*
        pub fn $name(mut self, value: [f64; 3]) -> Self {
            self.raw.$name = value;
            self
        }
    };
    ($(#[$doc:meta])* $name:ident count) => {
        $(#[$doc])*
        pub fn $name(mut self, value: usize) -> Self {
            self.raw.$name = to_i32(value);
            self
        }
    };
    ($(#[$doc:meta])* $name:ident bool) => {
        $(#[$doc])*
        pub fn $name(mut self, value: bool) -> Self {
            self.raw.$name = i32::from(value);
            self
        }
    };
}

fn to_i32(value: usize) -> i32 {
    // Out-of-range values become i32::MAX, which the library's validation rejects with a message naming
    // the field.
    i32::try_from(value).unwrap_or(i32::MAX)
}

impl Config {
    /// A builder starting from the library's defaults.
    pub fn builder() -> ConfigBuilder {
        ConfigBuilder::new()
    }

    /// A builder starting from the library's defaults with `preset` applied (`kissm_config_preset`): the
    /// voxel size and options of a common kind of data, which the builder's setters may then change. The
    /// same as `Config::builder().preset(preset)`; see [`Preset`].
    ///
    /// ```
    /// use kissm::{Config, Preset};
    /// let config = Config::preset(Preset::IndoorRgbd).min_inliers(20).build()?;
    /// assert_eq!((config.voxel_size(), config.min_inliers()), (0.05, 20));
    /// # Ok::<(), kissm::Error>(())
    /// ```
    pub fn preset(preset: Preset) -> ConfigBuilder {
        ConfigBuilder::new().preset(preset)
    }

    /// A builder starting from this configuration.
    pub fn to_builder(&self) -> ConfigBuilder {
        ConfigBuilder { raw: self.raw, pending: None }
    }

    /// Checks every field with `kissm_config_validate` (the same checks as creating a matcher).
    pub fn validate(&self) -> Result<(), Error> {
        // SAFETY: self.raw is a complete kissm_config with struct_size set.
        Error::check(unsafe { sys::kissm_config_validate(&self.raw) })
    }

    /// Wraps a raw config as it is (not validated: [`Matcher::new`](crate::Matcher::new) validates).
    /// The callbacks and their user data are cleared, as this crate never calls back into Rust.
    pub fn from_raw(mut raw: sys::kissm_config) -> Config {
        raw.log_fn = None;
        raw.log_user_data = std::ptr::null_mut();
        raw.progress_fn = None;
        raw.progress_user_data = std::ptr::null_mut();
        Config { raw }
    }

    /// The raw C struct, for use with `kissm-sys`.
    pub fn as_raw(&self) -> &sys::kissm_config {
        &self.raw
    }

    config_getters! {
        /// Worker threads per call; 0 = all hardware threads. Results do not depend on it.
        num_threads: count,
        /// Voxel size in the clouds' unit (metres for LiDAR); every radius and bound scales with it. 0 when it is
        /// automatic ([`ConfigBuilder::voxel_size_auto`]).
        voxel_size: f64,
        /// Normal estimation radius, in voxel sizes.
        normal_radius_gain: f64,
        /// FPFH descriptor radius, in voxel sizes.
        fpfh_radius_gain: f64,
        /// Linearity `(l1 - l2) / l1` above which a point gets no normal.
        max_linearity: f64,
        /// Lowe ratio on squared descriptor distances; 1 = off.
        ratio_test: f64,
        /// Correspondence-graph edge tolerance, in voxel sizes.
        prune_noise_bound_gain: f64,
        /// Solver inlier bound, in voxel sizes.
        solver_noise_bound_gain: f64,
        /// Cap on both noise bounds in the clouds' unit; 0 = no cap.
        noise_bound_max: f64,
    }
    /// Where normals are oriented toward.
    pub fn viewpoint(&self) -> Viewpoint {
        match self.raw.viewpoint_mode {
            sys::KISSM_VIEWPOINT_CLOUD_CENTER => Viewpoint::CloudCenter,
            sys::KISSM_VIEWPOINT_SIGN_FREE => Viewpoint::SignFree,
            sys::KISSM_VIEWPOINT_LOCAL => Viewpoint::Local,
            _ => Viewpoint::Fixed(self.raw.viewpoint),
        }
    }
    config_getters! {
        /// Neighbours needed for a normal and a descriptor.
        min_normal_neighbors: count,
        /// Cap on the mutual matches kept, best ratio first; 0: automatic (grows with the keypoints).
        max_correspondences: count,
        /// Final inliers needed for a valid pose without refinement
        /// ([`refine_min_inliers`](Config::refine_min_inliers) with it).
        min_inliers: count,
    }
    /// What happens to NaN and infinite coordinates.
    pub fn nonfinite_policy(&self) -> NonFinitePolicy {
        if self.raw.nonfinite_policy == sys::KISSM_NONFINITE_DROP {
            NonFinitePolicy::Drop
        } else {
            NonFinitePolicy::Reject
        }
    }
    /// The fine registration after the solver, and the cost of [`Matcher::refine`](crate::Matcher::refine).
    /// A raw config (see [`Config::from_raw`]) holding no `KISSM_REFINE_*` code reads as [`RefineMode::None`]
    /// here; creating a matcher from it fails.
    pub fn refine_mode(&self) -> RefineMode {
        RefineMode::from_code(self.raw.refine_mode).unwrap_or_default()
    }
    config_getters! {
        /// Refinement iteration cap.
        refine_max_iterations: count,
        /// Refinement's correspondence distance (and that of [`Refinement::overlap`](crate::Refinement::overlap)),
        /// in voxel sizes.
        refine_max_distance_gain: f64,
        /// Scale of refinement's Cauchy kernel, in voxel sizes.
        refine_kernel_gain: f64,
        /// Refinement has converged when a step turns the pose by less than this (radians) and moves it by less
        /// than [`refine_translation_epsilon_gain`](Config::refine_translation_epsilon_gain) voxel sizes.
        refine_rotation_epsilon: f64,
        /// Refinement's convergence threshold on translation steps, in voxel sizes.
        refine_translation_epsilon_gain: f64,
        /// Without refinement, a valid pose needs
        /// [`Registration::rotation_uncertainty`](crate::Registration::rotation_uncertainty) at most this
        /// (radians); with refinement, 2 times the rotation sigma its information states.
        max_rotation_uncertainty: f64,
        /// With refinement, a valid pose needs [`Refinement::overlap`](crate::Refinement::overlap) at least this.
        min_overlap: f64,
        /// With refinement, a valid registration needs
        /// [`Refinement::inlier_coverage`](crate::Refinement::inlier_coverage) at least this.
        min_inlier_coverage: f64,
        /// With refinement, final inliers a valid registration needs ([`min_inliers`](Config::min_inliers)
        /// applies without refinement).
        refine_min_inliers: count,
        /// With refinement (and in [`Matcher::refine`](crate::Matcher::refine)), a valid pose needs
        /// [`Refinement::condition`](crate::Refinement::condition) at least this.
        min_refine_condition: f64,
        /// Refinement aligns planes fitted to the neighbours within this many voxel sizes (at most
        /// [`normal_radius_gain`](Config::normal_radius_gain)); computed with the features.
        refine_normal_radius_gain: f64,
    }
    /// Geometric suppression before keypoints; computed with the features. A raw config (see
    /// [`Config::from_raw`]) holding no `KISSM_SUPPRESS_*` code reads as [`Suppression::None`] here;
    /// creating a matcher from it fails.
    pub fn suppression(&self) -> Suppression {
        Suppression::from_code(self.raw.suppression).unwrap_or_default()
    }
    config_getters! {
        /// Rotational degrees of freedom the solver estimates: 3, or 1 (yaw about [`up`](Config::up) only).
        rotation_dof: count,
        /// The up direction in each cloud's own frame, as given (the library normalises it), for
        /// [`Suppression::Ground`] and [`rotation_dof`](Config::rotation_dof) 1.
        up: vec3,
        /// Height of the sensor above the ground along [`up`](Config::up), metres, for
        /// [`Suppression::Ground`]; 0 = estimate it from the cloud.
        sensor_height: f64,
        /// With refinement (and in [`Matcher::refine`](crate::Matcher::refine)), a valid pose needs
        /// [`Refinement::rmse`](crate::Refinement::rmse) at most this many voxel sizes.
        max_refine_rmse_gain: f64,
        /// Whether a refined pose that leaves directions free
        /// ([`Refinement::degenerate`](crate::Refinement::degenerate): a corridor, a tunnel, a plane) may be
        /// valid, flagged, instead of not valid with [`Reason::Unconstrained`](crate::Reason::Unconstrained).
        /// A raw config (see [`Config::from_raw`]) holding anything but 0 reads as `true` here; creating a
        /// matcher from one holding neither 0 nor 1 fails.
        allow_degenerate: bool,
        /// A valid pose needs [`Registration::ambiguity`](crate::Registration::ambiguity) at most this.
        max_ambiguity: f64,
    }
}

impl Default for Config {
    /// The library's defaults (see [`Config`]).
    fn default() -> Self {
        Config { raw: raw_defaults().0 }
    }
}

impl fmt::Debug for Config {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Config")
            .field("num_threads", &self.raw.num_threads)
            .field("voxel_size", &self.raw.voxel_size)
            .field("normal_radius_gain", &self.raw.normal_radius_gain)
            .field("fpfh_radius_gain", &self.raw.fpfh_radius_gain)
            .field("max_linearity", &self.raw.max_linearity)
            .field("ratio_test", &self.raw.ratio_test)
            .field("prune_noise_bound_gain", &self.raw.prune_noise_bound_gain)
            .field("solver_noise_bound_gain", &self.raw.solver_noise_bound_gain)
            .field("noise_bound_max", &self.raw.noise_bound_max)
            .field("viewpoint", &self.viewpoint())
            .field("min_normal_neighbors", &self.raw.min_normal_neighbors)
            .field("max_correspondences", &self.raw.max_correspondences)
            .field("min_inliers", &self.raw.min_inliers)
            .field("nonfinite_policy", &self.nonfinite_policy())
            .field("refine_mode", &self.refine_mode())
            .field("refine_max_iterations", &self.raw.refine_max_iterations)
            .field("refine_max_distance_gain", &self.raw.refine_max_distance_gain)
            .field("refine_kernel_gain", &self.raw.refine_kernel_gain)
            .field("refine_rotation_epsilon", &self.raw.refine_rotation_epsilon)
            .field("refine_translation_epsilon_gain", &self.raw.refine_translation_epsilon_gain)
            .field("max_rotation_uncertainty", &self.raw.max_rotation_uncertainty)
            .field("min_overlap", &self.raw.min_overlap)
            .field("min_inlier_coverage", &self.raw.min_inlier_coverage)
            .field("refine_min_inliers", &self.raw.refine_min_inliers)
            .field("min_refine_condition", &self.raw.min_refine_condition)
            .field("refine_normal_radius_gain", &self.raw.refine_normal_radius_gain)
            .field("suppression", &self.suppression())
            .field("rotation_dof", &self.raw.rotation_dof)
            .field("up", &self.raw.up)
            .field("sensor_height", &self.raw.sensor_height)
            .field("max_refine_rmse_gain", &self.raw.max_refine_rmse_gain)
            .field("allow_degenerate", &self.allow_degenerate())
            .field("max_ambiguity", &self.raw.max_ambiguity)
            .finish()
    }
}

/// Builds a [`Config`]; [`build`](ConfigBuilder::build) validates every field with the C library and
/// returns an [`Error`] naming the first invalid one. Setters never fail or panic.
///
/// ```
/// use kissm::{Config, ErrorKind, NonFinitePolicy, Viewpoint};
/// let config = Config::builder()
///     .voxel_size(0.05)
///     .viewpoint(Viewpoint::CloudCenter)
///     .nonfinite_policy(NonFinitePolicy::Drop)
///     .min_inliers(20)
///     .build()?;
/// assert_eq!(config.min_inliers(), 20);
///
/// let err = Config::builder().num_threads(1_000_000).build().unwrap_err();
/// assert_eq!(err.kind(), ErrorKind::InvalidArgument);
/// # Ok::<(), kissm::Error>(())
/// ```
#[derive(Clone, Debug)]
pub struct ConfigBuilder {
    raw: sys::kissm_config,
    /// An error met by a step that calls the library (`kissm_config_init`, `kissm_config_preset`; neither
    /// can fail on this crate's layout and enums), reported by [`build`](ConfigBuilder::build).
    pending: Option<Error>,
}

impl Default for ConfigBuilder {
    fn default() -> Self {
        ConfigBuilder::new()
    }
}

impl ConfigBuilder {
    /// A builder holding the library's defaults.
    pub fn new() -> ConfigBuilder {
        let (raw, init_status) = raw_defaults();
        let pending = (init_status != sys::KISSM_OK).then(|| {
            Error::new(
                init_status,
                "kissm_config_init rejected this crate's kissm_config layout (library and bindings disagree)",
            )
        });
        ConfigBuilder { raw, pending }
    }

    /// Applies `preset` on top of the current values (`kissm_config_preset`): the voxel size and the options
    /// of a common kind of data; every other field keeps its value. Call it before your own changes, which
    /// it would otherwise overwrite. See [`Preset`] and [`Config::preset`].
    pub fn preset(mut self, preset: Preset) -> Self {
        let mut raw = self.raw;
        // SAFETY: raw is a complete kissm_config with struct_size set (by kissm_config_init, or the size of
        // this crate's struct when that failed); the library writes at most struct_size bytes.
        let status = unsafe { sys::kissm_config_preset(&mut raw, preset.code()) };
        if status == sys::KISSM_OK {
            self.raw = raw;
        } else if self.pending.is_none() {
            self.pending = Some(Error::last(status));
        }
        self
    }

    /// An automatic voxel size: each call describes its clouds with the voxel
    /// [`suggest_voxel_size`](crate::suggest_voxel_size) gives for them together (reported in
    /// [`Registration::voxel_size_used`](crate::Registration::voxel_size_used)); features computed apart get their
    /// own cloud's. The C value 0 of `kissm_config.voxel_size`.
    pub fn voxel_size_auto(mut self) -> Self {
        self.raw.voxel_size = 0.0;
        self
    }

    builder_setters! {
        /// Worker threads, 0..=1024; 0 (the default) = all hardware threads. Results do not depend on it.
        num_threads: count,
        /// Voxel size in the clouds' unit, > 0 (default 0.3), or 0 for automatic
        /// ([`voxel_size_auto`](ConfigBuilder::voxel_size_auto)). Try 0.3-0.5 for outdoor LiDAR in metres, 0.05
        /// for indoor RGB-D fragments.
        voxel_size: f64,
        /// Normal radius in voxel sizes, in (0, fpfh_radius_gain] (default 3.5).
        normal_radius_gain: f64,
        /// FPFH radius in voxel sizes, in [1.5, 50] and at least the normal gain (default 5.0).
        fpfh_radius_gain: f64,
        /// Linearity above which a point gets no normal, in (0, 1] (default 0.99).
        max_linearity: f64,
        /// Lowe ratio on squared descriptor distances, in (0, 1]; 1 = off (default 0.9).
        ratio_test: f64,
        /// Correspondence-graph edge tolerance in voxel sizes, in (0, 1e6] (default 1.0).
        prune_noise_bound_gain: f64,
        /// Solver inlier bound in voxel sizes, in (0, 1e6] (default 0.75).
        solver_noise_bound_gain: f64,
        /// Cap on both noise bounds in the clouds' unit, >= 0, finite; 0 = no cap (default 0).
        noise_bound_max: f64,
    }
    /// Where normals are oriented toward (default: [`Viewpoint::Local`], no viewpoint).
    pub fn viewpoint(mut self, viewpoint: Viewpoint) -> Self {
        match viewpoint {
            Viewpoint::Fixed(position) => {
                self.raw.viewpoint_mode = sys::KISSM_VIEWPOINT_FIXED;
                self.raw.viewpoint = position;
            }
            Viewpoint::CloudCenter => self.raw.viewpoint_mode = sys::KISSM_VIEWPOINT_CLOUD_CENTER,
            Viewpoint::SignFree => self.raw.viewpoint_mode = sys::KISSM_VIEWPOINT_SIGN_FREE,
            Viewpoint::Local => self.raw.viewpoint_mode = sys::KISSM_VIEWPOINT_LOCAL,
        }
        self
    }
    builder_setters! {
        /// Neighbours needed for a normal and a descriptor, 3..=100000 (default 3).
        min_normal_neighbors: count,
        /// Cap on the mutual matches kept (best ratio first), 3..=100000, or 0 (the default) for automatic: one per
        /// 20 keypoints of the smaller cloud, at least 5000 and at most 100000 (5000 for clouds of up to 100,000
        /// keypoints).
        max_correspondences: count,
        /// Final inliers a valid pose needs without refinement, 3..=100000 (default 15); with refinement
        /// [`refine_min_inliers`](ConfigBuilder::refine_min_inliers) applies instead.
        min_inliers: count,
    }
    /// What happens to NaN and infinite coordinates (default [`NonFinitePolicy::Reject`]).
    pub fn nonfinite_policy(mut self, policy: NonFinitePolicy) -> Self {
        self.raw.nonfinite_policy = match policy {
            NonFinitePolicy::Reject => sys::KISSM_NONFINITE_REJECT,
            NonFinitePolicy::Drop => sys::KISSM_NONFINITE_DROP,
        };
        self
    }
    /// Refines the solver's pose in every registration with this cost (default [`RefineMode::None`]), and
    /// the cost of [`Matcher::refine`](crate::Matcher::refine) (GICP when `None`).
    pub fn refine_mode(mut self, mode: RefineMode) -> Self {
        self.raw.refine_mode = mode.code();
        self
    }
    builder_setters! {
        /// Refinement iteration cap, 1..=1000 (default 30).
        refine_max_iterations: count,
        /// Refinement's correspondence distance (and that of [`Refinement::overlap`](crate::Refinement::overlap))
        /// in voxel sizes, in (0, 100] (default 3.0).
        refine_max_distance_gain: f64,
        /// Scale of refinement's Cauchy kernel in voxel sizes, in (0, 100] (default 1.0).
        refine_kernel_gain: f64,
        /// Convergence threshold on a step's rotation, radians, in [0, 1] (default 5e-4).
        refine_rotation_epsilon: f64,
        /// Convergence threshold on a step's translation in voxel sizes, in [0, 1] (default 5e-3).
        refine_translation_epsilon_gain: f64,
        /// With refinement, a valid pose needs [`Refinement::overlap`](crate::Refinement::overlap) at least this
        /// (below it: [`Reason::LowOverlap`](crate::Reason::LowOverlap)); in [0, 1] (default 0.2).
        min_overlap: f64,
        /// Without refinement, a valid pose needs inliers that pin its rotation down to this many radians
        /// ([`Registration::rotation_uncertainty`](crate::Registration::rotation_uncertainty) at most this;
        /// above it: [`Reason::UncertainRotation`](crate::Reason::UncertainRotation)); in (0, 3.15] (default
        /// 0.0349, 2 degrees). With refinement it bounds 2 times the rotation's 1-sigma that the refined
        /// information states (the square root of the largest eigenvalue of its inverse's rotation block).
        max_rotation_uncertainty: f64,
        /// With refinement, a valid registration needs solver inliers spread over at least this much of the
        /// aligned overlap ([`Refinement::inlier_coverage`](crate::Refinement::inlier_coverage); below it:
        /// [`Reason::ClusteredInliers`](crate::Reason::ClusteredInliers)); in [0, 1] (default 0.25).
        min_inlier_coverage: f64,
        /// With refinement, final inliers a valid registration needs (fewer:
        /// [`Reason::TooFewInliers`](crate::Reason::TooFewInliers)), 3..=100000 (default 10);
        /// [`min_inliers`](ConfigBuilder::min_inliers) applies without refinement.
        refine_min_inliers: count,
        /// With refinement (and in [`Matcher::refine`](crate::Matcher::refine)), a valid pose needs
        /// [`Refinement::condition`](crate::Refinement::condition) at least this (below it:
        /// [`Reason::Unconstrained`](crate::Reason::Unconstrained)): a direction carrying less than this share
        /// of the strongest one's information slides, as along a corridor; in [0, 1] (default 0.01).
        min_refine_condition: f64,
        /// Refinement aligns planes fitted to the neighbours within this many voxel sizes (at least 5 of them;
        /// a value above [`normal_radius_gain`](ConfigBuilder::normal_radius_gain) acts as it); in (0, 50]
        /// (default 2.0). They are computed with the features, so [`Features`](crate::Features) of
        /// a matcher with another value do not match this one's
        /// ([`ErrorKind::FeaturesMismatch`](crate::ErrorKind::FeaturesMismatch)).
        refine_normal_radius_gain: f64,
    }
    /// Geometric suppression before keypoints (default [`Suppression::None`]). [`Suppression::Ground`] uses
    /// [`up`](ConfigBuilder::up), [`sensor_height`](ConfigBuilder::sensor_height) and the sensor at the
    /// [`Viewpoint::Fixed`] position. Computed with the features, so [`Features`](crate::Features) of a
    /// matcher with another value do not match this one's
    /// ([`ErrorKind::FeaturesMismatch`](crate::ErrorKind::FeaturesMismatch)).
    pub fn suppression(mut self, suppression: Suppression) -> Self {
        self.raw.suppression = suppression.code();
        self
    }
    builder_setters! {
        /// Rotational degrees of freedom the solver estimates: 3 (the default), or 1 (yaw about
        /// [`up`](ConfigBuilder::up) only, roll and pitch taken as zero: ground vehicles). With 1, a pair that is
        /// clearly tilted is not valid ([`Reason::Tilted`](crate::Reason::Tilted), with
        /// [`Registration::tilt`](crate::Registration::tilt) the evidence). Any other value fails
        /// [`build`](ConfigBuilder::build).
        rotation_dof: count,
        /// The up direction in each cloud's own frame (the same vector for both clouds), for
        /// [`Suppression::Ground`] and [`rotation_dof`](ConfigBuilder::rotation_dof) 1: finite, of length above
        /// 1e-9, normalised by the library (default (0, 0, 1)). Computed with the features when suppression is
        /// on.
        up: vec3,
        /// Height of the sensor (the [`Viewpoint::Fixed`] position) above the ground along
        /// [`up`](ConfigBuilder::up), metres, for [`Suppression::Ground`]; 0 (the default) = estimate it from the
        /// cloud; in [0, 1000]. Helps on clouds whose nearby ground is hidden.
        sensor_height: f64,
        /// With refinement (and in [`Matcher::refine`](crate::Matcher::refine)), a valid pose needs
        /// [`Refinement::rmse`](crate::Refinement::rmse) at most this many voxel sizes (above it:
        /// [`Reason::LooseAlignment`](crate::Reason::LooseAlignment)): right alignments of voxelised clouds stay
        /// within a fraction of a voxel, the wrong local optima a refinement from a far prior reaches do not;
        /// in (0, 100] (default 0.45).
        max_refine_rmse_gain: f64,
        /// With refinement (and in [`Matcher::refine`](crate::Matcher::refine)): `true` lets a refined pose that
        /// leaves directions free be valid, flagged by [`Registration::degenerate`](crate::Registration::degenerate),
        /// for callers who take its [weak directions](crate::Registration::weak_directions) from elsewhere
        /// (odometry, a motion model); every other rule still applies. `false` makes such a pose not valid
        /// ([`Reason::Unconstrained`](crate::Reason::Unconstrained)). Which directions count as free is set by
        /// [`min_refine_condition`](ConfigBuilder::min_refine_condition). The C field holds 1 or 0, `0..=1`
        /// (default 0, `false`).
        allow_degenerate: bool,
        /// A valid pose needs [`Registration::ambiguity`](crate::Registration::ambiguity), the best distinct
        /// competing pose's support over its own, at most this (above it:
        /// [`Reason::Ambiguous`](crate::Reason::Ambiguous)): repetitive or symmetric scenes match as well one
        /// period along or turned onto their own symmetry; 1 never refuses a pose for it; in [0, 1] (default 0.7).
        max_ambiguity: f64,
    }

    /// Validates every field (`kissm_config_validate`) and returns the configuration, or an
    /// [`ErrorKind::InvalidArgument`](crate::ErrorKind::InvalidArgument) error whose message names the
    /// field.
    pub fn build(self) -> Result<Config, Error> {
        crate::check_library()?;
        if let Some(error) = self.pending {
            return Err(error);
        }
        let config = Config { raw: self.raw };
        config.validate()?;
        Ok(config)
    }
}

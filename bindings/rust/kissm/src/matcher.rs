// SPDX-License-Identifier: MIT
//! [`Matcher`], [`Features`] and [`CancelHandle`].

use std::cell::Cell;
use std::fmt;
use std::marker::PhantomData;
use std::mem;
use std::ptr::NonNull;
use std::sync::Arc;

use kissm_sys as sys;

use crate::config::Config;
use crate::error::Error;
use crate::points::AsPoints;
use crate::registration::Registration;

/// Owns a kissm_matcher; destroyed when the Matcher and every CancelHandle are gone.
struct RawMatcher(NonNull<sys::kissm_matcher>);

// SAFETY: a kissm_matcher is not tied to a thread. Through a shared RawMatcher (the CancelHandles) only
// kissm_cancel is called, which the C API documents as safe from any thread at any time; every other
// call goes through `&mut Matcher`, which is unique.
unsafe impl Send for RawMatcher {}
// SAFETY: as above.
unsafe impl Sync for RawMatcher {}

impl Drop for RawMatcher {
    fn drop(&mut self) {
        // SAFETY: the pointer came from kissm_create and this is its only owner, dropped once.
        unsafe { sys::kissm_destroy(self.0.as_ptr()) }
    }
}

/// A registration engine with a fixed [`Config`]: the C library's `kissm_matcher`, destroyed on drop.
///
/// A matcher may be reused for any number of registrations (reuse never changes results) and moved
/// between threads (`Send`), but is used by one thread at a time (not `Sync`; its calls take
/// `&mut self`). Run registrations in parallel with one matcher per thread; they can share
/// [`Features`]. A registration in progress can be stopped from another thread through a
/// [`CancelHandle`].
///
/// ```no_run
/// use kissm::{Config, Matcher};
/// let source: Vec<[f32; 3]> = load("source");
/// let target: Vec<[f64; 3]> = load("target");
///
/// let mut matcher = Matcher::new(&Config::builder().voxel_size(0.5).build()?)?;
/// let reg = matcher.register(&source, &target)?;
/// if reg.valid {
///     println!("transform: {:?}", reg.transform);
/// } else {
///     println!("no trustworthy pose: {} ({} inliers)", reg.reason, reg.final_inliers());
/// }
/// # fn load<T>(_: &str) -> Vec<T> { Vec::new() }
/// # Ok::<(), kissm::Error>(())
/// ```
pub struct Matcher {
    raw: Arc<RawMatcher>,
    config: Config,
    _not_sync: PhantomData<Cell<()>>,
}

impl Matcher {
    /// Creates a matcher; fails with [`ErrorKind::InvalidArgument`](crate::ErrorKind::InvalidArgument)
    /// naming the field when the configuration is invalid.
    pub fn new(config: &Config) -> Result<Matcher, Error> {
        crate::check_library()?;
        let mut raw: *mut sys::kissm_matcher = std::ptr::null_mut();
        // SAFETY: the config is a complete kissm_config (copied by the library); raw is a valid out pointer.
        Error::check(unsafe { sys::kissm_create(config.as_raw(), &mut raw) })?;
        let raw = NonNull::new(raw)
            .ok_or_else(|| Error::new(sys::KISSM_ERR_INTERNAL, "kissm_create succeeded but returned no matcher"))?;
        Ok(Matcher { raw: Arc::new(RawMatcher(raw)), config: config.clone(), _not_sync: PhantomData })
    }

    /// A matcher with the default configuration and the given voxel size.
    pub fn with_voxel_size(voxel_size: f64) -> Result<Matcher, Error> {
        Matcher::new(&Config::builder().voxel_size(voxel_size).build()?)
    }

    /// The configuration the matcher was created with.
    pub fn config(&self) -> &Config {
        &self.config
    }

    pub(crate) fn ptr(&mut self) -> *mut sys::kissm_matcher {
        self.raw.0.as_ptr()
    }

    /// A result prepared by `kissm_result_init`: struct_size set, no pose.
    fn new_result() -> Result<sys::kissm_result, Error> {
        let mut result = sys::kissm_result::default();
        // SAFETY: result is a writable kissm_result of exactly the size passed.
        Error::check(unsafe { sys::kissm_result_init(&mut result, mem::size_of::<sys::kissm_result>() as u32) })?;
        Ok(result)
    }

    /// Globally registers `source` against `target` (no initial guess needed): the returned transform
    /// maps source points into the target frame.
    ///
    /// Accepts any mix of `&[[f32; 3]]`, `&[[f64; 3]]`, `Vec`s of them, [`PointsView`](crate::PointsView)s
    /// (strided data) and [`Cloud`](crate::Cloud)s. Returns `Ok` whenever the inputs were acceptable,
    /// including when the pose is not [`valid`](Registration::valid); `Err` for an empty or too small
    /// cloud, rejected non-finite coordinates, a voxel size too small for the clouds' extent, or a
    /// cancellation.
    pub fn register<S, T>(&mut self, source: &S, target: &T) -> Result<Registration, Error>
    where
        S: AsPoints + ?Sized,
        T: AsPoints + ?Sized,
    {
        let source = source.as_points();
        let target = target.as_points();
        let mut result = Self::new_result()?;
        // SAFETY: the matcher is live and used by this thread only (&mut self); both views borrow data
        // that outlives the call; result is a writable kissm_result with struct_size set.
        let status = unsafe { sys::kissm_register(self.ptr(), source.as_raw(), target.as_raw(), &mut result) };
        Error::check(status)?;
        Ok(Registration::from_raw(&result))
    }

    /// Fine registration from a known pose (tracking, re-localisation from a prior, checking a loop
    /// closure): voxelises both clouds, estimates their normals and refines `initial` (4 x 4,
    /// `initial[row][col]`, maps source points into the target frame) with the config's
    /// [`refine_mode`](Config::refine_mode) ([`RefineMode::Gicp`](crate::RefineMode::Gicp) when it is
    /// `None`). No descriptors and no global search, so it needs a start within the refinement's reach (a
    /// few voxel sizes, a few degrees).
    ///
    /// The result's [`coarse_transform`](Registration::coarse_transform) is `initial` (its rotation block
    /// made exactly rigid: the nearest rotation), its
    /// [`transform`](Registration::transform) the refined pose, its
    /// [`refinement`](Registration::refinement) is `Some`, and [`valid`](Registration::valid) says whether
    /// the refined pose passes the refined rule (overlap, conditioning and convergence; otherwise
    /// [`Reason::LowOverlap`](crate::Reason::LowOverlap), [`Reason::Unconstrained`](crate::Reason::Unconstrained)
    /// or [`Reason::NotConverged`](crate::Reason::NotConverged)).
    /// Fails with [`ErrorKind::InvalidArgument`](crate::ErrorKind::InvalidArgument), the message naming
    /// `initial_transform`, when `initial` is not finite, its last row is not (0, 0, 0, 1), its rotation
    /// block is not a rotation (orthonormal to 1e-3, determinant +1) or a translation component exceeds 1e9;
    /// otherwise with the errors of [`register`](Matcher::register).
    ///
    /// ```no_run
    /// use kissm::{Config, Matcher, RefineMode};
    /// # let (scan, map): (Vec<[f32; 3]>, Vec<[f32; 3]>) = (Vec::new(), Vec::new());
    /// # let prior = [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]];
    /// let config = Config::builder().voxel_size(0.5).refine_mode(RefineMode::Gicp).build()?;
    /// let reg = Matcher::new(&config)?.refine(&scan, &map, &prior)?;
    /// if let (true, Some(fine)) = (reg.valid, reg.refinement) {
    ///     println!("{:?} overlap {:.2}, information {:?}", reg.transform, fine.overlap, fine.information);
    /// }
    /// # Ok::<(), kissm::Error>(())
    /// ```
    pub fn refine<S, T>(&mut self, source: &S, target: &T, initial: &[[f64; 4]; 4]) -> Result<Registration, Error>
    where
        S: AsPoints + ?Sized,
        T: AsPoints + ?Sized,
    {
        let source = source.as_points();
        let target = target.as_points();
        let initial = flat_transform(initial);
        let mut result = Self::new_result()?;
        // SAFETY: as in register; initial is 16 doubles read during the call only.
        let status =
            unsafe { sys::kissm_refine(self.ptr(), source.as_raw(), target.as_raw(), initial.as_ptr(), &mut result) };
        Error::check(status)?;
        Ok(Registration::from_raw(&result))
    }

    /// [`refine`](Matcher::refine) on described clouds: the same result as on the clouds the features were
    /// computed from (keypoint counts 0, as refinement uses no descriptor), but for the voxelisation and
    /// feature times, which are 0. Features computed
    /// by a matcher with refinement enabled carry the index refinement searches, so a map described once is
    /// not indexed again. Fails as [`register_features`](Matcher::register_features) does, and as
    /// [`refine`](Matcher::refine) does for a bad `initial`.
    pub fn refine_features(
        &mut self,
        source: &Features,
        target: &Features,
        initial: &[[f64; 4]; 4],
    ) -> Result<Registration, Error> {
        let initial = flat_transform(initial);
        let mut result = Self::new_result()?;
        // SAFETY: as in register_features; initial is 16 doubles read during the call only.
        let status = unsafe {
            sys::kissm_refine_features(
                self.ptr(),
                source.raw.as_ptr(),
                target.raw.as_ptr(),
                initial.as_ptr(),
                &mut result,
            )
        };
        Error::check(status)?;
        Ok(Registration::from_raw(&result))
    }

    /// Describes a cloud once (voxelisation, normals, descriptors) for any number of
    /// [`register_features`](Matcher::register_features) and [`refine_features`](Matcher::refine_features)
    /// calls, on any matcher with the same descriptor settings and from any thread.
    pub fn compute_features<P: AsPoints + ?Sized>(&mut self, cloud: &P) -> Result<Features, Error> {
        let cloud = cloud.as_points();
        let mut raw: *mut sys::kissm_features = std::ptr::null_mut();
        // SAFETY: as in register; raw is a valid out pointer.
        Error::check(unsafe { sys::kissm_features_compute(self.ptr(), cloud.as_raw(), &mut raw) })?;
        NonNull::new(raw).map(|raw| Features { raw }).ok_or_else(|| {
            Error::new(sys::KISSM_ERR_INTERNAL, "kissm_features_compute succeeded but returned no features")
        })
    }

    /// Registers two described clouds: the same pose, counts and validity as [`register`](Matcher::register)
    /// on the clouds themselves (voxelisation and feature times are 0). Fails with
    /// [`ErrorKind::FeaturesMismatch`](crate::ErrorKind::FeaturesMismatch) when either was computed under
    /// descriptor settings different from this matcher's.
    pub fn register_features(&mut self, source: &Features, target: &Features) -> Result<Registration, Error> {
        let mut result = Self::new_result()?;
        // SAFETY: the matcher is live and exclusively borrowed; features are immutable and live.
        let status =
            unsafe { sys::kissm_register_features(self.ptr(), source.raw.as_ptr(), target.raw.as_ptr(), &mut result) };
        Error::check(status)?;
        Ok(Registration::from_raw(&result))
    }

    /// Which points of `cloud` the ground model of [`Suppression::Ground`](crate::Suppression::Ground)
    /// labels ground (`kissm_ground_mask`), under this matcher's voxel size,
    /// [`up`](Config::up), [`viewpoint`](Config::viewpoint) (the sensor) and
    /// [`sensor_height`](Config::sensor_height), whatever its [`suppression`](Config::suppression): one
    /// `bool` per point of `cloud`, in order, `true` for ground.
    ///
    /// The model runs on the voxels, so every point of a voxel gets its voxel's label; points dropped as
    /// non-finite (under [`NonFinitePolicy::Drop`](crate::NonFinitePolicy::Drop)) are `false`, and a cloud
    /// without ground gets all `false`. Deterministic: the same mask for any thread count. Accepts the
    /// inputs of [`register`](Matcher::register) and fails as it does on a bad cloud (empty, too small,
    /// rejected non-finite coordinates, a voxel size too small for its extent) or a cancellation.
    ///
    /// ```no_run
    /// use kissm::{Config, Matcher, Preset};
    /// # let scan: Vec<[f32; 3]> = Vec::new();
    /// let mut matcher = Matcher::new(&Config::preset(Preset::LidarVehicle).build()?)?;
    /// let ground = matcher.ground_mask(&scan)?;
    /// let obstacles: Vec<[f32; 3]> = scan.iter().zip(&ground).filter(|&(_, &g)| !g).map(|(p, _)| *p).collect();
    /// # Ok::<(), kissm::Error>(())
    /// ```
    pub fn ground_mask<P: AsPoints + ?Sized>(&mut self, cloud: &P) -> Result<Vec<bool>, Error> {
        let cloud = cloud.as_points();
        let mut mask = vec![0u8; cloud.len()];
        // SAFETY: as in register; mask holds cloud.len() = points->count writable bytes, which the library
        // fills only on success.
        let status = unsafe { sys::kissm_ground_mask(self.ptr(), cloud.as_raw(), mask.as_mut_ptr()) };
        Error::check(status)?;
        Ok(mask.into_iter().map(|flag| flag != 0).collect())
    }

    /// A handle that stops this matcher's running call from another thread. The matcher lives on until
    /// it and all its handles are dropped.
    pub fn cancel_handle(&self) -> CancelHandle {
        CancelHandle { raw: Arc::clone(&self.raw) }
    }
}

/// A 4 x 4 transform as the 16 row-major doubles the C API takes.
fn flat_transform(m: &[[f64; 4]; 4]) -> [f64; 16] {
    let mut flat = [0.0; 16];
    for (out, row) in flat.chunks_exact_mut(4).zip(m) {
        out.copy_from_slice(row);
    }
    flat
}

impl fmt::Debug for Matcher {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Matcher").field("config", &self.config).finish()
    }
}

/// Stops a [`Matcher`]'s running registration (or refinement, or feature computation) from any thread: the call then
/// fails with [`ErrorKind::Cancelled`](crate::ErrorKind::Cancelled). A request made while no call is
/// running is cleared when the next call starts. `Send + Sync + Clone`.
///
/// ```no_run
/// # let (source, target) = (vec![[0.0f32; 3]; 100], vec![[0.0f32; 3]; 100]);
/// let mut matcher = kissm::Matcher::with_voxel_size(0.5)?;
/// let cancel = matcher.cancel_handle();
/// std::thread::spawn(move || {
///     std::thread::sleep(std::time::Duration::from_millis(100));
///     cancel.cancel();
/// });
/// match matcher.register(&source, &target) {
///     Err(e) if e.kind() == kissm::ErrorKind::Cancelled => println!("stopped"),
///     other => println!("{:?}", other.map(|r| r.valid)),
/// }
/// # Ok::<(), kissm::Error>(())
/// ```
#[derive(Clone)]
pub struct CancelHandle {
    raw: Arc<RawMatcher>,
}

impl CancelHandle {
    /// Requests that the call running on the matcher stop.
    pub fn cancel(&self) {
        // SAFETY: the matcher is alive (this handle co-owns it); kissm_cancel is safe from any thread.
        unsafe { sys::kissm_cancel(self.raw.0.as_ptr()) }
    }
}

impl fmt::Debug for CancelHandle {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("CancelHandle").finish_non_exhaustive()
    }
}

/// The length of [`Features::signature`] (`KISSM_SIGNATURE_SIZE`).
pub const SIGNATURE_SIZE: usize = sys::KISSM_SIGNATURE_SIZE as usize;

/// A described cloud ([`Matcher::compute_features`]): immutable, shareable between threads
/// (`Send + Sync`, e.g. in an `Arc`) and independent of the matcher that computed it.
///
/// Portable: [`to_bytes`](Features::to_bytes) writes them in the library's versioned, little-endian format
/// with a checksum (`docs/features-format.md`) and [`from_bytes`](Features::from_bytes) reads them back in
/// another process or on another machine; registering loaded features gives bit for bit the result of the
/// original ones.
pub struct Features {
    pub(crate) raw: NonNull<sys::kissm_features>,
}

// SAFETY: the C API documents kissm_features as immutable once created, usable from several threads at
// once, and free to outlive its matcher.
unsafe impl Send for Features {}
// SAFETY: as above.
unsafe impl Sync for Features {}

impl Features {
    /// Points of the described cloud.
    pub fn num_points(&self) -> u64 {
        // SAFETY: live features.
        unsafe { sys::kissm_features_num_points(self.raw.as_ptr()) }
    }
    /// Occupied voxels.
    pub fn num_voxels(&self) -> u64 {
        // SAFETY: live features.
        unsafe { sys::kissm_features_num_voxels(self.raw.as_ptr()) }
    }
    /// Voxels with a descriptor.
    pub fn num_keypoints(&self) -> u64 {
        // SAFETY: live features.
        unsafe { sys::kissm_features_num_keypoints(self.raw.as_ptr()) }
    }
    /// Memory the features hold (voxels, normals, descriptors and their search index), in bytes.
    pub fn memory_bytes(&self) -> u64 {
        // SAFETY: live features.
        unsafe { sys::kissm_features_memory_bytes(self.raw.as_ptr()) }
    }

    /// A fixed-length summary of the features for finding scans that see the same place
    /// (`kissm_features_signature`): the Euclidean distance between two clouds' signatures is small when they
    /// overlap. Three unit-length blocks: the keypoints' mean FPFH, its standard deviation per bin, and the
    /// square roots of the shares of keypoints per 12-voxel band of distance from their centroid. It depends
    /// on no coordinate frame, is the same bits for loaded features and at any thread count, and is all zeros
    /// for features without keypoints. Compare signatures of one voxel size only (`docs/multiway.md`, "Loop
    /// candidates by similarity").
    pub fn signature(&self) -> Result<[f64; SIGNATURE_SIZE], Error> {
        let mut out = [0.0f64; SIGNATURE_SIZE];
        // SAFETY: live features; out holds KISSM_SIGNATURE_SIZE writable doubles.
        Error::check(unsafe { sys::kissm_features_signature(self.raw.as_ptr(), out.as_mut_ptr()) })?;
        Ok(out)
    }

    /// The features as bytes (`kissm_features_serialize`) that [`from_bytes`](Features::from_bytes) reads
    /// back on any machine: a versioned, little-endian format with a checksum (`docs/features-format.md`).
    ///
    /// The bytes hold the voxels, normals, descriptors and counts and the descriptor settings they were
    /// computed under, so loaded features still fail with
    /// [`ErrorKind::FeaturesMismatch`](crate::ErrorKind::FeaturesMismatch) against a matcher of other settings;
    /// the search indexes are not stored but rebuilt on load. The same features always give the same bytes,
    /// so they can be hashed or deduplicated.
    ///
    /// ```no_run
    /// use kissm::{Features, Matcher};
    /// # let (scan, map): (Vec<[f32; 3]>, Vec<[f32; 3]>) = (Vec::new(), Vec::new());
    /// let mut matcher = Matcher::with_voxel_size(0.5)?;
    /// // Describe the map once and store its features...
    /// let bytes = matcher.compute_features(&map)?.to_bytes()?;
    /// std::fs::write("map.features", &bytes).expect("write");
    /// // ...then, in another process or on another machine, with the same settings:
    /// let map = Features::from_bytes(&std::fs::read("map.features").expect("read"))?;
    /// let scan = matcher.compute_features(&scan)?;
    /// let reg = matcher.register_features(&scan, &map)?;
    /// # Ok::<(), kissm::Error>(())
    /// ```
    pub fn to_bytes(&self) -> Result<Vec<u8>, Error> {
        let mut size: u64 = 0;
        // SAFETY: live features; a NULL buffer asks for the size only; size is a valid out pointer.
        Error::check(unsafe { sys::kissm_features_serialize(self.raw.as_ptr(), std::ptr::null_mut(), 0, &mut size) })?;
        let len = usize::try_from(size)
            .map_err(|_| Error::new(sys::KISSM_ERR_OUT_OF_MEMORY, format!("the features take {size} bytes")))?;
        let mut bytes = vec![0u8; len];
        let mut written: u64 = 0;
        // SAFETY: bytes holds len = size writable bytes; written is a valid out pointer.
        Error::check(unsafe {
            sys::kissm_features_serialize(self.raw.as_ptr(), bytes.as_mut_ptr().cast(), size, &mut written)
        })?;
        if written != size {
            return Err(Error::new(
                sys::KISSM_ERR_INTERNAL,
                format!("kissm_features_serialize wrote {written} bytes after announcing {size}"),
            ));
        }
        Ok(bytes)
    }

    /// Features from the bytes of [`to_bytes`](Features::to_bytes) (`kissm_features_deserialize`), possibly
    /// written by another process or machine: exactly those bytes (trailing bytes are refused).
    ///
    /// Nothing in the bytes is trusted: they are bounds-checked and validated (magic, version, checksum,
    /// counts, values), and the search indexes are rebuilt on the calling thread. Fails with
    /// [`ErrorKind::Parse`](crate::ErrorKind::Parse) when the bytes are not features of this format version,
    /// are truncated or corrupted, or hold a value the library cannot have written; the message names what is
    /// wrong and its byte offset.
    ///
    /// ```
    /// let err = kissm::Features::from_bytes(b"not features").unwrap_err();
    /// assert_eq!(err.kind(), kissm::ErrorKind::Parse);
    /// assert!(err.message().contains("features bytes"), "{err}");
    /// ```
    pub fn from_bytes(bytes: &[u8]) -> Result<Features, Error> {
        crate::check_library()?;
        let mut raw: *mut sys::kissm_features = std::ptr::null_mut();
        // SAFETY: bytes is readable for its length (an empty slice has a dangling but non-NULL pointer, which
        // the library does not read past the size 0); raw is a valid out pointer.
        Error::check(unsafe { sys::kissm_features_deserialize(bytes.as_ptr().cast(), bytes.len() as u64, &mut raw) })?;
        NonNull::new(raw).map(|raw| Features { raw }).ok_or_else(|| {
            Error::new(sys::KISSM_ERR_INTERNAL, "kissm_features_deserialize succeeded but returned no features")
        })
    }
}

impl Drop for Features {
    fn drop(&mut self) {
        // SAFETY: the pointer came from kissm_features_compute or kissm_features_deserialize and is destroyed
        // exactly once.
        unsafe { sys::kissm_features_destroy(self.raw.as_ptr()) }
    }
}

impl fmt::Debug for Features {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Features")
            .field("num_points", &self.num_points())
            .field("num_voxels", &self.num_voxels())
            .field("num_keypoints", &self.num_keypoints())
            .field("memory_bytes", &self.memory_bytes())
            .finish()
    }
}

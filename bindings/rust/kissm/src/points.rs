// SPDX-License-Identifier: MIT
//! Point input ([`PointsView`], [`AsPoints`]) and point files ([`Cloud`], [`read_points`]).

use std::ffi::CString;
use std::fmt;
use std::marker::PhantomData;
use std::mem;
use std::path::Path;
use std::ptr::NonNull;

use kissm_sys as sys;

use crate::error::Error;

/// A borrowed, zero-copy view of x, y, z coordinates (float32 or float64), as the C library reads them.
///
/// Make one from `&[[f32; 3]]` or `&[[f64; 3]]` (packed points), or from a flat slice with a stride
/// (for example x, y, z, intensity rows), or through [`AsPoints`]. The registration reads the
/// coordinates during the call only.
///
/// ```
/// use kissm::PointsView;
/// let xyz: Vec<[f32; 3]> = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]];
/// assert_eq!(PointsView::from_f32(&xyz).len(), 2);
///
/// // KITTI-style rows of x, y, z, intensity:
/// let xyzi = [0.0f32, 0.0, 0.0, 0.5, 1.0, 2.0, 3.0, 0.7];
/// assert_eq!(PointsView::strided_f32(&xyzi, 4)?.len(), 2);
/// # Ok::<(), kissm::Error>(())
/// ```
#[derive(Clone, Copy)]
pub struct PointsView<'a> {
    raw: sys::kissm_points,
    len: usize,
    _borrow: PhantomData<&'a [u8]>,
}

// SAFETY: a PointsView is a shared borrow of f32/f64 data (which is Send + Sync); it only reads it.
unsafe impl Send for PointsView<'_> {}
// SAFETY: as above.
unsafe impl Sync for PointsView<'_> {}

fn strided_len(data_len: usize, stride: usize) -> Result<usize, Error> {
    if stride < 3 {
        return Err(Error::new(
            sys::KISSM_ERR_INVALID_ARGUMENT,
            format!("points: stride {stride} is smaller than 3 (x, y, z)"),
        ));
    }
    Ok(if data_len < 3 { 0 } else { (data_len - 3) / stride + 1 })
}

impl<'a> PointsView<'a> {
    fn make(data: *const std::ffi::c_void, len: usize, stride_bytes: usize, scalar_type: i32) -> Self {
        PointsView {
            raw: sys::kissm_points {
                data,
                count: len as u64,
                stride_bytes: stride_bytes as u64,
                scalar_type,
                reserved: 0,
            },
            len,
            _borrow: PhantomData,
        }
    }

    /// Packed float32 points.
    pub fn from_f32(points: &'a [[f32; 3]]) -> Self {
        Self::make(points.as_ptr().cast(), points.len(), 0, sys::KISSM_SCALAR_FLOAT32)
    }

    /// Packed float64 points.
    pub fn from_f64(points: &'a [[f64; 3]]) -> Self {
        Self::make(points.as_ptr().cast(), points.len(), 0, sys::KISSM_SCALAR_FLOAT64)
    }

    /// Float32 points at element offsets 0, `stride`, 2 `stride`, ... of `data`, each made of 3
    /// consecutive values x, y, z. There are as many points as complete x, y, z triples start at those
    /// offsets, so both a row-major `(N, stride)` array and the same array sliced from a column offset
    /// work. Fails with [`ErrorKind::InvalidArgument`](crate::ErrorKind::InvalidArgument) when
    /// `stride < 3`.
    pub fn strided_f32(data: &'a [f32], stride: usize) -> Result<Self, Error> {
        let len = strided_len(data.len(), stride)?;
        Ok(Self::make(
            data.as_ptr().cast(),
            len,
            stride.saturating_mul(mem::size_of::<f32>()),
            sys::KISSM_SCALAR_FLOAT32,
        ))
    }

    /// Float64 points with a stride in elements; see [`strided_f32`](PointsView::strided_f32).
    pub fn strided_f64(data: &'a [f64], stride: usize) -> Result<Self, Error> {
        let len = strided_len(data.len(), stride)?;
        Ok(Self::make(
            data.as_ptr().cast(),
            len,
            stride.saturating_mul(mem::size_of::<f64>()),
            sys::KISSM_SCALAR_FLOAT64,
        ))
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether there are no points.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The raw C view, for use with `kissm-sys` while the borrowed data lives.
    pub fn as_raw(&self) -> &sys::kissm_points {
        &self.raw
    }
}

impl fmt::Debug for PointsView<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let scalar = if self.raw.scalar_type == sys::KISSM_SCALAR_FLOAT32 { "f32" } else { "f64" };
        f.debug_struct("PointsView")
            .field("len", &self.len)
            .field("scalar", &scalar)
            .field("stride_bytes", &self.raw.stride_bytes)
            .finish()
    }
}

impl<'a> From<&'a [[f32; 3]]> for PointsView<'a> {
    fn from(points: &'a [[f32; 3]]) -> Self {
        PointsView::from_f32(points)
    }
}

impl<'a> From<&'a [[f64; 3]]> for PointsView<'a> {
    fn from(points: &'a [[f64; 3]]) -> Self {
        PointsView::from_f64(points)
    }
}

/// Anything that can be registered: gives a [`PointsView`] of its coordinates.
///
/// Implemented for `[[f32; 3]]`, `[[f64; 3]]`, their `Vec`s and arrays, [`PointsView`] (for strided
/// data) and [`Cloud`]. Implement it for your own point type by returning a view, for example with
/// [`PointsView::strided_f32`] over its coordinate buffer.
pub trait AsPoints {
    /// The coordinates, borrowed from `self`.
    fn as_points(&self) -> PointsView<'_>;
}

impl AsPoints for [[f32; 3]] {
    fn as_points(&self) -> PointsView<'_> {
        PointsView::from_f32(self)
    }
}
impl AsPoints for [[f64; 3]] {
    fn as_points(&self) -> PointsView<'_> {
        PointsView::from_f64(self)
    }
}
impl AsPoints for Vec<[f32; 3]> {
    fn as_points(&self) -> PointsView<'_> {
        PointsView::from_f32(self)
    }
}
impl AsPoints for Vec<[f64; 3]> {
    fn as_points(&self) -> PointsView<'_> {
        PointsView::from_f64(self)
    }
}
impl<const N: usize> AsPoints for [[f32; 3]; N] {
    fn as_points(&self) -> PointsView<'_> {
        PointsView::from_f32(self)
    }
}
impl<const N: usize> AsPoints for [[f64; 3]; N] {
    fn as_points(&self) -> PointsView<'_> {
        PointsView::from_f64(self)
    }
}
impl AsPoints for PointsView<'_> {
    fn as_points(&self) -> PointsView<'_> {
        *self
    }
}
impl<T: AsPoints + ?Sized> AsPoints for &T {
    fn as_points(&self) -> PointsView<'_> {
        (**self).as_points()
    }
}

/// Point file formats for [`read_points_with_format`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
#[non_exhaustive]
pub enum Format {
    /// By extension, then by content (the default).
    #[default]
    Auto,
    /// PLY, ascii or binary.
    Ply,
    /// PCD, ascii or binary.
    Pcd,
    /// KITTI `.bin`: float32 x, y, z, intensity.
    KittiBin,
    /// `.npy`: float32 or float64, shape (N, 3) or (N, k >= 3).
    Npy,
    /// Whitespace-separated x y z text.
    Xyz,
    /// Raw float32 x, y, z triples (no intensity, no header).
    BinXyz,
    /// LAS 1.0-1.4, point formats 0-10: x, y, z with the file's scale and offset applied in float64; points
    /// flagged withheld are left out. LAZ is read only by a libkissm built with the CMake option
    /// `KISSM_WITH_LAZ` (off by default, and off in the library this crate builds); otherwise it fails with
    /// [`ErrorKind::UnsupportedFormat`](crate::ErrorKind::UnsupportedFormat).
    Las,
}

impl Format {
    /// The `KISSM_FORMAT_*` value.
    pub fn code(self) -> i32 {
        match self {
            Format::Auto => sys::KISSM_FORMAT_AUTO,
            Format::Ply => sys::KISSM_FORMAT_PLY,
            Format::Pcd => sys::KISSM_FORMAT_PCD,
            Format::KittiBin => sys::KISSM_FORMAT_KITTI_BIN,
            Format::Npy => sys::KISSM_FORMAT_NPY,
            Format::Xyz => sys::KISSM_FORMAT_XYZ,
            Format::BinXyz => sys::KISSM_FORMAT_BIN_XYZ,
            Format::Las => sys::KISSM_FORMAT_LAS,
        }
    }

    /// The format of a name as the `kissm` tool spells it: `auto`, `ply`, `pcd`, `kitti_bin`, `npy`,
    /// `xyz`, `bin_xyz`, `las` (case-insensitive; `kitti`, `txt`, `npy_xyz` and the data sets' `bin_xyz_f32` and
    /// `kitti_bin_xyzi_f32` work too).
    pub fn from_name(name: &str) -> Option<Format> {
        let name = name.to_ascii_lowercase();
        Some(match name.as_str() {
            "auto" => Format::Auto,
            "ply" => Format::Ply,
            "pcd" => Format::Pcd,
            "kitti_bin" | "kitti" | "kitti_bin_xyzi_f32" => Format::KittiBin,
            "npy" | "npy_xyz" => Format::Npy,
            "xyz" | "txt" => Format::Xyz,
            "bin_xyz" | "bin_xyz_f32" => Format::BinXyz,
            "las" => Format::Las,
            _ => return None,
        })
    }
}

/// A cloud read from a file by the library: float64 x, y, z, packed. Immutable, so `Send + Sync`.
pub struct Cloud {
    raw: NonNull<sys::kissm_cloud>,
}

// SAFETY: a kissm_cloud is never modified after kissm_read_points returns; reading it from several
// threads at once is fine, and it may be destroyed on any thread.
unsafe impl Send for Cloud {}
// SAFETY: as above.
unsafe impl Sync for Cloud {}

impl Cloud {
    /// Number of points (non-finite ones included: the registration's policy decides about them).
    pub fn len(&self) -> usize {
        // SAFETY: self.raw is a live cloud.
        usize::try_from(unsafe { sys::kissm_cloud_count(self.raw.as_ptr()) }).unwrap_or(0)
    }

    /// Number of points the reader left out on purpose: for LAS/LAZ the points flagged withheld (not in
    /// [`Cloud::len`]); 0 for the other formats.
    pub fn num_withheld(&self) -> u64 {
        // SAFETY: self.raw is a live cloud.
        unsafe { sys::kissm_cloud_num_withheld(self.raw.as_ptr()) }
    }

    /// Whether the cloud has no points.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The points.
    pub fn as_slice(&self) -> &[[f64; 3]] {
        // SAFETY: self.raw is a live cloud; its data is count * 3 doubles (NULL when empty), alive and
        // unchanged until kissm_cloud_destroy, which only Drop calls.
        unsafe {
            let data = sys::kissm_cloud_data(self.raw.as_ptr());
            let count = sys::kissm_cloud_count(self.raw.as_ptr());
            match usize::try_from(count) {
                Ok(count) if !data.is_null() && count > 0 => std::slice::from_raw_parts(data.cast::<[f64; 3]>(), count),
                _ => &[],
            }
        }
    }

    /// A copy of the points.
    pub fn to_vec(&self) -> Vec<[f64; 3]> {
        self.as_slice().to_vec()
    }
}

impl AsPoints for Cloud {
    fn as_points(&self) -> PointsView<'_> {
        PointsView::from_f64(self.as_slice())
    }
}

impl Drop for Cloud {
    fn drop(&mut self) {
        // SAFETY: self.raw came from kissm_read_points and is destroyed exactly once.
        unsafe { sys::kissm_cloud_destroy(self.raw.as_ptr()) }
    }
}

impl fmt::Debug for Cloud {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Cloud").field("len", &self.len()).finish()
    }
}

fn path_to_cstring(path: &Path) -> Result<CString, Error> {
    #[cfg(unix)]
    let bytes = {
        use std::os::unix::ffi::OsStrExt;
        path.as_os_str().as_bytes().to_vec()
    };
    #[cfg(not(unix))]
    let bytes = match path.to_str() {
        Some(text) => text.as_bytes().to_vec(),
        None => {
            return Err(Error::new(
                sys::KISSM_ERR_INVALID_ARGUMENT,
                format!("path {} is not valid UTF-8", path.display()),
            ))
        }
    };
    CString::new(bytes).map_err(|_| {
        Error::new(sys::KISSM_ERR_INVALID_ARGUMENT, format!("path {} contains a NUL byte", path.display()))
    })
}

/// Reads a point file with the library's readers (the `kissm` tool's): PLY, PCD, KITTI `.bin`, `.npy`,
/// xyz text and LAS, picked by extension, then by content.
///
/// Raw float32 x, y, z `.bin` files (no intensity) need [`read_points_with_format`] with
/// [`Format::BinXyz`]: by extension `.bin` means KITTI x, y, z, intensity.
///
/// ```no_run
/// let cloud = kissm::read_points("scan.ply")?;
/// println!("{} points", cloud.len());
/// # Ok::<(), kissm::Error>(())
/// ```
pub fn read_points(path: impl AsRef<Path>) -> Result<Cloud, Error> {
    read_points_with_format(path, Format::Auto)
}

/// Reads a point file in the given format ([`Format::Auto`] is [`read_points`]).
pub fn read_points_with_format(path: impl AsRef<Path>, format: Format) -> Result<Cloud, Error> {
    crate::check_library()?;
    let c_path = path_to_cstring(path.as_ref())?;
    let mut raw: *mut sys::kissm_cloud = std::ptr::null_mut();
    // SAFETY: c_path is NUL-terminated and outlives the call; raw is a valid out pointer.
    Error::check(unsafe { sys::kissm_read_points(c_path.as_ptr(), format.code(), &mut raw) })?;
    NonNull::new(raw)
        .map(|raw| Cloud { raw })
        .ok_or_else(|| Error::new(sys::KISSM_ERR_INTERNAL, "kissm_read_points succeeded but returned no cloud"))
}

/// The voxel size an automatic voxel size ([`ConfigBuilder::voxel_size_auto`](crate::ConfigBuilder::voxel_size_auto))
/// uses for these clouds together (`kissm_suggest_voxel_size`): one cloud, a pair (in either order) or a set of
/// scans to be described alike. Each cloud's own voxel is the smallest of 2^(k/8) (k an integer, in the clouds'
/// unit) whose grid holds at most 3000 occupied voxels, or 2000 for a compact cloud (an object scan, an indoor
/// fragment); a quarter of its points when it has fewer than 4 times as many. The suggestion is the clouds' own
/// lower median (the smaller of a pair). It depends on the points alone; non-finite points are ignored.
///
/// ```
/// let a = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 1.0, 1.0]];
/// let b = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 2.0], [2.0, 2.0, 2.0]];
/// let v = kissm::suggest_voxel_size(&[&a, &b])?;
/// assert_eq!(v, kissm::suggest_voxel_size(&[&b, &a])?);
/// # Ok::<(), kissm::Error>(())
/// ```
pub fn suggest_voxel_size(clouds: &[&dyn AsPoints]) -> Result<f64, Error> {
    let views: Vec<PointsView<'_>> = clouds.iter().map(|c| c.as_points()).collect();
    let raw: Vec<sys::kissm_points> = views.iter().map(|v| *v.as_raw()).collect();
    let mut voxel = 0.0;
    // SAFETY: raw holds raw.len() views of data that `clouds` borrows for the whole call; voxel is writable.
    let status = unsafe { sys::kissm_suggest_voxel_size(raw.as_ptr(), raw.len() as u64, &mut voxel) };
    Error::check(status)?;
    Ok(voxel)
}

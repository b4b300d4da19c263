// SPDX-License-Identifier: MIT
//! [`Error`]: a failed call's status code and message.

use std::ffi::{c_char, CStr};
use std::fmt;

use kissm_sys as sys;

/// The error of a failed kissm call: the C library's status code (`KISSM_ERR_*`, negative) and the detailed
/// message that names the offending argument.
///
/// The message is read with `kissm_last_error_message()` on the calling thread right after the failing
/// call, so it always belongs to this failure. Errors detected on the Rust side before any call (a stride
/// smaller than 3, a path with a NUL byte, ...) use the same codes.
///
/// ```
/// let err = kissm::Config::builder().voxel_size(-1.0).build().unwrap_err();
/// assert_eq!(err.kind(), kissm::ErrorKind::InvalidArgument);
/// assert_eq!(err.code(), kissm_sys::KISSM_ERR_INVALID_ARGUMENT);
/// assert!(err.message().contains("voxel_size"));
/// ```
#[derive(Clone, PartialEq, Eq, Hash)]
pub struct Error {
    code: i32,
    message: String,
}

/// The kind of an [`Error`], one per documented `KISSM_ERR_*` status code.
///
/// New kinds may be added (as the C library's codes are only ever appended), so matches need a `_` arm.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum ErrorKind {
    /// `KISSM_ERR_INVALID_ARGUMENT`: a config value or argument is out of its documented range.
    InvalidArgument,
    /// `KISSM_ERR_NULL_ARGUMENT`: a required pointer is NULL (cannot happen through this crate).
    NullArgument,
    /// `KISSM_ERR_EMPTY_INPUT`: a cloud has no points, or none left after dropping non-finite ones.
    EmptyInput,
    /// `KISSM_ERR_TOO_FEW_POINTS`: a cloud has fewer than [`MIN_POINTS`](crate::MIN_POINTS) points.
    TooFewPoints,
    /// `KISSM_ERR_NONFINITE`: a NaN or infinite coordinate under [`NonFinitePolicy::Reject`](crate::NonFinitePolicy::Reject).
    NonFinite,
    /// `KISSM_ERR_VOXEL_RANGE`: the voxel size is too small for the cloud's extent.
    VoxelRange,
    /// `KISSM_ERR_STRUCT_SIZE`: the library and these bindings disagree on a struct's layout.
    StructSize,
    /// `KISSM_ERR_OUT_OF_MEMORY`: an allocation failed; nothing was changed.
    OutOfMemory,
    /// `KISSM_ERR_CANCELLED`: [`CancelHandle::cancel`](crate::CancelHandle::cancel) (or
    /// [`PoseGraphCancelHandle::cancel`](crate::PoseGraphCancelHandle::cancel)) stopped the call.
    Cancelled,
    /// `KISSM_ERR_FEATURES_MISMATCH`: features computed under a different configuration.
    FeaturesMismatch,
    /// `KISSM_ERR_IO`: a file could not be opened or read.
    Io,
    /// `KISSM_ERR_PARSE`: a file, or the bytes given to [`Features::from_bytes`](crate::Features::from_bytes), is
    /// malformed, truncated or of an unsupported layout.
    Parse,
    /// `KISSM_ERR_UNSUPPORTED_FORMAT`: a file's format is not recognised.
    UnsupportedFormat,
    /// `KISSM_ERR_INTERNAL`: a bug in kissm; please report it with the message.
    Internal,
    /// A status code this version of the crate does not know (from a newer library).
    Unknown,
}

impl ErrorKind {
    /// The kind of a `KISSM_ERR_*` status code ([`ErrorKind::Unknown`] for any other value).
    pub fn from_code(code: i32) -> ErrorKind {
        match code {
            sys::KISSM_ERR_INVALID_ARGUMENT => ErrorKind::InvalidArgument,
            sys::KISSM_ERR_NULL_ARGUMENT => ErrorKind::NullArgument,
            sys::KISSM_ERR_EMPTY_INPUT => ErrorKind::EmptyInput,
            sys::KISSM_ERR_TOO_FEW_POINTS => ErrorKind::TooFewPoints,
            sys::KISSM_ERR_NONFINITE => ErrorKind::NonFinite,
            sys::KISSM_ERR_VOXEL_RANGE => ErrorKind::VoxelRange,
            sys::KISSM_ERR_STRUCT_SIZE => ErrorKind::StructSize,
            sys::KISSM_ERR_OUT_OF_MEMORY => ErrorKind::OutOfMemory,
            sys::KISSM_ERR_CANCELLED => ErrorKind::Cancelled,
            sys::KISSM_ERR_FEATURES_MISMATCH => ErrorKind::FeaturesMismatch,
            sys::KISSM_ERR_IO => ErrorKind::Io,
            sys::KISSM_ERR_PARSE => ErrorKind::Parse,
            sys::KISSM_ERR_UNSUPPORTED_FORMAT => ErrorKind::UnsupportedFormat,
            sys::KISSM_ERR_INTERNAL => ErrorKind::Internal,
            _ => ErrorKind::Unknown,
        }
    }
}

/// Converts a static, library-owned C string to `&'static str` (`fallback` for NULL or non-UTF-8 text).
pub(crate) fn static_str(ptr: *const c_char, fallback: &'static str) -> &'static str {
    if ptr.is_null() {
        return fallback;
    }
    // SAFETY: the library documents these strings as static and NUL-terminated.
    unsafe { CStr::from_ptr(ptr) }.to_str().unwrap_or(fallback)
}

/// The static description of a status code, as `kissm_status_string()` gives it ("unknown status" for
/// unknown values).
///
/// ```
/// assert_eq!(kissm::status_string(kissm_sys::KISSM_OK), kissm::status_string(0));
/// assert!(!kissm::status_string(kissm_sys::KISSM_ERR_IO).is_empty());
/// ```
pub fn status_string(code: i32) -> &'static str {
    // SAFETY: no preconditions; returns a static string.
    static_str(unsafe { sys::kissm_status_string(code) }, "unknown status")
}

impl Error {
    /// An error with the given status code and message (used for checks done on the Rust side).
    pub(crate) fn new(code: i32, message: impl Into<String>) -> Error {
        Error { code, message: message.into() }
    }

    /// The error of the kissm call that just returned `code` on this thread: reads
    /// `kissm_last_error_message()`, which must happen before any other kissm call on this thread.
    pub(crate) fn last(code: i32) -> Error {
        // SAFETY: no preconditions; the returned string is valid until the next kissm call on this thread,
        // and it is copied right away.
        let ptr = unsafe { sys::kissm_last_error_message() };
        let message = if ptr.is_null() {
            String::new()
        } else {
            // SAFETY: non-NULL, NUL-terminated, library-owned and alive until the next call on this thread.
            unsafe { CStr::from_ptr(ptr) }.to_string_lossy().into_owned()
        };
        Error { code, message }
    }

    /// Turns a status into `Ok(())` or the error of the call that just returned it.
    pub(crate) fn check(code: i32) -> Result<(), Error> {
        if code == sys::KISSM_OK {
            Ok(())
        } else {
            Err(Error::last(code))
        }
    }

    /// The C status code, one of the `kissm_sys::KISSM_ERR_*` constants (negative).
    pub fn code(&self) -> i32 {
        self.code
    }

    /// The kind of error, from [`code`](Error::code).
    pub fn kind(&self) -> ErrorKind {
        ErrorKind::from_code(self.code)
    }

    /// The detailed message (it names the offending argument, field or file). May be empty when the
    /// library gave none; [`Display`](fmt::Display) then falls back to the status description.
    pub fn message(&self) -> &str {
        &self.message
    }

    /// The static description of the status code (`kissm_status_string()`).
    pub fn status_string(&self) -> &'static str {
        status_string(self.code)
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.message.is_empty() {
            write!(f, "{} (kissm status {})", self.status_string(), self.code)
        } else {
            write!(f, "{} (kissm status {}: {})", self.message, self.code, self.status_string())
        }
    }
}

impl fmt::Debug for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Error")
            .field("code", &self.code)
            .field("kind", &self.kind())
            .field("message", &self.message)
            .finish()
    }
}

impl std::error::Error for Error {}

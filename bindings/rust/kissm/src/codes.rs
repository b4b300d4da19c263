// SPDX-License-Identifier: MIT
//! `from_code` and `code` of the enums that stand for C constants, from one list of pairs each: a variant and
//! its code are written once, so the two directions cannot disagree.

/// `impl $ty { fn from_code; fn code }` from `Variant => sys::CONSTANT` pairs. The first form gives
/// `from_code -> Option<$ty>` (`None` for a code the library does not define); the second, for an enum with an
/// `$other(i32)` variant, keeps an unknown code there.
macro_rules! c_codes {
    ($ty:ident, $prefix:literal, $what:literal { $($variant:ident => $code:path),+ $(,)? }) => {
        impl $ty {
            #[doc = concat!("The ", $what, " of a `", $prefix, "*` code (`None` for a value the library does not define).")]
            pub fn from_code(code: i32) -> Option<$ty> {
                match code {
                    $($code => Some($ty::$variant),)+
                    _ => None,
                }
            }

            #[doc = concat!("The `", $prefix, "*` code.")]
            pub fn code(self) -> i32 {
                match self {
                    $($ty::$variant => $code,)+
                }
            }
        }
    };
    ($ty:ident, $prefix:literal, $what:literal, $other:ident { $($variant:ident => $code:path),+ $(,)? }) => {
        impl $ty {
            #[doc = concat!("The ", $what, " of a `", $prefix, "*` code (`", stringify!($other), "` for a value this crate does not know).")]
            pub fn from_code(code: i32) -> $ty {
                match code {
                    $($code => $ty::$variant,)+
                    other => $ty::$other(other),
                }
            }

            #[doc = concat!("The `", $prefix, "*` code.")]
            pub fn code(self) -> i32 {
                match self {
                    $($ty::$variant => $code,)+
                    $ty::$other(code) => code,
                }
            }
        }
    };
}

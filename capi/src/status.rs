//! The status codes: `MlabStatus`, what every function but two returns, the kernel's errors
//! mapped to it, and the text of each (`mlab_error_message`).

use core::ffi::{c_char, c_int};

use mlab::{FragmentError, FramebufferError};

/// The result of every function but `mlab_error_message` and `mlab_abi_version`: `MLAB_STATUS_OK` (0),
/// or why nothing was done. Unless a function says otherwise, an error leaves the
/// framebuffer's rows and every output unchanged. `mlab_error_message` gives each a text.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MlabStatus {
    /// Success.
    Ok = 0,
    /// A pointer argument is null.
    NullPointer = 1,
    /// A pointer argument is not aligned for its type (rows: 8 bytes; the framebuffer
    /// struct: its alignment, 8 on 64-bit targets; f32 output: 16; RGBA16F output: 2;
    /// fragments: 4).
    Misaligned = 2,
    /// The framebuffer struct was not filled by a successful `mlab_framebuffer_init` (or
    /// `mlab_framebuffer_band`), or has been changed since.
    NotInitialized = 3,
    /// A method, arithmetic or background kind that is not one of the defined constants.
    InvalidArgument = 4,
    /// A width, height, or number of lines of 0.
    ZeroSize = 5,
    /// A size whose rows or bytes do not fit in `size_t` (or `ptrdiff_t`).
    SizeOverflow = 6,
    /// A number of layers that is not 1 to 8.
    UnsupportedLayers = 7,
    /// The storage does not hold exactly `mlab_rows_needed` rows.
    StorageLength = 8,
    /// An output does not hold exactly `width * height` pixels.
    OutputLength = 9,
    /// A pixel (or a lane of a span that is on) lies outside the framebuffer, or a band's
    /// lines do.
    OutOfBounds = 10,
    /// A fragment's color channel is NaN.
    NanColor = 11,
    /// A fragment's color channel is infinite.
    InfiniteColor = 12,
    /// A fragment's color channel is negative.
    NegativeColor = 13,
    /// A fragment's premultiplied color (straight color times alpha) is above 1.
    ColorAboveOne = 14,
    /// A fragment's alpha is NaN.
    NanAlpha = 15,
    /// A fragment's alpha is outside `[0, 1]`.
    AlphaOutOfRange = 16,
    /// A fragment's depth is NaN.
    NanDepth = 17,
    /// A fragment's depth is infinite.
    InfiniteDepth = 18,
    /// A bug in mlab: a panic was caught at the boundary (the framebuffer's contents are
    /// unspecified: clear it), or an internal inconsistency. (A panic in a per-pixel insert
    /// aborts the process instead; see `docs/c.md`.)
    Internal = 19,
}

impl From<FragmentError> for MlabStatus {
    fn from(e: FragmentError) -> MlabStatus {
        match e {
            FragmentError::NanColor => MlabStatus::NanColor,
            FragmentError::InfiniteColor => MlabStatus::InfiniteColor,
            FragmentError::NegativeColor => MlabStatus::NegativeColor,
            FragmentError::ColorAboveOne => MlabStatus::ColorAboveOne,
            FragmentError::NanAlpha => MlabStatus::NanAlpha,
            FragmentError::AlphaOutOfRange => MlabStatus::AlphaOutOfRange,
            FragmentError::NanDepth => MlabStatus::NanDepth,
            FragmentError::InfiniteDepth => MlabStatus::InfiniteDepth,
            _ => MlabStatus::Internal,
        }
    }
}

impl From<FramebufferError> for MlabStatus {
    fn from(e: FramebufferError) -> MlabStatus {
        match e {
            FramebufferError::StorageLength { .. } => MlabStatus::StorageLength,
            FramebufferError::SizeOverflow => MlabStatus::SizeOverflow,
            FramebufferError::OutOfBounds { .. } => MlabStatus::OutOfBounds,
            FramebufferError::OutputLength { .. } => MlabStatus::OutputLength,
            FramebufferError::UnsupportedLayers { .. } => MlabStatus::UnsupportedLayers,
            _ => MlabStatus::Internal,
        }
    }
}

/// The messages of `MlabStatus`, in the order of its values.
const MESSAGES: [&core::ffi::CStr; 20] = [
    c"ok",
    c"a pointer argument is null",
    c"a pointer argument is not aligned for its type",
    c"the framebuffer struct was not initialized by mlab_framebuffer_init, or was changed since",
    c"a method, arithmetic or background kind is not one of the defined constants",
    c"a width, height or number of lines is 0",
    c"the size overflows size_t",
    c"the number of layers is not 1 to 8",
    c"the storage does not hold exactly mlab_rows_needed rows",
    c"the output does not hold exactly width * height pixels",
    c"a pixel lies outside the framebuffer",
    c"fragment color is NaN",
    c"fragment color is infinite",
    c"fragment color is negative",
    c"premultiplied fragment color is above 1",
    c"fragment alpha is NaN",
    c"fragment alpha is outside [0, 1]",
    c"fragment depth is NaN",
    c"fragment depth is infinite",
    c"internal error in mlab (a caught panic): clear the framebuffer",
];

/// A static, NUL-terminated English message for a status code (any `int`: an unknown code
/// gets "unknown mlab status code"). Never null; do not free it.
#[unsafe(no_mangle)]
pub extern "C" fn mlab_error_message(status: c_int) -> *const c_char {
    usize::try_from(status)
        .ok()
        .and_then(|i| MESSAGES.get(i))
        .map_or(c"unknown mlab status code".as_ptr(), |m| m.as_ptr())
}

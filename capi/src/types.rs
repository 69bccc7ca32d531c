//! The plain ABI types: the method, arithmetic and background kinds (`u32` constants, so that
//! a value out of range from C is an error, not undefined behaviour), the background, and
//! the row of storage.

use mlab::Row;

/// A method: `MLAB_METHOD_MLAB` or `MLAB_METHOD_HYBRID` (any other value is
/// `MLAB_STATUS_INVALID_ARGUMENT`).
pub type MlabMethod = u32;
/// Multi-Layer Alpha Blending: `layers` rows per pixel (`M`).
pub const MLAB_METHOD_MLAB: MlabMethod = 0;
/// Hybrid Transparency: `layers` head rows per pixel (`K`) and a tail (one more row slot).
pub const MLAB_METHOD_HYBRID: MlabMethod = 1;

/// An arithmetic: `MLAB_ARITHMETIC_UNBIASED` (the default) or `MLAB_ARITHMETIC_PAPER`.
pub type MlabArithmetic = u32;
/// The default arithmetic (`mlab::Unbiased`): dithered merge and faint-fragment quantization,
/// the 13/13/13/14/11-bit HT tail.
pub const MLAB_ARITHMETIC_UNBIASED: MlabArithmetic = 0;
/// The paper's arithmetic (`mlab::Paper`): round to nearest, the 10/16/16-bit HT tail.
pub const MLAB_ARITHMETIC_PAPER: MlabArithmetic = 1;

/// A background kind: `MLAB_BACKGROUND_TRANSPARENT` or `MLAB_BACKGROUND_OPAQUE`.
pub type MlabBackgroundKind = u32;
/// Nothing behind: the resolve writes premultiplied RGBA (`alpha = 1 - prod T`).
pub const MLAB_BACKGROUND_TRANSPARENT: MlabBackgroundKind = 0;
/// An opaque color behind (Eq. 6 of the paper); the written alpha is 1.
pub const MLAB_BACKGROUND_OPAQUE: MlabBackgroundKind = 1;

/// What the resolves composite over. `rgb` (linear) is read only for
/// `MLAB_BACKGROUND_OPAQUE`; it is used as given (not checked, as in the Rust API).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MlabBackground {
    /// `MLAB_BACKGROUND_TRANSPARENT` or `MLAB_BACKGROUND_OPAQUE`.
    pub kind: MlabBackgroundKind,
    /// The opaque background's linear R, G, B.
    pub rgb: [f32; 3],
}

/// One row of storage: 8 bytes, 8-byte aligned. Storage is an array of
/// `mlab_rows_needed` of these, owned by the caller; its contents are the kernel's (the
/// layout is documented in the header's opening comment and in `docs/layout.md`), and need
/// no initialization before `mlab_framebuffer_init`, which clears them.
#[repr(C, align(8))]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MlabRow {
    /// The row's bytes: premultiplied R, G, B and transmittance as unorm8, then the depth as
    /// a little-endian f32 (in an HT tail slot: the tail's bytes).
    pub bytes: [u8; 8],
}

const _: () = assert!(size_of::<MlabRow>() == size_of::<Row>() && align_of::<MlabRow>() == align_of::<Row>());

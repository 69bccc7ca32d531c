//! The C API of the `mlab` kernel: the run-time framebuffer (`mlab::DynFramebuffer`: MLAB or
//! HT, 1 to 8 rows, either arithmetic) over storage the caller owns, as `extern "C"` functions
//! with error codes. The header `include/mlab.h` is generated from this file by cbindgen
//! (`tests/header.rs` fails when it differs); `docs/c.md` is the guide (build, link,
//! ownership, threads, cost).
//!
//! # The state: a caller-allocated struct over caller-owned storage
//!
//! `MlabFramebuffer` is a small `#[repr(C)]` struct (32 bytes on 64-bit targets) that the
//! caller declares (on the stack, inside its own renderer struct) and
//! `mlab_framebuffer_init` fills: a pointer to the storage, its length in rows, the size,
//! the method and the arithmetic. It owns nothing; the rows are the caller's
//! (`mlab_rows_needed` says how many). Chosen over an opaque heap handle because the kernel
//! allocates nothing and this crate does not either: no `malloc` inside, no `free` to
//! forget, nothing to leak, and the state can live wherever the caller's other state lives.
//! It is a plain view: copying it is allowed (the copies are views of the same rows).
//!
//! Every call rebuilds the kernel's borrowed view (the span grid that `DynFramebuffer` would
//! hold, `SpanFramebuffer<M, A>` or `HybridSpanFramebuffer<K, A>` over `&mut [Row]`) from the
//! pointer and length for the duration of the call, and drops it before returning: no Rust
//! reference outlives a call, so the only lifetime rule is the C
//! one (the rows stay valid, and are not used by anything else during a call). What that
//! rebuild costs per insert is measured in `docs/performance.md` ("C API").
//!
//! # What is checked, and what the caller guarantees
//!
//! Checked on every call, each with its own `MlabStatus`: null pointers, pointers not
//! aligned for their type, a framebuffer struct that was not initialized (its magic word),
//! enum values out of range, sizes (zero, overflow, storage and output lengths), pixels
//! outside the framebuffer, invalid fragments (NaN, infinities, ranges). Nothing unwinds into
//! C. A panic (none is expected: the kernel returns errors, on every input) is caught and
//! returned as `MlabStatus::Internal` by every function but the two per-pixel inserts; in
//! those, where the cost per fragment is the point, it aborts the process, as Rust does for
//! any panic that reaches an `extern "C"` function.
//!
//! Not checkable, so guaranteed by the caller: every non-null pointer points to memory that
//! is valid for the length passed (`storage_rows` rows, `out_pixels` pixels, `count`
//! fragments), readable and, for outputs and storage, writable; no other thread reads or
//! writes the same rows during a call that writes them, nor writes them during a call that
//! reads them (different bands, `mlab_framebuffer_band`, may be used at the same time);
//! the storage outlives every use of the framebuffer struct.
#![deny(unsafe_op_in_unsafe_fn)]
#![warn(missing_docs)]

use core::ffi::{c_char, c_int};
use std::panic::{AssertUnwindSafe, catch_unwind};

use mlab::framebuffer::{Ht, Mlab, Pixel};
use mlab::glam::{Vec3, Vec4};
use mlab::half::f16;
use mlab::lanes::FragmentLanes;
use mlab::{
    Background, Fragment, FragmentError, Framebuffer, FramebufferError, Grid, HybridSpanFramebuffer, Layers, Paper,
    Row, SpanBatcher, SpanFramebuffer, Spans, Unbiased,
};

/// The version of this C API. Additions (new functions, new status codes at the end) keep
/// it; a changed signature or layout raises it. Compare `mlab_abi_version` (the library
/// linked) with this constant (the header compiled against).
pub const MLAB_ABI_VERSION: u32 = 1;

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
    c"the framebuffer struct was not initialized by mlab_framebuffer_init",
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

/// A framebuffer: the state `mlab_framebuffer_init` fills, over storage the caller owns.
/// Declare it anywhere (stack, heap, inside another struct); **its fields are private**: read
/// and write none of them. It owns nothing and may be copied (copies view the same rows).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct MlabFramebuffer {
    /// Private: the first row of the storage.
    storage: *mut MlabRow,
    /// Private: rows of storage.
    storage_rows: usize,
    /// Private: width in pixels.
    width: u32,
    /// Private: height in lines.
    height: u32,
    /// Private: `layers - 1 + 8 * method + 16 * arithmetic`.
    kind: u32,
    /// Private: set by a successful init.
    magic: u32,
}

#[cfg(target_pointer_width = "64")]
const _: () = assert!(size_of::<MlabFramebuffer>() == 32 && align_of::<MlabFramebuffer>() == 8);

/// The word that marks an initialized `MlabFramebuffer` ("MLAB").
const MAGIC: u32 = 0x4d4c_4142;

impl MlabFramebuffer {
    const ZEROED: MlabFramebuffer = MlabFramebuffer {
        storage: core::ptr::null_mut(),
        storage_rows: 0,
        width: 0,
        height: 0,
        kind: 0,
        magic: 0,
    };
}

/// Eight fragments of one line of 8 pixels, structure of arrays (lane `i` is pixel
/// `(x + i, y)`), for the span inserts. Reserved for new fields: a keyed span (issue 30's
/// stable fragment key) will be a struct and functions of their own, not a change of this one.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MlabFragmentSpan {
    /// Red per lane (straight or premultiplied, as the function says; linear).
    pub r: [f32; 8],
    /// Green per lane.
    pub g: [f32; 8],
    /// Blue per lane.
    pub b: [f32; 8],
    /// Alpha per lane.
    pub a: [f32; 8],
    /// Depth per lane (smaller is nearer).
    pub depth: [f32; 8],
}

/// One fragment of a batch: its pixel, its straight or premultiplied RGBA (linear) and depth.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MlabPixelFragment {
    /// Column.
    pub x: u32,
    /// Line.
    pub y: u32,
    /// R, G, B, A (straight or premultiplied, as the function says).
    pub rgba: [f32; 4],
    /// Depth (smaller is nearer).
    pub depth: f32,
}

/// Run `f`, catching a panic: no unwinding crosses the C boundary.
#[inline(always)]
fn guard(f: impl FnOnce() -> Result<(), MlabStatus>) -> MlabStatus {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(Ok(())) => MlabStatus::Ok,
        Ok(Err(status)) => status,
        Err(_) => MlabStatus::Internal,
    }
}

/// The kernel's `Layers` of a method and a size (size not checked here).
fn layers_of(method: MlabMethod, layers: u32) -> Result<Layers, MlabStatus> {
    let n = layers as usize;
    match method {
        MLAB_METHOD_MLAB => Ok(Layers::Mlab(n)),
        MLAB_METHOD_HYBRID => Ok(Layers::Hybrid(n)),
        _ => Err(MlabStatus::InvalidArgument),
    }
}

/// Rows of storage of a framebuffer, every argument checked (sizes 0 refused).
fn rows_needed(method: MlabMethod, layers: u32, width: u32, height: u32) -> Result<usize, MlabStatus> {
    let l = layers_of(method, layers)?;
    if width == 0 || height == 0 {
        return Err(MlabStatus::ZeroSize);
    }
    let rows = l.rows_needed(width, height)?;
    // The storage must be addressable as one Rust slice: at most isize::MAX bytes.
    if rows > isize::MAX as usize / size_of::<Row>() {
        return Err(MlabStatus::SizeOverflow);
    }
    Ok(rows)
}

/// Check a pointer: not null, aligned to `align` bytes.
#[inline(always)]
fn check_ptr<T>(p: *const T, align: usize) -> Result<(), MlabStatus> {
    if p.is_null() {
        Err(MlabStatus::NullPointer)
    } else if !(p as usize).is_multiple_of(align) {
        Err(MlabStatus::Misaligned)
    } else {
        Ok(())
    }
}

/// The initialized framebuffer struct behind `fb`.
///
/// # Safety
/// `fb` is null or points to a readable `MlabFramebuffer` (initialized or not).
#[inline(always)]
unsafe fn state<'s>(fb: *const MlabFramebuffer) -> Result<&'s MlabFramebuffer, MlabStatus> {
    check_ptr(fb, align_of::<MlabFramebuffer>())?;
    // SAFETY: non-null and aligned (checked); readable (the caller's guarantee).
    let s = unsafe { &*fb };
    if s.magic != MAGIC {
        return Err(MlabStatus::NotInitialized);
    }
    Ok(s)
}

/// `$body` with `$fb` bound to the kernel's typed span grid over the rows of `$s` (an
/// initialized [`MlabFramebuffer`]): `SpanFramebuffer<M, A>` or `HybridSpanFramebuffer<K, A>`,
/// the grids that `DynFramebuffer` dispatches to, chosen by one `match` on the kind stored
/// at init. The view is rebuilt for the call (`Grid::new`: a length check) and dropped at
/// its end. Not `DynFramebuffer::new` itself: with its choice of the variant from `Layers`
/// (16 comparisons) and then its `match`, a per-pixel insert through this API ran 373
/// instructions, against 313 with this macro and 233 for the Rust loop over
/// `DynFramebuffer::insert` (MLAB 4, callgrind; `docs/performance.md`, "C API"). The
/// per-pixel inserts go further (`insert_one`).
macro_rules! with_grid {
    ($s:expr, $fb:ident => $body:expr) => {
        with_grid!(@arms $s, $fb, $body;
            0 SpanFramebuffer<'_, 1, Unbiased>, 1 SpanFramebuffer<'_, 2, Unbiased>,
            2 SpanFramebuffer<'_, 3, Unbiased>, 3 SpanFramebuffer<'_, 4, Unbiased>,
            4 SpanFramebuffer<'_, 5, Unbiased>, 5 SpanFramebuffer<'_, 6, Unbiased>,
            6 SpanFramebuffer<'_, 7, Unbiased>, 7 SpanFramebuffer<'_, 8, Unbiased>,
            8 HybridSpanFramebuffer<'_, 1, Unbiased>, 9 HybridSpanFramebuffer<'_, 2, Unbiased>,
            10 HybridSpanFramebuffer<'_, 3, Unbiased>, 11 HybridSpanFramebuffer<'_, 4, Unbiased>,
            12 HybridSpanFramebuffer<'_, 5, Unbiased>, 13 HybridSpanFramebuffer<'_, 6, Unbiased>,
            14 HybridSpanFramebuffer<'_, 7, Unbiased>, 15 HybridSpanFramebuffer<'_, 8, Unbiased>,
            16 SpanFramebuffer<'_, 1, Paper>, 17 SpanFramebuffer<'_, 2, Paper>,
            18 SpanFramebuffer<'_, 3, Paper>, 19 SpanFramebuffer<'_, 4, Paper>,
            20 SpanFramebuffer<'_, 5, Paper>, 21 SpanFramebuffer<'_, 6, Paper>,
            22 SpanFramebuffer<'_, 7, Paper>, 23 SpanFramebuffer<'_, 8, Paper>,
            24 HybridSpanFramebuffer<'_, 1, Paper>, 25 HybridSpanFramebuffer<'_, 2, Paper>,
            26 HybridSpanFramebuffer<'_, 3, Paper>, 27 HybridSpanFramebuffer<'_, 4, Paper>,
            28 HybridSpanFramebuffer<'_, 5, Paper>, 29 HybridSpanFramebuffer<'_, 6, Paper>,
            30 HybridSpanFramebuffer<'_, 7, Paper>, 31 HybridSpanFramebuffer<'_, 8, Paper>)
    };
    (@arms $s:expr, $fb:ident, $body:expr; $($k:literal $t:ty),*) => {{
        let s: &MlabFramebuffer = $s;
        // SAFETY: `storage` was checked non-null and 8-byte aligned by `mlab_framebuffer_init`
        // (or derived from such a pointer by `mlab_framebuffer_band`), and `storage_rows`
        // rows of it fit in isize::MAX bytes; the caller guarantees that these rows are
        // valid, writable and not used elsewhere during this call. Any 8 bytes are a valid
        // `Row` (it is Pod), and `MlabRow` has its size and alignment (asserted above). The
        // slice lives only until this block ends.
        let rows = unsafe { core::slice::from_raw_parts_mut(s.storage.cast::<Row>(), s.storage_rows) };
        match s.kind {
            $($k => {
                #[allow(unused_mut)]
                let mut $fb = <$t>::new(rows, s.width, s.height)?;
                $body
            })*
            _ => Err(MlabStatus::NotInitialized),
        }
    }};
}

/// An output slice of `pixels` elements of `T` at `out`, after checking the pointer
/// (alignment `align`) and that it holds exactly `width * height` pixels.
///
/// # Safety
/// `out`, if non-null, is valid for writes of `pixels` elements of `T` for `'o`, and used by
/// nothing else meanwhile; any bit pattern is a valid `T`.
#[inline(always)]
unsafe fn output<'o, T>(
    s: &MlabFramebuffer,
    out: *mut T,
    pixels: usize,
    align: usize,
) -> Result<&'o mut [T], MlabStatus> {
    check_ptr(out, align)?;
    if pixels as u64 != s.width as u64 * s.height as u64 {
        return Err(MlabStatus::OutputLength);
    }
    if pixels > isize::MAX as usize / size_of::<T>() {
        return Err(MlabStatus::SizeOverflow);
    }
    // SAFETY: non-null, aligned (checked), at most isize::MAX bytes (checked); valid and
    // exclusive for `pixels` elements by the caller's guarantee; any bits are a valid `T`.
    Ok(unsafe { core::slice::from_raw_parts_mut(out, pixels) })
}

/// The kernel's background.
fn background(bg: MlabBackground) -> Result<Background, MlabStatus> {
    match bg.kind {
        MLAB_BACKGROUND_TRANSPARENT => Ok(Background::Transparent),
        MLAB_BACKGROUND_OPAQUE => Ok(Background::Opaque(Vec3::from_array(bg.rgb))),
        _ => Err(MlabStatus::InvalidArgument),
    }
}

/// The version of the C API of this library (`MLAB_ABI_VERSION` when it was built).
#[unsafe(no_mangle)]
pub extern "C" fn mlab_abi_version() -> u32 {
    MLAB_ABI_VERSION
}

/// A static, NUL-terminated English message for a status code (any `int`: an unknown code
/// gets "unknown mlab status code"). Never null; do not free it.
#[unsafe(no_mangle)]
pub extern "C" fn mlab_error_message(status: c_int) -> *const c_char {
    usize::try_from(status)
        .ok()
        .and_then(|i| MESSAGES.get(i))
        .map_or(c"unknown mlab status code".as_ptr(), |m| m.as_ptr())
}

/// Writes to `*rows` the rows of storage (`MlabRow`, 8 bytes each) of a framebuffer of
/// `width x height` pixels: `ceil(width / 8) * 8 * height * R`, `R = layers` for MLAB and
/// `layers + 1` for HT (pixels are stored in 8-pixel spans). `layers` is 1 to 8; width and
/// height are at least 1. On error `*rows` is unchanged.
///
/// # Safety
/// `rows` is null or valid for a write of one `size_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlab_rows_needed(
    method: MlabMethod,
    layers: u32,
    width: u32,
    height: u32,
    rows: *mut usize,
) -> MlabStatus {
    guard(|| {
        check_ptr(rows, align_of::<usize>())?;
        let n = rows_needed(method, layers, width, height)?;
        // SAFETY: non-null and aligned (checked), writable (the caller's guarantee).
        unsafe { rows.write(n) };
        Ok(())
    })
}

/// Fills `*fb` with a framebuffer of `width x height` pixels over `storage` (exactly
/// `mlab_rows_needed` rows, 8-byte aligned: `malloc` and `calloc` memory is), in the
/// method, size and arithmetic given, and clears it (every pixel empty). `storage` need not
/// be initialized. On error after `fb` was checked, `*fb` is marked uninitialized (later
/// calls with it return `MLAB_STATUS_NOT_INITIALIZED`) and the storage is not touched.
///
/// # Safety
/// `fb` is null or valid for a write of one `MlabFramebuffer`; `storage` is null or valid
/// for reads and writes of `storage_rows` rows, now and for every later call with `*fb` (or
/// a copy, or a band of it), and not used by anything else during those calls.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlab_framebuffer_init(
    fb: *mut MlabFramebuffer,
    method: MlabMethod,
    layers: u32,
    arithmetic: MlabArithmetic,
    storage: *mut MlabRow,
    storage_rows: usize,
    width: u32,
    height: u32,
) -> MlabStatus {
    guard(|| {
        check_ptr(fb, align_of::<MlabFramebuffer>())?;
        // SAFETY: non-null and aligned (checked); writable (the caller's guarantee).
        unsafe { fb.write(MlabFramebuffer::ZEROED) };
        if arithmetic > MLAB_ARITHMETIC_PAPER {
            return Err(MlabStatus::InvalidArgument);
        }
        let expected = rows_needed(method, layers, width, height)?;
        check_ptr(storage, align_of::<MlabRow>())?;
        if storage_rows != expected {
            return Err(MlabStatus::StorageLength);
        }
        let state = MlabFramebuffer {
            storage,
            storage_rows,
            width,
            height,
            // In 0..32: method is 0 or 1, layers 1 to 8, arithmetic 0 or 1 (checked above).
            kind: (layers - 1) | method << 3 | arithmetic << 4,
            magic: MAGIC,
        };
        with_grid!(&state, f => {
            f.clear();
            Ok::<(), MlabStatus>(())
        })?;
        // SAFETY: as above.
        unsafe { fb.write(state) };
        Ok(())
    })
}

/// Fills `*band` with a view of lines `first_line .. first_line + lines` of `*fb` (the same
/// width, method and arithmetic; its line 0 is `first_line` of `fb`), for another thread:
/// bands that do not overlap may be used at the same time, one thread each. The rows are
/// not changed (no clear). On error after `band` was checked, `*band` is marked
/// uninitialized.
///
/// # Safety
/// `fb` is null or points to a readable `MlabFramebuffer`; `band` is null or valid for a
/// write of one, and is not `fb`'s struct in use by another thread.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlab_framebuffer_band(
    fb: *const MlabFramebuffer,
    first_line: u32,
    lines: u32,
    band: *mut MlabFramebuffer,
) -> MlabStatus {
    guard(|| {
        // SAFETY: the caller's guarantee on `fb`.
        let s = *unsafe { state(fb) }?;
        check_ptr(band, align_of::<MlabFramebuffer>())?;
        // SAFETY: non-null and aligned (checked); writable (the caller's guarantee).
        unsafe { band.write(MlabFramebuffer::ZEROED) };
        if lines == 0 {
            return Err(MlabStatus::ZeroSize);
        }
        if first_line as u64 + lines as u64 > s.height as u64 {
            return Err(MlabStatus::OutOfBounds);
        }
        // Spans store lines one after the other: a band is a contiguous run of rows.
        let line_rows = rows_needed(s.kind >> 3 & 1, (s.kind & 7) + 1, s.width, 1)?;
        if line_rows.checked_mul(s.height as usize) != Some(s.storage_rows) {
            return Err(MlabStatus::NotInitialized);
        }
        // Both at most `storage_rows` (checked just above): no overflow.
        let offset = first_line as usize * line_rows;
        let rows = lines as usize * line_rows;
        let sub = MlabFramebuffer {
            // `wrapping_add`: no dereference here; in bounds of the storage (checked above),
            // so the pointer keeps the storage's provenance and alignment.
            storage: s.storage.wrapping_add(offset),
            storage_rows: rows,
            height: lines,
            ..s
        };
        // SAFETY: as above.
        unsafe { band.write(sub) };
        Ok(())
    })
}

/// Clears every pixel of `*fb` (empty rows, empty HT tails): the start of a frame.
///
/// # Safety
/// `fb` is null or points to a readable `MlabFramebuffer` whose storage satisfies the
/// guarantees of `mlab_framebuffer_init`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlab_framebuffer_clear(fb: *mut MlabFramebuffer) -> MlabStatus {
    guard(|| {
        // SAFETY: the caller's guarantee on `fb`.
        let s = unsafe { state(fb) }?;
        with_grid!(s, f => {
            f.clear();
            Ok(())
        })
    })
}

/// One fragment into the pixel of a typed grid: straight or premultiplied color (`S`),
/// validated, then inserted.
///
/// The per-pixel inserts are the one place where the cost of the boundary is paid per
/// fragment, so they are written for it (MLAB 4, callgrind, against 233 instructions per
/// fragment for the Rust loop over `DynFramebuffer::insert`): the exported function checks
/// the state and calls the typed insert of its kind through a table (`insert_one`), with
/// the color as scalars in registers all the way, 277 instructions. Through `guard` and
/// `with_grid!` (a closure called by `catch_unwind`, the fragment validated outside it and
/// read back through memory, and 32 inlined inserts in one function) it ran 313; the same
/// with the table but still inside `guard`, 307.
type InsertTyped = fn(&MlabFramebuffer, u32, u32, f32, f32, f32, f32, f32) -> MlabStatus;

#[allow(clippy::too_many_arguments)]
fn insert_typed<P: Pixel, const S: bool>(
    s: &MlabFramebuffer,
    x: u32,
    y: u32,
    r: f32,
    g: f32,
    b: f32,
    a: f32,
    depth: f32,
) -> MlabStatus {
    let fragment = if S {
        Fragment::straight_rgba([r, g, b, a], depth)
    } else {
        Fragment::premultiplied_rgba([r, g, b, a], depth)
    };
    let fragment = match fragment {
        Ok(f) => f,
        Err(e) => return e.into(),
    };
    // SAFETY: as in `with_grid!`.
    let rows = unsafe { core::slice::from_raw_parts_mut(s.storage.cast::<Row>(), s.storage_rows) };
    let r = Grid::<P, Spans>::new(rows, s.width, s.height).and_then(|mut g| g.insert(x, y, &fragment));
    match r {
        Ok(()) => MlabStatus::Ok,
        Err(e) => e.into(),
    }
}

macro_rules! insert_table {
    ($s:literal) => {
        [
            insert_typed::<Mlab<1, Unbiased>, $s>,
            insert_typed::<Mlab<2, Unbiased>, $s>,
            insert_typed::<Mlab<3, Unbiased>, $s>,
            insert_typed::<Mlab<4, Unbiased>, $s>,
            insert_typed::<Mlab<5, Unbiased>, $s>,
            insert_typed::<Mlab<6, Unbiased>, $s>,
            insert_typed::<Mlab<7, Unbiased>, $s>,
            insert_typed::<Mlab<8, Unbiased>, $s>,
            insert_typed::<Ht<1, Unbiased>, $s>,
            insert_typed::<Ht<2, Unbiased>, $s>,
            insert_typed::<Ht<3, Unbiased>, $s>,
            insert_typed::<Ht<4, Unbiased>, $s>,
            insert_typed::<Ht<5, Unbiased>, $s>,
            insert_typed::<Ht<6, Unbiased>, $s>,
            insert_typed::<Ht<7, Unbiased>, $s>,
            insert_typed::<Ht<8, Unbiased>, $s>,
            insert_typed::<Mlab<1, Paper>, $s>,
            insert_typed::<Mlab<2, Paper>, $s>,
            insert_typed::<Mlab<3, Paper>, $s>,
            insert_typed::<Mlab<4, Paper>, $s>,
            insert_typed::<Mlab<5, Paper>, $s>,
            insert_typed::<Mlab<6, Paper>, $s>,
            insert_typed::<Mlab<7, Paper>, $s>,
            insert_typed::<Mlab<8, Paper>, $s>,
            insert_typed::<Ht<1, Paper>, $s>,
            insert_typed::<Ht<2, Paper>, $s>,
            insert_typed::<Ht<3, Paper>, $s>,
            insert_typed::<Ht<4, Paper>, $s>,
            insert_typed::<Ht<5, Paper>, $s>,
            insert_typed::<Ht<6, Paper>, $s>,
            insert_typed::<Ht<7, Paper>, $s>,
            insert_typed::<Ht<8, Paper>, $s>,
        ]
    };
}

/// The per-pixel inserts by kind (the index `with_grid!` matches on), straight color.
static INSERT_STRAIGHT: [InsertTyped; 32] = insert_table!(true);
/// The per-pixel inserts by kind, premultiplied color.
static INSERT_PREMULTIPLIED: [InsertTyped; 32] = insert_table!(false);

/// A per-pixel insert: the state checked, then a tail call of the typed insert of its kind.
///
/// # Safety
/// As `mlab_insert_straight`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
unsafe fn insert_one(
    table: &[InsertTyped; 32],
    fb: *mut MlabFramebuffer,
    x: u32,
    y: u32,
    r: f32,
    g: f32,
    b: f32,
    a: f32,
    depth: f32,
) -> MlabStatus {
    // SAFETY: the caller's guarantee on `fb`.
    let s = match unsafe { state(fb) } {
        Ok(s) => s,
        Err(e) => return e,
    };
    match table.get(s.kind as usize) {
        Some(insert) => insert(s, x, y, r, g, b, a, depth),
        None => MlabStatus::NotInitialized,
    }
}

/// Inserts one fragment of **straight** (not premultiplied) linear color `r, g, b`, alpha `a`
/// and depth (smaller is nearer) into pixel `(x, y)`: Listing 1 (MLAB) or 2 (HT) of the
/// paper, quantized by the framebuffer's arithmetic. Refused, nothing changed: an invalid
/// fragment (NaN, infinite, negative color, alpha outside `[0, 1]`, `color * alpha` above
/// 1, infinite depth; checked first, the first failing check in the order of `docs/c.md`),
/// then a pixel outside.
///
/// # Safety
/// `fb` is null or points to a readable `MlabFramebuffer` whose storage satisfies the
/// guarantees of `mlab_framebuffer_init`.
#[unsafe(no_mangle)]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn mlab_insert_straight(
    fb: *mut MlabFramebuffer,
    x: u32,
    y: u32,
    r: f32,
    g: f32,
    b: f32,
    a: f32,
    depth: f32,
) -> MlabStatus {
    // SAFETY: the caller's guarantee, passed on.
    unsafe { insert_one(&INSERT_STRAIGHT, fb, x, y, r, g, b, a, depth) }
}

/// `mlab_insert_straight` with **premultiplied** color (`r, g, b` already multiplied by
/// alpha; each at most 1, may exceed alpha: additive light).
///
/// # Safety
/// As `mlab_insert_straight`.
#[unsafe(no_mangle)]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn mlab_insert_premultiplied(
    fb: *mut MlabFramebuffer,
    x: u32,
    y: u32,
    r: f32,
    g: f32,
    b: f32,
    a: f32,
    depth: f32,
) -> MlabStatus {
    // SAFETY: the caller's guarantee, passed on.
    unsafe { insert_one(&INSERT_PREMULTIPLIED, fb, x, y, r, g, b, a, depth) }
}

/// A span insert of fragments (straight color or not).
///
/// # Safety
/// As `mlab_insert_span_straight`.
unsafe fn insert_span(
    fb: *mut MlabFramebuffer,
    x: u32,
    y: u32,
    fragments: *const MlabFragmentSpan,
    mask: u8,
    refused: *mut u8,
    straight: bool,
) -> MlabStatus {
    guard(|| {
        // SAFETY: the caller's guarantee on `fb`.
        let s = unsafe { state(fb) }?;
        check_ptr(fragments, align_of::<MlabFragmentSpan>())?;
        check_ptr(refused, 1)?;
        // SAFETY: non-null, aligned (checked), readable (the caller's guarantee); a copy.
        let span = unsafe { fragments.read() };
        let lanes = FragmentLanes {
            color: [span.r, span.g, span.b],
            alpha: span.a,
            depth: span.depth,
            key: None,
        };
        let invalid = with_grid!(s, f => {
            let r = if straight {
                f.insert_span_straight(x, y, &lanes, mask)
            } else {
                f.insert_span_fragments(x, y, &lanes, mask)
            };
            r.map_err(MlabStatus::from)
        })?;
        // SAFETY: non-null (checked), writable (the caller's guarantee).
        unsafe { refused.write(invalid.0) };
        if invalid.0 == 0 {
            return Ok(());
        }
        // The first refused lane's reason, by the scalar constructor (the same checks).
        let i = invalid.0.trailing_zeros() as usize;
        let rgba = [span.r[i], span.g[i], span.b[i], span.a[i]];
        let one = if straight {
            Fragment::straight_rgba(rgba, span.depth[i])
        } else {
            Fragment::premultiplied_rgba(rgba, span.depth[i])
        };
        match one {
            Err(e) => Err(e.into()),
            Ok(_) => Err(MlabStatus::Internal),
        }
    })
}

/// Inserts the lanes of `*fragments` that are on in `mask` (bit `i`: pixel `(x + i, y)`),
/// straight color, 8 at a time: byte-identical to `mlab_insert_straight` lane by lane, in
/// lane order. `x` need not be a multiple of 8; every lane that is on must lie inside
/// (otherwise `MLAB_STATUS_OUT_OF_BOUNDS` and nothing changes). `*refused` gets the mask of
/// the lanes that were on and held an invalid fragment: these are skipped, the valid lanes
/// are inserted, and the status is the first refused lane's fragment error (0 refused:
/// `MLAB_STATUS_OK`). On any other error `*refused` is unchanged.
///
/// # Safety
/// `fb` as for `mlab_insert_straight`; `fragments` is null or valid for a read of one
/// `MlabFragmentSpan`; `refused` is null or valid for a write of one byte.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlab_insert_span_straight(
    fb: *mut MlabFramebuffer,
    x: u32,
    y: u32,
    fragments: *const MlabFragmentSpan,
    mask: u8,
    refused: *mut u8,
) -> MlabStatus {
    // SAFETY: the caller's guarantee, passed on.
    unsafe { insert_span(fb, x, y, fragments, mask, refused, true) }
}

/// `mlab_insert_span_straight` with premultiplied color.
///
/// # Safety
/// As `mlab_insert_span_straight`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlab_insert_span_premultiplied(
    fb: *mut MlabFramebuffer,
    x: u32,
    y: u32,
    fragments: *const MlabFragmentSpan,
    mask: u8,
    refused: *mut u8,
) -> MlabStatus {
    // SAFETY: the caller's guarantee, passed on.
    unsafe { insert_span(fb, x, y, fragments, mask, refused, false) }
}

/// `events` through a span batcher over `fb`, stopping at the first refused one: how many
/// went in, and the status. A function of its own (not inlined into each arm of
/// `with_grid!`), so that one batcher (about 44 KiB) is on the stack, not one per arm.
#[inline(never)]
fn batch_into<F: Framebuffer>(
    fb: &mut F,
    events: &[MlabPixelFragment],
    straight: bool,
) -> Result<(usize, Result<(), MlabStatus>), MlabStatus> {
    let mut batch = SpanBatcher::new(fb);
    for (i, e) in events.iter().enumerate() {
        let one = if straight {
            Fragment::straight_rgba(e.rgba, e.depth)
        } else {
            Fragment::premultiplied_rgba(e.rgba, e.depth)
        };
        let r = one
            .map_err(MlabStatus::from)
            .and_then(|v| Ok(batch.insert(e.x, e.y, &v)?));
        if let Err(st) = r {
            batch.finish()?;
            return Ok((i, Err(st)));
        }
    }
    batch.finish()?;
    Ok((events.len(), Ok(())))
}

/// A batch of fragments through the kernel's span batcher.
///
/// # Safety
/// As `mlab_insert_batch_straight`.
unsafe fn insert_batch(
    fb: *mut MlabFramebuffer,
    fragments: *const MlabPixelFragment,
    count: usize,
    inserted: *mut usize,
    straight: bool,
) -> MlabStatus {
    guard(|| {
        // SAFETY: the caller's guarantee on `fb`.
        let s = unsafe { state(fb) }?;
        check_ptr(fragments, align_of::<MlabPixelFragment>())?;
        check_ptr(inserted, align_of::<usize>())?;
        if count > isize::MAX as usize / size_of::<MlabPixelFragment>() {
            return Err(MlabStatus::SizeOverflow);
        }
        // SAFETY: non-null, aligned, at most isize::MAX bytes (checked); readable for
        // `count` fragments and not written during the call (the caller's guarantee).
        let events = unsafe { core::slice::from_raw_parts(fragments, count) };
        let (done, status) = with_grid!(s, f => batch_into(&mut f, events, straight))?;
        // SAFETY: non-null and aligned (checked), writable (the caller's guarantee).
        unsafe { inserted.write(done) };
        status
    })
}

/// Inserts `count` fragments (straight color) in array order, each into its own pixel,
/// through the kernel's span batcher (fragments gathered into 8-pixel span inserts inside
/// the call): byte-identical to calling `mlab_insert_straight` on each in order, faster
/// for MLAB when the fragments of a line come together (`docs/performance.md`). Stops at
/// the first fragment that is invalid or outside: `*inserted` is then its index (the
/// fragments before it are in the framebuffer, it and those after it are not) and the
/// status says why; otherwise `*inserted = count`. Uses about 44 KiB of stack.
///
/// # Safety
/// `fb` as for `mlab_insert_straight`; `fragments` is null or valid for reads of `count`
/// fragments; `inserted` is null or valid for a write of one `size_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlab_insert_batch_straight(
    fb: *mut MlabFramebuffer,
    fragments: *const MlabPixelFragment,
    count: usize,
    inserted: *mut usize,
) -> MlabStatus {
    // SAFETY: the caller's guarantee, passed on.
    unsafe { insert_batch(fb, fragments, count, inserted, true) }
}

/// `mlab_insert_batch_straight` with premultiplied color.
///
/// # Safety
/// As `mlab_insert_batch_straight`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlab_insert_batch_premultiplied(
    fb: *mut MlabFramebuffer,
    fragments: *const MlabPixelFragment,
    count: usize,
    inserted: *mut usize,
) -> MlabStatus {
    // SAFETY: the caller's guarantee, passed on.
    unsafe { insert_batch(fb, fragments, count, inserted, false) }
}

/// Resolves every pixel into RGBA8 (`out`: `4 * out_pixels` bytes, `out_pixels = width *
/// height`, row-major, R, G, B, A per pixel): the kernel's integer resolve (the same bytes in
/// scalar code, every SIMD backend and its WGSL twin), linear unorm8 (not sRGB), over
/// `background` (opaque: alpha 255; transparent: premultiplied).
///
/// # Safety
/// `fb` as for `mlab_insert_straight` (the rows are read); `out` is null or valid for
/// writes of `4 * out_pixels` bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlab_resolve_rgba8(
    fb: *const MlabFramebuffer,
    background: MlabBackground,
    out: *mut u8,
    out_pixels: usize,
) -> MlabStatus {
    guard(|| {
        // SAFETY: the caller's guarantee on `fb`.
        let s = unsafe { state(fb) }?;
        let bg = self::background(background)?;
        // SAFETY: the caller's guarantee on `out`; `[u8; 4]` takes any bits.
        let out = unsafe { output(s, out.cast::<[u8; 4]>(), out_pixels, 1) }?;
        with_grid!(s, f => Ok(f.resolve_rgba8(out, bg)?))
    })
}

/// Resolves every pixel into f32 RGBA (`out`: `4 * out_pixels` floats, **16-byte aligned**,
/// row-major): the kernel's f32 resolve (Eq. 5 and 6), linear, over `background`.
///
/// # Safety
/// As `mlab_resolve_rgba8`, `out` valid for writes of `4 * out_pixels` floats.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlab_resolve_f32(
    fb: *const MlabFramebuffer,
    background: MlabBackground,
    out: *mut f32,
    out_pixels: usize,
) -> MlabStatus {
    const { assert!(size_of::<Vec4>() == 16 && align_of::<Vec4>() <= 16) };
    guard(|| {
        // SAFETY: the caller's guarantee on `fb`.
        let s = unsafe { state(fb) }?;
        let bg = self::background(background)?;
        // SAFETY: the caller's guarantee on `out`; a `Vec4` is four f32 (asserted above:
        // 16 bytes, alignment at most the 16 checked), any bits valid.
        let out = unsafe { output(s, out.cast::<Vec4>(), out_pixels, 16) }?;
        with_grid!(s, f => Ok(f.resolve_into(out, bg)?))
    })
}

/// Resolves every pixel into RGBA16F (`out`: `4 * out_pixels` IEEE binary16 values as
/// `uint16_t`, 2-byte aligned, row-major): the f32 resolve rounded to nearest half, linear.
///
/// # Safety
/// As `mlab_resolve_rgba8`, `out` valid for writes of `4 * out_pixels` `uint16_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlab_resolve_rgba16f(
    fb: *const MlabFramebuffer,
    background: MlabBackground,
    out: *mut u16,
    out_pixels: usize,
) -> MlabStatus {
    const { assert!(size_of::<[f16; 4]>() == 8 && align_of::<[f16; 4]>() == 2) };
    guard(|| {
        // SAFETY: the caller's guarantee on `fb`.
        let s = unsafe { state(fb) }?;
        let bg = self::background(background)?;
        // SAFETY: the caller's guarantee on `out`; `f16` is a transparent u16 (any bits).
        let out = unsafe { output(s, out.cast::<[f16; 4]>(), out_pixels, 2) }?;
        with_grid!(s, f => Ok(f.resolve_rgba16f(out, bg)?))
    })
}

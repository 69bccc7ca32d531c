//! The C API of the `mlab` kernel: the run-time framebuffer (`mlab::DynFramebuffer`: MLAB or
//! HT, 1 to 8 rows, either arithmetic) over storage the caller owns, as `extern "C"` functions
//! with error codes. The header `include/mlab.h` is generated from this crate by cbindgen (from
//! this file and the modules it declares, in their order; `tests/header.rs` fails when it
//! differs); `docs/c.md` is the guide (build, link,
//! ownership, threads, cost).
//!
//! # The state: a caller-allocated struct over caller-owned storage
//!
//! `MlabFramebuffer` is a small `#[repr(C)]` struct (32 bytes on 64-bit targets) that the
//! caller declares (on the stack, inside its own renderer struct) and
//! `mlab_framebuffer_init` fills: a pointer to the storage, its length in rows, the size,
//! the method and the arithmetic, and for a band (`mlab_framebuffer_band`) the id of its
//! first pixel in the whole framebuffer, which the dithers hash. It owns nothing; the rows
//! are the caller's (`mlab_rows_needed` says how many). Chosen over an opaque heap handle
//! because the kernel allocates nothing and this crate does not either: no `malloc` inside,
//! no `free` to forget, nothing to leak, and the state can live wherever the caller's other
//! state lives. It is a plain view: copying it is allowed (the copies are views of the same
//! rows).
//!
//! Every call rebuilds the kernel's borrowed view (the span grid that `DynFramebuffer` would
//! hold, `SpanFramebuffer<M, A>` or `HybridSpanFramebuffer<K, A>` over `&mut [Row]`, with the
//! band's first pixel id: `Grid::with_first_pixel`) from the pointer and length for the
//! duration of the call, and drops it before returning: no Rust reference outlives a call,
//! so the only lifetime rule is the C one (the rows stay valid, and are not used by anything
//! else during a call). What that rebuild costs per insert is measured in
//! `docs/performance.md` ("C API").
//!
//! # What is checked, and what the caller guarantees
//!
//! Checked on every call, each with its own `MlabStatus`: null pointers, pointers not
//! aligned for their type, a framebuffer struct that was not initialized or was changed since
//! (the checksum of its fields),
//! enum values out of range, sizes (zero, overflow, storage and output lengths), pixels
//! outside the framebuffer, invalid fragments (NaN, infinities, ranges). Nothing unwinds into
//! C. A panic (none is expected: the kernel returns errors, on every input) is caught and
//! returned as `MlabStatus::Internal` by every function but the four per-pixel inserts; in
//! those, where the cost per fragment is the point, it aborts the process, as Rust does for
//! any panic that reaches an `extern "C"` function.
//!
//! Not checkable, so guaranteed by the caller: every non-null pointer points to memory that
//! is valid for the length passed (`storage_rows` rows, `out_pixels` pixels, `count`
//! fragments), readable and, for outputs and storage, writable; no other thread reads or
//! writes the same rows during a call that writes them, nor writes them during a call that
//! reads them (different bands, `mlab_framebuffer_band`, may be used at the same time);
//! the storage outlives every use of the framebuffer struct.
//!
//! # The modules, one concept each
//!
//! `status` (the status codes and their texts), `types` (the method, arithmetic and
//! background kinds, the background, the row), `fragment` (the fragment structs of the span
//! and batch inserts, keyed or not, and the validation of one fragment), `boundary` (the
//! panic guard and the pointer check every function does), `framebuffer` (the framebuffer
//! struct, its checks, and the kernel's span grid rebuilt over its rows), `lifecycle`
//! (storage size, init, band, clear), `insert` (per pixel, span, batch) and `resolve`. Each
//! imports only modules before it in that list; this file declares them and re-exports
//! the C API. The order of the `mod` lines is the order of the functions in the header.
//!
//! The keyed inserts (`mlab_insert_*_keyed`) and the unkeyed ones share one body per insert
//! kind (the key a type parameter of it); their `extern "C"` functions stay written out one
//! by one, each a single call, because cbindgen reads the source without expanding macros:
//! a function that a macro wrote would be missing from the header.
#![deny(unsafe_op_in_unsafe_fn)]
#![warn(missing_docs)]

// One `mod` a paragraph: in this order (the order of the header), not sorted by rustfmt.
mod status;

mod types;

mod fragment;

mod boundary;

mod framebuffer;

mod lifecycle;

mod insert;

mod resolve;

pub use fragment::{MlabFragmentSpan, MlabFragmentSpanKeyed, MlabPixelFragment, MlabPixelFragmentKeyed};
pub use framebuffer::MlabFramebuffer;
pub use insert::batch::{
    mlab_insert_batch_premultiplied, mlab_insert_batch_premultiplied_keyed, mlab_insert_batch_straight,
    mlab_insert_batch_straight_keyed,
};
pub use insert::pixel::{
    mlab_insert_premultiplied, mlab_insert_premultiplied_keyed, mlab_insert_straight, mlab_insert_straight_keyed,
};
pub use insert::span::{
    mlab_insert_span_premultiplied, mlab_insert_span_premultiplied_keyed, mlab_insert_span_straight,
    mlab_insert_span_straight_keyed,
};
pub use lifecycle::{mlab_framebuffer_band, mlab_framebuffer_clear, mlab_framebuffer_init, mlab_rows_needed};
pub use resolve::{mlab_resolve_f32, mlab_resolve_rgba8, mlab_resolve_rgba16f};
pub use status::{MlabStatus, mlab_error_message};
pub use types::{
    MLAB_ARITHMETIC_PAPER, MLAB_ARITHMETIC_UNBIASED, MLAB_BACKGROUND_OPAQUE, MLAB_BACKGROUND_TRANSPARENT,
    MLAB_METHOD_HYBRID, MLAB_METHOD_MLAB, MlabArithmetic, MlabBackground, MlabBackgroundKind, MlabMethod, MlabRow,
};

/// The major version of this library (the crate's version, `MAJOR.MINOR.PATCH`; `tests/header.rs`
/// checks that it is `Cargo.toml`'s). The C API's compatibility is `MLAB_ABI_VERSION`'s.
pub const MLAB_VERSION_MAJOR: u32 = 0;
/// The minor version of this library.
pub const MLAB_VERSION_MINOR: u32 = 1;
/// The patch version of this library.
pub const MLAB_VERSION_PATCH: u32 = 0;

/// The version of this C API, and the number in the shared library's SONAME
/// (`libmlab.so.1`: `build.rs`). Additions (new functions, new status codes at the end) keep
/// it; a changed signature or layout raises it. Compare `mlab_abi_version` (the library
/// linked) with this constant (the header compiled against).
pub const MLAB_ABI_VERSION: u32 = 1;

/// The version of the C API of this library (`MLAB_ABI_VERSION` when it was built).
#[unsafe(no_mangle)]
pub extern "C" fn mlab_abi_version() -> u32 {
    MLAB_ABI_VERSION
}

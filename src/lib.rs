//! # mlab
//!
//! A `no_std`, allocation-free compositing kernel for order-independent transparency:
//! Multi-Layer Alpha Blending (MLAB; Salvi & Vaidyanathan, *Multi-Layer Alpha Blending*,
//! I3D 2014) and Hybrid Transparency (HT; Maule et al. 2013, in the single-pass form of
//! the same paper), over packed 8-byte rows.
//!
//! # Which level for which renderer
//!
//! | your renderer | use | example |
//! |---|---|---|
//! | one pixel, or your own storage per pixel (a shader port, a ray tracer) | [`BlendingArray`], [`Hybrid`] | [pixel](#a-pixel) |
//! | fragments arrive one pixel at a time, in any order, read back per pixel | [`MlabFramebuffer`], [`HybridFramebuffer`] ([`Framebuffer`]) | [framebuffer](#a-framebuffer) |
//! | a rasterizer that emits one pixel at a time (scanline, tile, `euc`-like) | [`SpanBatcher`] over a [`SpanFramebuffer`] (faster than per-pixel inserts for MLAB; `docs/performance.md`) | [batcher](#a-rasterizer-one-pixel-at-a-time) |
//! | a rasterizer that shades 8 pixels of a line at once | [`SpanFramebuffer`], [`HybridSpanFramebuffer`] span inserts | [spans](#a-rasterizer-8-pixels-at-a-time) |
//! | quality chosen at run time (a settings menu) | [`DynFramebuffer`] with [`Layers`] | [run time](#quality-at-run-time) |
//! | code generic over the method and the arrangement | [`Grid`]`<P: Pixel, L: Arrangement>`, of which the four framebuffers are aliases | [`framebuffer`] |
//! | your own span storage, your own loops | [`lanes`]: `mlab_insert_with`, `hybrid_insert`, resolves | [`lanes`] |
//!
//! All framebuffers implement the [`Framebuffer`] trait (bring it into scope: `use
//! mlab::Framebuffer;`): pixel and span inserts, resolves to f32, premultiplied RGBA,
//! RGBA8 and RGBA16F, bands for threads, byte and word views for a GPU upload. The span
//! arrangement is the fast one (inserts and resolves in SIMD lanes without a transpose);
//! the pixel-major one keeps each pixel's rows together (`[Row; M]`).
//!
//! **Colors** are linear everywhere: fragment colors (premultiplied unless a constructor
//! says straight) and every output. [`to_rgba8`] and [`Framebuffer::resolve_rgba8`] write
//! linear unorm8 (the nearest byte of `255 v`; for MLAB `resolve_rgba8` is the integer
//! resolve of `docs/layout.md`, the same bytes on every backend and in a shader), **not**
//! sRGB-encoded bytes: upload them to a linear `Rgba8Unorm` target, or resolve to f32 or
//! RGBA16F and encode for display.
//!
//! **Equal depths**: a fragment goes in front of the rows at its depth (Listing 1's `<=`), so
//! coplanar fragments blend like OVER in submission order, the **later one in front**. A
//! reference that sorts by depth with a stable sort puts the earlier one in front and differs
//! wherever depths tie (`examples/rasterizer.rs` writes the exact answer with this rule).
//!
//! **"Row"** means the paper's 8-byte layer of one pixel ([`Row`]: premultiplied RGB8,
//! transmittance, depth), never a line of the image; lines are `y`.
//!
//! **Errors**: [`Fragment`]'s constructors return [`FragmentError`], framebuffer
//! operations [`FramebufferError`]; both convert into [`Error`], so `?` works in a function
//! returning `Result<_, mlab::Error>`. Span inserts of fragments return the lanes they
//! refused ([`InvalidLanes`], `#[must_use]`).
//!
//! **glam**: the glam types at the API (`Vec3`, `Vec4`) are this crate's glam, re-exported
//! as [`mlab::glam`](glam); write `use mlab::glam::Vec3;`. A renderer on another glam
//! version passes plain arrays ([`Fragment::straight_rgba`], [`Fragment::premultiplied_rgba`],
//! [`FragmentLanes::from_rgba`]).
//!
//! ## A pixel
//!
//! ```
//! use mlab::glam::Vec3;
//! use mlab::{BlendingArray, Fragment};
//!
//! let mut pixel = BlendingArray::<4>::new();
//! // Submitted back to front, red behind blue; MLAB sorts them.
//! pixel.insert(&Fragment::straight(Vec3::new(0.0, 0.0, 1.0), 0.5, 1.0)?);
//! pixel.insert(&Fragment::straight(Vec3::new(1.0, 0.0, 0.0), 0.5, 2.0)?);
//! let color = pixel.resolve().over(Vec3::ONE);
//! // blue*0.5 + red*0.25 + white*0.25
//! assert!((color - Vec3::new(0.5, 0.25, 0.75)).abs().max_element() < 2.0 / 255.0);
//! # Ok::<(), mlab::FragmentError>(())
//! ```
//!
//! ## A framebuffer
//!
//! ```
//! use mlab::{Background, Fragment, Framebuffer, MlabFramebuffer, Row};
//!
//! let (w, h) = (320, 240);
//! let mut storage = vec![Row::EMPTY; MlabFramebuffer::<4>::rows_needed(w, h)?];
//! let mut fb = MlabFramebuffer::<4>::new_cleared(&mut storage, w, h)?;
//! fb.insert(10, 20, &Fragment::straight_rgba([1.0, 0.0, 0.0, 0.5], 2.0)?)?;
//! fb.insert(10, 20, &Fragment::straight_rgba([0.0, 0.0, 1.0, 0.5], 1.0)?)?;
//! let mut out = vec![[0u8; 4]; (w * h) as usize];
//! fb.resolve_rgba8(&mut out, Background::Transparent)?; // premultiplied, linear
//! let alpha = out[20 * 320 + 10][3]; // 1 - 0.5 * 0.5, within one rounding of the merge
//! assert!((191..=192).contains(&alpha));
//! # Ok::<(), mlab::Error>(())
//! ```
//!
//! ## A rasterizer, one pixel at a time
//!
//! ```
//! use mlab::{Background, Fragment, Framebuffer, Row, SpanBatcher, SpanFramebuffer};
//!
//! let (w, h) = (64, 64);
//! let mut storage = vec![Row::EMPTY; SpanFramebuffer::<4>::rows_needed(w, h)?];
//! let mut fb = SpanFramebuffer::<4>::new_cleared(&mut storage, w, h)?;
//! let mut batch = SpanBatcher::new(&mut fb);
//! for y in 8..24 {
//!     for x in 8..40 {
//!         // What your rasterizer emits, pixel by pixel.
//!         batch.insert(x, y, &Fragment::straight_rgba([0.2, 0.8, 0.2, 0.5], 3.0)?)?;
//!     }
//! }
//! batch.finish()?;
//! let mut out = vec![mlab::glam::Vec4::ZERO; (w * h) as usize];
//! fb.resolve_into(&mut out, Background::Opaque(mlab::glam::Vec3::ONE))?;
//! # Ok::<(), mlab::Error>(())
//! ```
//!
//! `examples/rasterizer.rs` is a complete one: a triangle rasterizer, a transparent mesh,
//! a PNG, and the PSNR against the exact A-buffer.
//!
//! ## A rasterizer, 8 pixels at a time
//!
//! ```
//! use mlab::{Framebuffer, FragmentLanes, HybridSpanFramebuffer, Row};
//!
//! let mut storage = vec![Row::EMPTY; HybridSpanFramebuffer::<3>::rows_needed(100, 10)?];
//! let mut fb = HybridSpanFramebuffer::<3>::new_cleared(&mut storage, 100, 10)?;
//! // Straight color per lane, alpha, depth; lane 2 is NaN and is refused.
//! let mut frags = FragmentLanes::from_rgba([[1.0, 0.5, 0.0, 0.5]; 8], [4.0; 8]);
//! frags.depth[2] = f32::NAN;
//! let invalid = fb.insert_span_straight(96, 3, &frags, 0b0000_1111)?; // x = 96..100
//! assert_eq!(invalid, 0b0000_0100);
//! # Ok::<(), mlab::Error>(())
//! ```
//!
//! ## Quality at run time
//!
//! ```
//! use mlab::{DynFramebuffer, Fragment, Framebuffer, Layers, Row};
//!
//! let quality = Layers::Hybrid(3); // or Layers::Mlab(1 to 8)
//! let mut storage = vec![Row::EMPTY; quality.rows_needed(64, 64)?];
//! // `: DynFramebuffer` names the default arithmetic (a default does not drive inference).
//! let mut fb: DynFramebuffer = DynFramebuffer::new_cleared(quality, &mut storage, 64, 64)?;
//! fb.insert(1, 2, &Fragment::premultiplied_rgba([0.1, 0.1, 0.1, 0.2], 1.0)?)?;
//! # Ok::<(), mlab::Error>(())
//! ```
//!
//! # The kernel
//!
//! | type | what | size |
//! |---|---|---|
//! | [`Row`] | premultiplied RGB8 + transmittance T8 + depth f32 | 8 bytes, align 8 |
//! | [`Tail`] | HT tail: color sums 3 x 13 bit, alpha sum 14 bit, count 11 bit | 8 bytes, align 8 |
//! | [`hybrid::PaperTail`] | the paper's HT tail: 3 x 10, 16, 16 bit | 8 bytes, align 8 |
//! | [`BlendingArray<M>`] | MLAB blending array, `M >= 1` rows | `8 * M` bytes |
//! | [`Hybrid<K>`] | HT: `K` head rows + tail | `8 * (K + 1)` bytes |
//! | framebuffers ([`Grid`]), [`SpanBatcher`] | views over caller-owned `&mut [Row]`; a fixed-size batcher | none; about 52 KiB |
//!
//! - [`mlab::insert_with`] is Listing 1 (insert-and-merge), [`hybrid::insert`] is Listing 2,
//!   [`resolve_rows`] is Eq. 5 and [`Resolved::over`] Eq. 6. The module `mlab::mlab` is
//!   named after the method, as `mlab::hybrid` is: its functions are written with the path
//!   (`mlab::mlab::insert_with`), the crate root re-exports its type ([`BlendingArray`]).
//! - Fragments are validated once ([`Fragment`], typed [`FragmentError`]) and quantized once.
//! - The merge is exact unorm8 integer arithmetic, reproducible on any machine and in a
//!   shader, in one of two arithmetics ([`arith`]), a type parameter of every kernel type:
//!   [`Unbiased`] (the default: a dithered merge and dithered faint fragments, no
//!   transmittance stall on many faint layers, and a tail that saturates far later than the
//!   paper's: never on the lab's scenes, on a few pixels of a dense point cloud;
//!   [`Grid::saturated_pixels`] counts them) or [`Paper`] (the paper's
//!   round-to-nearest and 3 x 10-bit tail, bit for bit): `BlendingArray<4>` is
//!   `BlendingArray<4, Unbiased>`; `BlendingArray<4, Paper>` is the paper's.
//!
//! The documents named here (`docs/layout.md`, `docs/algorithm.md`, `docs/performance.md`,
//! `docs/quality.md`) and `CHANGELOG.md` are in the crate's source, beside `src/`.

#![no_std]
#![forbid(unsafe_code)]
#![deny(missing_docs)]
#![warn(clippy::cast_possible_truncation, clippy::cast_sign_loss, clippy::cast_possible_wrap)]

pub mod arith;
pub mod batch;
pub mod error;
pub mod fragment;
pub mod framebuffer;
mod hash;
pub mod hybrid;
pub mod lanes;
pub mod mlab;
pub mod resolve;
pub mod row;
mod tail;
mod unorm;
mod vector;

/// The supertrait that keeps [`Arithmetic`], [`TailFormat`], [`framebuffer::Pixel`] and
/// [`framebuffer::Arrangement`] closed: their lane code implements exactly the kernel's types.
mod sealed {
    pub trait Sealed {}
}

pub use arith::{ArithKind, Arithmetic, Paper, Unbiased};
pub use batch::SpanBatcher;
pub use error::Error;
pub use fragment::{Fragment, FragmentError};
pub use framebuffer::{
    DynFramebuffer, Framebuffer, FramebufferError, Grid, Ht, HybridFramebuffer, HybridSpanFramebuffer, Layers, Mlab,
    MlabFramebuffer, PixelMajor, SpanFramebuffer, Spans,
};
pub use hash::{fragment_hash, lowbias32};
pub use hybrid::{Hybrid, Tail, TailFormat};
pub use lanes::{FragmentLanes, InvalidLanes};
pub use mlab::BlendingArray;
pub use resolve::{Background, Resolved, resolve_rows, to_rgba8, to_rgba16f};
pub use row::Row;

pub use glam;
pub use half;

/// The README's example is compiled and run as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctest;

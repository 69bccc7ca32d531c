//! # mlab
//!
//! A `no_std`, allocation-free compositing kernel for order-independent transparency:
//! Multi-Layer Alpha Blending (MLAB; Salvi & Vaidyanathan, *Multi-Layer Alpha Blending*,
//! I3D 2014) and Hybrid Transparency (HT; Maule et al. 2013, in the single-pass form of
//! the same paper), over packed 8-byte rows.
//!
//! | type | what | size |
//! |---|---|---|
//! | [`Row`] | premultiplied RGB8 + transmittance T8 + depth f32 | 8 bytes, align 8 |
//! | [`Tail`] | HT tail: color sums 3 x 13 bit, alpha sum 14 bit, count 11 bit | 8 bytes, align 8 |
//! | [`hybrid::PaperTail`] | the paper's HT tail: 3 x 10, 16, 16 bit | 8 bytes, align 8 |
//! | [`BlendingArray<M>`] | MLAB blending array, `M >= 1` rows | `8 * M` bytes |
//! | [`Hybrid<K>`] | HT: `K` head rows + tail | `8 * (K + 1)` bytes |
//! | [`MlabFramebuffer`], [`HybridFramebuffer`] | views over caller-owned `&mut [Row]` | none |
//!
//! - [`mlab::insert`] is Listing 1 (insert-and-merge), [`hybrid::insert`] is Listing 2,
//!   [`resolve_rows`] is Eq. 5 and [`Resolved::over`] Eq. 6.
//! - Fragments are validated once ([`Fragment`], typed [`FragmentError`]) and quantized once.
//! - The merge is exact unorm8 integer arithmetic, reproducible on any machine and in a
//!   shader, in one of two arithmetics ([`arith`]), a type parameter of every kernel type:
//!   [`Unbiased`] (the default: a dithered merge and dithered faint fragments, no
//!   transmittance stall on many faint layers, and a tail that does not saturate on dense
//!   content) or [`Paper`] (the paper's
//!   round-to-nearest and 3 x 10-bit tail, bit for bit): `BlendingArray<4>` is
//!   `BlendingArray<4, Unbiased>`; `BlendingArray<4, Paper>` is the paper's.
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
//! See `docs/layout.md` and `docs/algorithm.md` in the repository.

#![no_std]
#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub mod arith;
pub mod fragment;
pub mod framebuffer;
pub mod hybrid;
pub mod lanes;
pub mod mlab;
pub mod resolve;
pub mod row;
pub mod spans;
pub mod unorm;

pub use arith::{Arithmetic, Paper, Unbiased};
pub use fragment::{Fragment, FragmentError};
pub use framebuffer::{FramebufferError, HybridFramebuffer, MlabFramebuffer};
pub use hybrid::{Hybrid, Tail, TailFormat};
pub use mlab::BlendingArray;
pub use resolve::{Background, Resolved, resolve_rows, to_rgba8, to_rgba16f};
pub use row::Row;
pub use spans::{HybridSpanFramebuffer, SpanFramebuffer};

pub use glam;
pub use half;

/// The README's example is compiled and run as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctest;

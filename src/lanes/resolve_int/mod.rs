//! The integer RGBA8 resolves in lanes (`crate::resolve::int` is their definition): MLAB's
//! in 16-bit lanes, in two forms chosen by the build, and HT's (`ht.rs`).
//!
//! MLAB's form: `ssse3.rs` (a byte shuffle and `pmulhrsw` per layer) everywhere but x86
//! without SSSE3 (the x86-64 baseline, SSE2), where `wide` would emulate those lane by lane
//! (195 instructions per pixel at M = 4) and `sse2.rs` has a form of its own.

pub(super) mod ht;
#[cfg(all(any(target_arch = "x86", target_arch = "x86_64"), not(target_feature = "ssse3")))]
mod sse2;
#[cfg(not(all(any(target_arch = "x86", target_arch = "x86_64"), not(target_feature = "ssse3"))))]
mod ssse3;

#[cfg(all(any(target_arch = "x86", target_arch = "x86_64"), not(target_feature = "ssse3")))]
use sse2 as int8;
#[cfg(not(all(any(target_arch = "x86", target_arch = "x86_64"), not(target_feature = "ssse3"))))]
use ssse3 as int8;

use super::{LANES, MlabSpan};
use crate::row::Row;

/// The integer RGBA8 resolve of an MLAB span (layer-major).
#[inline(always)]
pub(super) fn mlab_resolve_rgba8_int<const M: usize, const OPAQUE: bool>(
    span: &MlabSpan<M>,
    bg: [u32; 3],
) -> [[u8; 4]; LANES] {
    int8::resolve::<OPAQUE>(M, |j| span.get(j).copied().unwrap_or([Row::EMPTY; LANES]), bg)
}

/// The integer RGBA8 resolve of 8 pixels stored pixel-major (`pixels[lane][layer]`).
#[inline(always)]
pub(super) fn mlab_resolve_pixel_major_rgba8_int<const M: usize, const OPAQUE: bool>(
    pixels: &[[Row; M]; LANES],
    bg: [u32; 3],
) -> [[u8; 4]; LANES] {
    int8::resolve::<OPAQUE>(
        M,
        |j| core::array::from_fn(|p| pixels[p].get(j).copied().unwrap_or(Row::EMPTY)),
        bg,
    )
}

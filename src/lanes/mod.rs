//! Lanes: eight pixels at a time, bit-exact with the scalar kernel.
//!
//! A software rasterizer shades a primitive a span of pixels at a time; these functions take
//! one fragment per lane for eight pixels (each lane its own pixel and its own blending
//! array), with a coverage mask (`u8`, bit `i` = lane `i`; lanes that are off are untouched).
//!
//! # Arrangement: layer-major spans
//!
//! The rows stay the packed 8-byte [`Row`]. A span of 8 pixels with `M` rows each is stored
//! layer-major, `[[Row; 8]; M]`: layer `j` of the 8 pixels is 64 contiguous bytes (one cache
//! line when the span is 64-byte aligned), and each SIMD register holds four whole rows in
//! its four 64-bit lanes. Nothing is deinterleaved to insert: the depth test is an f32
//! compare whose result in the odd (depth) dword is widened to the whole 64-bit lane, and the
//! swap of Listing 1 is two selects of whole rows. [`Grid::copy_from`](crate::Grid::copy_from)
//! converts framebuffers losslessly between it and the per-pixel `[Row; M]` arrangement of
//! [`MlabFramebuffer`](crate::MlabFramebuffer); `docs/performance.md` measures the two.
//!
//! # One algorithm, two widths
//!
//! Listing 1 and 2 are written once ([`crate::mlab`], [`crate::hybrid`]) over the private
//! `RowLanes` trait (`src/vector.rs`, with its width-1 implementation by [`Row`] and the
//! tails: the scalar kernel) and implemented for eight rows in two registers in
//! `src/lanes/w256.rs` (and one 512-bit register in `w512.rs`). The resolve (Eq. 5-6, the
//! HT tail) is written once in [`crate::resolve`] over its `FloatLanes` trait, implemented
//! by `f32` and `wide::f32x8`: scalar and lanes evaluate the same f32 expression tree in the
//! same order, multiply then add, never FMA. The merge and the tail are exact integer
//! arithmetic; the lanes use SWAR on 16-bit slots (`pmullw`), the scalar path per-channel
//! bytes ([`crate::arith`]); both compute the same bytes. This module is the public span
//! API; one file per concept below it, each beside its scalar half:
//!
//! | file | what | scalar half |
//! |---|---|---|
//! | `backend.rs` | [`BACKEND`] and every instruction-set choice | |
//! | `swar.rs` | the merges and tail adds on 16-bit slots, once for any width (`swar!`); their exhaustive tests | `arith.rs`, `tail.rs` |
//! | `w256.rs`, `w512.rs` | the register leaves: `RowLanes` and `FloatLanes` for 8 rows in two 256-bit registers, or in one 512-bit one (HT with AVX-512) | `vector.rs` |
//! | `quantize.rs` | [`FragmentLanes`], the lane quantizer and hashes | `fragment.rs`, `arith.rs` |
//! | `layout.rs` | where each pixel sits in a resolve's registers | |
//! | `resolve.rs` | the f32 resolves in registers and their RGBA8 writer | `resolve.rs` |
//! | `resolve_int/` | the integer RGBA8 resolves: MLAB's (SSSE3 or SSE2 form) and HT's | `resolve.rs` (`int`) |
//!
//! `wide` picks its instruction set at compile time ([`BACKEND`] says which). Every operation
//! of the inserts and resolves is a native instruction on SSE2 and AVX2 but the hash's 32-bit
//! multiplies (`lowbias32`, 4 per 8 fragments), which SSE2 lacks (`pmuludq` and shuffles).
//!
//! ```
//! use mlab::lanes::{self, FragmentLanes};
//! use mlab::Row;
//! let mut span = [[Row::EMPTY; 8]; 4]; // 8 pixels, M = 4, layer-major
//! let frags = FragmentLanes {
//!     color: [[0.4; 8], [0.0; 8], [0.0; 8]],
//!     alpha: [0.6; 8],
//!     depth: [1.0, 2.0, 3.0, f32::NAN, 5.0, 6.0, 7.0, 8.0],
//!     key: Some([10, 11, 12, 13, 14, 15, 16, 17]), // the primitives' ids
//! };
//! let q = frags.quantize_at::<mlab::Unbiased>(0b0111_1111, 0); // validate, quantize: pixels 0..8
//! assert_eq!(q.invalid, 0b0000_1000); // lane 3 has a NaN depth: reported, not inserted
//! lanes::mlab_insert_hashed::<mlab::Unbiased, 4>(&mut span, &q.rows, &q.hashes, q.valid);
//! assert_eq!(span[0][3], Row::EMPTY);
//! assert_eq!(span[0][7], Row::EMPTY); // lane 7 was off
//! assert_eq!(span[0][0], Row::new([102, 0, 0], 102, 1.0)); // 0.4 and 0.6 are exact bytes
//! ```

mod backend;
mod layout;
mod quantize;
mod resolve;
// The lane helpers narrow lanes whose range their comments state (bytes of 16-bit slots).
#[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss, clippy::cast_possible_wrap)]
mod resolve_int;
// The same (and its tests).
#[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss, clippy::cast_possible_wrap)]
mod swar;
// The same.
#[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss, clippy::cast_possible_wrap)]
mod w256;
// The same.
#[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss, clippy::cast_possible_wrap)]
mod w512;

use crate::arith::{Arithmetic, Unbiased};
use crate::resolve::{Background, Resolved};
use crate::row::Row;
use crate::tail::TailFormat;
use glam::Vec4;
// Listing 1 runs on the 8-wide lanes of `w256.rs`. Listing 2 runs on one 512-bit register per
// layer where the build has AVX-512 (`w512.rs`, `backend::HT_512`), else on `HtRows8` (no
// masked stores).
#[cfg(not(all(target_feature = "avx512f", target_feature = "avx512bw")))]
use w256::{HtMask8, HtRows8};
use w256::{Mask8, Rows8};
#[cfg(all(target_feature = "avx512f", target_feature = "avx512bw"))]
use w512::{Mask8 as HtMask8, Rows8 as HtRows8};

pub use backend::BACKEND;
pub use quantize::{FragmentLanes, QuantizedLanes};
pub(crate) use resolve_int::ht::{hybrid_resolve_parts2_rgba8, hybrid_resolve_parts4_rgba8};
pub(crate) use resolve_int::{
    PixelCell, hybrid_resolve_head_rgba8, hybrid_resolve_parts_rgba8, mlab_resolve_line_rgba8, mlab_resolve_rgba8,
};

/// Pixels per lane group.
pub const LANES: usize = 8;

/// [`LANES`] as a `u32` (pixel coordinates are `u32`).
#[expect(clippy::cast_possible_truncation, reason = "8")]
pub(crate) const LANES_U32: u32 = LANES as u32;

/// An MLAB span: 8 pixels with `M` rows each, layer-major (`span[j][lane]` is row `j` of
/// pixel `lane`). The public signatures spell it out.
pub(crate) type MlabSpan<const M: usize> = [[Row; LANES]; M];

/// A Hybrid Transparency span: 8 pixels with `K` head rows (layer-major) and 8 tails of the
/// arithmetic `A` ([`Unbiased`] by default).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(C)]
pub struct HybridSpan<const K: usize, A: Arithmetic = Unbiased> {
    /// `head[j][lane]` is head row `j` of pixel `lane`.
    pub head: [[Row; LANES]; K],
    /// The tail of each pixel.
    pub tails: [A::Tail; LANES],
}

impl<const K: usize, A: Arithmetic> Default for HybridSpan<K, A> {
    /// Empty heads and tails.
    fn default() -> Self {
        HybridSpan {
            head: [[Row::EMPTY; LANES]; K],
            tails: [A::Tail::EMPTY; LANES],
        }
    }
}

/// Listing 1 on 8 pixels in the arithmetic `A`: insert `rows[lane]` into pixel `lane` for
/// every lane whose bit is set in `mask`, each merge seeded by its row's content
/// ([`crate::mlab::row_hash`] of pixel 0, as [`crate::mlab::insert_with`]). Byte-identical
/// to [`crate::mlab::insert_with`]`::<A, M>` on each lane, for any rows.
#[inline(always)]
pub fn mlab_insert_with<A: Arithmetic, const M: usize>(span: &mut [[Row; LANES]; M], rows: &[Row; LANES], mask: u8) {
    mlab_insert_hashed::<A, M>(span, rows, &quantize::row_hashes(rows, 0, 0), mask);
}

/// Listing 1 on 8 pixels as [`mlab_insert_with`], lane `i`'s merge seeded by `hashes[i]`
/// (the inserted fragment's hash, [`crate::Fragment::hash`]; what
/// [`FragmentLanes::quantize_at`] returns with the rows). Byte-identical to
/// [`crate::mlab::insert_hashed`]`::<A, M>` on each lane, for any rows.
#[inline(always)] // a span insert is the inner loop of a rasterizer: never a call
pub fn mlab_insert_hashed<A: Arithmetic, const M: usize>(
    span: &mut [[Row; LANES]; M],
    rows: &[Row; LANES],
    hashes: &[u32; LANES],
    mask: u8,
) {
    let d = w256::Dither8::new(hashes);
    // Full spans (the common case) skip the mask: with a constant all-ones mask the
    // compiler drops the ANDs and the final select.
    if mask == 0xff {
        crate::mlab::insert_lanes::<A, _, _, M>(span, Rows8::load(rows), Mask8::ALL, d);
    } else {
        crate::mlab::insert_lanes::<A, _, _, M>(span, Rows8::load(rows), Mask8::from_bits(mask), d);
    }
}

/// [`crate::mlab::row_hash`] of 8 rows in the pixels of ids `first_pixel + lane` (wrapping).
#[inline]
pub fn row_hashes(rows: &[Row; LANES], first_pixel: u32) -> [u32; LANES] {
    quantize::row_hashes(rows, first_pixel, 1)
}

/// Listing 2 on 8 pixels. Byte-identical to [`crate::hybrid::insert`] on each lane.
#[inline]
pub fn hybrid_insert<const K: usize, A: Arithmetic>(span: &mut HybridSpan<K, A>, rows: &[Row; LANES], mask: u8) {
    hybrid_insert_parts(&mut span.head, &mut span.tails, rows, mask);
}

/// [`hybrid_insert`] on a span stored as separate head layers and tails (as in a
/// [`HybridSpanFramebuffer`](crate::HybridSpanFramebuffer)); the tail type picks the layout.
#[inline]
pub(crate) fn hybrid_insert_parts<T: TailFormat, const K: usize>(
    head: &mut [[Row; LANES]; K],
    tails: &mut [T; LANES],
    rows: &[Row; LANES],
    mask: u8,
) {
    if mask == 0xff {
        crate::hybrid::insert_lanes::<_, _, _, T, K>(head, tails, HtRows8::load(rows), HtMask8::ALL);
    } else {
        crate::hybrid::insert_lanes::<_, _, _, T, K>(head, tails, HtRows8::load(rows), HtMask8::from_bits(mask));
    }
}

/// The lanes of a span insert of fragments that were on but invalid (NaN, infinite or out
/// of range, as [`crate::Fragment`]'s constructors refuse them): they were **not** inserted.
/// Bit `i` = lane `i`. Compares with a `u8` mask (`invalid == 0`).
#[must_use = "the lanes in this mask were not inserted: check it (`== 0`) or count them (`.0.count_ones()`)"]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct InvalidLanes(pub u8);

impl PartialEq<u8> for InvalidLanes {
    fn eq(&self, other: &u8) -> bool {
        self.0 == *other
    }
}

impl From<InvalidLanes> for u8 {
    fn from(v: InvalidLanes) -> u8 {
        v.0
    }
}

/// The resolve of 8 pixels, structure of arrays; lane `i` equals the scalar [`Resolved`]
/// of pixel `i` bit for bit ([`ResolvedLanes::get`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ResolvedLanes {
    /// `color[channel][lane]`: premultiplied color of the transparent layers.
    pub color: [[f32; LANES]; 3],
    /// Background visibility per lane.
    pub transmittance: [f32; LANES],
}

/// Eq. 5 over an MLAB span (as [`crate::resolve_rows`] on each pixel).
#[inline]
pub fn mlab_resolve<const M: usize>(span: &[[Row; LANES]; M]) -> ResolvedLanes {
    resolve::mlab_resolve(span).lanes()
}

/// [`mlab_resolve`] of 8 pixels stored pixel-major (`[pixel][row]`, as in an
/// [`MlabFramebuffer`](crate::MlabFramebuffer)), without transposing them first. (Always
/// inlined: passed as a function value, it was a call per span on SSE2, which costs more than
/// its body saves: `docs/performance.md`, resolves.)
#[inline(always)]
pub(crate) fn mlab_resolve_pixel_major<const M: usize>(pixels: &[[Row; M]; LANES]) -> ResolvedLanes {
    resolve::mlab_resolve_pixel_major(pixels).lanes()
}

/// HT resolve over a span (as [`Hybrid::resolve`](crate::Hybrid::resolve) on each pixel).
#[inline]
pub fn hybrid_resolve<const K: usize, A: Arithmetic>(span: &HybridSpan<K, A>) -> ResolvedLanes {
    resolve::hybrid_resolve(&span.head, &span.tails).lanes()
}

impl ResolvedLanes {
    /// Lane `lane` (0..8) as a scalar [`Resolved`]; `None` past the last lane.
    #[inline]
    pub fn get(&self, lane: usize) -> Option<Resolved> {
        let t = *self.transmittance.get(lane)?;
        let c = glam::Vec3::new(self.color[0][lane], self.color[1][lane], self.color[2][lane]);
        Some(Resolved {
            color: c,
            transmittance: t,
        })
    }

    /// The 8 pixels for `background` ([`Resolved::pixel`] per lane).
    #[inline(always)]
    pub fn pixels(&self, background: Background) -> [Vec4; LANES] {
        core::array::from_fn(|i| self.get(i).unwrap_or(Resolved::CLEAR).pixel(background))
    }

    /// The 8 pixels as RGBA8 ([`crate::to_rgba8`] per lane), computed in lanes.
    pub fn rgba8(&self, background: Background) -> [[u8; 4]; LANES] {
        resolve::rgba8(&self.color, &self.transmittance, background)
    }
}

/// [`hybrid_resolve`] on separate head layers and tails.
#[inline]
pub(crate) fn hybrid_resolve_parts<T: TailFormat, const K: usize>(
    head: &[[Row; LANES]; K],
    tails: &[T; LANES],
) -> ResolvedLanes {
    resolve::hybrid_resolve(head, tails).lanes()
}

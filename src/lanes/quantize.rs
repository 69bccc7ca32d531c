//! Lane quantization: eight fragments (structure of arrays) validated and quantized to rows
//! as [`crate::Fragment`]'s constructors and [`Arithmetic::quantize`] do lane by lane.

use crate::arith::{Arithmetic, Kind};
use crate::resolve::FloatLanes;
use crate::row::Row;

use super::LANES;
use bytemuck::cast;
use wide::{f32x8, i32x8, u32x8, u64x4};

/// Eight fragments, structure of arrays, linear color: premultiplied for
/// [`quantize_with`](Self::quantize_with) and `Framebuffer::insert_span_fragments`, straight for
/// [`quantize_straight_with`](Self::quantize_straight_with) (and
/// [`Framebuffer::insert_span_straight`](crate::Framebuffer::insert_span_straight)).
///
/// ```
/// use mlab::lanes::FragmentLanes;
/// let straight = FragmentLanes::from_rgba([[1.0, 0.5, 0.0, 0.5]; 8], [2.0; 8]);
/// let q = straight.quantize_straight_with::<mlab::Unbiased>(0xff);
/// assert_eq!(q.valid, 0xff);
/// // With stable keys (the primitives' ids) for pixels 640..648 of a framebuffer:
/// let keyed = FragmentLanes { key: Some([7; 8]), ..straight };
/// let q = keyed.quantize_straight_at::<mlab::Unbiased>(0xff, 640);
/// assert_eq!(q.hashes[1], mlab::fragment_hash(7, 641));
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FragmentLanes {
    /// `color[channel][lane]`, channels R, G, B.
    pub color: [[f32; LANES]; 3],
    /// Alpha per lane.
    pub alpha: [f32; LANES],
    /// Depth per lane.
    pub depth: [f32; LANES],
    /// The stable key per lane ([`crate::Fragment::with_key`]: the primitive's id), or `None`
    /// for the content keys (which re-roll the dithers when the depth changes).
    pub key: Option<[u32; LANES]>,
}

/// Rows quantized from [`FragmentLanes`], and which lanes were valid.
#[must_use = "lanes in `invalid` were refused: insert `rows` with the mask `valid`"]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct QuantizedLanes {
    /// The rows (lanes not in `valid` hold [`Row::EMPTY`]).
    pub rows: [Row; LANES],
    /// The hash of each lane's fragment in its pixel ([`crate::Fragment::hash`]): what the
    /// rows were quantized with, and what their insert merges with
    /// ([`mlab_insert_hashed`](super::mlab_insert_hashed)). Unspecified in lanes not in `valid`.
    pub hashes: [u32; LANES],
    /// Lanes that were on and valid.
    pub valid: u8,
    /// Lanes that were on and invalid: exactly the lanes where the scalar constructor
    /// ([`crate::Fragment::premultiplied`] or [`crate::Fragment::straight`]) returns an error.
    pub invalid: u8,
}

impl FragmentLanes {
    /// Eight fragments from `[R, G, B, A]` per lane and a depth per lane (premultiplied or
    /// straight: the quantizer you call decides).
    pub fn from_rgba(rgba: [[f32; 4]; LANES], depth: [f32; LANES]) -> FragmentLanes {
        FragmentLanes {
            color: core::array::from_fn(|c| core::array::from_fn(|lane| rgba[lane][c])),
            alpha: core::array::from_fn(|lane| rgba[lane][3]),
            depth,
            key: None,
        }
    }

    /// Eight fully transparent black fragments at depth 0 (valid; a placeholder for lanes
    /// that are off).
    pub const TRANSPARENT: FragmentLanes = FragmentLanes {
        color: [[0.0; LANES]; 3],
        alpha: [0.0; LANES],
        depth: [0.0; LANES],
        key: None,
    };

    /// Validate and quantize premultiplied fragments as [`crate::Fragment::premultiplied`]
    /// then [`Arithmetic::quantize`] would, lane by lane, as the fragments of pixels `0..8`
    /// ([`quantize_at`](Self::quantize_at)).
    pub fn quantize_with<A: Arithmetic>(&self, mask: u8) -> QuantizedLanes {
        self.quantize_at::<A>(mask, 0)
    }

    /// Validate and quantize straight-color fragments, as [`crate::Fragment::straight`] then
    /// [`Arithmetic::quantize`] would (`color * alpha`, one f32 multiply), as the fragments
    /// of pixels `0..8`.
    pub fn quantize_straight_with<A: Arithmetic>(&self, mask: u8) -> QuantizedLanes {
        self.quantize_straight_at::<A>(mask, 0)
    }

    /// [`quantize_with`](Self::quantize_with) for lane `i` in the pixel of id
    /// `first_pixel + i` (wrapping): the hashes are [`crate::Fragment::hash`] of those
    /// pixels (`y * width + x` and its neighbours in a framebuffer, which passes them).
    pub fn quantize_at<A: Arithmetic>(&self, mask: u8, first_pixel: u32) -> QuantizedLanes {
        quantize_lanes::<A>(self, mask, false, true, first_pixel, true)
    }

    /// [`quantize_straight_with`](Self::quantize_straight_with) in pixels
    /// `first_pixel + i`, as [`quantize_at`](Self::quantize_at).
    pub fn quantize_straight_at<A: Arithmetic>(&self, mask: u8, first_pixel: u32) -> QuantizedLanes {
        quantize_lanes::<A>(self, mask, true, true, first_pixel, true)
    }

    /// [`quantize_at`](Self::quantize_at) or [`quantize_straight_at`](Self::quantize_straight_at)
    /// for a framebuffer's span insert, the hashes as [`quantize_validated_at`](Self::quantize_validated_at)
    /// computes them.
    #[inline]
    pub(crate) fn quantize_for_insert<A: Arithmetic>(
        &self,
        mask: u8,
        straight: bool,
        first_pixel: u32,
        all_hashes: bool,
    ) -> QuantizedLanes {
        quantize_lanes::<A>(self, mask, straight, true, first_pixel, all_hashes)
    }

    /// [`quantize_with`](Self::quantize_with) for lanes that hold validated
    /// [`crate::Fragment`]s (premultiplied), without the checks: every lane in `mask` is
    /// valid. For lanes that would fail a check the rows are unspecified (never UB, never a
    /// panic); the span batcher only holds fragments it took as `Fragment`s.
    ///
    /// With `all_hashes` false (the insert does not merge: HT), `hashes` are computed only
    /// where the quantization reads them (faint fragments of `Unbiased`) and are 0 otherwise.
    #[inline]
    pub(crate) fn quantize_validated_at<A: Arithmetic>(
        &self,
        mask: u8,
        first_pixel: u32,
        all_hashes: bool,
    ) -> QuantizedLanes {
        quantize_lanes::<A>(self, mask, false, false, first_pixel, all_hashes)
    }
}

/// [`FragmentLanes::quantize_with`] and [`FragmentLanes::quantize_straight_with`].
#[inline(always)]
#[expect(clippy::cast_possible_truncation, reason = "the bitmask of 8 lanes fits a u8")]
pub(super) fn quantize_lanes<A: Arithmetic>(
    f: &FragmentLanes,
    mask: u8,
    straight: bool,
    check: bool,
    first_pixel: u32,
    all_hashes: bool,
) -> QuantizedLanes {
    let zero = f32x8::ZERO;
    let one = f32x8::ONE;
    let alpha = f32x8::new(f.alpha);
    let depth = f32x8::new(f.depth);
    // Every comparison is false for NaN, so NaN anywhere makes the lane invalid. Without
    // `check` (lanes of validated `Fragment`s) every lane is valid.
    let mut ok = if check {
        alpha.simd_ge(zero) & alpha.simd_le(one) & depth.abs().simd_lt(f32x8::splat(f32::INFINITY))
    } else {
        cast(u32x8::MAX)
    };
    let mut pre = [zero; 3];
    for (c, out) in f.color.iter().zip(pre.iter_mut()) {
        let raw = f32x8::new(*c);
        *out = if straight {
            if check {
                ok &= raw.simd_ge(zero) & raw.simd_lt(f32x8::splat(f32::INFINITY));
            }
            raw * alpha
        } else {
            raw
        };
        if check {
            ok &= out.simd_ge(zero) & out.simd_le(one);
        }
    }
    // The hashes (`Fragment::hash`): the stable keys, or the content keys, of pixels
    // `first_pixel + lane`.
    // Without `all_hashes` (an insert that does not merge: HT) they are computed only where
    // the quantization reads them, for faint fragments of `Unbiased`; else they are 0.
    let hashes = || {
        let bits = |v: f32x8| cast::<f32x8, u32x8>(v);
        let key = match f.key {
            Some(k) => u32x8::new(k),
            None => bits(pre[0]) ^ bits(pre[1]) ^ bits(pre[2]) ^ bits(alpha) ^ bits(depth),
        };
        fragment_hashes8(key, first_pixel, 1)
    };
    let half = f32x8::splat(0.5);
    let (u, h) = match A::KIND {
        Kind::Paper => (half, if all_hashes { hashes() } else { u32x8::ZERO }),
        // Faint fragments dithered, the others to nearest (as `Unbiased::quantize`):
        // `u = ((h >> 24) + 0.5) / 256`.
        Kind::Unbiased => {
            let faint = (alpha * f32x8::splat(255.0)).simd_lt(f32x8::splat(crate::arith::FAINT_BYTES));
            if all_hashes || faint.any() {
                let h = hashes();
                let dither = (f32x8::from_u(h >> 24) + half) * f32x8::splat(1.0 / 256.0);
                (faint.select(dither, half), h)
            } else {
                (half, u32x8::ZERO)
            }
        }
    };
    let bytes = pre.map(|c| quantize8(c, u));
    let t = u32x8::splat(255) - quantize8(alpha, u);
    let rgbt = bytes[0] | (bytes[1] << 8) | (bytes[2] << 16) | (t << 24);
    // The lanes that are on and valid, as a lane mask and as bits.
    let on = {
        let bits = u32x8::new([1, 2, 4, 8, 16, 32, 64, 128]);
        (u32x8::splat(mask as u32) & bits).simd_eq(bits) & cast::<f32x8, u32x8>(ok)
    };
    let valid = cast::<u32x8, f32x8>(on).to_bitmask() as u8;
    // Lanes that are off hold the empty row; selected without a branch, then interleaved
    // into rows (word0, word1) per lane.
    let [e0, e1] = Row::EMPTY.words();
    let rgbt: [u32; LANES] = cast(on.select(rgbt, u32x8::splat(e0)));
    let z: [u32; LANES] = cast(on.select(cast(depth), u32x8::splat(e1)));
    QuantizedLanes {
        rows: core::array::from_fn(|i| Row::from_words([rgbt[i], z[i]])),
        hashes: h.to_array(),
        valid,
        invalid: mask & !valid,
    }
}

/// [`crate::lowbias32`] of 8 lanes (32-bit lane multiplies).
#[inline(always)]
pub(super) fn lowbias32_8(x: u32x8) -> u32x8 {
    let x = (x ^ (x >> 16)) * u32x8::splat(0x7feb_352d);
    let x = (x ^ (x >> 15)) * u32x8::splat(0x846c_a68b);
    x ^ (x >> 16)
}

/// [`crate::mlab::row_hash`] of 8 rows in pixels `first_pixel + step * lane`.
#[inline(always)]
pub(super) fn row_hashes(rows: &[Row; LANES], first_pixel: u32, step: u32) -> [u32; LANES] {
    let [a, b]: [u32x8; 2] = cast(*rows);
    // word0 ^ word1 of rows 0-3 in the low dwords of `a`, of rows 4-7 in the high dwords of `b`.
    let xa = a ^ cast::<u64x4, u32x8>(cast::<u32x8, u64x4>(a) >> 32);
    let xb = b ^ cast::<u64x4, u32x8>(cast::<u32x8, u64x4>(b) << 32);
    let [a, b] = [xa.to_array(), xb.to_array()];
    let key = u32x8::new([a[0], a[2], a[4], a[6], b[1], b[3], b[5], b[7]]);
    fragment_hashes8(key, first_pixel, step).to_array()
}

/// [`crate::fragment_hash`] of 8 keys in pixels `first_pixel + step * lane` (wrapping).
#[inline(always)]
fn fragment_hashes8(key: u32x8, first_pixel: u32, step: u32) -> u32x8 {
    let pixel = u32x8::splat(first_pixel) + u32x8::new([0, 1, 2, 3, 4, 5, 6, 7]) * u32x8::splat(step);
    lowbias32_8(key ^ lowbias32_8(pixel))
}

/// `floor(v * 255 + u)` for `v` in `[0, 1]` (as [`crate::unorm::quantize`] for `u = 0.5`);
/// other lanes give unspecified bytes and must be masked.
#[inline(always)]
fn quantize8(v: f32x8, u: f32x8) -> u32x8 {
    let x = v * f32x8::splat(255.0) + u;
    cast::<i32x8, u32x8>(x.fast_trunc_int()) & u32x8::splat(0xff)
}

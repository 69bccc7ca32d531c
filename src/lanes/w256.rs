//! The 256-bit leaves: eight rows in two registers (`Lanes8`, `Mask8`), the merge's dithers
//! and merged depth on one packed register, `FloatLanes` for `f32x8`, and the packing of the
//! rows' words into one register (`words0`, `words1`). With `w512.rs` and the resolves, one
//! of the files that name `wide`'s register types.

use super::LANES;
use super::backend::{PACK_PAPER_MERGE, SIGN_SELECT};
use crate::arith::{Arithmetic, Kind};
use crate::resolve::FloatLanes;
use crate::row::Row;
use crate::tail::{Layout, TailFormat};
use crate::vector::{Layer8, RowLanes};
use bytemuck::cast;
use wide::{f32x8, f64x4, i16x16, i32x8, u8x32, u16x16, u32x8, u64x4};

super::swar::swar!(u32x8, u16x16, u8x32, i16x16, u64x4);

/// `(lo & LO) | (hi & HI)` (on AVX2 one `vpblendd`).
#[inline(always)]
pub(super) fn lo_hi(lo: u32x8, hi: u32x8) -> u32x8 {
    (lo & LO) | (hi & HI)
}

/// Copy the mask in the low dword of each 64-bit lane to the whole lane.
#[inline(always)]
fn widen_lo(m: u32x8) -> u32x8 {
    let l = m & LO;
    l | cast::<u64x4, u32x8>(cast::<u32x8, u64x4>(l) << 32)
}

/// `tail` in the lanes where `row` is invisible (no color, T = 255), else `new`.
#[inline(always)]
fn skip_invisible(row: u32x8, tail: u32x8, new: u32x8) -> u32x8 {
    let invisible = widen_lo(row.simd_eq(u32x8::splat(0xff00_0000)));
    invisible.select(tail, new)
}

/// `(y * 257) >> 16` in each 16-bit slot: one high multiply (`pmulhuw`).
#[inline(always)]
fn mul257_high(y: u16x16) -> u16x16 {
    y.mul_keep_high(u16x16::splat(257))
}

impl FloatLanes for f32x8 {
    type U = u32x8;
    type Mask = f32x8;
    #[inline(always)]
    fn splat(v: f32) -> Self {
        f32x8::splat(v)
    }
    #[inline(always)]
    fn select(mask: f32x8, a: Self, b: Self) -> Self {
        mask.select(a, b)
    }
    #[inline(always)]
    fn bit(n: u32x8, bit: u32) -> f32x8 {
        let one = u32x8::splat(1 << bit);
        cast((n & one).simd_eq(one))
    }
    #[inline(always)]
    fn is_zero(n: u32x8) -> f32x8 {
        cast(n.simd_eq(u32x8::ZERO))
    }
    #[inline(always)]
    fn gt(self, other: Self) -> f32x8 {
        self.simd_gt(other)
    }
    #[inline(always)]
    fn div(self, other: Self) -> Self {
        self / other
    }
    #[inline(always)]
    fn from_u(n: u32x8) -> Self {
        cast::<u32x8, i32x8>(n).round_float()
    }
    #[inline(always)]
    fn bit_length(n: u32x8) -> u32 {
        u32::BITS - n.to_array().iter().fold(0, |m, &x| m | x).leading_zeros()
    }
}

/// Eight rows (or eight tails), one per lane: lanes 0-3 in `a`, 4-7 in `b`, each 64-bit
/// lane one whole row (`word0` in the low dword, `word1` in the high dword). `SIGN`: whether
/// its selects read only the sign bit of each 64-bit lane ([`Rows8`]) or a mask widened to
/// whole rows ([`HtRows8`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Lanes8<const SIGN: bool> {
    pub(super) a: u32x8,
    pub(super) b: u32x8,
}

/// The lanes of Listing 1 (MLAB): with AVX, a select of whole rows is `vblendvpd`, which
/// reads only the sign bit of each 64-bit lane, that is the depth dword's compare result: the
/// masks need no widening. Without AVX the select is bitwise and the masks are widened to
/// whole lanes. Both give the same rows.
pub(crate) type Rows8 = Lanes8<SIGN_SELECT>;

/// The lanes of Listing 2 (the HT span insert): every select is a byte blend (`vpblendvb`
/// with AVX2) on a mask widened to whole rows, never `vblendvpd`.
///
/// Listing 2 stores `select(swap, f, row)` back to the slot `row` was loaded from; with
/// `vblendvpd`, LLVM 22 folds that store into `vmaskmovpd` (llvm/llvm-project#145176), which
/// AMD CPUs microcode, seven per span insert at `K = 3`. With widened masks and byte blends
/// the stores stay plain stores, for one more instruction per mask (`vmovshdup`).
/// `docs/performance.md` measures both. Listing 1 keeps [`Rows8`]: its full-span inserts have
/// no masked store to remove, and its instruction count would grow.
#[cfg_attr(all(target_feature = "avx512f", target_feature = "avx512bw"), allow(dead_code))]
pub(crate) type HtRows8 = Lanes8<false>;

/// Per-lane mask for [`Lanes8`]: all ones or all zeros over each 64-bit lane (with `SIGN`,
/// only the sign bit of each 64-bit lane is meaningful).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Mask8<const SIGN: bool> {
    a: u32x8,
    b: u32x8,
}

/// The mask of [`HtRows8`].
#[cfg_attr(all(target_feature = "avx512f", target_feature = "avx512bw"), allow(dead_code))]
pub(crate) type HtMask8 = Mask8<false>;

impl<const S: bool> core::ops::BitAnd for Mask8<S> {
    type Output = Self;
    #[inline(always)]
    fn bitand(self, rhs: Self) -> Self {
        Mask8 {
            a: self.a & rhs.a,
            b: self.b & rhs.b,
        }
    }
}

impl<const S: bool> Mask8<S> {
    /// Every lane on.
    pub(super) const ALL: Self = Mask8 {
        a: u32x8::MAX,
        b: u32x8::MAX,
    };

    /// From a bitmask (bit `i` = lane `i`).
    #[inline(always)]
    pub(super) fn from_bits(bits: u8) -> Self {
        let v = u32x8::splat(bits as u32);
        let sa = u32x8::new([1, 1, 2, 2, 4, 4, 8, 8]);
        let sb = u32x8::new([16, 16, 32, 32, 64, 64, 128, 128]);
        Mask8 {
            a: (v & sa).simd_eq(sa),
            b: (v & sb).simd_eq(sb),
        }
    }
}

/// The merge dithers of eight lanes ([`crate::arith::merge_dither`] of each lane's hash), as
/// the merge reads them: `d` of lane `p` in both 16-bit slots of dword [`POSITION`]`[p]` (the
/// order in which [`pack_words`] packs the rows' first words).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Dither8(u16x16);

impl Dither8 {
    /// From the hashes of the eight inserted fragments.
    #[inline(always)]
    pub(super) fn new(h: &[u32; LANES]) -> Dither8 {
        // `(h & 0xffff) * 255 >> 16` in the low slot of each dword (one `pmulhuw`), then in
        // both slots, then to the packed order (one `vpermd` with AVX2).
        let lo: u16x16 = cast(u32x8::new(*h) & u32x8::splat(0xffff));
        let d: u32x8 = cast::<u16x16, u32x8>(lo.mul_keep_high(u16x16::splat(255)));
        let d = (d | (d << 16_u32)).to_array();
        Dither8(cast(u32x8::new([d[0], d[4], d[1], d[5], d[2], d[6], d[3], d[7]])))
    }
}

/// Each 64-bit lane's high dword moved to its low dword.
#[inline(always)]
fn high(x: u32x8) -> u32x8 {
    cast::<u64x4, u32x8>(cast::<u32x8, u64x4>(x) >> 32)
}

/// [`crate::arith::depth_key`] of each dword: its own inverse.
#[inline(always)]
fn depth_keys(z: u32x8) -> u32x8 {
    z ^ (cast::<i32x8, u32x8>(cast::<u32x8, i32x8>(z) >> 31) & u32x8::splat(0x7fff_ffff))
}

/// [`crate::arith::centroid_depth`] of 8 row pairs, one per dword: `front0` and `back0` hold
/// the rows' first words (T in the high byte), `zf` and `zb` their depth bits; returns the
/// merged depths' bits.
///
/// The weight `floor(256 * cb / den)` is `trunc(256 * (f32(cb) / f32(den)))`, exact on every
/// backend with IEEE division (the argument is in [`crate::arith::centroid_weight`]; the
/// exhaustive test below checks every pair). The depth step `floor(diff * w / 65536)` is two
/// 16-bit products of the key difference's halves.
#[inline(always)]
fn centroid8(front0: u32x8, back0: u32x8, zf: u32x8, zb: u32x8) -> u32x8 {
    let i = |v: u32x8| cast::<u32x8, i32x8>(v);
    let u = |v: i32x8| cast::<i32x8, u32x8>(v);
    let u16s = |v: u32x8| cast::<u32x8, u16x16>(v);
    let u32s = |v: u16x16| cast::<u16x16, u32x8>(v);
    let tf = front0 >> 24;
    let tb = back0 >> 24;
    let p = u32s(u16s(tf) * u16s(tb)); // T_f * T_b < 2^16: the low slot's product
    let cb = ((tf << 8) - tf - p) << 8; // 256 (255 - T_b) T_f < 2^24: exact in f32
    // den = 65025 - p, 0 only where cb is 0 too: max(den, 1) makes that 0 / 1.
    let den = f32x8::from_u(u32x8::splat(65025) - p).fast_max(f32x8::splat(1.0));
    // The quotient is at most 256: capped at 255 before the truncation.
    let q = u((f32x8::from_u(cb) / den).fast_min(f32x8::splat(255.0)).fast_trunc_int());
    let gate = i(tf).simd_gt(i32x8::splat(crate::arith::CENTROID_MIN_T as i32 - 1));
    let w = (q << 8) & u(gate);
    let w2 = u16s(w | (w << 16));
    let (kf, kb) = (depth_keys(zf), depth_keys(zb));
    let diff = u(i(kb) - i(kf)) & u(i(kb).simd_gt(i(kf)));
    let d = u16s(diff);
    let step = u32s(d.mul_keep_high(w2)) + (u32s(d * w2) >> 16);
    depth_keys(u(i(kf) + i(step)))
}

/// The rows' first words of 8 lanes in one register, dword `2 i` = row `i`, `2 i + 1` = row
/// `4 + i` (no shuffle: [`words0`], the resolve's order), and their depths in the same order.
#[inline(always)]
fn pack_words<const S: bool>(r: Lanes8<S>) -> (u32x8, u32x8) {
    (words0(r), words1(r))
}

impl<const S: bool> Lanes8<S> {
    #[inline(always)]
    pub(super) fn load(rows: &[Row; 8]) -> Self {
        Self::from_rows(*rows)
    }
}

impl<const S: bool> Layer8 for Lanes8<S> {
    #[inline(always)]
    fn from_rows(rows: [Row; 8]) -> Self {
        let [a, b]: [u32x8; 2] = cast(rows);
        Lanes8 { a, b }
    }
    #[inline(always)]
    fn to_rows(self) -> [Row; 8] {
        cast([self.a, self.b])
    }
}

impl<const S: bool> RowLanes for Lanes8<S> {
    type Mask = Mask8<S>;
    type Tail<T: TailFormat> = Self;
    type Hash = Dither8;
    #[inline(always)]
    fn depth_le(self, other: Self) -> Mask8<S> {
        let le = |x: u32x8, y: u32x8| {
            let m = cast::<f32x8, u32x8>(cast::<u32x8, f32x8>(x).simd_le(cast::<u32x8, f32x8>(y)));
            // Only the high (depth) dword of each lane is meaningful.
            if S { m } else { widen_hi(m) }
        };
        Mask8 {
            a: le(self.a, other.a),
            b: le(self.b, other.b),
        }
    }
    #[inline(always)]
    fn select(mask: Mask8<S>, x: Self, y: Self) -> Self {
        let sel = |m: u32x8, p: u32x8, q: u32x8| -> u32x8 {
            if S {
                cast(cast::<u32x8, f64x4>(m).select(cast::<u32x8, f64x4>(p), cast::<u32x8, f64x4>(q)))
            } else {
                m.select(p, q)
            }
        };
        Lanes8 {
            a: sel(mask.a, x.a, y.a),
            b: sel(mask.b, x.b, y.b),
        }
    }
    /// With `SIGN`, the stored row is `a ^ b ^ next` (two xors) rather than a second
    /// `vblendvpd`: LLVM folds a `vblendvpd` whose result is stored where its second operand
    /// was loaded from into `vmaskmovpd`, which AMD CPUs microcode (much slower MLAB inserts
    /// on Zen 2-4; `benches/asm/check.sh` fails on it). The row the next layer waits on stays one `vblendvpd`.
    #[inline(always)]
    fn swap(mask: Mask8<S>, x: Self, y: Self) -> (Self, Self) {
        let next = Self::select(mask, y, x);
        if S {
            let front = Lanes8 {
                a: x.a ^ y.a ^ next.a,
                b: x.b ^ y.b ^ next.b,
            };
            (front, next)
        } else {
            (Self::select(mask, x, y), next)
        }
    }
    #[inline(always)]
    fn merge<A: Arithmetic>(front: Self, back: Self, d: Dither8) -> Self {
        match A::KIND {
            // All 8 merges in one register, then back to the rows' low dwords: faster than
            // one merge per register with AVX2, slower on SSE2, where the packing costs more
            // than it saves (docs/performance.md, span lanes).
            Kind::Paper if PACK_PAPER_MERGE => {
                let c = merge_words_paper(words0(front), words0(back));
                Lanes8 {
                    a: lo_hi(c, front.a),
                    b: lo_hi(high(c), front.b),
                }
            }
            Kind::Paper => Lanes8 {
                a: merge4_paper(front.a, back.a),
                b: merge4_paper(front.b, back.b),
            },
            Kind::Unbiased => {
                // All 8 merges in one register (`pack_words`): their first words and their
                // depths, then back to the rows' low and high dwords.
                let ((f0, zf), (b0, zb)) = (pack_words(front), pack_words(back));
                // The weight is 0 in every lane whose front is below the threshold: where no
                // lane's front is, the merged depth is the front's and its chain is skipped.
                let faint = cast::<i32x8, u32x8>(
                    cast::<u32x8, i32x8>(f0 >> 24).simd_gt(i32x8::splat(crate::arith::CENTROID_MIN_T as i32 - 1)),
                );
                let z = if faint.any() { centroid8(f0, b0, zf, zb) } else { zf };
                let c = merge_words_unbiased(f0, b0, d.0);
                let low = |x: u32x8| cast::<u64x4, u32x8>(cast::<u32x8, u64x4>(x) << 32);
                Lanes8 {
                    a: lo_hi(c, low(z)),
                    b: lo_hi(high(c), z),
                }
            }
        }
    }
    #[inline(always)]
    fn tail_add<T: TailFormat>(tail: Self, row: Self) -> Self {
        let f = match T::LAYOUT {
            Layout::Paper => tail_add4_paper,
            Layout::Wide => tail_add4_wide,
        };
        Lanes8 {
            a: f(tail.a, row.a),
            b: f(tail.b, row.b),
        }
    }
    #[inline(always)]
    fn select_tail<T: TailFormat>(mask: Mask8<S>, x: Self, y: Self) -> Self {
        Self::select(mask, x, y)
    }
}

/// `word0` of 8 rows (or tails) in one register, pixels in [`POSITION`] order.
#[inline(always)]
pub(super) fn words0<const S: bool>(r: Lanes8<S>) -> u32x8 {
    (r.a & LO) | cast::<u64x4, u32x8>(cast::<u32x8, u64x4>(r.b) << 32)
}

/// `word1` of 8 rows (or tails) in one register, pixels in [`POSITION`] order.
#[inline(always)]
pub(super) fn words1<const S: bool>(r: Lanes8<S>) -> u32x8 {
    cast::<u64x4, u32x8>(cast::<u32x8, u64x4>(r.a) >> 32) | (r.b & HI)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The lane centroid depth against the scalar [`crate::arith::centroid_depth`] for every
    /// pair of transmittance bytes and depth pairs of every order and sign (equal, swapped,
    /// across zero, far apart, +infinity behind, NaN), which covers every weight the f32
    /// estimate and its correction produce.
    #[test]
    fn centroid8_is_the_scalar_centroid_for_every_pair() {
        let depths: [(f32, f32); 8] = [
            (1.0, 2.0),
            (-3.0, 1.0e30),
            (0.25, 0.25),
            (5.0, 4.0),
            (-0.0, 0.0),
            (1.0e-30, f32::INFINITY),
            (-2.0e9, -1.0e-9),
            (f32::NAN, 1.0),
        ];
        for tf in 0..256u32 {
            for tb in (0..256u32).step_by(4) {
                for (zf, zb) in depths {
                    let fr: [Row; 4] = core::array::from_fn(|i| Row::new([3, 2, 1], tf as u8, zf + i as f32));
                    let bk: [Row; 4] = core::array::from_fn(|i| Row::new([9, 8, 7], (tb + i as u32) as u8, zb));
                    let words = |r: [Row; 4], w: usize| u32x8::new(core::array::from_fn(|k| r[k / 2].words()[w]));
                    let got = centroid8(words(fr, 0), words(bk, 0), words(fr, 1), words(bk, 1)).to_array();
                    for k in 0..8 {
                        let want = crate::arith::centroid_depth(fr[k / 2], bk[k / 2]);
                        assert_eq!(got[k], want, "T {tf} {}, z {zf} {zb}", tb + (k / 2) as u32);
                    }
                }
            }
        }
    }
}

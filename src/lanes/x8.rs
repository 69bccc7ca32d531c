//! The 8-wide implementation of the lane traits ([`crate::vector`],
//! [`crate::resolve::FloatLanes`]): eight rows in two 256-bit registers, SWAR merges and tail
//! adds on 16-bit slots, the lane quantizer and the resolve's register layout. The only file
//! of the crate that uses `wide`.

use super::{FragmentLanes, MlabSpan, QuantizedLanes};
use crate::arith::{Arithmetic, Kind};
use crate::resolve::{Background, FloatLanes};
use crate::row::Row;
use crate::tail::{Layout, TailFormat};
use crate::vector::{Layer8, RowLanes};
use bytemuck::cast;
use wide::{f32x8, f64x4, i16x16, i32x8, u8x32, u16x16, u32x8, u64x4};

use super::LANES;

/// `[v; N]` pairs: `[a, b, a, b, ...]` (the low and high half of each wider lane).
pub(super) const fn pairs<T: Copy, const N: usize>(a: T, b: T) -> [T; N] {
    let mut out = [a; N];
    let mut i = 1;
    while i < N {
        out[i] = b;
        i += 2;
    }
    out
}

/// The SWAR arithmetic on whole rows, written once for any register width: the merges
/// (Eq. 7-8) and the tail adds on the 16-bit slots of one register of 64-bit rows, and
/// their masks and constants. The calling module provides what lowers differently by width:
/// `mul257_high(y)`, `(y * 257) >> 16` in each 16-bit slot for `y <= 65280`; `lo_hi(lo, hi)`,
/// the low dword of each 64-bit lane from `lo` and the high one from `hi`; and
/// `skip_invisible(row, tail, new)`, `tail` where `row` is invisible (no color, T = 255),
/// else `new`. `swar!(u32xN, u16x2N, u8x4N, i16x2N, u64xN/2)` defines them for
/// that width in the module that calls it: 256 bits here (four rows per register), 512 bits
/// in `src/lanes/x16.rs` (eight rows). Each row's 64-bit lane is computed alone.
macro_rules! swar {
    ($u32:ident, $u16:ident, $u8:ident, $i16:ident, $u64:ident) => {
        /// Low dword of every 64-bit lane (a row's color and transmittance; a tail's color sums).
        pub(super) const LO: $u32 = $u32::new($crate::lanes::x8::pairs(!0, 0));
        /// High dword of every 64-bit lane (a row's depth; a tail's alpha sum and count).
        pub(super) const HI: $u32 = $u32::new($crate::lanes::x8::pairs(0, !0));
        pub(super) const BYTES02: $u32 = $u32::splat(0x00ff_00ff);

        /// Copy the mask in the high dword of each 64-bit lane to the whole lane.
        #[inline(always)]
        pub(super) fn widen_hi(m: $u32) -> $u32 {
            let h = m & HI;
            h | ::bytemuck::cast::<$u64, $u32>(::bytemuck::cast::<$u32, $u64>(h) >> 32)
        }

        /// `round(x / 255)` in each 16-bit slot holding `x <= 65025`: `((x + 128) * 257) >> 16`,
        /// one add and one high multiply (`pmulhuw`). Equal to [`crate::unorm::div255`] for every
        /// such `x` (`div255_slots_is_exact` checks all of them).
        #[inline(always)]
        pub(super) fn div255_slots(x: $u16) -> $u16 {
            mul257_high(x + $u16::splat(128))
        }

        /// `T_front` in both 16-bit slots of each row's low dword (the high dword is don't-care),
        /// and the back row's bytes 0 and 2 (R, B) and 1 and 3 (G, T), one per 16-bit slot.
        #[inline(always)]
        pub(super) fn merge_operands(front: $u32, back: $u32) -> ($u16, $u16, $u16) {
            let t = (front >> 24) & $u32::splat(0xff);
            let t2: $u16 = ::bytemuck::cast(t | (t << 16));
            let even: $u16 = ::bytemuck::cast(back & BYTES02);
            let odd: $u16 = ::bytemuck::cast((back >> 8) & BYTES02);
            (t2, even, odd)
        }

        /// `A_front + products` bytewise, saturating, in every dword; the front's T byte is
        /// replaced by the product's T.
        #[inline(always)]
        pub(super) fn merge_sum(front: $u32, pe: $u16, po: $u16) -> $u32 {
            let product = ::bytemuck::cast::<$u16, $u32>(pe) | (::bytemuck::cast::<$u16, $u32>(po) << 8);
            let a_front = front & $u32::splat(0x00ff_ffff);
            ::bytemuck::cast(::bytemuck::cast::<$u32, $u8>(a_front).saturating_add(::bytemuck::cast(product)))
        }

        /// The paper's merge (Eq. 7-8) of first words, dword for dword (as
        /// [`merge_words_unbiased`]): SWAR over 16-bit slots.
        #[inline(always)]
        pub(super) fn merge_words_paper(front: $u32, back: $u32) -> $u32 {
            let (t2, even, odd) = merge_operands(front, back);
            // Each product <= 255 * 255: no carry out of its slot.
            merge_sum(front, div255_slots(even * t2), div255_slots(odd * t2))
        }

        /// The paper's merge (Eq. 7-8) for the rows of one register (the depth is the front's).
        #[inline(always)]
        pub(super) fn merge4_paper(front: $u32, back: $u32) -> $u32 {
            lo_hi(merge_words_paper(front, back), front)
        }

        /// Turns `d` in both slots into `[255 - d, d + 1]` (G slot, T slot): `(d ^ 0xffff) + 256`
        /// is `255 - d` modulo 2^16.
        // The unbiased merge's constants and function are unused in `x16.rs`, whose MLAB merge
        // (tests only: MLAB runs on these 8-wide lanes) is the scalar one per lane.
        #[allow(dead_code)]
        pub(super) const ODD_XOR: $u16 = $u16::new($crate::lanes::x8::pairs(0xffff, 0));
        #[allow(dead_code)]
        pub(super) const ODD_ADD: $u16 = $u16::new($crate::lanes::x8::pairs(256, 1));

        /// The colors and transmittance of the unbiased merge ([`Unbiased`](crate::Unbiased)):
        /// each dword of `front` and `back` a row's first word (color and T; 8 rows packed in
        /// one register, or the low dwords of rows), with their dither `d` (one per dword, in
        /// both 16-bit slots): `floor((p + d') / 255)` as `((p + d' + 1) * 257) >> 16`, with
        /// `d' = d` for T and `254 - d` for the colors. Returns the merged first words, dword
        /// for dword.
        #[inline(always)]
        #[allow(dead_code)]
        pub(super) fn merge_words_unbiased(front: $u32, back: $u32, d: $u16) -> $u32 {
            let (t2, even, odd) = merge_operands(front, back);
            let inv = $u16::splat(255) - d; // (254 - d) + 1: R and B
            let odd_d = (d ^ ODD_XOR) + ODD_ADD; // G: (254 - d) + 1, T: d + 1
            // Products <= 65025, plus at most 255: no carry out of a slot.
            let pe = mul257_high(even * t2 + inv);
            let po = mul257_high(odd * t2 + odd_d);
            merge_sum(front, pe, po)
        }

        /// [`PaperTail`](crate::hybrid::PaperTail)`::add` for the tails of one register.
        #[inline(always)]
        pub(super) fn tail_add4_paper(tail: $u32, row: $u32) -> $u32 {
            let field = $u32::splat(0x3ff);
            let byte = $u32::splat(0xff);
            let max: $i16 = $i16::splat(1023);
            // Color sums: each field + its byte, capped at 1023 (values < 2^15: i16 min is exact).
            let sat = |sum: $u32| -> $u32 { ::bytemuck::cast(::bytemuck::cast::<$u32, $i16>(sum).min(max)) };
            let r = sat((tail & field) + (row & byte));
            let g = sat(((tail >> 10) & field) + ((row >> 8) & byte));
            let b = sat(((tail >> 20) & field) + ((row >> 16) & byte));
            let word0 = r | (g << 10) | (b << 20) | (tail & $u32::splat(0xc000_0000));
            // Alpha sum += 255 - T and count += 1: two saturating u16 adds in the high dword.
            let inc = ($u32::splat(255) - (row >> 24)) | $u32::splat(1 << 16);
            let inc = ::bytemuck::cast::<$u64, $u32>(::bytemuck::cast::<$u32, $u64>(inc & LO) << 32);
            let word1: $u32 =
                ::bytemuck::cast(::bytemuck::cast::<$u32, $u16>(tail).saturating_add(::bytemuck::cast(inc)));
            let new = lo_hi(word0, word1);
            // Invisible rows (no color, T = 255) are skipped.
            skip_invisible(row, tail, new)
        }

        /// Low dword masks for the fields of the wide tail.
        pub(super) const BYTE_LO: $u32 = $u32::new($crate::lanes::x8::pairs(0xff, 0));
        pub(super) const SUM_LO: $u32 = $u32::new($crate::lanes::x8::pairs(0x1fff, 0));
        pub(super) const ALPHA_LO: $u32 = $u32::new($crate::lanes::x8::pairs(0x3fff, 0));
        pub(super) const ONE_LO: $u32 = $u32::new($crate::lanes::x8::pairs(1, 0));

        /// [`Tail`](crate::Tail)`::add` for the tails of one register (each tail one `u64`:
        /// colors at bits 0, 13, 26, alpha at 39, count at 53).
        #[inline(always)]
        pub(super) fn tail_add4_wide(tail: $u32, row: $u32) -> $u32 {
            let shr = |v: $u32, n: u64| ::bytemuck::cast::<$u64, $u32>(::bytemuck::cast::<$u32, $u64>(v) >> n);
            let shl = |v: $u32, n: u64| ::bytemuck::cast::<$u64, $u32>(::bytemuck::cast::<$u32, $u64>(v) << n);
            // Sums below 2^15 in the low 16-bit slot, zero elsewhere: i16 min is exact.
            let sat = |v: $u32, max: i16| -> $u32 {
                ::bytemuck::cast(::bytemuck::cast::<$u32, $i16>(v).min($i16::splat(max)))
            };
            let r = row & BYTE_LO;
            let g = (row >> 8) & BYTE_LO;
            let b = (row >> 16) & BYTE_LO;
            let a = ((row >> 24) ^ BYTE_LO) & BYTE_LO; // 255 - T
            let sr = sat((tail & SUM_LO) + r, 8191);
            let sg = sat(((tail >> 13) & SUM_LO) + g, 8191);
            let sb = sat((shr(tail, 26) & SUM_LO) + b, 8191);
            let sa = sat((shr(tail, 39) & ALPHA_LO) + a, 16383);
            let sn = sat(shr(tail, 53) + ONE_LO, 2047);
            let new = sr | (sg << 13) | shl(sb, 26) | shl(sa, 39) | shl(sn, 53);
            // Invisible rows (no color, T = 255) are skipped.
            skip_invisible(row, tail, new)
        }
    };
}
pub(super) use swar;

swar!(u32x8, u16x16, u8x32, i16x16, u64x4);

/// `(lo & LO) | (hi & HI)` (on AVX2 one `vpblendd`).
#[inline(always)]
fn lo_hi(lo: u32x8, hi: u32x8) -> u32x8 {
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

/// The SIMD instruction set `wide` compiled the lanes for, chosen at compile time:
///
/// - `"avx512"`: a build with `avx512f` and `avx512bw` (`x86-64-v4`). The HT span inserts
///   keep the eight rows of a layer in one 512-bit register (`src/lanes/x16.rs`); the MLAB
///   span inserts, the quantizer and the resolves run on the 256-bit registers of the 8-wide
///   lanes (where 512-bit MLAB lanes measured slower: `docs/performance.md`).
/// - `"avx2 (avx512f build)"`: `avx512f` without `avx512bw` (no `x86-64-v*` level): the
///   8-wide lanes on AVX2, as `wide` compiles them there.
/// - `"avx2"`: one 256-bit register per 8-wide vector.
/// - `"sse2"`: x86 without AVX2, two 128-bit halves (`wide` uses SSSE3, SSE4.1 or AVX where
///   the build has them).
/// - `"neon"`: two 128-bit NEON halves (aarch64).
/// - `"simd128"`: two 128-bit halves (wasm32 with `simd128`).
/// - `"portable"`: no SIMD, plain arrays (wasm32 without `simd128`, any other target).
pub const BACKEND: &str = if cfg!(all(target_feature = "avx512f", target_feature = "avx512bw")) {
    "avx512"
} else if cfg!(target_feature = "avx512f") {
    "avx2 (avx512f build)"
} else if cfg!(target_feature = "avx2") {
    "avx2"
} else if cfg!(target_feature = "sse2") {
    "sse2"
} else if cfg!(all(target_arch = "aarch64", target_feature = "neon")) {
    "neon"
} else if cfg!(all(target_family = "wasm", target_feature = "simd128")) {
    "simd128"
} else {
    "portable"
};

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
    a: u32x8,
    b: u32x8,
}

/// The lanes of Listing 1 (MLAB): with AVX, a select of whole rows is `vblendvpd`, which
/// reads only the sign bit of each 64-bit lane, that is the depth dword's compare result: the
/// masks need no widening. Without AVX the select is bitwise and the masks are widened to
/// whole lanes. Both give the same rows.
pub(crate) type Rows8 = Lanes8<{ cfg!(target_feature = "avx") }>;

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

/// Whether the paper's merge packs the first words of the 8 merged rows into one register
/// (as the unbiased merge always does): faster with AVX2, slower on SSE2 at M = 8.
const PACK_PAPER_MERGE: bool = cfg!(target_feature = "avx2");

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
    /// was loaded from into `vmaskmovpd`, which AMD CPUs microcode (1.4-2.2x slower MLAB
    /// inserts on Zen 4, issue 31). The row the next layer waits on stays one `vblendvpd`.
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
            // All 8 merges in one register, then back to the rows' low dwords: 0.83-0.90x
            // the time of one merge per register with AVX2, but 1.43x at M = 8 on SSE2
            // (docs/performance.md, "The merge on one register").
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
                let z = centroid8(f0, b0, zf, zb);
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

/// [`FragmentLanes::quantize_with`] and [`FragmentLanes::quantize_straight_with`].
#[inline(always)]
pub(super) fn quantize<A: Arithmetic>(
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

/// Where pixel `p` of a span sits in the registers of the resolve: the 8 row words are
/// packed without a shuffle as `(a & LO) | (b << 32)`, which orders the pixels
/// `[0, 4, 1, 5, 2, 6, 3, 7]`. Every resolve step is per lane, so the order only matters when
/// the results are written out.
const POSITION: [usize; LANES] = [0, 2, 4, 6, 1, 3, 5, 7];

/// `word0` of 8 rows (or tails) in one register, pixels in [`POSITION`] order.
#[inline(always)]
fn words0<const S: bool>(r: Lanes8<S>) -> u32x8 {
    (r.a & LO) | cast::<u64x4, u32x8>(cast::<u32x8, u64x4>(r.b) << 32)
}

/// `word1` of 8 rows (or tails) in one register, pixels in [`POSITION`] order.
#[inline(always)]
fn words1<const S: bool>(r: Lanes8<S>) -> u32x8 {
    cast::<u64x4, u32x8>(cast::<u32x8, u64x4>(r.a) >> 32) | (r.b & HI)
}

/// Back to pixel order.
#[inline(always)]
pub(super) fn unpermute<T: Copy>(x: [T; LANES]) -> [T; LANES] {
    core::array::from_fn(|p| x[POSITION[p]])
}

/// Color and transmittance bytes of one layer of 8 rows, as exact f32 (`[R, G, B, T]`).
#[inline(always)]
fn layer_bytes(layer: &[Row; LANES]) -> [f32x8; 4] {
    rgbt_bytes(words0(Rows8::load(layer)))
}

/// The `[R, G, B, T]` bytes of 8 color words, as exact f32.
#[inline(always)]
fn rgbt_bytes(rgbt: u32x8) -> [f32x8; 4] {
    let byte = u32x8::splat(0xff);
    [rgbt & byte, (rgbt >> 8) & byte, (rgbt >> 16) & byte, rgbt >> 24].map(f32x8::from_u)
}

/// The HT resolve in registers, pixels in [`POSITION`] order.
#[inline(always)]
fn hybrid_resolve_regs<T: TailFormat, const K: usize>(
    head: &[[Row; LANES]; K],
    tails: &[T; LANES],
) -> ([f32x8; 3], f32x8) {
    let head = crate::resolve::resolve_layers(head.iter().map(layer_bytes));
    let (sums, alpha, count) = tail_fields(tails);
    crate::resolve::resolve_lanes::<f32x8>(head, sums, alpha, count)
}

/// `word0` (the `[R, G, B, T]` bytes) of one layer of 8 rows, pixels in [`POSITION`] order.
#[inline(always)]
pub(super) fn layer_words(layer: &[Row; LANES]) -> u32x8 {
    words0(Rows8::load(layer))
}

/// The fields of 8 tails (color sums, alpha sum, count), pixels in [`POSITION`] order.
#[inline(always)]
pub(super) fn tail_fields<T: TailFormat>(tails: &[T; LANES]) -> ([u32x8; 3], u32x8, u32x8) {
    let tails = Rows8::from_rows(cast(*tails));
    let (w0, w1) = (words0(tails), words1(tails));
    match T::LAYOUT {
        Layout::Paper => {
            let field = u32x8::splat(0x3ff);
            let sums = [w0 & field, (w0 >> 10) & field, (w0 >> 20) & field];
            (sums, w1 & u32x8::splat(0xffff), w1 >> 16)
        }
        Layout::Wide => {
            // Colors at bits 0, 13, 26 (the last one across the words), alpha at 39, count at 53.
            let field = u32x8::splat(0x1fff);
            let blue = (w0 >> 26) | ((w1 & u32x8::splat(0x7f)) << 6);
            (
                [w0 & field, (w0 >> 13) & field, blue],
                (w1 >> 7) & u32x8::splat(0x3fff),
                w1 >> 21,
            )
        }
    }
}

/// `x` clamped to `[0, 1]` with NaN to 0, as [`crate::to_rgba8`] clamps: `x > 1 ? 1 : x`,
/// then `x >= 0 ? x : 0`. On x86 these are exactly `minps(1, x)` then `maxps(x, 0)` (each
/// returns its second operand when the compare is false, NaN included); elsewhere `wide`'s
/// min and max differ on NaN between backends, so the selects are written out.
#[inline(always)]
fn clamp01(x: f32x8) -> f32x8 {
    let (zero, one) = (f32x8::ZERO, f32x8::ONE);
    if cfg!(any(target_arch = "x86", target_arch = "x86_64")) && cfg!(target_feature = "sse") {
        one.fast_min(x).fast_max(zero)
    } else {
        let x = x.simd_gt(one).select(one, x);
        x.simd_ge(zero).select(x, zero)
    }
}

/// [`crate::to_rgba8`] for 8 lanes, one channel: the byte in the low 8 bits of each lane,
/// the other bits zero (`x * 255 + 0.5` lies in `[0.5, 255.5]`: no mask needed).
#[inline(always)]
fn to_unorm8_lanes(x: f32x8) -> u32x8 {
    let q = clamp01(x) * f32x8::splat(255.0) + f32x8::splat(0.5);
    cast::<i32x8, u32x8>(q.fast_trunc_int())
}

/// [`crate::to_rgba8`] of [`Resolved::pixel`] for 8 lanes; the output keeps the lane order.
/// Over an opaque background the alpha byte is the constant 255 (`to_rgba8` of 1).
#[inline(always)]
fn rgba8_lanes(c: [f32x8; 3], t: f32x8, background: Background) -> [[u8; 4]; LANES] {
    let packed = match background {
        Background::Opaque(bg) => {
            let bg = bg.to_array().map(f32x8::splat);
            let q: [u32x8; 3] = core::array::from_fn(|i| to_unorm8_lanes(c[i] + bg[i] * t));
            q[0] | (q[1] << 8) | (q[2] << 16) | u32x8::splat(0xff00_0000)
        }
        Background::Transparent => {
            let q = [c[0], c[1], c[2], f32x8::ONE - t].map(to_unorm8_lanes);
            q[0] | (q[1] << 8) | (q[2] << 16) | (q[3] << 24)
        }
    };
    cast::<u32x8, [u32; LANES]>(packed).map(u32::to_le_bytes)
}

/// A resolve of 8 pixels in registers, pixels in [`POSITION`] order.
#[derive(Clone, Copy)]
pub(super) struct Resolved8 {
    color: [f32x8; 3],
    t: f32x8,
}

impl Resolved8 {
    /// Structure of arrays, in pixel order.
    #[inline(always)]
    pub(super) fn lanes(self) -> super::ResolvedLanes {
        super::ResolvedLanes {
            color: self.color.map(|c| unpermute(c.to_array())),
            transmittance: unpermute(self.t.to_array()),
        }
    }
}

/// Eq. 5 over an MLAB span.
#[inline(always)]
pub(super) fn mlab_resolve<const M: usize>(span: &MlabSpan<M>) -> Resolved8 {
    let (color, t) = crate::resolve::resolve_layers(span.iter().map(layer_bytes));
    Resolved8 { color, t }
}

/// Eq. 5 over 8 pixels stored pixel-major (`pixels[lane][layer]`): each layer's color and
/// transmittance words are read straight into a register in [`POSITION`] order, without
/// transposing whole rows first. The same values as [`mlab_resolve`] of the transposed span.
#[inline(always)]
pub(super) fn mlab_resolve_pixel_major<const M: usize>(pixels: &[[Row; M]; LANES]) -> Resolved8 {
    let layer = |j: usize| {
        let words = if M == 1 {
            // The rows are contiguous: two vector loads, then the color words in
            // [`POSITION`] order as for a span's layer ([`words0`]). (The inserts below took
            // 11-13 % longer on AVX2 than on SSE2 here.)
            let q = |p: usize| cast::<Row, u64>(pixels[p][j]);
            let (a, b) = (
                u64x4::new([q(0), q(1), q(2), q(3)]),
                u64x4::new([q(4), q(5), q(6), q(7)]),
            );
            words0(Rows8 { a: cast(a), b: cast(b) })
        } else {
            // Lane `POSITION[p]` holds pixel `p`: lanes 0..8 are pixels 0, 4, 1, 5, 2, 6, 3, 7.
            let w = |p: usize| pixels[p][j].words()[0];
            u32x8::new([w(0), w(4), w(1), w(5), w(2), w(6), w(3), w(7)])
        };
        rgbt_bytes(words)
    };
    let (color, t) = crate::resolve::resolve_layers((0..M).map(layer));
    Resolved8 { color, t }
}

/// The HT resolve of head layers and tails.
#[inline(always)]
pub(super) fn hybrid_resolve<T: TailFormat, const K: usize>(head: &[[Row; LANES]; K], tails: &[T; LANES]) -> Resolved8 {
    let (color, t) = hybrid_resolve_regs(head, tails);
    Resolved8 { color, t }
}

/// [`crate::to_rgba8`] per lane of a resolve given as arrays (lane order kept).
#[inline(always)]
pub(super) fn rgba8(color: &[[f32; LANES]; 3], t: &[f32; LANES], background: Background) -> [[u8; 4]; LANES] {
    rgba8_lanes(color.map(f32x8::new), f32x8::new(*t), background)
}

/// Whether the build is x86 without SSSE3 (the x86-64 baseline, SSE2): no byte shuffle and no
/// `pmulhrsw`, which `wide` would emulate lane by lane (195 instructions per pixel at M = 4);
/// [`int8`] then has an SSE2 form of its own.
macro_rules! sse2_only {
    ($($item:item)*) => {
        $(#[cfg(all(any(target_arch = "x86", target_arch = "x86_64"), not(target_feature = "ssse3")))] $item)*
    };
}
macro_rules! not_sse2_only {
    ($($item:item)*) => {
        $(#[cfg(not(all(any(target_arch = "x86", target_arch = "x86_64"), not(target_feature = "ssse3"))))] $item)*
    };
}

not_sse2_only! {
/// The integer resolve (`crate::resolve::int`) in 16-bit lanes: four pixels per register,
/// each pixel's four 16-bit slots `[R, G, B, T]` (its 8 bytes of a 128-bit half). Per layer,
/// one shuffle, one shift, one `pmulhrsw`, one saturating add and one shuffle.
mod int8 {
    use super::*;
    use crate::resolve::int;
    use wide::i8x32;

    /// A zeroing shuffle index.
    const Z: i8 = -128;

    /// Two copies of a 16-byte shuffle (each 128-bit half shuffles its own bytes).
    const fn halves(h: [i8; 16]) -> i8x32 {
        let mut out = [0i8; 32];
        let mut i = 0;
        while i < 16 {
            out[i] = h[i];
            out[i + 16] = h[i];
            i += 1;
        }
        i8x32::new(out)
    }

    /// Each row's bytes to the 16-bit slots `[256 R, 256 G, 256 B, 257 T]` (two rows per half;
    /// the depth bytes are dropped).
    const ROW_SLOTS: [i8; 16] = [Z, 0, Z, 1, Z, 2, 3, 3, Z, 8, Z, 9, Z, 10, 11, 11];
    /// Slot 3 of each pixel (its visibility product) to all four of its slots.
    const BROADCAST_T: [i8; 16] = [6, 7, 6, 7, 6, 7, 6, 7, 14, 15, 14, 15, 14, 15, 14, 15];
    /// The low bytes of the 16-bit slots of a half to its bytes 0..8 (`PACK_LO`) or 8..16
    /// (`PACK_HI`), the other bytes zero.
    const PACK_LO: [i8; 16] = [0, 2, 4, 6, 8, 10, 12, 14, Z, Z, Z, Z, Z, Z, Z, Z];
    const PACK_HI: [i8; 16] = [Z, Z, Z, Z, Z, Z, Z, Z, 0, 2, 4, 6, 8, 10, 12, 14];

    /// Four rows (pixels) as the factors `[128 R, 128 G, 128 B, floor(257 T / 2)]`.
    #[inline(always)]
    fn factors(rows: [Row; 4]) -> i16x16 {
        let x: i8x32 = cast(rows);
        let s: u16x16 = cast(x.swizzle_half(halves(ROW_SLOTS)));
        cast(s >> 1)
    }

    /// One layer of four pixels: `acc += q15(f, v)` (saturating at 32767), then
    /// `v = q15(T factor, v)` in every slot of the pixel.
    #[inline(always)]
    pub(super) fn layer(acc: &mut i16x16, v: &mut i16x16, f: i16x16) {
        let p = f.mul_scale_round(*v);
        *acc = acc.saturating_add(p);
        *v = cast(cast::<i16x16, i8x32>(p).swizzle_half(halves(BROADCAST_T)));
    }

    /// Eq. 5 in integers over `m` layers of 8 pixels (`layer(j)`: the factors of pixels 0..4
    /// and 4..8), then the pixels (`int::pixel` per lane): over the opaque background `bg`
    /// when `OPAQUE`, else premultiplied (`bg` unused).
    #[inline(always)]
    pub(super) fn resolve<const OPAQUE: bool>(
        m: usize,
        layer_rows: impl Fn(usize) -> [Row; LANES],
        bg: [u32; 3],
    ) -> [[u8; 4]; LANES] {
        let layer_factors = |j: usize| {
            let l = layer_rows(j);
            [factors([l[0], l[1], l[2], l[3]]), factors([l[4], l[5], l[6], l[7]])]
        };
        // Over an opaque background slot 3 (the visibility products, not read) starts at
        // 32767 and stays there (saturating adds of non-negative values): its byte is the
        // alpha 255.
        let start = int::ACC_START as i16;
        let alpha = if OPAQUE { int::ACC_MAX as i16 } else { start };
        let mut acc = [i16x16::new(core::array::from_fn(|i| if i % 4 == 3 { alpha } else { start })); 2];
        let mut v = [i16x16::splat(int::VIS_ONE as i16); 2];
        for j in 0..m {
            let f = layer_factors(j);
            layer(&mut acc[0], &mut v[0], f[0]);
            layer(&mut acc[1], &mut v[1], f[1]);
        }
        pixels::<OPAQUE>(acc, v, bg)
    }

    /// `int::pixel` on 8 pixels: the 16-bit results, then their low bytes in pixel order.
    #[inline(always)]
    fn pixels<const OPAQUE: bool>(acc: [i16x16; 2], v: [i16x16; 2], bg: [u32; 3]) -> [[u8; 4]; LANES] {
        let q: [u16x16; 2] = if OPAQUE {
            let [r, g, b] = bg;
            let bg = i16x16::new(core::array::from_fn(|i| [r, g, b, 0][i % 4] as i16));
            [0, 1].map(|i| cast::<i16x16, u16x16>(acc[i].saturating_add(bg.mul_scale_round(v[i]))) >> 7)
        } else {
            let color = u16x16::new(core::array::from_fn(|i| if i % 4 == 3 { 0 } else { 0xffff }));
            [0, 1].map(|i| {
                let a = (i16x16::splat(int::VIS_ONE as i16) - v[i]).mul_scale_round(i16x16::splat(32640));
                let a = cast::<i16x16, u16x16>(a + i16x16::splat(64)) >> 7;
                let c = cast::<i16x16, u16x16>(acc[i]) >> 7;
                (c & color) | (a & !color)
            })
        };
        let lo = cast::<u16x16, i8x32>(q[0]).swizzle_half(halves(PACK_LO));
        let hi = cast::<u16x16, i8x32>(q[1]).swizzle_half(halves(PACK_HI));
        let bytes: [u64; 4] = cast(lo | hi);
        // The halves hold pixels [0, 1, 4, 5] and [2, 3, 6, 7].
        let words: [u32; LANES] = cast([bytes[0], bytes[2], bytes[1], bytes[3]]);
        words.map(u32::to_le_bytes)
    }
}

}

sse2_only! {
/// The integer resolve (`crate::resolve::int`) on SSE2: two pixels per 128-bit register, each
/// pixel's four 16-bit slots, with the factors and the visibility both doubled:
/// `q15(f, v) = (pmulhuw(2 f, 2 v) + 1) >> 1` (`pmulhuw` gives `floor(4 f v / 65536) =
/// floor(p / 16384) = 2 (p >> 15) + bit 14 of p`, and `(x + 1) >> 1` of that is
/// `(p + 16384) >> 15`). The doubled factors `[256 R, 256 G, 256 B, 2 floor(257 T / 2)]` are one
/// `punpcklbw` of the rows with their T bytes `& 0xfe` (`257 T & !1 = 2 floor(257 T / 2)`).
mod int8 {
    use super::*;
    use crate::resolve::int;
    use wide::{i16x8, u8x16, u16x8, u32x4};

    /// `q15(f, v)` from `f2 = 2 f` (at most 65534) and `v2 = 2 v` (at most 65534).
    #[inline(always)]
    fn q15(f2: u16x8, v2: u16x8) -> u16x8 {
        (f2.mul_keep_high(v2) + u16x8::splat(1)) >> 1
    }

    /// Two rows (pixels) as the doubled factors `[256 R, 256 G, 256 B, 2 floor(257 T / 2)]`.
    #[inline(always)]
    fn factors(rows: [Row; 2]) -> u16x8 {
        let w: [u32; 4] = cast(rows);
        // The color words of both rows in the low 8 bytes (`pshufd`).
        let x: u8x16 = cast(u32x4::new([w[0], w[2], w[1], w[3]]));
        let t: u8x16 = x & cast::<u32x4, u8x16>(u32x4::splat(0xfe00_0000));
        cast(u8x16::unpack_low(t, x))
    }

    /// One layer of two pixels: `acc += q15(f, v)` (saturating at 32767), then the new `2 v`
    /// in every slot of the pixel (`pshuflw`, `pshufhw`, `paddw`).
    #[inline(always)]
    fn layer(acc: &mut i16x8, v2: &mut u16x8, f2: u16x8) {
        let p = q15(f2, *v2);
        *acc = acc.saturating_add(cast(p));
        let a = p.to_array();
        let v = u16x8::new([a[3], a[3], a[3], a[3], a[7], a[7], a[7], a[7]]);
        *v2 = v + v;
    }

    /// The integer resolve of `m` layers of 8 pixels, as the SSSE3/AVX2 form computes it.
    #[inline(always)]
    pub(super) fn resolve<const OPAQUE: bool>(
        m: usize,
        layer_rows: impl Fn(usize) -> [Row; LANES],
        bg: [u32; 3],
    ) -> [[u8; 4]; LANES] {
        let start = int::ACC_START as i16;
        let alpha = if OPAQUE { int::ACC_MAX as i16 } else { start };
        let mut acc = [i16x8::new(core::array::from_fn(|i| if i % 4 == 3 { alpha } else { start })); 4];
        let mut v2 = [u16x8::splat(2 * int::VIS_ONE as u16); 4];
        for j in 0..m {
            let l = layer_rows(j);
            for k in 0..4 {
                layer(&mut acc[k], &mut v2[k], factors([l[2 * k], l[2 * k + 1]]));
            }
        }
        let q: [i16x8; 4] = core::array::from_fn(|k| {
            if OPAQUE {
                let [r, g, b] = bg;
                let bg2 = u16x8::new(core::array::from_fn(|i| (2 * [r, g, b, 0][i % 4]) as u16));
                cast::<u16x8, i16x8>(cast::<i16x8, u16x8>(acc[k].saturating_add(cast(q15(bg2, v2[k])))) >> 7)
            } else {
                let color = u16x8::new(core::array::from_fn(|i| if i % 4 == 3 { 0 } else { 0xffff }));
                let a = q15(u16x8::splat(2 * 32640), u16x8::splat(2 * int::VIS_ONE as u16) - v2[k]);
                let a = (a + u16x8::splat(64)) >> 7;
                let c = cast::<i16x8, u16x8>(acc[k]) >> 7;
                cast((c & color) | (a & !color))
            }
        });
        let lo: [u32; 4] = cast(u8x16::narrow_i16x8(q[0], q[1]));
        let hi: [u32; 4] = cast(u8x16::narrow_i16x8(q[2], q[3]));
        core::array::from_fn(|p| if p < 4 { lo[p] } else { hi[p - 4] }.to_le_bytes())
    }
}
}

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

#[cfg(test)]
mod tests {
    //! The lane arithmetic helpers against plain integer formulas, for every operand
    //! combination they can see (16-bit slots, the SWAR tail fields), so that a backend whose
    //! `wide` lowering differs shows up on the first run, before any randomized test.
    use super::*;

    /// Four whole rows (or tails) as the `u64` lanes of one register.
    fn pack(v: [u64; 4]) -> u32x8 {
        cast(v)
    }

    fn unpack(x: u32x8) -> [u64; 4] {
        cast(x)
    }

    #[test]
    fn div255_slots_is_exact() {
        for x in 0..=255u32 * 255 {
            let got = div255_slots(u16x16::splat(x as u16)).to_array();
            assert!(got.iter().all(|&q| q as u32 == crate::unorm::div255(x)), "x = {x}");
        }
    }

    /// A front row with transmittance `tf` and colors that exercise the saturating add.
    fn front(tf: u32, salt: u32) -> u64 {
        let c = (tf * 37 + salt * 11) & 0xff;
        Row::new([c as u8, (c ^ 0x80) as u8, (255 - c) as u8], tf as u8, -(salt as f32)).to_le_u64()
    }

    /// The back row for byte `b`: every channel sees every byte value as `b` runs over 0..256.
    fn back(b: u32) -> u64 {
        Row::new([b as u8, (b ^ 0x5a) as u8, (b ^ 0xa5) as u8], (b ^ 0x3c) as u8, 7.5).to_le_u64()
    }

    /// The merge of `front` and `back` with products `p(a, b)` (colors) and `q(a, b)` (T).
    fn merged(front: u64, back: u64, p: impl Fn(u32, u32) -> u32, q: impl Fn(u32, u32) -> u32) -> u64 {
        let f = Row::from_le_u64(front);
        let b = Row::from_le_u64(back);
        let [fr, fg, fb, ft] = f.rgbt().map(u32::from);
        let [br, bg, bb, bt] = b.rgbt().map(u32::from);
        let add = |a: u32, x: u32| (a + p(x, ft)).min(255) as u8;
        Row::new([add(fr, br), add(fg, bg), add(fb, bb)], q(bt, ft) as u8, f.depth()).to_le_u64()
    }

    /// The paper's merge in 16-bit slots: every (T_front, back byte) pair in every channel.
    #[test]
    fn merge4_paper_is_exact_for_every_operand_pair() {
        let round = |x: u32, t: u32| (x * t + 127) / 255; // 255 is odd: never a tie
        for tf0 in (0..256).step_by(4) {
            let tfs = [tf0, tf0 + 1, tf0 + 2, tf0 + 3];
            for b in 0..256 {
                let fr = tfs.map(|t| front(t, b));
                let got = unpack(merge4_paper(pack(fr), pack([back(b); 4])));
                for i in 0..4 {
                    assert_eq!(
                        got[i],
                        merged(fr[i], back(b), round, round),
                        "T_front {}, b {b}",
                        tfs[i]
                    );
                }
            }
        }
    }

    /// The unbiased merge in 16-bit slots: every (T_front, back byte, dither) triple in every
    /// channel, `floor((x * T_front + 254 - d) / 255)` for colors, `floor((T * T_front + d) /
    /// 255)` for T.
    #[test]
    fn merge_words_unbiased_is_exact_for_every_operand_triple() {
        for tf in 0..256 {
            for d0 in (0..255).step_by(4) {
                let ds: [u32; 4] = core::array::from_fn(|i| (d0 + i as u32).min(254));
                // `d` in both 16-bit slots of each row's low dword (as `Dither8` holds it).
                let dv: u16x16 = cast(pack(ds.map(|d| (d | d << 16) as u64)));
                for b in 0..256 {
                    let fr = [front(tf, b); 4];
                    let got = unpack(lo_hi(merge_words_unbiased(pack(fr), pack([back(b); 4]), dv), pack(fr)));
                    for (i, &d) in ds.iter().enumerate() {
                        let want = merged(fr[i], back(b), |x, t| (x * t + 254 - d) / 255, |x, t| (x * t + d) / 255);
                        assert_eq!(got[i], want, "T_front {tf}, b {b}, d {d}");
                    }
                }
            }
        }
    }

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

    /// The lane writer against the scalar one ([`crate::to_rgba8`]) for every f32 whose bits
    /// are a multiple of 509 (8.4 M values spread over the whole bit range: NaNs, infinities,
    /// negatives, subnormals), every f32 in `[0, 1]` within 64 ulps of a rounding boundary
    /// `(k + 0.5) / 255`, and the special values; over both backgrounds' alpha paths.
    #[test]
    fn unorm8_writer_matches_the_scalar_writer() {
        let scalar = |x: f32| crate::to_rgba8(glam::Vec4::splat(x))[0] as u32;
        let check = |xs: [f32; 8]| {
            let got = to_unorm8_lanes(f32x8::new(xs)).to_array();
            for (x, g) in xs.iter().zip(got) {
                assert_eq!(g, scalar(*x), "x = {x:e} ({:#x})", x.to_bits());
            }
        };
        let batch = |bits: &mut dyn Iterator<Item = u32>| {
            let mut xs = [0.0f32; 8];
            let mut n = 0;
            for b in bits {
                xs[n] = f32::from_bits(b);
                n += 1;
                if n == 8 {
                    check(xs);
                    n = 0;
                }
            }
            if n > 0 {
                check(xs);
            }
        };
        batch(&mut (0..=u32::MAX / 509).map(|i| i * 509));
        for k in 0..255u32 {
            let b = ((k as f32 + 0.5) / 255.0).to_bits();
            batch(&mut (b - 64..b + 64));
        }
        let specials = [
            0.0,
            -0.0,
            1.0,
            f32::NAN,
            -f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::MIN_POSITIVE,
        ];
        batch(&mut specials.iter().map(|x| x.to_bits()));
    }

    /// `min(s + x, max)`.
    fn sat(s: u64, x: u64, max: u64) -> u64 {
        (s + x).min(max)
    }

    /// A row of color bytes `c` and alpha byte `a` (T = 255 - a); invisible when all are 0.
    fn row(c: [u32; 3], a: u32) -> u64 {
        Row::new(c.map(|v| v as u8), (255 - a) as u8, 1.0).to_le_u64()
    }

    /// Four rows for byte `x`: as `x` runs over 0..256 each lane's color and alpha bytes take
    /// every value; lane 3 is the invisible row (no color, T = 255) when `x == 0`.
    fn rows4(x: u32) -> [u64; 4] {
        [
            row([x, x ^ 0x81, 255 - x], x),
            row([255 - x, x, x], 255 - x),
            row([x, 0, x], x ^ 0xf0),
            row([x; 3], x),
        ]
    }

    /// `add` on four tails and the rows of [`rows4`]`(x)` against `want(lane, [R, G, B, alpha])`
    /// for visible rows; invisible rows leave the tail unchanged.
    fn check_tail_add(add: fn(u32x8, u32x8) -> u32x8, tails: [u64; 4], x: u32, want: impl Fn(usize, [u64; 4]) -> u64) {
        let rows = rows4(x);
        let got = unpack(add(pack(tails), pack(rows)));
        for i in 0..4 {
            let r = Row::from_le_u64(rows[i]);
            let [cr, cg, cb, t] = r.rgbt().map(u64::from);
            let expected = if r.is_invisible() {
                tails[i]
            } else {
                want(i, [cr, cg, cb, 255 - t])
            };
            assert_eq!(got[i], expected, "tail {:#x}, row {:#x}", tails[i], rows[i]);
        }
    }

    /// The wide tail add: every (field value, byte) pair of every field (colors 0..8192,
    /// alpha 0..16384, count 0..2048 with a visible row), and invisible rows skipped.
    #[test]
    fn tail_add4_wide_is_exact_for_every_operand_pair() {
        let tail = |c: [u64; 3], a: u64, n: u64| c[0] | c[1] << 13 | c[2] << 26 | a << 39 | n << 53;
        for s0 in (0..16384u64).step_by(4) {
            let ss = [s0, s0 + 1, s0 + 2, s0 + 3];
            let cs = ss.map(|s| [s & 8191, (s * 3 + 1) & 8191, (s ^ 8191) & 8191]);
            let tails: [u64; 4] = core::array::from_fn(|i| tail(cs[i], ss[i], ss[i] & 2047));
            for x in 0..256u32 {
                check_tail_add(tail_add4_wide, tails, x, |i, [r, g, b, a]| {
                    let c = cs[i];
                    tail(
                        [sat(c[0], r, 8191), sat(c[1], g, 8191), sat(c[2], b, 8191)],
                        sat(ss[i], a, 16383),
                        sat(ss[i] & 2047, 1, 2047),
                    )
                });
            }
        }
    }

    /// The paper's tail add: every (color sum 0..1024, byte) pair, every (alpha sum, byte)
    /// pair for alpha sums 0..65536 and every count 0..65536, spare bits kept, invisible rows
    /// skipped.
    #[test]
    fn tail_add4_paper_is_exact_for_every_operand_pair() {
        let tail =
            |c: [u64; 3], spare: u64, a: u64, n: u64| c[0] | c[1] << 10 | c[2] << 20 | spare << 30 | a << 32 | n << 48;
        for s0 in (0..65536u64).step_by(4) {
            let ss = [s0, s0 + 1, s0 + 2, s0 + 3];
            let cs = ss.map(|s| [s & 1023, (s >> 6) & 1023, (s ^ 1023) & 1023]);
            let tails: [u64; 4] = core::array::from_fn(|i| tail(cs[i], ss[i] & 3, ss[i], 65535 - ss[i]));
            for x in 0..256u32 {
                check_tail_add(tail_add4_paper, tails, x, |i, [r, g, b, a]| {
                    let c = cs[i];
                    tail(
                        [sat(c[0], r, 1023), sat(c[1], g, 1023), sat(c[2], b, 1023)],
                        ss[i] & 3,
                        sat(ss[i], a, 65535),
                        sat(65535 - ss[i], 1, 65535),
                    )
                });
            }
        }
    }
}

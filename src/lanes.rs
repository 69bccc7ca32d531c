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
//! swap of Listing 1 is two selects of whole rows. [`to_pixel_major`] and [`from_pixel_major`]
//! convert losslessly to and from the per-pixel `[Row; M]` arrangement of
//! [`MlabFramebuffer`](crate::MlabFramebuffer); `docs/performance.md` measures the two.
//!
//! # One algorithm, two widths
//!
//! Listing 1 and 2 are written once ([`crate::mlab`], [`crate::hybrid`]) over the private
//! `RowLanes` trait, implemented by [`Row`] (one pixel, the scalar kernel) and by an
//! eight-row register pair here. The resolve (Eq. 5-6, the HT tail) is written once over the
//! `FloatLanes` trait, implemented by `f32` and `wide::f32x8`: scalar and lanes evaluate the
//! same f32 expression tree in the same order, multiply then add, never FMA. The merge and
//! the tail are exact integer arithmetic; here they use SWAR on 16-bit slots (`pmullw`), the
//! scalar path per-channel bytes; both compute `round(a * b / 255)` exactly.
//!
//! `wide` picks AVX2 or SSE2 at compile time ([`BACKEND`] says which). Every operation used
//! here is a native instruction on both (no `u32` multiply or `u32` min, which `wide` emulates
//! lane by lane without SSE4.1).
//!
//! ```
//! use mlab::lanes::{self, FragmentLanes};
//! use mlab::Row;
//! let mut span = [[Row::EMPTY; 8]; 4]; // 8 pixels, M = 4, layer-major
//! let frags = FragmentLanes {
//!     color: [[0.4; 8], [0.0; 8], [0.0; 8]],
//!     alpha: [0.6; 8],
//!     depth: [1.0, 2.0, 3.0, f32::NAN, 5.0, 6.0, 7.0, 8.0],
//! };
//! let invalid = lanes::mlab_insert_fragments(&mut span, &frags, 0b0111_1111);
//! assert_eq!(invalid, 0b0000_1000); // lane 3 has a NaN depth: untouched, reported
//! assert_eq!(span[0][7], Row::EMPTY); // lane 7 was off
//! assert_eq!(span[0][0], Row::new([102, 0, 0], 102, 1.0)); // 0.4 and 0.6 are exact bytes
//! ```

use crate::arith::{Arithmetic, Kind, MIX_K, Unbiased};
use crate::hybrid::TailFormat;
use crate::resolve::{Background, Resolved};
use crate::row::Row;
use bytemuck::cast;
use glam::Vec4;
use wide::{f32x8, f64x4, i16x16, i32x8, u8x32, u16x16, u32x8, u64x4};

/// Pixels per lane group.
pub const LANES: usize = 8;

/// The SIMD instruction set `wide` compiled the lanes for, chosen at compile time:
///
/// - `"avx2 (avx512f build)"`: a build with `avx512f` (`x86-64-v4`). `wide` 1.7 keeps every
///   256-bit type the lanes use in one `ymm` register and calls the AVX2 intrinsics of an
///   `"avx2"` build: its only AVX-512 paths for these types are shuffles, per-lane variable
///   shifts, widening multiplies and f64-to-integer conversions, none of which the lanes call.
///   LLVM may still encode the code with EVEX and mask registers.
/// - `"avx2"`: one 256-bit register per 8-wide vector.
/// - `"sse2"`: x86 without AVX2, two 128-bit halves (`wide` uses SSSE3, SSE4.1 or AVX where
///   the build has them).
/// - `"neon"`: two 128-bit NEON halves (aarch64).
/// - `"simd128"`: two 128-bit halves (wasm32 with `simd128`).
/// - `"portable"`: no SIMD, plain arrays (wasm32 without `simd128`, any other target).
pub const BACKEND: &str = if cfg!(target_feature = "avx512f") {
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

// ---------------------------------------------------------------------------------------
// The lane abstractions shared with the scalar kernel.
// ---------------------------------------------------------------------------------------

/// Rows of one or more pixels, one pixel per lane: what Listings 1 and 2 are written over.
pub(crate) trait RowLanes: Copy {
    /// Per-lane condition.
    type Mask: Copy + core::ops::BitAnd<Output = Self::Mask>;
    /// Per-lane HT tail of layout `T`.
    type Tail<T: TailFormat>: Copy;
    /// `self.z <= other.z` in IEEE f32 (false when either is NaN).
    fn depth_le(self, other: Self) -> Self::Mask;
    /// `if mask { a } else { b }` per lane.
    fn select(mask: Self::Mask, a: Self, b: Self) -> Self;
    /// Eq. 7-8 per lane in the arithmetic `A` ([`Arithmetic::merge`]).
    fn merge<A: Arithmetic>(front: Self, back: Self) -> Self;
    /// [`TailFormat::add`] per lane.
    fn tail_add<T: TailFormat>(tail: Self::Tail<T>, row: Self) -> Self::Tail<T>;
    /// `if mask { a } else { b }` per lane, for tails.
    fn select_tail<T: TailFormat>(mask: Self::Mask, a: Self::Tail<T>, b: Self::Tail<T>) -> Self::Tail<T>;
}

impl RowLanes for Row {
    type Mask = bool;
    type Tail<T: TailFormat> = T;
    #[inline(always)]
    fn depth_le(self, other: Self) -> bool {
        self.depth() <= other.depth()
    }
    #[inline(always)]
    fn select(mask: bool, a: Self, b: Self) -> Self {
        // Branchless (cmov): a data-dependent branch mispredicts on every unsorted stream.
        Row::from_le_u64(core::hint::select_unpredictable(mask, a.to_le_u64(), b.to_le_u64()))
    }
    #[inline(always)]
    fn merge<A: Arithmetic>(front: Self, back: Self) -> Self {
        A::merge(front, back)
    }
    #[inline(always)]
    fn tail_add<T: TailFormat>(tail: T, row: Self) -> T {
        let mut t = tail;
        t.add(row);
        t
    }
    #[inline(always)]
    fn select_tail<T: TailFormat>(mask: bool, a: T, b: T) -> T {
        core::hint::select_unpredictable(mask, a, b)
    }
}

/// Where the rows of one layer live: Listings 1 and 2 load a layer, update it, and store it
/// back before the next one, so only one layer and the carried row are ever held in
/// registers (an array of `M` layers would spill, and copy, at large `M`).
pub(crate) trait Slot<L> {
    /// Read the layer.
    fn load(&self) -> L;
    /// Write the layer.
    fn store(&mut self, value: L);
}

impl Slot<Row> for Row {
    #[inline(always)]
    fn load(&self) -> Row {
        *self
    }
    #[inline(always)]
    fn store(&mut self, value: Row) {
        *self = value;
    }
}

impl<T: TailFormat> Slot<T> for T {
    #[inline(always)]
    fn load(&self) -> T {
        *self
    }
    #[inline(always)]
    fn store(&mut self, value: T) {
        *self = value;
    }
}

impl Slot<Rows8> for [Row; LANES] {
    #[inline(always)]
    fn load(&self) -> Rows8 {
        Rows8::load(self)
    }
    #[inline(always)]
    fn store(&mut self, value: Rows8) {
        *self = value.store();
    }
}

impl<T: TailFormat> Slot<Rows8> for [T; LANES] {
    #[inline(always)]
    fn load(&self) -> Rows8 {
        Rows8::load_tails(self)
    }
    #[inline(always)]
    fn store(&mut self, value: Rows8) {
        *self = value.store_tails();
    }
}

/// f32 values of one or more pixels: what the resolve is written over.
pub(crate) trait FloatLanes:
    Copy + core::ops::Add<Output = Self> + core::ops::Sub<Output = Self> + core::ops::Mul<Output = Self>
{
    /// Per-lane unsigned integer (tail fields).
    type U: Copy;
    /// Per-lane condition.
    type Mask: Copy;
    /// All lanes `v`.
    fn splat(v: f32) -> Self;
    /// `if mask { a } else { b }`.
    fn select(mask: Self::Mask, a: Self, b: Self) -> Self;
    /// Bit `bit` of `n` is set.
    fn bit(n: Self::U, bit: u32) -> Self::Mask;
    /// `n == 0`.
    fn is_zero(n: Self::U) -> Self::Mask;
    /// `self > other`.
    fn gt(self, other: Self) -> Self::Mask;
    /// `self / other` (IEEE, correctly rounded in both widths).
    fn div(self, other: Self) -> Self;
    /// Exact conversion of a small integer (below 2^24).
    fn from_u(n: Self::U) -> Self;
    /// Number of significant bits of the largest lane of `n`.
    fn bit_length(n: Self::U) -> u32;
}

impl FloatLanes for f32 {
    type U = u32;
    type Mask = bool;
    #[inline(always)]
    fn splat(v: f32) -> Self {
        v
    }
    #[inline(always)]
    fn select(mask: bool, a: Self, b: Self) -> Self {
        if mask { a } else { b }
    }
    #[inline(always)]
    fn bit(n: u32, bit: u32) -> bool {
        (n >> bit) & 1 != 0
    }
    #[inline(always)]
    fn is_zero(n: u32) -> bool {
        n == 0
    }
    #[inline(always)]
    fn gt(self, other: Self) -> bool {
        self > other
    }
    #[inline(always)]
    fn div(self, other: Self) -> Self {
        self / other
    }
    #[inline(always)]
    fn from_u(n: u32) -> Self {
        n as f32
    }
    #[inline(always)]
    fn bit_length(n: u32) -> u32 {
        u32::BITS - n.leading_zeros()
    }
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

// ---------------------------------------------------------------------------------------
// Eight rows in two registers.
// ---------------------------------------------------------------------------------------

/// Low dword of every 64-bit lane (a row's color and transmittance; a tail's color sums).
const LO: u32x8 = u32x8::new([!0, 0, !0, 0, !0, 0, !0, 0]);
/// High dword of every 64-bit lane (a row's depth; a tail's alpha sum and count).
const HI: u32x8 = u32x8::new([0, !0, 0, !0, 0, !0, 0, !0]);
const BYTES02: u32x8 = u32x8::splat(0x00ff_00ff);

/// Eight rows (or eight tails), one per lane: lanes 0-3 in `a`, 4-7 in `b`, each 64-bit
/// lane one whole row (`word0` in the low dword, `word1` in the high dword).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Rows8 {
    a: u32x8,
    b: u32x8,
}

/// Per-lane mask for [`Rows8`]: all ones or all zeros over each 64-bit lane (with AVX, only
/// the sign bit of each 64-bit lane is meaningful: see [`BLENDV_PD`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Mask8 {
    a: u32x8,
    b: u32x8,
}

impl core::ops::BitAnd for Mask8 {
    type Output = Mask8;
    #[inline(always)]
    fn bitand(self, rhs: Mask8) -> Mask8 {
        Mask8 {
            a: self.a & rhs.a,
            b: self.b & rhs.b,
        }
    }
}

impl Mask8 {
    /// Every lane on.
    const ALL: Mask8 = Mask8 {
        a: u32x8::MAX,
        b: u32x8::MAX,
    };

    /// From a bitmask (bit `i` = lane `i`).
    #[inline(always)]
    fn from_bits(bits: u8) -> Mask8 {
        let v = u32x8::splat(bits as u32);
        let sa = u32x8::new([1, 1, 2, 2, 4, 4, 8, 8]);
        let sb = u32x8::new([16, 16, 32, 32, 64, 64, 128, 128]);
        Mask8 {
            a: (v & sa).simd_eq(sa),
            b: (v & sb).simd_eq(sb),
        }
    }
}

/// Copy the mask in the high dword of each 64-bit lane to the whole lane.
#[inline(always)]
fn widen_hi(m: u32x8) -> u32x8 {
    let h = m & HI;
    h | cast::<u64x4, u32x8>(cast::<u32x8, u64x4>(h) >> 32)
}

/// Copy the mask in the low dword of each 64-bit lane to the whole lane.
#[inline(always)]
fn widen_lo(m: u32x8) -> u32x8 {
    let l = m & LO;
    l | cast::<u64x4, u32x8>(cast::<u32x8, u64x4>(l) << 32)
}

/// `round(x / 255)` in each 16-bit slot holding `x <= 65025`: `((x + 128) * 257) >> 16`,
/// one add and one high multiply (`pmulhuw`). Equal to [`crate::unorm::div255`] for every
/// such `x` (`div255_slots_is_exact` checks all of them).
#[inline(always)]
fn div255_slots(x: u16x16) -> u16x16 {
    (x + u16x16::splat(128)).mul_keep_high(u16x16::splat(257))
}

/// `T_front` in both 16-bit slots of each row's low dword (the high dword is don't-care),
/// and the back row's bytes 0 and 2 (R, B) and 1 and 3 (G, T), one per 16-bit slot.
#[inline(always)]
fn merge_operands(front: u32x8, back: u32x8) -> (u16x16, u16x16, u16x16) {
    let t = (front >> 24) & u32x8::splat(0xff);
    let t2: u16x16 = cast(t | (t << 16));
    let even: u16x16 = cast(back & BYTES02);
    let odd: u16x16 = cast((back >> 8) & BYTES02);
    (t2, even, odd)
}

/// `A_front + products` bytewise, saturating; the front's T byte is replaced by the
/// product's T; the depth is the front's.
#[inline(always)]
fn merge_result(front: u32x8, pe: u16x16, po: u16x16) -> u32x8 {
    let product = cast::<u16x16, u32x8>(pe) | (cast::<u16x16, u32x8>(po) << 8);
    let a_front = front & u32x8::splat(0x00ff_ffff);
    let sum: u32x8 = cast(cast::<u32x8, u8x32>(a_front).saturating_add(cast(product)));
    (sum & LO) | (front & HI)
}

/// The paper's merge (Eq. 7-8) for four rows in one register: SWAR over 16-bit slots.
#[inline(always)]
fn merge4_paper(front: u32x8, back: u32x8) -> u32x8 {
    let (t2, even, odd) = merge_operands(front, back);
    // Each product <= 255 * 255: no carry out of its slot.
    merge_result(front, div255_slots(even * t2), div255_slots(odd * t2))
}

/// `[MIX_K; 16]`: the multiplier of [`crate::arith::mix16`].
const K: u16x16 = u16x16::splat(MIX_K as u16);
/// Turns `d` in both slots into `[255 - d, d + 1]` (G slot, T slot): `(d ^ 0xffff) + 256`
/// is `255 - d` modulo 2^16.
const ODD_XOR: u16x16 = u16x16::new([
    0xffff, 0, 0xffff, 0, 0xffff, 0, 0xffff, 0, 0xffff, 0, 0xffff, 0, 0xffff, 0, 0xffff, 0,
]);
const ODD_ADD: u16x16 = u16x16::new([256, 1, 256, 1, 256, 1, 256, 1, 256, 1, 256, 1, 256, 1, 256, 1]);

/// [`crate::arith::merge_dither`] of eight row pairs at once: `d` of pixel `p` in both
/// 16-bit slots of the low dword of its 64-bit lane, lanes 0-3 in the first register and
/// 4-7 in the second (high dwords don't-care). The eight folds share one register for the
/// mix (pixels 0-3 in the low dwords, 4-7 in the high dwords).
#[inline(always)]
fn merge_dither8(front: Rows8, back: Rows8) -> (u16x16, u16x16) {
    let fa = front.a ^ back.a;
    let fb = front.b ^ back.b;
    // word0 ^ word1 of each pair: in the low dword for a, in the high dword for b.
    let xa = fa ^ cast::<u64x4, u32x8>(cast::<u32x8, u64x4>(fa) >> 32);
    let xb = fb ^ cast::<u64x4, u32x8>(cast::<u32x8, u64x4>(fb) << 32);
    let x = HI.select(xb, xa);
    // Both 16-bit slots of each dword = lo ^ hi (x ^ rotate(x, 16)), then the multiplicative
    // mix. Written as a rotate, LLVM emits one byte shuffle where it can.
    let s: u16x16 = cast(x ^ ((x >> 16) | (x << 16)));
    let s: u16x16 = s * K;
    let d = s.mul_keep_high(u16x16::splat(255)); // 0..=254
    let db = cast::<u64x4, u16x16>(cast::<u16x16, u64x4>(d) >> 32);
    (d, db)
}

/// The unbiased merge ([`Unbiased`]) for four rows in one register, with their dither `d`
/// ([`merge_dither8`]): `floor((p + d') / 255)` as `((p + d' + 1) * 257) >> 16`, with
/// `d' = d` for T and `254 - d` for the colors.
#[inline(always)]
fn merge4_unbiased(front: u32x8, back: u32x8, d: u16x16) -> u32x8 {
    let (t2, even, odd) = merge_operands(front, back);
    let inv = u16x16::splat(255) - d; // (254 - d) + 1: R and B
    let odd_d = (d ^ ODD_XOR) + ODD_ADD; // G: (254 - d) + 1, T: d + 1
    let m257 = u16x16::splat(257);
    // Products <= 65025, plus at most 255: no carry out of a slot.
    let pe = (even * t2 + inv).mul_keep_high(m257);
    let po = (odd * t2 + odd_d).mul_keep_high(m257);
    merge_result(front, pe, po)
}

/// [`PaperTail`](crate::hybrid::PaperTail)`::add` for four tails in one register.
#[inline(always)]
fn tail_add4_paper(tail: u32x8, row: u32x8) -> u32x8 {
    let field = u32x8::splat(0x3ff);
    let byte = u32x8::splat(0xff);
    let max: i16x16 = i16x16::splat(1023);
    // Color sums: each field + its byte, capped at 1023 (values < 2^15: i16 min is exact).
    let sat = |sum: u32x8| -> u32x8 { cast(cast::<u32x8, i16x16>(sum).min(max)) };
    let r = sat((tail & field) + (row & byte));
    let g = sat(((tail >> 10) & field) + ((row >> 8) & byte));
    let b = sat(((tail >> 20) & field) + ((row >> 16) & byte));
    let word0 = r | (g << 10) | (b << 20) | (tail & u32x8::splat(0xc000_0000));
    // Alpha sum += 255 - T and count += 1: two saturating u16 adds in the high dword.
    let inc = (u32x8::splat(255) - (row >> 24)) | u32x8::splat(1 << 16);
    let inc = cast::<u64x4, u32x8>(cast::<u32x8, u64x4>(inc & LO) << 32);
    let word1: u32x8 = cast(cast::<u32x8, u16x16>(tail).saturating_add(cast(inc)));
    let new = (word0 & LO) | (word1 & HI);
    // Invisible rows (no color, T = 255) are skipped.
    let invisible = widen_lo(row.simd_eq(u32x8::splat(0xff00_0000)));
    invisible.select(tail, new)
}

impl Rows8 {
    #[inline(always)]
    fn load(rows: &[Row; 8]) -> Rows8 {
        let [a, b]: [u32x8; 2] = cast(*rows);
        Rows8 { a, b }
    }

    #[inline(always)]
    fn store(self) -> [Row; 8] {
        cast([self.a, self.b])
    }

    #[inline(always)]
    fn load_tails<T: TailFormat>(tails: &[T; 8]) -> Rows8 {
        let [a, b]: [u32x8; 2] = cast(*tails);
        Rows8 { a, b }
    }

    #[inline(always)]
    fn store_tails<T: TailFormat>(self) -> [T; 8] {
        cast([self.a, self.b])
    }
}

/// Low dword masks for the fields of the wide tail.
const BYTE_LO: u32x8 = u32x8::new([0xff, 0, 0xff, 0, 0xff, 0, 0xff, 0]);
const SUM_LO: u32x8 = u32x8::new([0x1fff, 0, 0x1fff, 0, 0x1fff, 0, 0x1fff, 0]);
const ALPHA_LO: u32x8 = u32x8::new([0x3fff, 0, 0x3fff, 0, 0x3fff, 0, 0x3fff, 0]);
const ONE_LO: u32x8 = u32x8::new([1, 0, 1, 0, 1, 0, 1, 0]);

/// [`Tail`](crate::Tail)`::add` for four tails in one register (each tail one `u64`:
/// colors at bits 0, 13, 26, alpha at 39, count at 53).
#[inline(always)]
fn tail_add4_wide(tail: u32x8, row: u32x8) -> u32x8 {
    let shr = |v: u32x8, n: u64| cast::<u64x4, u32x8>(cast::<u32x8, u64x4>(v) >> n);
    let shl = |v: u32x8, n: u64| cast::<u64x4, u32x8>(cast::<u32x8, u64x4>(v) << n);
    // Sums below 2^15 in the low 16-bit slot, zero elsewhere: i16 min is exact.
    let sat = |v: u32x8, max: i16| -> u32x8 { cast(cast::<u32x8, i16x16>(v).min(i16x16::splat(max))) };
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
    let invisible = widen_lo(row.simd_eq(u32x8::splat(0xff00_0000)));
    invisible.select(tail, new)
}

/// With AVX, a select of whole rows is `vblendvpd`, which reads only the sign bit of each
/// 64-bit lane, that is the depth dword's compare result: the masks need no widening.
/// Without AVX the select is bitwise and the masks are widened to whole lanes. Both give
/// the same rows.
const BLENDV_PD: bool = cfg!(target_feature = "avx");

impl RowLanes for Rows8 {
    type Mask = Mask8;
    type Tail<T: TailFormat> = Rows8;
    #[inline(always)]
    fn depth_le(self, other: Self) -> Mask8 {
        let le = |x: u32x8, y: u32x8| {
            let m = cast::<f32x8, u32x8>(cast::<u32x8, f32x8>(x).simd_le(cast::<u32x8, f32x8>(y)));
            // Only the high (depth) dword of each lane is meaningful.
            if BLENDV_PD { m } else { widen_hi(m) }
        };
        Mask8 {
            a: le(self.a, other.a),
            b: le(self.b, other.b),
        }
    }
    #[inline(always)]
    fn select(mask: Mask8, x: Self, y: Self) -> Self {
        let sel = |m: u32x8, p: u32x8, q: u32x8| -> u32x8 {
            if BLENDV_PD {
                cast(cast::<u32x8, f64x4>(m).select(cast::<u32x8, f64x4>(p), cast::<u32x8, f64x4>(q)))
            } else {
                m.select(p, q)
            }
        };
        Rows8 {
            a: sel(mask.a, x.a, y.a),
            b: sel(mask.b, x.b, y.b),
        }
    }
    #[inline(always)]
    fn merge<A: Arithmetic>(front: Self, back: Self) -> Self {
        match A::KIND {
            Kind::Paper => Rows8 {
                a: merge4_paper(front.a, back.a),
                b: merge4_paper(front.b, back.b),
            },
            Kind::Unbiased => {
                let (da, db) = merge_dither8(front, back);
                Rows8 {
                    a: merge4_unbiased(front.a, back.a, da),
                    b: merge4_unbiased(front.b, back.b, db),
                }
            }
        }
    }
    #[inline(always)]
    fn tail_add<T: TailFormat>(tail: Rows8, row: Self) -> Rows8 {
        let f = match T::KIND {
            Kind::Paper => tail_add4_paper,
            Kind::Unbiased => tail_add4_wide,
        };
        Rows8 {
            a: f(tail.a, row.a),
            b: f(tail.b, row.b),
        }
    }
    #[inline(always)]
    fn select_tail<T: TailFormat>(mask: Mask8, x: Rows8, y: Rows8) -> Rows8 {
        Self::select(mask, x, y)
    }
}

// ---------------------------------------------------------------------------------------
// Public span API.
// ---------------------------------------------------------------------------------------

/// An MLAB span: 8 pixels with `M` rows each, layer-major (`span[j][lane]` is row `j` of
/// pixel `lane`).
pub type MlabSpan<const M: usize> = [[Row; LANES]; M];

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

impl<const K: usize, A: Arithmetic> HybridSpan<K, A> {
    /// Empty heads and tails.
    pub const fn new() -> Self {
        HybridSpan {
            head: [[Row::EMPTY; LANES]; K],
            tails: [A::Tail::EMPTY; LANES],
        }
    }
}

impl<const K: usize, A: Arithmetic> Default for HybridSpan<K, A> {
    fn default() -> Self {
        Self::new()
    }
}

/// Listing 1 on 8 pixels in the default arithmetic ([`Unbiased`]): see [`mlab_insert_with`].
#[inline]
pub fn mlab_insert<const M: usize>(span: &mut MlabSpan<M>, rows: &[Row; LANES], mask: u8) {
    mlab_insert_with::<Unbiased, M>(span, rows, mask);
}

/// Listing 1 on 8 pixels in the arithmetic `A`: insert `rows[lane]` into pixel `lane` for
/// every lane whose bit is set in `mask`. Byte-identical to
/// [`crate::mlab::insert_with`]`::<A, M>` on each lane, for any rows.
#[inline(always)] // a span insert is the inner loop of a rasterizer: never a call
pub fn mlab_insert_with<A: Arithmetic, const M: usize>(span: &mut MlabSpan<M>, rows: &[Row; LANES], mask: u8) {
    // Full spans (the common case) skip the mask: with a constant all-ones mask the
    // compiler drops the ANDs and the final select.
    if mask == 0xff {
        crate::mlab::insert_lanes::<A, _, _, M>(span, Rows8::load(rows), Mask8::ALL);
    } else {
        crate::mlab::insert_lanes::<A, _, _, M>(span, Rows8::load(rows), Mask8::from_bits(mask));
    }
}

/// Listing 2 on 8 pixels. Byte-identical to [`crate::hybrid::insert`] on each lane.
#[inline]
pub fn hybrid_insert<const K: usize, A: Arithmetic>(span: &mut HybridSpan<K, A>, rows: &[Row; LANES], mask: u8) {
    hybrid_insert_parts(&mut span.head, &mut span.tails, rows, mask);
}

/// [`hybrid_insert`] on a span stored as separate head layers and tails (as in a
/// [`HybridSpanFramebuffer`](crate::HybridSpanFramebuffer)); the tail type picks the layout.
#[inline]
pub fn hybrid_insert_parts<T: TailFormat, const K: usize>(
    head: &mut [[Row; LANES]; K],
    tails: &mut [T; LANES],
    rows: &[Row; LANES],
    mask: u8,
) {
    if mask == 0xff {
        crate::hybrid::insert_lanes::<_, _, _, T, K>(head, tails, Rows8::load(rows), Mask8::ALL);
    } else {
        crate::hybrid::insert_lanes::<_, _, _, T, K>(head, tails, Rows8::load(rows), Mask8::from_bits(mask));
    }
}

/// The lanes of a span insert of fragments that were on but invalid (NaN, infinite or out
/// of range, as [`crate::Fragment`]'s constructors refuse them): they were **not** inserted.
/// Bit `i` = lane `i`. Compares with a `u8` mask (`invalid == 0`).
#[must_use = "the lanes in this mask were not inserted: check it (`is_empty`) or count them"]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct InvalidLanes(pub u8);

impl InvalidLanes {
    /// The mask, bit `i` = lane `i`.
    pub const fn bits(self) -> u8 {
        self.0
    }

    /// No lane was invalid.
    pub const fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// How many lanes were invalid.
    pub const fn count(self) -> u32 {
        self.0.count_ones()
    }
}

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

/// Eight fragments, structure of arrays, linear color: premultiplied for
/// [`quantize`](Self::quantize) and the `insert_*_fragments` functions, straight for
/// [`quantize_straight`](Self::quantize_straight) (and
/// [`Framebuffer::insert_span_straight`](crate::Framebuffer::insert_span_straight)).
///
/// ```
/// use mlab::lanes::FragmentLanes;
/// let straight = FragmentLanes::from_rgba([[1.0, 0.5, 0.0, 0.5]; 8], [2.0; 8]);
/// let q = straight.quantize_straight(0xff);
/// assert_eq!(q.valid, 0xff);
/// let pre = FragmentLanes::from_fn(|lane| ([0.5, 0.25, 0.0], 0.5, 2.0 + lane as f32));
/// assert_eq!(pre.depth[7], 9.0);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FragmentLanes {
    /// `color[channel][lane]`, channels R, G, B.
    pub color: [[f32; LANES]; 3],
    /// Alpha per lane.
    pub alpha: [f32; LANES],
    /// Depth per lane.
    pub depth: [f32; LANES],
}

/// Rows quantized from [`FragmentLanes`], and which lanes were valid.
#[must_use = "lanes in `invalid` were refused: insert `rows` with the mask `valid`"]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct QuantizedLanes {
    /// The rows (lanes not in `valid` hold [`Row::EMPTY`]).
    pub rows: [Row; LANES],
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
        }
    }

    /// Eight fragments from `(color [R, G, B], alpha, depth)` per lane.
    pub fn from_fn(mut f: impl FnMut(usize) -> ([f32; 3], f32, f32)) -> FragmentLanes {
        let mut out = FragmentLanes::TRANSPARENT;
        for lane in 0..LANES {
            let (c, a, z) = f(lane);
            for (ch, v) in out.color.iter_mut().zip(c) {
                ch[lane] = v;
            }
            out.alpha[lane] = a;
            out.depth[lane] = z;
        }
        out
    }

    /// Up to eight fragments from slices of `[R, G, B, A]` and depths (the shorter length
    /// counts); returns the lanes and the mask of the lanes filled (`(1 << n) - 1`). Lanes
    /// past the slices are [`TRANSPARENT`](Self::TRANSPARENT) and off.
    pub fn from_slices(rgba: &[[f32; 4]], depth: &[f32]) -> (FragmentLanes, u8) {
        let n = rgba.len().min(depth.len()).min(LANES);
        let mut out = FragmentLanes::TRANSPARENT;
        for (lane, (c, z)) in rgba.iter().zip(depth).take(n).enumerate() {
            for (ch, v) in out.color.iter_mut().zip(c) {
                ch[lane] = *v;
            }
            out.alpha[lane] = c[3];
            out.depth[lane] = *z;
        }
        (out, ((1u16 << n) - 1) as u8)
    }

    /// Eight fully transparent black fragments at depth 0 (valid; a placeholder for lanes
    /// that are off).
    pub const TRANSPARENT: FragmentLanes = FragmentLanes {
        color: [[0.0; LANES]; 3],
        alpha: [0.0; LANES],
        depth: [0.0; LANES],
    };

    /// Validate and quantize premultiplied fragments in the default arithmetic
    /// ([`Unbiased`]): see [`quantize_with`](Self::quantize_with).
    pub fn quantize(&self, mask: u8) -> QuantizedLanes {
        self.quantize_impl::<Unbiased>(mask, false)
    }

    /// Validate and quantize premultiplied fragments as [`crate::Fragment::premultiplied`]
    /// then [`Arithmetic::quantize`] would, lane by lane.
    pub fn quantize_with<A: Arithmetic>(&self, mask: u8) -> QuantizedLanes {
        self.quantize_impl::<A>(mask, false)
    }

    /// Validate and quantize straight-color fragments in the default arithmetic: see
    /// [`quantize_straight_with`](Self::quantize_straight_with).
    pub fn quantize_straight(&self, mask: u8) -> QuantizedLanes {
        self.quantize_impl::<Unbiased>(mask, true)
    }

    /// Validate and quantize straight-color fragments, as [`crate::Fragment::straight`] then
    /// [`Arithmetic::quantize`] would (`color * alpha`, one f32 multiply).
    pub fn quantize_straight_with<A: Arithmetic>(&self, mask: u8) -> QuantizedLanes {
        self.quantize_impl::<A>(mask, true)
    }

    fn quantize_impl<A: Arithmetic>(&self, mask: u8, straight: bool) -> QuantizedLanes {
        let zero = f32x8::ZERO;
        let one = f32x8::ONE;
        let alpha = f32x8::new(self.alpha);
        let depth = f32x8::new(self.depth);
        // Every comparison is false for NaN, so NaN anywhere makes the lane invalid.
        let mut ok = alpha.simd_ge(zero) & alpha.simd_le(one) & depth.abs().simd_lt(f32x8::splat(f32::INFINITY));
        let mut pre = [zero; 3];
        for (c, out) in self.color.iter().zip(pre.iter_mut()) {
            let raw = f32x8::new(*c);
            *out = if straight {
                ok &= raw.simd_ge(zero) & raw.simd_lt(f32x8::splat(f32::INFINITY));
                raw * alpha
            } else {
                raw
            };
            ok &= out.simd_ge(zero) & out.simd_le(one);
        }
        let half = f32x8::splat(0.5);
        let u = match A::KIND {
            Kind::Paper => half,
            // Faint fragments dithered, the others to nearest (as `Unbiased::quantize`).
            Kind::Unbiased => {
                let faint = (alpha * f32x8::splat(255.0)).simd_lt(f32x8::splat(crate::arith::FAINT_BYTES));
                faint.select(fragment_dither8(pre, alpha, depth), half)
            }
        };
        let bytes = pre.map(|c| quantize8(c, u));
        let t = u32x8::splat(255) - quantize8(alpha, u);
        let rgbt: [u32; LANES] = cast(bytes[0] | (bytes[1] << 8) | (bytes[2] << 16) | (t << 24));
        let z: [u32; LANES] = cast(depth);
        let valid = (ok.to_bitmask() as u8) & mask;
        let rows = core::array::from_fn(|i| {
            if valid & (1 << i) != 0 {
                Row::from_words([rgbt[i], z[i]])
            } else {
                Row::EMPTY
            }
        });
        QuantizedLanes {
            rows,
            valid,
            invalid: mask & !valid,
        }
    }
}

/// [`crate::arith::fragment_dither`] for 8 lanes (16-bit mix in the low slot of each dword).
#[inline(always)]
fn fragment_dither8(pre: [f32x8; 3], alpha: f32x8, depth: f32x8) -> f32x8 {
    let bits = |v: f32x8| cast::<f32x8, u32x8>(v);
    let x = bits(pre[0]) ^ bits(pre[1]) ^ bits(pre[2]) ^ bits(alpha) ^ bits(depth);
    let s: u16x16 = cast((x ^ (x >> 16)) & u32x8::splat(0xffff));
    let s: u16x16 = s * K;
    let h = cast::<u16x16, u32x8>(s >> 8) & u32x8::splat(0xff);
    (f32x8::from_u(h) + f32x8::splat(0.5)) * f32x8::splat(1.0 / 256.0)
}

/// `floor(v * 255 + u)` for `v` in `[0, 1]` (as [`crate::unorm::quantize`] for `u = 0.5`);
/// other lanes give unspecified bytes and must be masked.
#[inline(always)]
fn quantize8(v: f32x8, u: f32x8) -> u32x8 {
    let x = v * f32x8::splat(255.0) + u;
    cast::<i32x8, u32x8>(x.fast_trunc_int()) & u32x8::splat(0xff)
}

/// Validate, quantize and insert (Listing 1) one fragment per lane in the default
/// arithmetic; returns the lanes that were on but invalid (left untouched).
#[inline]
pub fn mlab_insert_fragments<const M: usize>(
    span: &mut MlabSpan<M>,
    fragments: &FragmentLanes,
    mask: u8,
) -> InvalidLanes {
    mlab_insert_fragments_with::<Unbiased, M>(span, fragments, mask)
}

/// [`mlab_insert_fragments`] in the arithmetic `A`.
#[inline]
pub fn mlab_insert_fragments_with<A: Arithmetic, const M: usize>(
    span: &mut MlabSpan<M>,
    fragments: &FragmentLanes,
    mask: u8,
) -> InvalidLanes {
    let q = fragments.quantize_with::<A>(mask);
    mlab_insert_with::<A, M>(span, &q.rows, q.valid);
    InvalidLanes(q.invalid)
}

/// Validate, quantize and insert (Listing 2) one fragment per lane; returns the invalid lanes.
#[inline]
pub fn hybrid_insert_fragments<const K: usize, A: Arithmetic>(
    span: &mut HybridSpan<K, A>,
    fragments: &FragmentLanes,
    mask: u8,
) -> InvalidLanes {
    let q = fragments.quantize_with::<A>(mask);
    hybrid_insert(span, &q.rows, q.valid);
    InvalidLanes(q.invalid)
}

// ---------------------------------------------------------------------------------------
// Resolve.
// ---------------------------------------------------------------------------------------

/// The resolve of 8 pixels, structure of arrays; lane `i` equals the scalar [`Resolved`]
/// of pixel `i` bit for bit ([`ResolvedLanes::get`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ResolvedLanes {
    /// `color[channel][lane]`: premultiplied color of the transparent layers.
    pub color: [[f32; LANES]; 3],
    /// Background visibility per lane.
    pub transmittance: [f32; LANES],
}

/// Where pixel `p` of a span sits in the registers of the resolve: the 8 row words are
/// packed without a shuffle as `(a & LO) | (b << 32)`, which orders the pixels
/// `[0, 4, 1, 5, 2, 6, 3, 7]`. Every resolve step is per lane, so the order only matters when
/// the results are written out.
const POSITION: [usize; LANES] = [0, 2, 4, 6, 1, 3, 5, 7];

/// `word0` of 8 rows (or tails) in one register, pixels in [`POSITION`] order.
#[inline(always)]
fn words0(r: Rows8) -> u32x8 {
    (r.a & LO) | cast::<u64x4, u32x8>(cast::<u32x8, u64x4>(r.b) << 32)
}

/// `word1` of 8 rows (or tails) in one register, pixels in [`POSITION`] order.
#[inline(always)]
fn words1(r: Rows8) -> u32x8 {
    cast::<u64x4, u32x8>(cast::<u32x8, u64x4>(r.a) >> 32) | (r.b & HI)
}

/// Back to pixel order.
#[inline(always)]
fn unpermute<T: Copy>(x: [T; LANES]) -> [T; LANES] {
    core::array::from_fn(|p| x[POSITION[p]])
}

/// Color and transmittance bytes of one layer of 8 rows, as exact f32 (`[R, G, B, T]`).
#[inline(always)]
fn layer_bytes(layer: &[Row; LANES]) -> [f32x8; 4] {
    let rgbt = words0(Rows8::load(layer));
    let byte = u32x8::splat(0xff);
    [rgbt & byte, (rgbt >> 8) & byte, (rgbt >> 16) & byte, rgbt >> 24].map(f32x8::from_u)
}

/// Eq. 5 over an MLAB span (as [`crate::resolve_rows`] on each pixel).
#[inline]
pub fn mlab_resolve<const M: usize>(span: &MlabSpan<M>) -> ResolvedLanes {
    let (color, t) = crate::resolve::resolve_layers(span.iter().map(layer_bytes));
    ResolvedLanes::from_lanes(color, t)
}

/// HT resolve over a span (as [`crate::hybrid::resolve`] on each pixel).
#[inline]
pub fn hybrid_resolve<const K: usize, A: Arithmetic>(span: &HybridSpan<K, A>) -> ResolvedLanes {
    let (color, t) = hybrid_resolve_regs(&span.head, &span.tails);
    ResolvedLanes::from_lanes(color, t)
}

/// The HT resolve in registers, pixels in [`POSITION`] order.
#[inline(always)]
fn hybrid_resolve_regs<T: TailFormat, const K: usize>(
    head: &[[Row; LANES]; K],
    tails: &[T; LANES],
) -> ([f32x8; 3], f32x8) {
    let head = crate::resolve::resolve_layers(head.iter().map(layer_bytes));
    let tails = Rows8::load_tails(tails);
    let (w0, w1) = (words0(tails), words1(tails));
    let (sums, alpha, count) = match T::KIND {
        Kind::Paper => {
            let field = u32x8::splat(0x3ff);
            let sums = [w0 & field, (w0 >> 10) & field, (w0 >> 20) & field];
            (sums, w1 & u32x8::splat(0xffff), w1 >> 16)
        }
        Kind::Unbiased => {
            // Colors at bits 0, 13, 26 (the last one across the words), alpha at 39, count at 53.
            let field = u32x8::splat(0x1fff);
            let blue = (w0 >> 26) | ((w1 & u32x8::splat(0x7f)) << 6);
            (
                [w0 & field, (w0 >> 13) & field, blue],
                (w1 >> 7) & u32x8::splat(0x3fff),
                w1 >> 21,
            )
        }
    };
    crate::hybrid::resolve_lanes::<f32x8>(head, sums, alpha, count)
}

impl ResolvedLanes {
    /// From registers in [`POSITION`] order.
    fn from_lanes(color: [f32x8; 3], t: f32x8) -> ResolvedLanes {
        ResolvedLanes {
            color: color.map(|c| unpermute(c.to_array())),
            transmittance: unpermute(t.to_array()),
        }
    }

    /// Lane `lane` (0..8) as a scalar [`Resolved`]; `None` past the last lane.
    pub fn get(&self, lane: usize) -> Option<Resolved> {
        let t = *self.transmittance.get(lane)?;
        let c = glam::Vec3::new(self.color[0][lane], self.color[1][lane], self.color[2][lane]);
        Some(Resolved {
            color: c,
            transmittance: t,
        })
    }

    /// The 8 pixels for `background` ([`Resolved::pixel`] per lane).
    pub fn pixels(&self, background: Background) -> [Vec4; LANES] {
        core::array::from_fn(|i| self.get(i).unwrap_or(Resolved::CLEAR).pixel(background))
    }

    /// The 8 pixels as RGBA8 ([`crate::to_rgba8`] per lane), computed in lanes.
    pub fn rgba8(&self, background: Background) -> [[u8; 4]; LANES] {
        rgba8_lanes(self.color.map(f32x8::new), f32x8::new(self.transmittance), background)
    }
}

/// [`crate::to_rgba8`] of [`Resolved::pixel`] for 8 lanes; the output keeps the lane order.
#[inline(always)]
fn rgba8_lanes(c: [f32x8; 3], t: f32x8, background: Background) -> [[u8; 4]; LANES] {
    let rgba: [f32x8; 4] = match background {
        Background::Opaque(bg) => {
            let bg = bg.to_array().map(f32x8::splat);
            [c[0] + bg[0] * t, c[1] + bg[1] * t, c[2] + bg[2] * t, f32x8::ONE]
        }
        Background::Transparent => [c[0], c[1], c[2], f32x8::ONE - t],
    };
    let q = rgba.map(crate::resolve::to_unorm8_lanes);
    let packed: [u32; LANES] = cast(q[0] | (q[1] << 8) | (q[2] << 16) | (q[3] << 24));
    packed.map(u32::to_le_bytes)
}

/// [`mlab_resolve`] straight to RGBA8, without leaving the registers until the end.
#[inline]
pub fn mlab_resolve_rgba8<const M: usize>(span: &MlabSpan<M>, background: Background) -> [[u8; 4]; LANES] {
    let (color, t) = crate::resolve::resolve_layers(span.iter().map(layer_bytes));
    unpermute(rgba8_lanes(color, t, background))
}

/// [`hybrid_resolve`] straight to RGBA8.
#[inline]
pub fn hybrid_resolve_rgba8<const K: usize, A: Arithmetic>(
    span: &HybridSpan<K, A>,
    background: Background,
) -> [[u8; 4]; LANES] {
    hybrid_resolve_parts_rgba8(&span.head, &span.tails, background)
}

/// [`hybrid_resolve_rgba8`] on separate head layers and tails.
#[inline]
pub fn hybrid_resolve_parts_rgba8<T: TailFormat, const K: usize>(
    head: &[[Row; LANES]; K],
    tails: &[T; LANES],
    background: Background,
) -> [[u8; 4]; LANES] {
    let (color, t) = hybrid_resolve_regs(head, tails);
    unpermute(rgba8_lanes(color, t, background))
}

/// [`hybrid_resolve`] on separate head layers and tails.
#[inline]
pub fn hybrid_resolve_parts<T: TailFormat, const K: usize>(
    head: &[[Row; LANES]; K],
    tails: &[T; LANES],
) -> ResolvedLanes {
    let (color, t) = hybrid_resolve_regs(head, tails);
    ResolvedLanes::from_lanes(color, t)
}

/// The same span in the per-pixel arrangement: `[pixel][row]`.
pub fn to_pixel_major<const M: usize>(span: &MlabSpan<M>) -> [[Row; M]; LANES] {
    core::array::from_fn(|lane| core::array::from_fn(|j| span[j][lane]))
}

/// The inverse of [`to_pixel_major`].
pub fn from_pixel_major<const M: usize>(pixels: &[[Row; M]; LANES]) -> MlabSpan<M> {
    core::array::from_fn(|j| core::array::from_fn(|lane| pixels[lane][j]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn div255_slots_is_exact() {
        for x in 0..=255u32 * 255 {
            let got = div255_slots(u16x16::splat(x as u16)).to_array();
            assert!(got.iter().all(|&q| q as u32 == crate::unorm::div255(x)), "x = {x}");
        }
    }
}

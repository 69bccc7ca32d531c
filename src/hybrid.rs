//! Hybrid Transparency (Maule et al. 2013) as in Listing 2 of Salvi & Vaidyanathan (2014):
//! `K` head rows hold the `K` nearest fragments exactly; every fragment pushed out of the
//! head is accumulated into one 8-byte [`Tail`].
//!
//! ```text
//! HT(in Fragment f, inout Fragment B[K], inout Tail T)   // Listing 2
//!   for i in 0..K:                                      // 1-pass bubble sort
//!     if f.z <= B[i].z: swap(B[i], f)
//!   if f carries color or opacity:                      // the paper tests only T != 1,
//!     T.color += f.A; T.alpha += 1 - f.T; T.count += 1  // which would drop additive light
//! ```
//!
//! Resolve (Bavoil-Myers 2008 for the tail, as Maule et al. 2013): with `n = count`,
//! `S_a = sum(alpha)`, `S_c = sum(C)`:
//!
//! ```text
//! T_tail = (1 - S_a / n)^n
//! c_tail = S_c / S_a                                    (the tail's average color)
//! C      = C_head + T_head * (c_tail * (1 - T_tail) + C_background * T_tail)
//! ```
//!
//! `c_tail * (1 - T_tail) = S_c * g` with `g = (1 - T_tail) / S_a`. With `x = 1 - S_a / n`,
//! `g = (1 - x^n) / (n (1 - x)) = (1 + x + ... + x^(n-1)) / n`: the kernel computes this
//! geometric sum alongside `x^n`, which needs no subtraction of nearly equal numbers (the
//! printed form loses most of its digits in f32 when the mean alpha is tiny) and gives
//! `g = 1` for a tail of pure additive light, which then adds its light instead of vanishing
//! (the printed form divides by zero there).
//!
//! Order independence: the head ends up holding the `K` nearest fragments whatever the
//! order (for distinct depths), and the tail holds exact integer sums that saturate;
//! saturating addition of non-negative integers is associative and commutative
//! (`min(a + b, MAX)` composed in any order is `min(sum, MAX)`), so the bytes of a
//! [`Hybrid`] do not depend on submission order.

use crate::arith::{Arithmetic, Kind, Unbiased};
use crate::fragment::Fragment;
use crate::lanes::{FloatLanes, RowLanes, Slot};
use crate::resolve::{INV255, Resolved};
use crate::row::Row;
use bytemuck::{Pod, Zeroable};
use glam::Vec3;

/// What both HT tails offer ([`Tail`], the default, and [`PaperTail`]): exact saturating
/// integer sums over the fragments that left the head, in units of `1/255`. Sealed.
pub trait TailFormat:
    sealed::Sealed + Pod + Default + PartialEq + Eq + core::hash::Hash + core::fmt::Debug + Send + Sync + 'static
{
    /// No fragment accumulated (all bits zero).
    const EMPTY: Self;
    /// Which layout (used by the lane code).
    #[doc(hidden)]
    const KIND: Kind;
    /// Largest value of each color sum.
    const COLOR_MAX: u32;
    /// Largest value of the alpha sum.
    const ALPHA_MAX: u32;
    /// Largest fragment count.
    const COUNT_MAX: u32;

    /// A tail from its fields; values above the field maxima saturate (spare bits 0).
    fn from_sums(color: [u32; 3], alpha: u32, count: u32) -> Self;
    /// Sums of premultiplied color bytes `[R, G, B]`.
    fn color_sum(self) -> [u32; 3];
    /// Sum of alpha bytes (`255 - T`).
    fn alpha_sum(self) -> u32;
    /// Number of fragments accumulated.
    fn count(self) -> u32;

    /// Accumulate a row that left the head, unless it is invisible (no color, `T = 255`).
    /// Every field saturates, never wraps.
    #[inline]
    fn add(&mut self, row: Row) {
        if row.is_invisible() {
            return;
        }
        let [r, g, b, t] = row.rgbt();
        let [cr, cg, cb] = self.color_sum();
        *self = self.with_sums(
            [cr + r as u32, cg + g as u32, cb + b as u32],
            self.alpha_sum() + (255 - t) as u32,
            self.count() + 1,
        );
    }

    /// [`from_sums`](Self::from_sums), keeping this tail's spare bits.
    #[doc(hidden)]
    fn with_sums(self, color: [u32; 3], alpha: u32, count: u32) -> Self;

    /// True when any field is at its maximum: the tail has (or may have) stopped counting.
    fn saturated(self) -> bool {
        let c = self.color_sum();
        c.iter().any(|&v| v >= Self::COLOR_MAX)
            || self.alpha_sum() >= Self::ALPHA_MAX
            || self.count() >= Self::COUNT_MAX
    }

    /// The 8 bytes.
    fn to_bytes(self) -> [u8; 8] {
        bytemuck::cast(self)
    }

    /// The tail from 8 bytes (any bytes are a valid tail).
    fn from_bytes(bytes: [u8; 8]) -> Self {
        bytemuck::cast(bytes)
    }

    /// Resolve the tail alone (Bavoil-Myers, see the [module docs](self)).
    ///
    /// Any tail bytes give a finite result: color channels in `[0, COLOR_MAX / 255]` (the
    /// tail never amplifies its light), transmittance in `[0, 1]` (a mean alpha above 1,
    /// possible only in arbitrary bytes, is clamped to 1; a zero count resolves as if the
    /// count were 1).
    #[inline]
    fn resolve(self) -> Resolved {
        let (color, t) = tail_lanes::<f32>(self.color_sum(), self.alpha_sum(), self.count());
        Resolved {
            color: Vec3::from_array(color),
            transmittance: t,
        }
    }
}

mod sealed {
    pub trait Sealed {}
    impl Sealed for super::Tail {}
    impl Sealed for super::PaperTail {}
}

/// The [`TailFormat`] methods as inherent methods of a tail type, so that they need no
/// trait import (`tail.count()` would otherwise resolve to `Iterator::count` in the error).
macro_rules! tail_methods {
    ($t:ty) => {
        impl $t {
            /// No fragment accumulated.
            pub const EMPTY: $t = <$t as TailFormat>::EMPTY;

            /// Sums of premultiplied color bytes `[R, G, B]` ([`TailFormat::color_sum`]).
            pub fn color_sum(self) -> [u32; 3] {
                <$t as TailFormat>::color_sum(self)
            }

            /// Sum of alpha bytes ([`TailFormat::alpha_sum`]).
            pub fn alpha_sum(self) -> u32 {
                <$t as TailFormat>::alpha_sum(self)
            }

            /// Number of fragments accumulated ([`TailFormat::count`]).
            pub fn count(self) -> u32 {
                <$t as TailFormat>::count(self)
            }

            /// Accumulate a row ([`TailFormat::add`]).
            pub fn add(&mut self, row: Row) {
                <$t as TailFormat>::add(self, row)
            }

            /// Whether any field is at its maximum ([`TailFormat::saturated`]).
            pub fn saturated(self) -> bool {
                <$t as TailFormat>::saturated(self)
            }

            /// Resolve the tail alone ([`TailFormat::resolve`]).
            pub fn resolve(self) -> Resolved {
                <$t as TailFormat>::resolve(self)
            }

            /// A tail from its fields, saturating ([`TailFormat::from_sums`]).
            pub fn from_sums(color: [u32; 3], alpha: u32, count: u32) -> $t {
                <$t as TailFormat>::from_sums(color, alpha, count)
            }

            /// The 8 bytes.
            pub fn to_bytes(self) -> [u8; 8] {
                <$t as TailFormat>::to_bytes(self)
            }

            /// The tail from 8 bytes (any bytes are a valid tail).
            pub fn from_bytes(bytes: [u8; 8]) -> $t {
                <$t as TailFormat>::from_bytes(bytes)
            }
        }
    };
}
tail_methods!(Tail);
tail_methods!(PaperTail);

/// The paper's 8-byte tail of Hybrid Transparency ([`Paper`](crate::Paper) arithmetic).
///
/// | bits of `word0` (bytes 0..4, LE) | field |
/// |---|---|
/// | 0..10 | sum of premultiplied R bytes, saturates at 1023 (about 4.01 in color units) |
/// | 10..20 | sum of premultiplied G bytes, saturates at 1023 |
/// | 20..30 | sum of premultiplied B bytes, saturates at 1023 |
/// | 30..32 | spare: ignored on read, preserved on write |
///
/// | bits of `word1` (bytes 4..8, LE) | field |
/// |---|---|
/// | 0..16 | sum of alpha bytes (`255 - T`), saturates at 65535 (257.0 in alpha units) |
/// | 16..32 | fragment count, saturates at 65535 |
///
/// Units are those of the row: one unit is `1/255`. The all-zero tail is the empty tail.
/// The color sums saturate at 4.0, which 200 fragments of alpha 0.03 already exceed: the
/// default [`Tail`] does not.
///
/// ```
/// use mlab::{Row, hybrid::PaperTail};
/// let mut tail = PaperTail::EMPTY;
/// tail.add(Row::new([255, 2, 3], 128, 5.0));
/// assert_eq!(tail.words(), [255 | 2 << 10 | 3 << 20, 127 | 1 << 16]);
/// assert_eq!(tail.to_bytes(), [0xff, 0x08, 0x30, 0x00, 0x7f, 0x00, 0x01, 0x00]);
/// ```
#[repr(C, align(8))]
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default, Pod, Zeroable)]
pub struct PaperTail {
    word0: [u8; 4],
    word1: [u8; 4],
}

const _: () = assert!(core::mem::size_of::<PaperTail>() == 8);
const _: () = assert!(core::mem::align_of::<PaperTail>() == 8);

/// Largest value of a 10-bit color sum of the [`PaperTail`].
pub const TAIL_COLOR_MAX: u32 = 1023;
/// Largest value of the 16-bit alpha sum of the [`PaperTail`].
pub const TAIL_ALPHA_MAX: u32 = 65535;
/// Largest fragment count of the [`PaperTail`].
pub const TAIL_COUNT_MAX: u32 = 65535;

impl PaperTail {
    /// The tail from its two little-endian words.
    pub const fn from_words(words: [u32; 2]) -> PaperTail {
        PaperTail {
            word0: words[0].to_le_bytes(),
            word1: words[1].to_le_bytes(),
        }
    }

    /// The two words (layout in the [type docs](PaperTail)).
    pub const fn words(self) -> [u32; 2] {
        [u32::from_le_bytes(self.word0), u32::from_le_bytes(self.word1)]
    }

    /// The two spare bits (30 and 31 of `word0`).
    pub const fn spare(self) -> u32 {
        self.words()[0] >> 30
    }
}

impl TailFormat for PaperTail {
    const EMPTY: PaperTail = PaperTail {
        word0: [0; 4],
        word1: [0; 4],
    };
    const KIND: Kind = Kind::Paper;
    const COLOR_MAX: u32 = TAIL_COLOR_MAX;
    const ALPHA_MAX: u32 = TAIL_ALPHA_MAX;
    const COUNT_MAX: u32 = TAIL_COUNT_MAX;

    fn from_sums(color: [u32; 3], alpha: u32, count: u32) -> PaperTail {
        PaperTail::EMPTY.with_sums(color, alpha, count)
    }

    #[inline(always)]
    fn with_sums(self, color: [u32; 3], alpha: u32, count: u32) -> PaperTail {
        let c = color.map(|v| v.min(TAIL_COLOR_MAX));
        PaperTail::from_words([
            c[0] | c[1] << 10 | c[2] << 20 | self.spare() << 30,
            alpha.min(TAIL_ALPHA_MAX) | count.min(TAIL_COUNT_MAX) << 16,
        ])
    }

    #[inline(always)]
    fn color_sum(self) -> [u32; 3] {
        let w = self.words()[0];
        [w & 0x3ff, (w >> 10) & 0x3ff, (w >> 20) & 0x3ff]
    }

    #[inline(always)]
    fn alpha_sum(self) -> u32 {
        self.words()[1] & 0xffff
    }

    #[inline(always)]
    fn count(self) -> u32 {
        self.words()[1] >> 16
    }
}

/// Width in bits of each color sum of the default [`Tail`].
pub const WIDE_COLOR_BITS: u32 = 13;
/// Width in bits of the alpha sum of the default [`Tail`].
pub const WIDE_ALPHA_BITS: u32 = 14;
/// Width in bits of the fragment count of the default [`Tail`].
pub const WIDE_COUNT_BITS: u32 = 11;

/// The default 8-byte tail of Hybrid Transparency ([`Unbiased`]
/// arithmetic): the same exact saturating sums as the paper's, re-split so that they do not
/// saturate on dense content. Read as one little-endian `u64` (`word0 | word1 << 32`):
///
/// | bits | field | saturates at |
/// |---|---|---|
/// | 0..13 | sum of premultiplied R bytes | 8191 (32.1 in color units) |
/// | 13..26 | sum of premultiplied G bytes | 8191 |
/// | 26..39 | sum of premultiplied B bytes | 8191 |
/// | 39..53 | sum of alpha bytes (`255 - T`) | 16383 (64.2 in alpha units) |
/// | 53..64 | fragment count | 2047 |
///
/// Units are those of the row (`1/255`), so the sums are exact and every fragment's
/// contribution depends on that fragment alone: the tail is exactly order independent, as
/// the paper's. Departure from the paper (3 x 10-bit colors, 16-bit alpha and count): 8x
/// the paper's color range, a quarter of its alpha range and 1/32 of its count range, sized
/// on the lab's densest scenes (`lab/TAIL_SIZES.md`: up to 19.4 color units, 31.9 alpha
/// units and 299 fragments in a tail behind 3 head rows). An alpha sum of 64 means a tail
/// transmittance below `e^-64`; the colors (which do not exceed alpha for fragments that are
/// not additive) saturate first only past 32 units of light behind the head.
///
/// ```
/// use mlab::{Row, Tail};
/// let mut tail = Tail::EMPTY;
/// tail.add(Row::new([255, 2, 3], 128, 5.0));
/// assert_eq!(tail.to_le_u64(), 255 | 2 << 13 | 3 << 26 | 127 << 39 | 1 << 53);
/// assert_eq!(tail.to_bytes(), [0xff, 0x40, 0x00, 0x0c, 0x80, 0x3f, 0x20, 0x00]);
/// ```
#[repr(C, align(8))]
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default, Pod, Zeroable)]
pub struct Tail {
    bytes: [u8; 8],
}

const _: () = assert!(core::mem::size_of::<Tail>() == 8);
const _: () = assert!(core::mem::align_of::<Tail>() == 8);

const WIDE_COLOR_MAX: u64 = (1 << WIDE_COLOR_BITS) - 1;
const WIDE_ALPHA_MAX: u64 = (1 << WIDE_ALPHA_BITS) - 1;
const WIDE_COUNT_MAX: u64 = (1 << WIDE_COUNT_BITS) - 1;
/// Bit positions of the fields of [`Tail`].
const WIDE_ALPHA_SHIFT: u32 = 3 * WIDE_COLOR_BITS;
const WIDE_COUNT_SHIFT: u32 = WIDE_ALPHA_SHIFT + WIDE_ALPHA_BITS;
const _: () = assert!(WIDE_COUNT_SHIFT + WIDE_COUNT_BITS == 64);

impl Tail {
    /// The tail as one little-endian `u64` (layout in the [type docs](Tail)).
    pub const fn to_le_u64(self) -> u64 {
        u64::from_le_bytes(self.bytes)
    }

    /// The tail from one little-endian `u64`.
    pub const fn from_le_u64(v: u64) -> Tail {
        Tail { bytes: v.to_le_bytes() }
    }

    /// The two little-endian words (`word0` = bits 0..32).
    pub const fn words(self) -> [u32; 2] {
        let v = self.to_le_u64();
        [v as u32, (v >> 32) as u32]
    }

    /// The tail from its two little-endian words.
    pub const fn from_words(words: [u32; 2]) -> Tail {
        Tail::from_le_u64(words[0] as u64 | (words[1] as u64) << 32)
    }

    #[inline(always)]
    const fn field(self, shift: u32, max: u64) -> u32 {
        ((self.to_le_u64() >> shift) & max) as u32
    }
}

impl TailFormat for Tail {
    const EMPTY: Tail = Tail { bytes: [0; 8] };
    const KIND: Kind = Kind::Unbiased;
    const COLOR_MAX: u32 = WIDE_COLOR_MAX as u32;
    const ALPHA_MAX: u32 = WIDE_ALPHA_MAX as u32;
    const COUNT_MAX: u32 = WIDE_COUNT_MAX as u32;

    fn from_sums(color: [u32; 3], alpha: u32, count: u32) -> Tail {
        Tail::EMPTY.with_sums(color, alpha, count)
    }

    #[inline(always)]
    fn with_sums(self, color: [u32; 3], alpha: u32, count: u32) -> Tail {
        let s = |v: u32| (v as u64).min(WIDE_COLOR_MAX);
        let b = WIDE_COLOR_BITS;
        Tail::from_le_u64(
            s(color[0])
                | s(color[1]) << b
                | s(color[2]) << (2 * b)
                | (alpha as u64).min(WIDE_ALPHA_MAX) << WIDE_ALPHA_SHIFT
                | (count as u64).min(WIDE_COUNT_MAX) << WIDE_COUNT_SHIFT,
        )
    }

    #[inline(always)]
    fn color_sum(self) -> [u32; 3] {
        let b = WIDE_COLOR_BITS;
        [
            self.field(0, WIDE_COLOR_MAX),
            self.field(b, WIDE_COLOR_MAX),
            self.field(2 * b, WIDE_COLOR_MAX),
        ]
    }

    #[inline(always)]
    fn alpha_sum(self) -> u32 {
        self.field(WIDE_ALPHA_SHIFT, WIDE_ALPHA_MAX)
    }

    #[inline(always)]
    fn count(self) -> u32 {
        self.field(WIDE_COUNT_SHIFT, WIDE_COUNT_MAX)
    }
}

/// The tail resolve, written once for every lane width (`f32` or `f32x8`): color and
/// transmittance of the tail from its sums. Multiplies and adds are separate (no FMA).
#[inline(always)]
pub(crate) fn tail_lanes<F: FloatLanes>(sums: [F::U; 3], alpha: F::U, count: F::U) -> ([F; 3], F) {
    let inv = F::splat(INV255);
    let one = F::splat(1.0);
    let empty = F::is_zero(count);
    let s_a = F::from_u(alpha) * inv;
    let n = F::select(empty, one, F::from_u(count));
    let mean = s_a.div(n);
    // A mean alpha above 1 (arbitrary bytes only) is clamped to 1: the tail is opaque.
    let clamped = mean.gt(one);
    let mean = F::select(clamped, one, mean);
    let x = one - mean;
    // T_tail = x^n and the geometric sum S_n = 1 + x + ... + x^(n-1), both by binary
    // exponentiation over the bits of the count (at most 16; bits above the largest count of
    // all lanes are zero and would change nothing). The color factor
    // g = (1 - T_tail) / S_a = (1 - x^n) / (n (1 - x)) = S_n / n
    // is computed from S_n: only products and sums of non-negative terms, where the printed
    // formula subtracts two numbers close to 1 (for a tiny mean alpha it lost a third of the
    // tail's light in f32). g = 1 exactly for pure additive light (x = 1).
    let mut power = one; // x^k for the bits seen so far
    let mut sum = F::splat(0.0); // S_k
    let mut base = x; // x^(2^i)
    let mut base_sum = one; // S_(2^i)
    for bit in 0..F::bit_length(count).min(16) {
        let on = F::bit(count, bit);
        sum = F::select(on, sum + power * base_sum, sum); // S_(k + 2^i) = S_k + x^k S_(2^i)
        power = F::select(on, power * base, power);
        base_sum = base_sum * (one + base); // S_(2^(i+1)) = S_(2^i) (1 + x^(2^i))
        base = base * base;
    }
    let t_tail = F::select(empty, x, power);
    // A zero count (arbitrary bytes only) resolves as a count of 1: S_1 / 1 = 1. With the
    // mean clamped, S_a is no longer n (1 - x): x = 0, T_tail = 0 and g = (1 - 0) / S_a.
    let g = F::select(empty, one, sum.div(n));
    let g = F::select(clamped, one.div(s_a), g);
    let g = F::select(g.gt(one), one, g); // rounding only: S_n <= n
    let [r, gr, b] = sums;
    (
        [F::from_u(r) * inv * g, F::from_u(gr) * inv * g, F::from_u(b) * inv * g],
        t_tail,
    )
}

/// Head then tail: `C = C_head + T_head * C_tail`, `T = T_head * T_tail`.
#[inline(always)]
pub(crate) fn combine_lanes<F: FloatLanes>(head: ([F; 3], F), tail: ([F; 3], F)) -> ([F; 3], F) {
    let ([hr, hg, hb], ht) = head;
    let ([tr, tg, tb], tt) = tail;
    ([hr + tr * ht, hg + tg * ht, hb + tb * ht], ht * tt)
}

/// Resolved head and tail fields to a resolved pixel, for every lane width.
#[inline(always)]
pub(crate) fn resolve_lanes<F: FloatLanes>(
    head: ([F; 3], F),
    sums: [F::U; 3],
    alpha: F::U,
    count: F::U,
) -> ([F; 3], F) {
    combine_lanes(head, tail_lanes::<F>(sums, alpha, count))
}

impl core::fmt::Debug for PaperTail {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "PaperTail {{ color: {:?}, alpha: {}, count: {}, spare: {} }}",
            self.color_sum(),
            self.alpha_sum(),
            self.count(),
            self.spare()
        )
    }
}

impl core::fmt::Debug for Tail {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "Tail {{ color: {:?}, alpha: {}, count: {} }}",
            self.color_sum(),
            self.alpha_sum(),
            self.count()
        )
    }
}

/// Listing 2 on `K` head rows and a tail: insert `row` into the head, accumulate the row
/// pushed out into the tail. `K = 0` is allowed (every fragment goes to the tail). The tail
/// type picks the layout: [`Tail`] (default) or [`PaperTail`].
#[inline]
pub fn insert<T: TailFormat, const K: usize>(head: &mut [Row; K], tail: &mut T, row: Row) {
    insert_lanes::<_, _, _, T, K>(head, tail, row, true);
}

/// Listing 2, written once for every lane width; lanes where `on` is false are untouched.
#[inline(always)]
pub(crate) fn insert_lanes<L: RowLanes, S: Slot<L>, TS: Slot<L::Tail<T>>, T: TailFormat, const K: usize>(
    b: &mut [S; K],
    tail: &mut TS,
    fragment: L,
    on: L::Mask,
) {
    let mut f = fragment;
    // 1-pass bubble sort to insert fragment, one layer at a time.
    for slot in b.iter_mut() {
        let row = slot.load();
        let swap = f.depth_le(row) & on;
        slot.store(L::select(swap, f, row));
        f = L::select(swap, row, f);
    }
    // Update tail if the row pushed out carries color or opacity.
    let t = tail.load();
    tail.store(L::select_tail(on, L::tail_add::<T>(t, f), t));
}

/// Resolve head and tail: `C = C_head + T_head * C_tail`, `T = T_head * T_tail`, where
/// the head is Eq. 5 over its rows and the tail is [`TailFormat::resolve`].
#[inline]
pub fn resolve<T: TailFormat>(head: &[Row], tail: T) -> Resolved {
    let h = crate::resolve::resolve_layers(head.iter().map(crate::resolve::row_bytes));
    let ([r, g, b], t) = resolve_lanes::<f32>(h, tail.color_sum(), tail.alpha_sum(), tail.count());
    Resolved {
        color: Vec3::new(r, g, b),
        transmittance: t,
    }
}

/// A Hybrid Transparency pixel: `K` head rows and a tail, `8 * (K + 1)` bytes, in the
/// arithmetic `A` ([`Unbiased`] by default: the [`Tail`] layout and dithered
/// quantization; [`Paper`](crate::Paper): the paper's [`PaperTail`] and rounding).
///
/// ```
/// use mlab::glam::Vec3;
/// use mlab::{Fragment, Hybrid};
/// let mut h = Hybrid::<1>::new();
/// h.insert(&Fragment::straight(Vec3::X, 0.5, 1.0)?);
/// h.insert(&Fragment::straight(Vec3::Y, 0.5, 2.0)?); // goes to the tail
/// assert_eq!(h.tail().count(), 1);
/// let px = h.resolve().over(Vec3::ZERO);
/// assert!((px - Vec3::new(0.5, 0.25, 0.0)).abs().max_element() < 2.0 / 255.0);
/// # Ok::<(), mlab::FragmentError>(())
/// ```
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[repr(C)]
pub struct Hybrid<const K: usize, A: Arithmetic = Unbiased> {
    head: [Row; K],
    tail: A::Tail,
}

impl<const K: usize, A: Arithmetic> Hybrid<K, A> {
    /// Size in bytes (`8 * (K + 1)`).
    pub const BYTES: usize = 8 * (K + 1);

    /// Empty head rows and an empty tail.
    pub const fn new() -> Self {
        Hybrid {
            head: [Row::EMPTY; K],
            tail: A::Tail::EMPTY,
        }
    }

    /// From stored head rows and tail (any bytes are accepted).
    pub const fn from_parts(head: [Row; K], tail: A::Tail) -> Self {
        Hybrid { head, tail }
    }

    /// Head rows, front to back.
    pub const fn head(&self) -> &[Row; K] {
        &self.head
    }

    /// The tail.
    pub const fn tail(&self) -> A::Tail {
        self.tail
    }

    /// Reset.
    pub fn clear(&mut self) {
        *self = Self::new();
    }

    /// Insert a validated fragment with Listing 2 (quantized once, by `A`).
    #[inline]
    pub fn insert(&mut self, fragment: &Fragment) {
        insert(&mut self.head, &mut self.tail, A::quantize(fragment));
    }

    /// Insert an already quantized row with Listing 2.
    #[inline]
    pub fn insert_row(&mut self, row: Row) {
        insert(&mut self.head, &mut self.tail, row);
    }

    /// Resolve head and tail ([`resolve`]).
    #[inline]
    pub fn resolve(&self) -> Resolved {
        resolve(&self.head, self.tail)
    }
}

impl<const K: usize, A: Arithmetic> Default for Hybrid<K, A> {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tail_saturates_instead_of_wrapping() {
        let mut t = PaperTail::EMPTY;
        for _ in 0..10 {
            t.add(Row::new([255, 0, 128], 0, 1.0));
        }
        assert_eq!(t.color_sum(), [1023, 0, 1023]);
        assert_eq!(t.alpha_sum(), 2550);
        assert_eq!(t.count(), 10);
        let mut t = PaperTail::from_words([0, 0xffff_ffff]);
        t.add(Row::new([0, 0, 0], 0, 1.0));
        assert_eq!((t.alpha_sum(), t.count()), (65535, 65535));
    }

    #[test]
    fn tail_skips_only_invisible_rows_and_keeps_spare_bits() {
        let mut t = PaperTail::from_words([3 << 30, 0]);
        t.add(Row::EMPTY);
        t.add(Row::new([0, 0, 0], 255, 1.0));
        assert_eq!(t, PaperTail::from_words([3 << 30, 0]));
        t.add(Row::new([9, 0, 0], 255, 1.0)); // additive light is kept
        assert_eq!(
            (t.color_sum(), t.alpha_sum(), t.count(), t.spare()),
            ([9, 0, 0], 0, 1, 3)
        );
    }

    /// Bavoil-Myers in f64 as printed, with the documented handling of arbitrary bytes
    /// (count 0 as count 1, mean alpha clamped to 1).
    fn bavoil_myers(t: PaperTail) -> (f64, f64) {
        let n = t.count().max(1) as f64;
        let s_a = t.alpha_sum() as f64 / 255.0;
        let x = 1.0 - (s_a / n).min(1.0);
        let t_tail = x.powf(n);
        let g = if s_a == 0.0 { 1.0 } else { (1.0 - t_tail) / s_a };
        (t.color_sum()[0] as f64 / 255.0 * g, t_tail)
    }

    #[test]
    fn tail_resolve_matches_bavoil_myers_including_arbitrary_bytes() {
        let cases = [
            (767, 65280, 0), // count 0, mean above 1 (the fuzz finding of the S_n / n rewrite)
            (500, 600, 2),   // mean above 1
            (300, 200, 0),   // count 0, mean below 1
            (1023, 1, 45372),
            (255, 255, 1),
            (1000, 5000, 60),
            (12, 0, 7), // pure additive light
        ];
        for (c, a, n) in cases {
            let t = PaperTail::from_sums([c, 0, 0], a, n);
            let r = t.resolve();
            let (want_c, want_t) = bavoil_myers(t);
            // The documented precision: `1 - mean` is a multiple of 2^-24, so |dT| <= n 2^-24,
            // and the color is within n 2^-23 relative (docs/reliability.md).
            let n = t.count().max(1) as f64;
            let dt = n * 2f64.powi(-24) + 1e-5;
            assert!(
                (r.transmittance as f64 - want_t).abs() <= dt,
                "{t:?}: {r:?} vs T {want_t}"
            );
            let dc = 1e-5 + (n * 2f64.powi(-23) + 1e-5) * want_c;
            assert!((r.color.x as f64 - want_c).abs() <= dc, "{t:?}: {r:?} vs C {want_c}");
        }
    }

    #[test]
    fn additive_tail_adds_its_light() {
        let mut t = PaperTail::EMPTY;
        t.add(Row::new([51, 0, 0], 255, 1.0));
        t.add(Row::new([51, 0, 0], 255, 2.0));
        let r = t.resolve();
        assert_eq!(r.transmittance, 1.0);
        assert!((r.color.x - 102.0 / 255.0).abs() < 1e-6);
    }
}

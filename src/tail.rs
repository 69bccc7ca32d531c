//! The Hybrid Transparency tails: [`Tail`] (the default, 13-bit colors) and [`PaperTail`]
//! (the paper's Listing 2 layout), exact saturating integer sums in one `u64`. Public as
//! `mlab::hybrid::{Tail, PaperTail, TailFormat}`; the tail resolve is written over the lane
//! widths in [`crate::resolve`].

use crate::resolve::{Resolved, tail_lanes};
use crate::row::Row;
use bytemuck::{Pod, Zeroable};
use glam::Vec3;

/// Which tail layout (used by the lane code to pick its instructions).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Layout {
    /// [`PaperTail`]: 10/10/10-bit colors, 16-bit alpha and count.
    Paper,
    /// [`Tail`]: 13/13/13-bit colors, 14-bit alpha, 11-bit count.
    Wide,
}

/// What both HT tails offer ([`Tail`], the default, and [`PaperTail`]): exact saturating
/// integer sums over the fragments that left the head, in units of `1/255`. Sealed.
pub trait TailFormat:
    crate::sealed::Sealed + Pod + Default + PartialEq + Eq + core::hash::Hash + core::fmt::Debug + Send + Sync + 'static
{
    /// No fragment accumulated (all bits zero).
    const EMPTY: Self;
    /// Which layout (used by the lane code).
    // The type is the crate's own: the trait is sealed, no other crate implements or reads it.
    #[allow(private_interfaces)]
    #[doc(hidden)]
    const LAYOUT: Layout;
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

    /// Resolve the tail alone (Bavoil-Myers, see the [`crate::hybrid`] docs).
    ///
    /// Any tail bytes give a finite result: color channels in `[0, COLOR_MAX / 255]` (the
    /// tail never amplifies its light), transmittance in `[0, 1]` (a zero count resolves as
    /// if the count were 1). A mean alpha above 1 is clamped to 1, and the color factor is
    /// then `1 / (S_a / 255)`: in f32 this happens for most all-opaque tails too (`S_a / 255`
    /// rounds above `n` for counts 3, 5, 6, ...), not only in arbitrary bytes. The exact f32
    /// program is in `docs/layout.md` ("f32 resolve of HT").
    #[inline]
    fn resolve(self) -> Resolved {
        let (color, t) = tail_lanes::<f32>(self.color_sum(), self.alpha_sum(), self.count());
        Resolved {
            color: Vec3::from_array(color),
            transmittance: t,
        }
    }
}

impl crate::sealed::Sealed for Tail {}
impl crate::sealed::Sealed for PaperTail {}

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
/// use mlab::{Row, TailFormat, hybrid::PaperTail};
/// let mut tail = PaperTail::EMPTY;
/// tail.add(Row::new([255, 2, 3], 128, 5.0));
/// assert_eq!(Row::from_bytes(tail.to_bytes()).words(), [255 | 2 << 10 | 3 << 20, 127 | 1 << 16]);
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
pub(crate) const TAIL_COLOR_MAX: u32 = 1023;
/// Largest value of the 16-bit alpha sum of the [`PaperTail`].
pub(crate) const TAIL_ALPHA_MAX: u32 = 65535;
/// Largest fragment count of the [`PaperTail`].
pub(crate) const TAIL_COUNT_MAX: u32 = 65535;

impl PaperTail {
    /// The tail from its two little-endian words.
    pub(crate) const fn from_words(words: [u32; 2]) -> PaperTail {
        PaperTail {
            word0: words[0].to_le_bytes(),
            word1: words[1].to_le_bytes(),
        }
    }

    /// The two words (layout in the [type docs](PaperTail)).
    pub(crate) const fn words(self) -> [u32; 2] {
        [u32::from_le_bytes(self.word0), u32::from_le_bytes(self.word1)]
    }

    /// The two spare bits (30 and 31 of `word0`).
    pub(crate) const fn spare(self) -> u32 {
        self.words()[0] >> 30
    }
}

impl TailFormat for PaperTail {
    const EMPTY: PaperTail = PaperTail {
        word0: [0; 4],
        word1: [0; 4],
    };
    #[allow(private_interfaces)]
    const LAYOUT: Layout = Layout::Paper;
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
pub(crate) const WIDE_COLOR_BITS: u32 = 13;
/// Width in bits of the alpha sum of the default [`Tail`].
pub(crate) const WIDE_ALPHA_BITS: u32 = 14;
/// Width in bits of the fragment count of the default [`Tail`].
pub(crate) const WIDE_COUNT_BITS: u32 = 11;

/// The default 8-byte tail of Hybrid Transparency ([`Unbiased`](crate::Unbiased)
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
/// use mlab::{Row, Tail, TailFormat};
/// let mut tail = Tail::EMPTY;
/// tail.add(Row::new([255, 2, 3], 128, 5.0));
/// assert_eq!(u64::from_le_bytes(tail.to_bytes()), 255 | 2 << 13 | 3 << 26 | 127 << 39 | 1 << 53);
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
    pub(crate) const fn to_le_u64(self) -> u64 {
        u64::from_le_bytes(self.bytes)
    }

    /// The tail from one little-endian `u64`.
    pub(crate) const fn from_le_u64(v: u64) -> Tail {
        Tail { bytes: v.to_le_bytes() }
    }

    #[inline(always)]
    #[expect(clippy::cast_possible_truncation, reason = "masked to at most 14 bits")]
    const fn field(self, shift: u32, max: u64) -> u32 {
        ((self.to_le_u64() >> shift) & max) as u32
    }
}

#[expect(clippy::cast_possible_truncation, reason = "the field maxima are below 2^14")]
impl TailFormat for Tail {
    const EMPTY: Tail = Tail { bytes: [0; 8] };
    #[allow(private_interfaces)]
    const LAYOUT: Layout = Layout::Wide;
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

//! The packed 8-byte row of a blending array.
//!
//! | byte | field | encoding |
//! |---|---|---|
//! | 0, 1, 2 | premultiplied R, G, B (accumulated color `A`) | unorm8: value = byte / 255 |
//! | 3 | transmittance `T = 1 - alpha` | unorm8; 255 = fully transparent |
//! | 4..8 | depth `z`, distance from the viewer (smaller = nearer) | IEEE-754 f32, little-endian |
//!
//! Read as two little-endian `u32` words (one `RG32Uint` texel):
//! `word0 = R | G << 8 | B << 16 | T << 24`, `word1 = z.to_bits()`.
//! The layout is the same on every host (the fields are byte arrays, so big-endian hosts
//! see the same bytes), size 8, alignment 8.

use bytemuck::{Pod, Zeroable};

/// One row of a blending array: accumulated premultiplied color, transmittance and depth.
///
/// See the [module docs](self) for the byte table. Any 8 bytes are a valid `Row` (it is
/// [`Pod`]): rows read back from a GPU buffer or a file never make the kernel panic.
///
/// The *empty* row is [`Row::EMPTY`]: black, fully transparent (`T = 255`), at
/// `z = +infinity`. Note that [`Row::zeroed`](Zeroable::zeroed) is **not** empty: it is
/// an opaque black row at depth 0.
///
/// ```
/// use mlab::Row;
/// let row = Row::new([10, 20, 30], 200, 1.5);
/// assert_eq!(row.to_bytes(), [10, 20, 30, 200, 0x00, 0x00, 0xc0, 0x3f]);
/// assert_eq!(row.words(), [0xc8_1e_14_0a, 1.5f32.to_bits()]);
/// ```
#[repr(C, align(8))]
#[derive(Clone, Copy, PartialEq, Eq, Hash, Pod, Zeroable)]
pub struct Row {
    rgbt: [u8; 4],
    z: [u8; 4],
}

const _: () = assert!(core::mem::size_of::<Row>() == 8);
const _: () = assert!(core::mem::align_of::<Row>() == 8);

impl Row {
    /// The empty row: color 0, `T = 255`, `z = +infinity`. A new blending array holds only these.
    pub const EMPTY: Row = Row::new([0, 0, 0], 255, f32::INFINITY);

    /// A row from its fields: premultiplied color bytes, transmittance byte, depth.
    #[inline(always)]
    pub const fn new(color: [u8; 3], transmittance: u8, depth: f32) -> Row {
        Row {
            rgbt: [color[0], color[1], color[2], transmittance],
            z: depth.to_bits().to_le_bytes(),
        }
    }

    /// The row stored in 8 bytes (the layout in the [module docs](self)).
    #[inline(always)]
    pub const fn from_bytes(bytes: [u8; 8]) -> Row {
        Row {
            rgbt: [bytes[0], bytes[1], bytes[2], bytes[3]],
            z: [bytes[4], bytes[5], bytes[6], bytes[7]],
        }
    }

    /// The 8 bytes of this row.
    #[inline(always)]
    pub const fn to_bytes(self) -> [u8; 8] {
        let [r, g, b, t] = self.rgbt;
        let [z0, z1, z2, z3] = self.z;
        [r, g, b, t, z0, z1, z2, z3]
    }

    /// The row from its two little-endian words (`RG32Uint` texel).
    #[inline(always)]
    pub const fn from_words(words: [u32; 2]) -> Row {
        Row {
            rgbt: words[0].to_le_bytes(),
            z: words[1].to_le_bytes(),
        }
    }

    /// The two words: `[R | G << 8 | B << 16 | T << 24, z.to_bits()]`.
    #[inline(always)]
    pub const fn words(self) -> [u32; 2] {
        [u32::from_le_bytes(self.rgbt), u32::from_le_bytes(self.z)]
    }

    /// The row as one little-endian `u64` (`word0 | word1 << 32`).
    #[inline(always)]
    pub(crate) const fn to_le_u64(self) -> u64 {
        u64::from_le_bytes(self.to_bytes())
    }

    /// The row from one little-endian `u64` (`word0 | word1 << 32`).
    #[inline(always)]
    pub(crate) const fn from_le_u64(v: u64) -> Row {
        Row::from_bytes(v.to_le_bytes())
    }

    /// Premultiplied color bytes `[R, G, B]`.
    #[inline(always)]
    pub const fn color(self) -> [u8; 3] {
        [self.rgbt[0], self.rgbt[1], self.rgbt[2]]
    }

    /// Transmittance byte (`255` = fully transparent, `0` = opaque).
    #[inline(always)]
    pub const fn transmittance(self) -> u8 {
        self.rgbt[3]
    }

    /// Depth (distance from the viewer). Rows read from arbitrary bytes may hold NaN or infinities.
    #[inline(always)]
    pub const fn depth(self) -> f32 {
        f32::from_bits(u32::from_le_bytes(self.z))
    }

    /// Color and transmittance as bytes `[R, G, B, T]`.
    #[inline(always)]
    pub(crate) const fn rgbt(self) -> [u8; 4] {
        self.rgbt
    }

    /// True for [`Row::EMPTY`] exactly (bitwise).
    #[inline(always)]
    pub fn is_empty(self) -> bool {
        self == Row::EMPTY
    }

    /// True if the row changes nothing when composited: no color and no opacity
    /// (`R = G = B = 0`, `T = 255`), whatever its depth. Hybrid Transparency skips such rows
    /// when they leave the head; rows with color but `T = 255` (additive light) are kept.
    #[inline(always)]
    pub const fn is_invisible(self) -> bool {
        u32::from_le_bytes(self.rgbt) == 0xff00_0000
    }
}

impl Default for Row {
    /// [`Row::EMPTY`].
    fn default() -> Row {
        Row::EMPTY
    }
}

impl core::fmt::Debug for Row {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let [r, g, b, t] = self.rgbt;
        write!(f, "Row {{ rgb: [{r}, {g}, {b}], t: {t}, z: {:?} }}", self.depth())
    }
}

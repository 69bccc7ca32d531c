//! Decoding fuzzer bytes into floats, fragments and rows.
//!
//! Floats use one tag byte so that the fuzzer reaches valid values cheaply and still
//! every f32 bit pattern:
//!
//! | tag | value |
//! |---|---|
//! | `0x00..=0xBF` | a small grid value (`unit`: `t / 191` in `[0, 1]`; `depth`: `(t - 64) / 8`, many ties) |
//! | `0xC0..=0xDF` | a table of special values (NaN, infinities, `-0.0`, just above 1, subnormals, ...) |
//! | `0xE0..=0xFF` | the next four bytes as raw IEEE-754 bits, little-endian (any NaN payload) |

use mlab::glam::Vec3;
use mlab::{Fragment, FragmentError};

/// Special values reached by one tag byte.
pub const SPECIALS: [f32; 24] = [
    f32::NAN,
    -f32::NAN,
    f32::INFINITY,
    f32::NEG_INFINITY,
    -0.0,
    0.0,
    1.0,
    1.000_000_1,
    0.999_999_94,
    -1e-30,
    1e-45,
    f32::MIN_POSITIVE,
    0.5 / 255.0,
    1.5 / 255.0,
    254.5 / 255.0,
    0.5,
    2.0,
    255.0,
    f32::MAX,
    -f32::MAX,
    -1.0,
    1e-7,
    0.1,
    0.3,
];

/// A cursor over the fuzzer's bytes (a clone reads the same bytes again: every target runs
/// the rest of the input once per arithmetic).
#[derive(Clone, Debug)]
pub struct Input<'a> {
    data: &'a [u8],
}

impl<'a> Input<'a> {
    /// A cursor at the start of `data`.
    pub fn new(data: &'a [u8]) -> Self {
        Input { data }
    }

    /// Bytes not read yet.
    pub fn remaining(&self) -> usize {
        self.data.len()
    }

    /// The next byte.
    pub fn u8(&mut self) -> Option<u8> {
        let (&b, rest) = self.data.split_first()?;
        self.data = rest;
        Some(b)
    }

    /// The next `N` bytes.
    pub fn array<const N: usize>(&mut self) -> Option<[u8; N]> {
        let (head, rest) = self.data.split_first_chunk::<N>()?;
        self.data = rest;
        Some(*head)
    }

    /// A little-endian u16.
    pub fn u16(&mut self) -> Option<u16> {
        self.array().map(u16::from_le_bytes)
    }

    /// A little-endian u32.
    pub fn u32(&mut self) -> Option<u32> {
        self.array().map(u32::from_le_bytes)
    }

    fn tagged(&mut self, grid: impl Fn(u8) -> f32) -> Option<f32> {
        let t = self.u8()?;
        Some(match t {
            0x00..=0xbf => grid(t),
            0xc0..=0xdf => SPECIALS[(t - 0xc0) as usize % SPECIALS.len()],
            0xe0..=0xff => f32::from_bits(self.u32()?),
        })
    }

    /// A color, alpha or transmittance value (see the module table).
    pub fn unit(&mut self) -> Option<f32> {
        self.tagged(|t| t as f32 / 191.0)
    }

    /// A depth (see the module table).
    pub fn depth(&mut self) -> Option<f32> {
        self.tagged(|t| (t as f32 - 64.0) * 0.125)
    }

    /// A fragment as the caller would pass it to one of the constructors.
    pub fn raw_fragment(&mut self) -> Option<RawFragment> {
        let ctor = match self.u8()? % 5 {
            0 => Ctor::Premultiplied,
            1 => Ctor::Straight,
            2 => Ctor::WithTransmittance,
            3 => Ctor::Additive,
            _ => Ctor::PremultipliedRgba,
        };
        let color = [self.unit()?, self.unit()?, self.unit()?];
        let a = if ctor == Ctor::Additive { 0.0 } else { self.unit()? };
        let z = self.depth()?;
        Some(RawFragment { ctor, color, a, z })
    }
}

/// Which public constructor a [`RawFragment`] goes through.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ctor {
    /// `Fragment::premultiplied(color, a, z)`.
    Premultiplied,
    /// `Fragment::straight(color, a, z)`.
    Straight,
    /// `Fragment::with_transmittance(color, a, z)` (`a` is the transmittance).
    WithTransmittance,
    /// `Fragment::additive(color, z)` (`a` is unused, 0).
    Additive,
    /// `Fragment::premultiplied_rgba(color.extend(a).to_array(), z)`.
    PremultipliedRgba,
}

/// Constructor arguments, possibly invalid.
#[derive(Clone, Copy, Debug)]
pub struct RawFragment {
    /// The constructor.
    pub ctor: Ctor,
    /// Color (straight for [`Ctor::Straight`], premultiplied otherwise).
    pub color: [f32; 3],
    /// Alpha, or transmittance for [`Ctor::WithTransmittance`].
    pub a: f32,
    /// Depth.
    pub z: f32,
}

impl RawFragment {
    /// Call the kernel's constructor.
    pub fn build(&self) -> Result<Fragment, FragmentError> {
        let c = Vec3::from_array(self.color);
        match self.ctor {
            Ctor::Premultiplied => Fragment::premultiplied(c, self.a, self.z),
            Ctor::Straight => Fragment::straight(c, self.a, self.z),
            Ctor::WithTransmittance => Fragment::with_transmittance(c, self.a, self.z),
            Ctor::Additive => Fragment::additive(c, self.z),
            Ctor::PremultipliedRgba => Fragment::premultiplied_rgba([c.x, c.y, c.z, self.a], self.z),
        }
    }
}

//! Lane quantization: eight fragments (structure of arrays) validated and quantized to rows
//! as [`crate::Fragment`]'s constructors and [`Arithmetic::quantize`] do lane by lane.

use crate::arith::Arithmetic;
use crate::row::Row;

use super::LANES;
use super::x8;

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
        x8::quantize::<A>(self, mask, false, true, first_pixel, true)
    }

    /// [`quantize_straight_with`](Self::quantize_straight_with) in pixels
    /// `first_pixel + i`, as [`quantize_at`](Self::quantize_at).
    pub fn quantize_straight_at<A: Arithmetic>(&self, mask: u8, first_pixel: u32) -> QuantizedLanes {
        x8::quantize::<A>(self, mask, true, true, first_pixel, true)
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
        x8::quantize::<A>(self, mask, straight, true, first_pixel, all_hashes)
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
        x8::quantize::<A>(self, mask, false, false, first_pixel, all_hashes)
    }
}

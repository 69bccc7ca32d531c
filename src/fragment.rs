//! Input fragments: validated color, alpha and depth, quantized once into a [`Row`].

use crate::row::Row;
use crate::unorm::quantize;
use glam::{Vec3, Vec4};

/// Why a fragment was rejected. Nothing is clamped or changed silently: a fragment is
/// either valid as given or refused with one of these.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum FragmentError {
    /// A color channel is NaN.
    NanColor,
    /// A color channel is infinite.
    InfiniteColor,
    /// A color channel is negative (`-0.0` is accepted as zero).
    NegativeColor,
    /// A premultiplied color channel is above 1 (after multiplying by alpha for the
    /// straight constructors). Premultiplied color may exceed alpha (additive light), not 1.
    ColorAboveOne,
    /// Alpha (or transmittance) is NaN.
    NanAlpha,
    /// Alpha (or transmittance) is outside `[0, 1]`.
    AlphaOutOfRange,
    /// Depth is NaN.
    NanDepth,
    /// Depth is `+infinity` or `-infinity` (`+infinity` is reserved for empty rows).
    InfiniteDepth,
}

impl core::fmt::Display for FragmentError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            FragmentError::NanColor => "fragment color is NaN",
            FragmentError::InfiniteColor => "fragment color is infinite",
            FragmentError::NegativeColor => "fragment color is negative",
            FragmentError::ColorAboveOne => "premultiplied fragment color is above 1",
            FragmentError::NanAlpha => "fragment alpha is NaN",
            FragmentError::AlphaOutOfRange => "fragment alpha is outside [0, 1]",
            FragmentError::NanDepth => "fragment depth is NaN",
            FragmentError::InfiniteDepth => "fragment depth is infinite",
        })
    }
}

impl core::error::Error for FragmentError {}

/// A validated transparent fragment: premultiplied linear color, alpha (coverage) and depth.
///
/// Colors are **linear** (not sRGB-encoded): convert sRGB texture or vertex colors to
/// linear before building a fragment. Constructors take glam's [`Vec3`] (the
/// `glam` re-exported as `mlab::glam`) or plain `[R, G, B, A]` arrays (`*_rgba`), so a renderer on
/// another glam version passes `v.to_array()`.
///
/// Invariants (checked by every constructor): color channels finite and in `[0, 1]`
/// (premultiplied; they may exceed alpha, which makes the fragment partly additive), alpha
/// in `[0, 1]`, depth finite. A fragment with alpha 0 and color above 0 is pure additive
/// light: it occludes nothing.
///
/// The fragment becomes a [`Row`] (8 bits per channel) exactly once, by the arithmetic's
/// [`Arithmetic::quantize`](crate::Arithmetic::quantize), which every insert calls. In the
/// paper's arithmetic ([`Paper`](crate::Paper)), and in the default one
/// ([`Unbiased`](crate::Unbiased)) for every fragment with `alpha * 255 >= 16`:
/// - color byte = `floor(c * 255 + 0.5)` (f32 multiply, then f32 add, then truncate);
/// - transmittance byte = `255 - floor(alpha * 255 + 0.5)`, so that a fragment whose color
///   does not exceed its alpha gives `color byte <= 255 - T byte`;
/// - depth stored bit for bit (`-0.0` stays `-0.0`; it compares equal to `+0.0`).
///
/// The quantization error is then at most `0.5 / 255` per channel (plus f32 rounding, below
/// `1e-7`). Fainter fragments are dithered by `Unbiased` (`docs/algorithm.md`), so that many
/// of them do not all round the same way.
///
/// ```
/// use mlab::glam::Vec3;
/// use mlab::{Arithmetic, Fragment, FragmentError, Paper, Row, Unbiased};
/// let f = Fragment::straight(Vec3::new(1.0, 0.5, 0.0), 0.5, 2.0)?;
/// assert_eq!(Paper::quantize(&f, f.hash(0)), Row::new([128, 64, 0], 127, 2.0));
/// assert_eq!(Unbiased::quantize(&f, f.hash(0)), Paper::quantize(&f, 0)); // not faint: the same bytes
/// assert_eq!(Fragment::premultiplied(Vec3::ONE, 1.5, 2.0), Err(FragmentError::AlphaOutOfRange));
/// assert_eq!(Fragment::straight_rgba([1.0, 0.5, 0.0, 0.5], 2.0)?, f);
/// # Ok::<(), FragmentError>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fragment {
    color: Vec3,
    alpha: f32,
    depth: f32,
    key: Option<u32>,
}

impl Fragment {
    /// A fragment from premultiplied color (`color * alpha` already applied), alpha and depth.
    ///
    /// Errors are checked in this order, and the first one found is returned: NaN (depth,
    /// alpha, color), then infinities (color, depth), then ranges (negative color, alpha
    /// outside `[0, 1]`, premultiplied color above 1).
    #[inline]
    pub fn premultiplied(color: Vec3, alpha: f32, depth: f32) -> Result<Fragment, FragmentError> {
        Self::checked(color, color, alpha, depth, false)
    }

    /// A fragment from straight (non-premultiplied) color, alpha and depth. The stored color is
    /// `color * alpha` (one f32 multiply per channel), which must not exceed 1.
    ///
    /// NaN, infinity and a negative value are checked on the given `color`, not on the
    /// product (a NaN or infinite color is refused at alpha 0 too); only the bound `<= 1` is
    /// checked on `color * alpha`. The order of the errors is [`Fragment::premultiplied`]'s.
    #[inline]
    pub fn straight(color: Vec3, alpha: f32, depth: f32) -> Result<Fragment, FragmentError> {
        // A straight color may exceed 1, its product with alpha may not; an infinite channel
        // fails `pre <= 1` (its product is infinite, or NaN at alpha 0), so `color >= 0` and
        // `pre <= 1` are the whole color test.
        Self::checked(color, color * alpha, alpha, depth, true)
    }

    /// The fragment of premultiplied color `pre` (`color` itself, or straight `color` times
    /// alpha): one test of every bound (four lanes at once; a NaN fails every comparison),
    /// then the documented order of errors only for a fragment that fails it.
    #[inline(always)]
    fn checked(color: Vec3, pre: Vec3, alpha: f32, depth: f32, straight: bool) -> Result<Fragment, FragmentError> {
        let low = color.extend(alpha).cmpge(Vec4::ZERO);
        let high = pre.extend(alpha).cmple(Vec4::ONE);
        if (low & high).all() & (depth.abs() < f32::INFINITY) {
            return Ok(Fragment {
                color: pre,
                alpha,
                depth,
                key: None,
            });
        }
        Self::error(color.x, color.y, color.z, alpha, depth, straight)
    }

    /// The error of an invalid fragment (`straight`: its color is straight): the first
    /// failing check in the documented order (or, where none fails, the fragment).
    #[cold]
    #[inline(never)]
    // Channels as scalars: they travel in registers, so the hot path stores nothing for it.
    fn error(r: f32, g: f32, b: f32, alpha: f32, depth: f32, straight: bool) -> Result<Fragment, FragmentError> {
        use FragmentError as E;
        let color = Vec3::new(r, g, b);
        let pre = if straight { color * alpha } else { color };
        let any = |f: fn(f32) -> bool| color.to_array().into_iter().any(f);
        let checks = [
            (depth.is_nan(), E::NanDepth),
            (alpha.is_nan(), E::NanAlpha),
            (any(f32::is_nan), E::NanColor),
            (any(f32::is_infinite), E::InfiniteColor),
            (depth.is_infinite(), E::InfiniteDepth),
            (any(|v| v < 0.0), E::NegativeColor),
            (!(0.0..=1.0).contains(&alpha), E::AlphaOutOfRange),
            (pre.to_array().into_iter().any(|v| v > 1.0), E::ColorAboveOne),
        ];
        match checks.into_iter().find(|&(failed, _)| failed) {
            Some((_, e)) => Err(e),
            None => Ok(Fragment {
                color: pre,
                alpha,
                depth,
                key: None,
            }),
        }
    }

    /// A fragment from premultiplied `[R, G, B, A]` (color already multiplied by alpha; no
    /// glam type needed: any glam version's `to_array()` gives the array).
    #[inline]
    pub fn premultiplied_rgba(rgba: [f32; 4], depth: f32) -> Result<Fragment, FragmentError> {
        let [r, g, b, a] = rgba;
        Fragment::premultiplied(Vec3::new(r, g, b), a, depth)
    }

    /// A fragment from straight `[R, G, B, A]` (color not multiplied by alpha).
    #[inline]
    pub fn straight_rgba(rgba: [f32; 4], depth: f32) -> Result<Fragment, FragmentError> {
        let [r, g, b, a] = rgba;
        Fragment::straight(Vec3::new(r, g, b), a, depth)
    }

    /// A fragment from premultiplied color and transmittance `t = 1 - alpha` in `[0, 1]`.
    /// Alpha is computed as `1 - t` in f32 (exact for `t >= 0.5`). The range is checked on `t`
    /// itself, before the subtraction: `t` outside `[0, 1]` is
    /// [`FragmentError::AlphaOutOfRange`] even where `1 - t` rounds into range (`t = -1e-10`
    /// gives `1 - t = 1.0` in f32, and is refused).
    pub fn with_transmittance(color: Vec3, transmittance: f32, depth: f32) -> Result<Fragment, FragmentError> {
        if transmittance.is_nan() {
            return Err(FragmentError::NanAlpha);
        }
        if !(0.0..=1.0).contains(&transmittance) {
            return Err(FragmentError::AlphaOutOfRange);
        }
        Fragment::premultiplied(color, 1.0 - transmittance, depth)
    }

    /// Pure additive light (alpha 0): adds `light` to whatever lies behind it, occludes nothing.
    pub fn additive(light: Vec3, depth: f32) -> Result<Fragment, FragmentError> {
        Fragment::premultiplied(light, 0.0, depth)
    }

    /// This fragment with a stable key: a 32-bit id of what emitted it, unique in the frame
    /// and the same in every frame (the primitive's id: `SV_PrimitiveID` or
    /// `gl_PrimitiveID` mixed with a draw or instance id in a shader, the triangle's index in
    /// a software rasterizer). The default arithmetic ([`Unbiased`](crate::Unbiased)) seeds
    /// its dithers with it ([`Fragment::hash`]), so a fragment is rounded the same way in
    /// every frame while the camera moves. Without a key the seed is the fragment's content,
    /// which changes with its depth: the dithers re-roll every frame, and a dense faint
    /// layer (fog) shimmers under camera motion (`docs/quality.md`). [`Paper`](crate::Paper)
    /// has no dither and ignores the key.
    ///
    /// **The contract: a key is unique per primitive among the fragments of one pixel.** Two
    /// fragments of different primitives with the same key in the same pixel get the same hash
    /// there, so both dithers (the faint fragment's quantization and the merge's rounding) draw
    /// the same value for every one of them: the rounding errors no longer average out, and a
    /// pixel crossed by many such fragments can stall or drift further from the exact image
    /// than [`Paper`](crate::Paper)'s rounding to nearest (`docs/layout.md`, "Fragment key").
    /// One primitive may cover many pixels with its key: the pixel is part of the hash.
    ///
    /// ```
    /// use mlab::glam::Vec3;
    /// use mlab::{Fragment, fragment_hash};
    /// let f = Fragment::straight(Vec3::ONE, 0.02, 5.0)?.with_key(42);
    /// assert_eq!(f.key(), Some(42));
    /// // The seed of pixel 7: the same whatever the depth.
    /// let g = Fragment::straight(Vec3::ONE, 0.02, 6.0)?.with_key(42);
    /// assert_eq!(f.hash(7), g.hash(7));
    /// assert_eq!(f.hash(7), fragment_hash(42, 7));
    /// # Ok::<(), mlab::FragmentError>(())
    /// ```
    #[inline]
    #[must_use]
    pub const fn with_key(self, key: u32) -> Fragment {
        Fragment { key: Some(key), ..self }
    }

    /// The stable key, if one was given ([`with_key`](Self::with_key)).
    #[inline]
    pub const fn key(&self) -> Option<u32> {
        self.key
    }

    /// The hash of this fragment in pixel `pixel`, which seeds the dithers of
    /// [`Unbiased`](crate::Unbiased): [`fragment_hash`](crate::fragment_hash)`(key, pixel)`,
    /// with the stable key, or without one the content key: the XOR of the f32 bits of the
    /// premultiplied color channels, alpha and depth (`docs/layout.md`).
    #[inline]
    pub fn hash(&self, pixel: u32) -> u32 {
        crate::hash::fragment_hash(self.seed_key(), pixel)
    }

    /// The stable key, or the content key ([`hash`](Self::hash)).
    #[inline(always)]
    pub(crate) fn seed_key(&self) -> u32 {
        let content = || {
            let c = self.color;
            c.x.to_bits() ^ c.y.to_bits() ^ c.z.to_bits() ^ self.alpha.to_bits() ^ self.depth.to_bits()
        };
        self.key.unwrap_or_else(content)
    }

    /// Premultiplied color.
    #[inline]
    pub fn color(&self) -> Vec3 {
        self.color
    }

    /// Alpha (coverage, `1 - transmittance`).
    #[inline]
    pub fn alpha(&self) -> f32 {
        self.alpha
    }

    /// Depth.
    #[inline]
    pub fn depth(&self) -> f32 {
        self.depth
    }

    /// The row rounded to nearest (the paper's rule, [`Paper::quantize`](crate::Paper);
    /// the default [`Unbiased`](crate::Unbiased) dithers faint fragments instead).
    #[inline]
    pub(crate) fn row_nearest(&self) -> Row {
        Row::new(
            [quantize(self.color.x), quantize(self.color.y), quantize(self.color.z)],
            255 - quantize(self.alpha),
            self.depth,
        )
    }
}

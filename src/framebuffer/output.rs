//! [`Output`]: the pixel formats a framebuffer resolves into, one sealed impl each: f32
//! ([`Vec4`]), RGBA16F (`[f16; 4]`), RGBA8 (`[u8; 4]`, the integer resolve). Each impl says
//! how it resolves the storage of one span of a [`Pixel`] kind, the whole spans of a line,
//! a span of another crate's [`Framebuffer`], and what a span that does not exist holds;
//! [`Framebuffer::resolve_as`] and the writers (`write.rs`) do the rest.

use glam::Vec4;
use half::f16;

use super::arrangement::Arrangement;
use super::pixel::Pixel;
use super::{CLEAR_LANES, Framebuffer};
use crate::lanes::{LANES, ResolvedLanes};
use crate::resolve::int::{self, IntBackground};
use crate::resolve::{Background, to_rgba16f};
use crate::row::Row;

impl crate::sealed::Sealed for Vec4 {}
impl crate::sealed::Sealed for [f16; 4] {}
impl crate::sealed::Sealed for [u8; 4] {}

/// A pixel format that every [`Framebuffer`] resolves into
/// ([`resolve_as`](Framebuffer::resolve_as)), row-major, linear (sealed):
///
/// | format | resolve | background as the resolve takes it |
/// |---|---|---|
/// | [`Vec4`] | f32 (Eq. 5, [`Resolved::pixel`](crate::Resolved::pixel)): opaque over a background, or premultiplied | the background |
/// | `[f16; 4]` | the f32 resolve through [`to_rgba16f`] | the background |
/// | `[u8; 4]` | the integer resolve (`docs/layout.md`, "Integer resolve"), linear unorm8 | its channels in the accumulator's unit, once per call |
///
/// ```
/// use mlab::glam::{Vec3, Vec4};
/// use mlab::{Background, Framebuffer, Row, SpanFramebuffer};
/// let mut storage = vec![Row::EMPTY; SpanFramebuffer::<2>::rows_needed(3, 1)?];
/// let mut fb = SpanFramebuffer::<2>::new_cleared(&mut storage, 3, 1)?;
/// fb.insert_row(1, 0, Row::new([255, 0, 0], 0, 1.0))?; // opaque red
/// let mut rgba8 = [[0u8; 4]; 3];
/// fb.resolve_as(&mut rgba8, Background::Opaque(Vec3::ZERO))?; // = resolve_rgba8
/// assert_eq!(rgba8[1], [255, 0, 0, 255]);
/// let mut f32s = [Vec4::ZERO; 3];
/// fb.resolve_as(&mut f32s, Background::Transparent)?; // = resolve_into
/// assert_eq!(f32s[0], Vec4::ZERO);
/// # Ok::<(), mlab::Error>(())
/// ```
///
/// **Adding a format** is one impl of this trait in `src/framebuffer/output.rs` (plus, for a
/// format that is not derived from the f32 resolve, its lane writer in `crate::lanes`); the
/// framebuffers, the whole-frame writers and [`DynFramebuffer`](crate::DynFramebuffer) need
/// nothing new. A hypothetical sRGB-encoded RGBA8 would be:
///
/// ```ignore
/// impl Output for Srgb8 {
///     type Bg = Background; // what the resolve takes, prepared once per call
///     fn background(bg: Background) -> Background { bg }
///     // A span of a framebuffer of another crate, through its f32 resolve.
///     fn span<F: Framebuffer + ?Sized>(fb: &F, span: u32, y: u32, bg: Background) -> [Srgb8; 8] {
///         fb.resolve_span(span, y).unwrap_or(CLEAR_LANES).pixels(bg).map(encode_srgb8)
///     }
///     // The storage of one span of a kind P in the arrangement L.
///     fn unit<P: Pixel, L: Arrangement>(unit: &[Row], bg: Background) -> [Srgb8; 8] {
///         P::resolve_f32::<L>(unit).pixels(bg).map(encode_srgb8)
///     }
///     // A span that does not exist: empty pixels.
///     fn clear<P: Pixel>(bg: Background) -> [Srgb8; 8] {
///         CLEAR_LANES.pixels(bg).map(encode_srgb8)
///     }
/// }
/// // and then: fb.resolve_as::<Srgb8>(&mut out, background)
/// ```
pub trait Output: crate::sealed::Sealed + Copy + core::fmt::Debug + PartialEq + Send + Sync + 'static {
    /// The background as this format's resolve takes it, prepared once per call.
    #[doc(hidden)]
    type Bg: Copy;
    /// Prepare the background.
    #[doc(hidden)]
    fn background(bg: Background) -> Self::Bg;
    /// Span `span` of line `y` of a framebuffer of another crate, through its own span
    /// resolves (lanes past the edge, and every lane of a span outside, empty pixels).
    #[doc(hidden)]
    fn span<F: Framebuffer + ?Sized>(fb: &F, span: u32, y: u32, bg: Background) -> [Self; LANES];
    /// The storage `unit` of one span of the kind `P` in the arrangement `L`.
    #[doc(hidden)]
    fn unit<P: Pixel, L: Arrangement>(unit: &[Row], bg: Self::Bg) -> [Self; LANES];
    /// The whole spans of one line (`line`: its rows) into `out`.
    #[doc(hidden)]
    #[inline(always)]
    fn line<P: Pixel, L: Arrangement>(line: &[Row], out: &mut [[Self; LANES]], bg: Self::Bg) {
        for (o, u) in out.iter_mut().zip(line.chunks_exact(LANES * P::ROWS)) {
            *o = Self::unit::<P, L>(u, bg);
        }
    }
    /// What a span that does not exist resolves to: 8 empty pixels of the kind `P`.
    #[doc(hidden)]
    fn clear<P: Pixel>(bg: Background) -> [Self; LANES];
}

impl Output for Vec4 {
    type Bg = Background;

    #[inline(always)]
    fn background(bg: Background) -> Background {
        bg
    }

    #[inline]
    fn span<F: Framebuffer + ?Sized>(fb: &F, span: u32, y: u32, bg: Background) -> [Vec4; LANES] {
        fb.resolve_span(span, y).unwrap_or(CLEAR_LANES).pixels(bg)
    }

    #[inline(always)]
    fn unit<P: Pixel, L: Arrangement>(unit: &[Row], bg: Background) -> [Vec4; LANES] {
        P::resolve_f32::<L>(unit).pixels(bg)
    }

    fn clear<P: Pixel>(bg: Background) -> [Vec4; LANES] {
        CLEAR_LANES.pixels(bg)
    }
}

impl Output for [f16; 4] {
    type Bg = Background;

    #[inline(always)]
    fn background(bg: Background) -> Background {
        bg
    }

    #[inline]
    fn span<F: Framebuffer + ?Sized>(fb: &F, span: u32, y: u32, bg: Background) -> [[f16; 4]; LANES] {
        fb.resolve_span(span, y)
            .unwrap_or(CLEAR_LANES)
            .pixels(bg)
            .map(to_rgba16f)
    }

    /// Large stored spans (5 rows or more) convert through a call of their own, as before
    /// issue 32 (inlined there, the 32 conversions ran 6-7 % more instructions then). Every
    /// other size and pixel-major inline them: through the call they ran 4-17 % longer than
    /// before issue 32 with 2-8 % fewer instructions, inlined 0.80-0.98x the time (x86-64-v3,
    /// `benches/compare.sh`, `benches/callgrind_compare.sh`).
    #[inline(always)]
    fn unit<P: Pixel, L: Arrangement>(unit: &[Row], bg: Background) -> [[f16; 4]; LANES] {
        let r = P::resolve_f32::<L>(unit);
        if L::SPANS && P::ROWS >= 5 {
            rgba16f_lanes(&r, bg)
        } else {
            r.pixels(bg).map(to_rgba16f)
        }
    }

    fn clear<P: Pixel>(bg: Background) -> [[f16; 4]; LANES] {
        CLEAR_LANES.pixels(bg).map(to_rgba16f)
    }
}

/// The 8 pixels of a resolved span as RGBA16F, not inlined (see the RGBA16F `Output::unit`).
#[inline(never)]
fn rgba16f_lanes(r: &ResolvedLanes, bg: Background) -> [[f16; 4]; LANES] {
    r.pixels(bg).map(to_rgba16f)
}

impl Output for [u8; 4] {
    type Bg = IntBackground;

    #[inline(always)]
    fn background(bg: Background) -> IntBackground {
        int::background(bg)
    }

    #[inline]
    fn span<F: Framebuffer + ?Sized>(fb: &F, span: u32, y: u32, bg: Background) -> [[u8; 4]; LANES] {
        fb.resolve_span_rgba8(span, y, bg)
    }

    #[inline(always)]
    fn unit<P: Pixel, L: Arrangement>(unit: &[Row], bg: IntBackground) -> [[u8; 4]; LANES] {
        P::resolve_int::<L>(unit, bg)
    }

    #[inline(always)]
    fn line<P: Pixel, L: Arrangement>(line: &[Row], out: &mut [[[u8; 4]; LANES]], bg: IntBackground) {
        P::resolve_line_int::<L>(line, out, bg);
    }

    fn clear<P: Pixel>(bg: Background) -> [[u8; 4]; LANES] {
        P::clear_int(bg)
    }
}

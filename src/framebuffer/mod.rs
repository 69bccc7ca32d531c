//! Framebuffers over borrowed storage: no allocation, every size and coordinate checked,
//! errors instead of panics. One type, [`Grid`], generic over what a pixel holds ([`Mlab`],
//! [`Ht`]) and how pixels are laid out ([`PixelMajor`], [`Spans`]); one interface, the
//! [`Framebuffer`] trait, which [`DynFramebuffer`] (method and size chosen at run time) shares.
//!
//! | alias | is | pixel | arrangement |
//! |---|---|---|---|
//! | [`MlabFramebuffer<M>`] | `Grid<Mlab<M>, PixelMajor>` | MLAB, `M` rows | `[Row; M]` per pixel, row-major |
//! | [`HybridFramebuffer<K>`] | `Grid<Ht<K>, PixelMajor>` | HT, `K` head rows + tail | `K` rows then the tail, per pixel |
//! | [`SpanFramebuffer<M>`] | `Grid<Mlab<M>, Spans>` | MLAB | 8-pixel spans, layer-major |
//! | [`HybridSpanFramebuffer<K>`] | `Grid<Ht<K>, Spans>` | HT | 8-pixel spans, layer-major |
//! | [`DynFramebuffer`] | one of the span grids | MLAB or HT, [`Layers`] at run time | 8-pixel spans |
//!
//! Every alias takes the arithmetic as its last parameter (`SpanFramebuffer<4, Paper>`;
//! [`Unbiased`] by default). [`Framebuffer`] gives pixel inserts, span inserts (8 pixels and
//! a coverage mask, on both arrangements), resolves into f32, premultiplied RGBA, RGBA8 and
//! RGBA16F, bands for threads, and byte/word views for a GPU upload: bring it into scope
//! (`use mlab::Framebuffer;`). [`Grid::pixel`] reads a pixel, [`Grid::copy_from`] converts
//! between arrangements. Storage layouts: `docs/layout.md`. "Row" is always the paper's
//! 8-byte layer of a pixel, never a line of the image: lines are `y`.
//!
//! Which one: pixel-major suits a renderer that inserts one pixel at a time in random order
//! and reads pixels back one by one; spans are faster for span inserts and resolves (no
//! transpose around the lanes), and are what the [`SpanBatcher`](crate::SpanBatcher) feeds
//! best (`docs/performance.md`).
//!
//! ```
//! use mlab::glam::Vec3;
//! use mlab::{Background, Fragment, Framebuffer, MlabFramebuffer, Row};
//! let mut storage = vec![Row::EMPTY; 4 * 2 * 2]; // 4x2 pixels, 2 rows each
//! let mut fb = MlabFramebuffer::<2>::new(&mut storage, 4, 2)?;
//! fb.insert(1, 1, &Fragment::straight(Vec3::X, 1.0, 5.0)?)?;
//! assert!(fb.insert(4, 0, &Fragment::straight(Vec3::X, 1.0, 5.0)?).is_err());
//! let mut out = [[0u8; 4]; 8];
//! fb.resolve_rgba8(&mut out, Background::Opaque(Vec3::ZERO))?;
//! assert_eq!(out[5], [255, 0, 0, 255]);
//! assert_eq!(out[0], [0, 0, 0, 255]);
//! # Ok::<(), mlab::Error>(())
//! ```

mod arrangement;
mod dims;
mod dynamic;
mod grid;
mod output;
mod pixel;
mod write;

use glam::Vec4;
use half::f16;

use crate::arith::{Arithmetic, Unbiased};
use crate::fragment::Fragment;
use crate::lanes::{FragmentLanes, InvalidLanes, LANES, ResolvedLanes};
use crate::resolve::{Background, Resolved};
use crate::row::Row;

pub use crate::error::FramebufferError;

pub(crate) use arrangement::SpanRows;
pub use arrangement::{Arrangement, PixelMajor, Spans};
pub(crate) use dims::{Dims, SpanAt};
pub use dynamic::{DynFramebuffer, DynPixel, Layers};
pub use grid::Grid;
pub use output::Output;
pub use pixel::{Ht, Mlab, Pixel};

use write::write_spans;

/// MLAB, `M` rows per pixel, pixel-major.
pub type MlabFramebuffer<'a, const M: usize, A = Unbiased> = Grid<'a, Mlab<M, A>, PixelMajor>;
/// Hybrid Transparency, `K` head rows and a tail per pixel, pixel-major.
pub type HybridFramebuffer<'a, const K: usize, A = Unbiased> = Grid<'a, Ht<K, A>, PixelMajor>;
/// MLAB, `M` rows per pixel, in 8-pixel layer-major spans.
pub type SpanFramebuffer<'a, const M: usize, A = Unbiased> = Grid<'a, Mlab<M, A>, Spans>;
/// Hybrid Transparency, `K` head rows and a tail per pixel, in 8-pixel spans.
pub type HybridSpanFramebuffer<'a, const K: usize, A = Unbiased> = Grid<'a, Ht<K, A>, Spans>;

/// Resolved lanes of nothing (lanes past the edge, or spans that cannot exist).
pub(crate) const CLEAR_LANES: ResolvedLanes = ResolvedLanes {
    color: [[0.0; LANES]; 3],
    transmittance: [1.0; LANES],
};

/// What every framebuffer offers, whatever its method (MLAB or HT), its arrangement
/// (pixel-major or spans), its size (compile time or [run time](crate::DynFramebuffer)) and
/// its arithmetic.
///
/// Coordinates: `x` is the column, `y` the line, `(0, 0)` the first pixel of the storage.
/// Span operations take the pixel `(x, y)` of lane 0 and a coverage mask (`u8`, bit `i` =
/// lane `i` = pixel `(x + i, y)`); `x` need not be a multiple of 8, and a lane outside the
/// framebuffer must be off (otherwise [`FramebufferError::OutOfBounds`] and nothing
/// changes). Every operation either succeeds or changes nothing.
///
/// Colors: every input is **linear** (not sRGB), premultiplied unless a method says
/// straight; every output is linear too. [`resolve_rgba8`](Self::resolve_rgba8) writes
/// linear unorm8, not sRGB-encoded bytes: upload it to an `Rgba8Unorm` texture (not
/// `Rgba8UnormSrgb`), or encode it yourself from [`resolve_into`](Self::resolve_into) for
/// display.
///
/// Which resolve: [`resolve_rgba8`](Self::resolve_rgba8) and
/// [`resolve_span_rgba8`](Self::resolve_span_rgba8) are the integer resolve, MLAB's and HT's
/// (`docs/layout.md`, "Integer resolve" and "Integer resolve of HT": the same bytes in scalar
/// code, every SIMD backend and a shader; for valid fragments within one step of
/// [`to_rgba8`](crate::to_rgba8) of the f32 resolve, `docs/performance.md`). Every other
/// resolve is the f32 one ([`Resolved`]; exact f32 programs in `docs/layout.md`).
pub trait Framebuffer {
    /// The arithmetic of the merge, of quantization and of the HT tail.
    type Arith: Arithmetic;
    /// A band of lines of this framebuffer (the same type over a shorter borrow).
    type Band<'b>: Framebuffer<Arith = Self::Arith>
    where
        Self: 'b;

    /// Whether fragments gathered into span inserts go in faster than one pixel at a time
    /// (measured, `docs/performance.md`): true everywhere but the pixel-major
    /// [`HybridFramebuffer`], whose span insert gathers and scatters the pixels around an
    /// insert that has no merge to share (HT `K = 3`: 0.75-0.88x per-pixel speed through a
    /// [`SpanBatcher`](crate::SpanBatcher)). A [`SpanBatcher`](crate::SpanBatcher) over a
    /// framebuffer where this is false passes each fragment straight to
    /// [`insert`](Self::insert) (nothing pending, the same bytes).
    const SPAN_INSERTS_PAY: bool = true;

    /// Whether inserts merge rows and so read every fragment's hash
    /// ([`insert_span_hashed`](Self::insert_span_hashed)): true unless the framebuffer holds HT
    /// pixels, whose inserts read the hash only to quantize faint fragments. A batcher over a
    /// framebuffer where it is false skips the hashes it does not need.
    #[doc(hidden)]
    const MERGES: bool = true;

    /// Width in pixels.
    fn width(&self) -> u32;

    /// Height in pixels (lines).
    fn height(&self) -> u32;

    /// The method and size: `Layers::Mlab(M)` has `M` row-sized slots per pixel,
    /// `Layers::Hybrid(K)` has `K + 1`.
    fn layers(&self) -> Layers;

    /// Reset every pixel to empty (empty rows, empty tails; padding lanes included).
    fn clear(&mut self);

    /// Insert a quantized row at `(x, y)` (Listing 1 or 2); the merge is seeded by the row's
    /// content ([`row_hash`](crate::mlab::row_hash) of [`pixel_id`](Self::pixel_id)).
    fn insert_row(&mut self, x: u32, y: u32, row: Row) -> Result<(), FramebufferError>;

    /// Insert one row per lane at pixels `(x + i, y)` for the lanes set in `mask` (Listing 1
    /// or 2 in lanes), byte-identical to [`insert_row`](Self::insert_row) on each lane.
    fn insert_span(&mut self, x: u32, y: u32, rows: &[Row; LANES], mask: u8) -> Result<(), FramebufferError>;

    /// Resolve one pixel (Eq. 5, or head and tail for HT).
    fn resolve(&self, x: u32, y: u32) -> Result<Resolved, FramebufferError>;

    /// Resolve the 8 pixels `(8 * span + i, y)`, lanes past the right edge clear
    /// ([`Resolved::CLEAR`]); lane `i` is [`resolve`](Self::resolve) of its pixel bit for bit.
    /// `None` when the span or the line is outside.
    fn resolve_span(&self, span: u32, y: u32) -> Option<ResolvedLanes>;

    /// The storage as rows (pixel-major or spans, as the type says; HT tail slots hold
    /// tail bytes).
    fn as_rows(&self) -> &[Row];

    /// This framebuffer over a shorter borrow (all lines).
    fn reborrow(&mut self) -> Self::Band<'_>;

    /// Split into the first `lines` lines and the rest (empty when `lines >= height`).
    fn split_lines(self, lines: u32) -> (Self, Self)
    where
        Self: Sized;

    /// The id of pixel `(x, y)` in the hashes that seed the dithers
    /// ([`Fragment::hash`], `docs/layout.md`): `first + y * width + x` (wrapping), where
    /// `first` is 0 for a whole framebuffer and the id of a band's first pixel for a band
    /// ([`bands_mut`](Self::bands_mut)), so that bands insert the same bytes as the whole.
    #[inline(always)]
    fn pixel_id(&self, x: u32, y: u32) -> u32 {
        self.first_pixel()
            .wrapping_add(y.wrapping_mul(self.width()))
            .wrapping_add(x)
    }

    /// The id of pixel `(0, 0)` ([`pixel_id`](Self::pixel_id)): 0 unless this is a band.
    #[inline(always)]
    fn first_pixel(&self) -> u32 {
        0
    }

    /// Insert a quantized row at `(x, y)` whose merge is seeded by `h`, the hash of the
    /// fragment it was quantized from ([`Fragment::hash`] of [`pixel_id`](Self::pixel_id)).
    /// This default, for a framebuffer of another crate, is [`insert_row`](Self::insert_row).
    #[inline(always)]
    fn insert_hashed(&mut self, x: u32, y: u32, row: Row, h: u32) -> Result<(), FramebufferError> {
        let _ = h;
        self.insert_row(x, y, row)
    }

    /// [`insert_span`](Self::insert_span) with each lane's merge seeded by `hashes[i]` (as
    /// [`insert_hashed`](Self::insert_hashed)). For a framebuffer of another crate this
    /// default is [`insert_span`](Self::insert_span).
    #[inline(always)]
    fn insert_span_hashed(
        &mut self,
        x: u32,
        y: u32,
        rows: &[Row; LANES],
        hashes: &[u32; LANES],
        mask: u8,
    ) -> Result<(), FramebufferError> {
        self.insert_span_rows(x, y, SpanRows { rows, hashes, mask })
    }

    /// [`insert_span_hashed`](Self::insert_span_hashed) with its lanes as one value (what a
    /// [`Grid`] overrides; no other crate can name a `SpanRows`). This default is
    /// [`insert_span`](Self::insert_span).
    #[doc(hidden)]
    #[inline(always)]
    #[allow(private_interfaces)]
    fn insert_span_rows(&mut self, x: u32, y: u32, span: SpanRows<'_>) -> Result<(), FramebufferError> {
        self.insert_span(x, y, span.rows, span.mask)
    }

    /// [`insert_span_hashed`](Self::insert_span_hashed) at an aligned span found (and
    /// checked) before, without a second check: the [`SpanBatcher`](crate::SpanBatcher)'s
    /// flush. Crate-private in effect (no other crate can name a `SpanAt`); this default is
    /// [`insert_span_hashed`](Self::insert_span_hashed) at its coordinates.
    #[doc(hidden)]
    #[inline(always)]
    #[allow(private_interfaces)]
    fn insert_span_at(&mut self, at: SpanAt, span: SpanRows<'_>) -> Result<(), FramebufferError> {
        self.insert_span_hashed(at.x, at.y, span.rows, span.hashes, span.mask)
    }

    /// Insert a fragment at `(x, y)`, quantized by [`Self::Arith`](Arithmetic::quantize)
    /// with its hash in this pixel ([`Fragment::hash`] of [`pixel_id`](Self::pixel_id)).
    #[inline(always)]
    fn insert(&mut self, x: u32, y: u32, fragment: &Fragment) -> Result<(), FramebufferError> {
        let h = fragment.hash(self.pixel_id(x, y));
        self.insert_hashed(x, y, <Self::Arith as Arithmetic>::quantize(fragment, h), h)
    }

    /// Validate, quantize and insert one fragment per lane, premultiplied color
    /// ([`FragmentLanes::quantize_with`]); returns the lanes that were on but invalid (left
    /// untouched). Coordinates are checked first, for every lane that is on.
    #[inline]
    fn insert_span_fragments(&mut self, x: u32, y: u32, fragments: &FragmentLanes, mask: u8) -> SpanInsert {
        insert_fragments(self, x, y, fragments, mask, false)
    }

    /// [`insert_span_fragments`](Self::insert_span_fragments) with straight color (each
    /// channel multiplied by alpha first, [`FragmentLanes::quantize_straight_with`]).
    #[inline]
    fn insert_span_straight(&mut self, x: u32, y: u32, fragments: &FragmentLanes, mask: u8) -> SpanInsert {
        insert_fragments(self, x, y, fragments, mask, true)
    }

    /// Resolve the 8 pixels of a span straight to RGBA8 (the integer resolve, see the trait
    /// docs; this default, for a framebuffer of another crate, is [`to_rgba8`](crate::to_rgba8)
    /// of [`resolve_span`](Self::resolve_span)); lanes past the edge, and every lane of a span
    /// outside, are an empty pixel's.
    #[inline]
    fn resolve_span_rgba8(&self, span: u32, y: u32, background: Background) -> [[u8; 4]; LANES] {
        self.resolve_span(span, y).unwrap_or(CLEAR_LANES).rgba8(background)
    }

    /// Resolve every pixel into the format `O` ([`Output`]: f32 [`Vec4`], RGBA8 `[u8; 4]`
    /// (the integer resolve), RGBA16F `[f16; 4]`), row-major (`width * height`), linear.
    /// [`resolve_into`](Self::resolve_into), [`resolve_rgba8`](Self::resolve_rgba8) and
    /// [`resolve_rgba16f`](Self::resolve_rgba16f) are this for their formats. This default,
    /// for a framebuffer of another crate, resolves span by span through
    /// [`resolve_span`](Self::resolve_span) (RGBA8: [`resolve_span_rgba8`](Self::resolve_span_rgba8)).
    ///
    /// ```
    /// use mlab::glam::Vec3;
    /// use mlab::{Background, Framebuffer, MlabFramebuffer, Row};
    /// let mut storage = vec![Row::EMPTY; 2 * 1 * 4];
    /// let mut fb = MlabFramebuffer::<4>::new_cleared(&mut storage, 2, 1)?;
    /// fb.insert_row(0, 0, Row::new([0, 255, 0], 0, 1.0))?;
    /// let mut out = [[0u8; 4]; 2];
    /// fb.resolve_as(&mut out, Background::Opaque(Vec3::ONE))?;
    /// assert_eq!(out, [[0, 255, 0, 255], [255, 255, 255, 255]]);
    /// # Ok::<(), mlab::Error>(())
    /// ```
    fn resolve_as<O: Output>(&self, out: &mut [O], background: Background) -> Result<(), FramebufferError> {
        let span = |s, y| O::span(self, s, y, background);
        write_spans(Dims::new(self.width(), self.height()), out, span)
    }

    /// Resolve every pixel into f32 RGBA, row-major (`width * height`): opaque over a
    /// background, or premultiplied ([`Resolved::pixel`]). Linear. [`resolve_as`](Self::resolve_as)
    /// into [`Vec4`].
    fn resolve_into(&self, out: &mut [Vec4], background: Background) -> Result<(), FramebufferError> {
        self.resolve_as(out, background)
    }

    /// Resolve every pixel into RGBA8 (linear unorm8, not sRGB), row-major: the integer
    /// resolve (see the trait docs); the same bytes as [`resolve_span_rgba8`](Self::resolve_span_rgba8)
    /// span by span. [`resolve_as`](Self::resolve_as) into `[u8; 4]`.
    fn resolve_rgba8(&self, out: &mut [[u8; 4]], background: Background) -> Result<(), FramebufferError> {
        self.resolve_as(out, background)
    }

    /// Resolve every pixel into RGBA16F ([`to_rgba16f`](crate::to_rgba16f), linear),
    /// row-major. [`resolve_as`](Self::resolve_as) into `[f16; 4]`.
    fn resolve_rgba16f(&self, out: &mut [[f16; 4]], background: Background) -> Result<(), FramebufferError> {
        self.resolve_as(out, background)
    }

    /// Split into bands of `lines` lines (the last one may be shorter), each a framebuffer
    /// of its own over its part of the storage, so that threads can own them. Band `b`
    /// covers lines `b * lines ..`; coordinates inside a band are relative to its first
    /// line. `lines == 0`, or an empty framebuffer, yields no band.
    fn bands_mut(&mut self, lines: u32) -> impl Iterator<Item = Self::Band<'_>> {
        let none = lines == 0 || self.width() == 0 || self.height() == 0;
        Bands {
            rest: if none { None } else { Some(self.reborrow()) },
            lines,
        }
    }

    /// The storage as bytes (8 per row; layout in [`Row`] and [`Tail`](crate::Tail)).
    fn as_bytes(&self) -> &[u8] {
        bytemuck::cast_slice(self.as_rows())
    }

    /// The storage as native-endian `u32` words, two per row (`RG32Uint` texels). On
    /// little-endian hosts these are the words of [`Row::words`].
    fn as_words(&self) -> &[u32] {
        bytemuck::cast_slice(self.as_rows())
    }
}

/// What a span insert of fragments returns: the lanes refused, or why nothing changed.
type SpanInsert = Result<InvalidLanes, FramebufferError>;

/// Check the lanes' pixels, validate and quantize (straight or premultiplied color), insert
/// the valid lanes: [`Framebuffer::insert_span_fragments`] and `insert_span_straight`.
#[inline(always)]
fn insert_fragments<F: Framebuffer + ?Sized>(
    fb: &mut F,
    x: u32,
    y: u32,
    fragments: &FragmentLanes,
    mask: u8,
    straight: bool,
) -> SpanInsert {
    Dims::new(fb.width(), fb.height()).check_span(x, y, mask)?;
    let first = fb.pixel_id(x, y);
    let q = fragments.quantize_for_insert::<F::Arith>(mask, straight, first, F::MERGES);
    fb.insert_span_hashed(x, y, &q.rows, &q.hashes, q.valid)?;
    Ok(InvalidLanes(q.invalid))
}

/// The bands of a framebuffer ([`Framebuffer::bands_mut`]).
#[derive(Debug)]
struct Bands<F> {
    rest: Option<F>,
    lines: u32,
}

impl<F: Framebuffer> Iterator for Bands<F> {
    type Item = F;
    fn next(&mut self) -> Option<F> {
        let fb = self.rest.take()?;
        if fb.height() <= self.lines {
            return Some(fb);
        }
        let (band, rest) = fb.split_lines(self.lines);
        self.rest = Some(rest);
        Some(band)
    }
}

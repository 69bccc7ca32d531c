//! Framebuffers over borrowed storage: no allocation, every size and coordinate checked,
//! errors instead of panics, and one interface, the [`Framebuffer`] trait, for the four
//! arrangements.
//!
//! | type | method | arrangement |
//! |---|---|---|
//! | [`MlabFramebuffer<M>`] | MLAB, `M` rows per pixel | pixel-major: `[Row; M]` per pixel, row-major |
//! | [`HybridFramebuffer<K>`] | HT, `K` head rows + tail | pixel-major: `K` rows then the tail per pixel |
//! | [`SpanFramebuffer<M>`](crate::SpanFramebuffer) | MLAB | 8-pixel spans, layer-major ([`crate::spans`]) |
//! | [`HybridSpanFramebuffer<K>`](crate::HybridSpanFramebuffer) | HT | 8-pixel spans, layer-major |
//! | [`DynFramebuffer`](crate::DynFramebuffer) | MLAB or HT, size chosen at run time | 8-pixel spans |
//!
//! All of them implement [`Framebuffer`]: pixel inserts, span inserts (8 pixels and a
//! coverage mask, on both arrangements), resolves into f32, premultiplied RGBA, RGBA8 and
//! RGBA16F, bands for threads, and byte/word views for a GPU upload. Bring the trait into
//! scope to call them (`use mlab::Framebuffer;`).
//!
//! Pixel-major storage: pixel `(x, y)` owns the rows `[(y * width + x) * R, (y * width +
//! x + 1) * R)` where `R` is the number of rows per pixel (`M` for MLAB, `K + 1` for Hybrid
//! Transparency, whose last row-sized slot holds the 8-byte [`Tail`](crate::Tail)). "Row"
//! is always the paper's 8-byte layer of a pixel, never a line of the image: lines are `y`.
//!
//! Which one: the pixel-major framebuffers suit a renderer that inserts one pixel at a time
//! in random order and reads pixels back one by one; the span framebuffers are 1.5-3x faster
//! for span inserts and resolves (no transpose around the lanes), and are what the
//! [`SpanBatcher`](crate::SpanBatcher) feeds best.
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

use glam::Vec4;
use half::f16;

use core::marker::PhantomData;

use crate::arith::{Arithmetic, Unbiased};
use crate::fragment::Fragment;
use crate::hybrid::{self, TailFormat};
use crate::lanes::{self, FragmentLanes, InvalidLanes, LANES, ResolvedLanes};
use crate::mlab;
use crate::resolve::{Background, Resolved, resolve_rows, to_rgba8, to_rgba16f};
use crate::row::Row;

/// Why a framebuffer operation was refused. Nothing was changed when one is returned.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum FramebufferError {
    /// The storage slice does not hold exactly `width * height * rows_per_pixel` rows.
    StorageLength {
        /// Rows required.
        expected: usize,
        /// Rows given.
        actual: usize,
    },
    /// `width * height * rows_per_pixel` does not fit in `usize`.
    SizeOverflow,
    /// A coordinate lies outside the framebuffer.
    OutOfBounds {
        /// Column asked for.
        x: u32,
        /// Line asked for.
        y: u32,
        /// Framebuffer width.
        width: u32,
        /// Framebuffer height.
        height: u32,
    },
    /// An output slice does not hold exactly `width * height` pixels.
    OutputLength {
        /// Pixels required.
        expected: usize,
        /// Pixels given.
        actual: usize,
    },
    /// A run-time layer count that [`DynFramebuffer`](crate::DynFramebuffer) does not
    /// offer (see [`Layers::SIZES`](crate::Layers::SIZES)).
    UnsupportedLayers {
        /// Rows (MLAB) or head rows (HT) asked for.
        rows: usize,
    },
}

impl core::fmt::Display for FramebufferError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            FramebufferError::StorageLength { expected, actual } => {
                write!(f, "framebuffer storage holds {actual} rows, expected {expected}")
            }
            FramebufferError::SizeOverflow => f.write_str("framebuffer size overflows usize"),
            FramebufferError::OutOfBounds { x, y, width, height } => {
                write!(f, "pixel ({x}, {y}) is outside the {width}x{height} framebuffer")
            }
            FramebufferError::OutputLength { expected, actual } => {
                write!(f, "output holds {actual} pixels, expected {expected}")
            }
            FramebufferError::UnsupportedLayers { rows } => {
                write!(
                    f,
                    "{rows} rows per pixel is not one of the run-time sizes 1, 2, 3, 4, 6, 8"
                )
            }
        }
    }
}

impl core::error::Error for FramebufferError {}

/// Width and height with the checks shared by every framebuffer view.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Dims {
    pub(crate) width: u32,
    pub(crate) height: u32,
}

impl Dims {
    fn pixels(self) -> Option<usize> {
        (self.width as usize).checked_mul(self.height as usize)
    }

    /// `width * height * rows_per_pixel`, or [`FramebufferError::SizeOverflow`].
    fn rows_needed(self, rows_per_pixel: usize) -> Result<usize, FramebufferError> {
        self.pixels()
            .and_then(|p| p.checked_mul(rows_per_pixel))
            .ok_or(FramebufferError::SizeOverflow)
    }

    /// Check that `storage_len` is exactly the rows needed.
    fn check_storage(self, rows_per_pixel: usize, storage_len: usize) -> Result<(), FramebufferError> {
        let expected = self.rows_needed(rows_per_pixel)?;
        if expected != storage_len {
            return Err(FramebufferError::StorageLength {
                expected,
                actual: storage_len,
            });
        }
        Ok(())
    }

    /// The error for pixel `(x, y)` outside these dimensions.
    pub(crate) fn out_of_bounds(self, x: u32, y: u32) -> FramebufferError {
        FramebufferError::OutOfBounds {
            x,
            y,
            width: self.width,
            height: self.height,
        }
    }

    /// Pixel index of `(x, y)`.
    fn index(self, x: u32, y: u32) -> Result<usize, FramebufferError> {
        if x >= self.width || y >= self.height {
            return Err(self.out_of_bounds(x, y));
        }
        Ok(y as usize * self.width as usize + x as usize)
    }

    /// Check a span operation at `(x, y)` with `mask`: every lane that is on lies inside.
    /// Returns the pixel index of lane 0 (off, but inside the line, when lanes past it are
    /// on); 0 for a zero mask, which touches no pixel and may lie anywhere on a valid line
    /// (its `y * width + x` can exceed a 32-bit `usize`).
    #[inline(always)]
    pub(crate) fn check_span(self, x: u32, y: u32, mask: u8) -> Result<usize, FramebufferError> {
        if y >= self.height {
            return Err(self.out_of_bounds(x, y));
        }
        if mask == 0 {
            return Ok(0);
        }
        let last = x as u64 + 7 - mask.leading_zeros() as u64;
        if last >= self.width as u64 {
            return Err(self.out_of_bounds(last.min(u32::MAX as u64) as u32, y));
        }
        Ok(y as usize * self.width as usize + x as usize)
    }

    /// Check an output slice length: exactly `width * height` pixels.
    pub(crate) fn check_output(self, len: usize) -> Result<(), FramebufferError> {
        let expected = self.pixels().ok_or(FramebufferError::SizeOverflow)?;
        if len != expected {
            return Err(FramebufferError::OutputLength { expected, actual: len });
        }
        Ok(())
    }
}

/// Write the 8 lanes of each span (`span(span_index_in_line, y)`) into a row-major output
/// of `width * height` pixels, dropping lanes past the right edge.
pub(crate) fn write_spans<T: Copy>(
    width: u32,
    height: u32,
    out: &mut [T],
    span: impl Fn(u32, u32) -> [T; LANES],
) -> Result<(), FramebufferError> {
    Dims { width, height }.check_output(out.len())?;
    if width == 0 {
        return Ok(());
    }
    for (y, line) in out.chunks_exact_mut(width as usize).enumerate() {
        // Whole spans as arrays: a fixed-size store each. (A copy of `o.len()` elements, the
        // same for every chunk, compiled to a call to `memmove` per span: 16-22 % of an RGBA8
        // resolve at M = 1.) The loop of `write_lines`, kept apart: through its closure the
        // span resolves ran 2 more instructions per span (callgrind, MLAB spans).
        let (whole, rest) = line.as_chunks_mut::<LANES>();
        for (sx, o) in whole.iter_mut().enumerate() {
            *o = span(sx as u32, y as u32);
        }
        if !rest.is_empty() {
            let px = span(whole.len() as u32, y as u32);
            rest.copy_from_slice(&px[..rest.len()]);
        }
    }
    Ok(())
}

/// [`write_spans`] with the whole spans of each line written by `whole(y, spans)` (a
/// pixel-major framebuffer's own loop over its storage, without a bounds check per span),
/// the partial last span by `span`.
pub(crate) fn write_lines<T: Copy>(
    width: u32,
    height: u32,
    out: &mut [T],
    mut whole: impl FnMut(usize, &mut [[T; LANES]]),
    span: impl Fn(u32, u32) -> [T; LANES],
) -> Result<(), FramebufferError> {
    Dims { width, height }.check_output(out.len())?;
    if width == 0 {
        return Ok(());
    }
    for (y, line) in out.chunks_exact_mut(width as usize).enumerate() {
        let (spans, rest) = line.as_chunks_mut::<LANES>();
        whole(y, spans);
        if !rest.is_empty() {
            let px = span(spans.len() as u32, y as u32);
            rest.copy_from_slice(&px[..rest.len()]);
        }
    }
    Ok(())
}

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
/// linear unorm8 (`floor(v * 255 + 0.5)`), not sRGB-encoded bytes: upload it to an
/// `Rgba8Unorm` texture (not `Rgba8UnormSrgb`), or encode it yourself from
/// [`resolve_into`](Self::resolve_into) for display.
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

    /// Width in pixels.
    fn width(&self) -> u32;

    /// Height in pixels (lines).
    fn height(&self) -> u32;

    /// Rows (8-byte slots) per pixel: `M` for MLAB, `K + 1` for HT.
    fn rows_per_pixel(&self) -> usize;

    /// Reset every pixel to empty (empty rows, empty tails; padding lanes included).
    fn clear(&mut self);

    /// Insert a quantized row at `(x, y)` (Listing 1 or 2).
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

    /// Insert a fragment at `(x, y)`, quantized by [`Self::Arith`](Arithmetic::quantize).
    #[inline]
    fn insert(&mut self, x: u32, y: u32, fragment: &Fragment) -> Result<(), FramebufferError> {
        self.insert_row(x, y, <Self::Arith as Arithmetic>::quantize(fragment))
    }

    /// Validate, quantize and insert one fragment per lane, premultiplied color
    /// ([`FragmentLanes::quantize_with`]); returns the lanes that were on but invalid (left
    /// untouched). Coordinates are checked first, for every lane that is on.
    #[inline]
    fn insert_span_fragments(
        &mut self,
        x: u32,
        y: u32,
        fragments: &FragmentLanes,
        mask: u8,
    ) -> Result<InvalidLanes, FramebufferError> {
        Dims {
            width: self.width(),
            height: self.height(),
        }
        .check_span(x, y, mask)?;
        let q = fragments.quantize_with::<Self::Arith>(mask);
        self.insert_span(x, y, &q.rows, q.valid)?;
        Ok(InvalidLanes(q.invalid))
    }

    /// [`insert_span_fragments`](Self::insert_span_fragments) with straight (not
    /// premultiplied) color: each channel is multiplied by alpha first
    /// ([`FragmentLanes::quantize_straight_with`]).
    #[inline]
    fn insert_span_straight(
        &mut self,
        x: u32,
        y: u32,
        fragments: &FragmentLanes,
        mask: u8,
    ) -> Result<InvalidLanes, FramebufferError> {
        Dims {
            width: self.width(),
            height: self.height(),
        }
        .check_span(x, y, mask)?;
        let q = fragments.quantize_straight_with::<Self::Arith>(mask);
        self.insert_span(x, y, &q.rows, q.valid)?;
        Ok(InvalidLanes(q.invalid))
    }

    /// Resolve the 8 pixels of a span straight to RGBA8 (the span framebuffers keep the
    /// values in registers); lanes past the edge are the background's.
    #[inline]
    fn resolve_span_rgba8(&self, span: u32, y: u32, background: Background) -> [[u8; 4]; LANES] {
        self.resolve_span(span, y).unwrap_or(CLEAR_LANES).rgba8(background)
    }

    /// Resolve every pixel into f32 RGBA, row-major (`width * height`): opaque over a
    /// background, or premultiplied ([`Resolved::pixel`]). Linear.
    fn resolve_into(&self, out: &mut [Vec4], background: Background) -> Result<(), FramebufferError> {
        write_spans(self.width(), self.height(), out, |s, y| {
            self.resolve_span(s, y).unwrap_or(CLEAR_LANES).pixels(background)
        })
    }

    /// [`resolve_into`](Self::resolve_into) into plain `[R, G, B, A]` arrays (no glam type).
    fn resolve_rgba32f(&self, out: &mut [[f32; 4]], background: Background) -> Result<(), FramebufferError> {
        write_spans(self.width(), self.height(), out, |s, y| {
            self.resolve_span(s, y)
                .unwrap_or(CLEAR_LANES)
                .pixels(background)
                .map(|p| p.to_array())
        })
    }

    /// Resolve every pixel into RGBA8 ([`to_rgba8`]: linear unorm8, not sRGB), row-major.
    fn resolve_rgba8(&self, out: &mut [[u8; 4]], background: Background) -> Result<(), FramebufferError> {
        write_spans(self.width(), self.height(), out, |s, y| {
            self.resolve_span_rgba8(s, y, background)
        })
    }

    /// Resolve every pixel into RGBA16F ([`to_rgba16f`], linear), row-major.
    fn resolve_rgba16f(&self, out: &mut [[f16; 4]], background: Background) -> Result<(), FramebufferError> {
        write_spans(self.width(), self.height(), out, |s, y| {
            self.resolve_span(s, y)
                .unwrap_or(CLEAR_LANES)
                .pixels(background)
                .map(to_rgba16f)
        })
    }

    /// Split into bands of `lines` lines (the last one may be shorter), each a framebuffer
    /// of its own over its part of the storage, so that threads can own them. Band `b`
    /// covers lines `b * lines ..`; coordinates inside a band are relative to its first
    /// line. `lines == 0`, or an empty framebuffer, yields no band.
    fn bands_mut(&mut self, lines: u32) -> Bands<Self::Band<'_>> {
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

/// The bands of a framebuffer ([`Framebuffer::bands_mut`]).
#[derive(Debug)]
pub struct Bands<F> {
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

/// Gather rows `offset..offset + N` of the pixels `first..first + valid` (`stride` rows per
/// pixel) into a layer-major span; lanes from `valid` on hold `fill`.
#[inline(always)]
fn gather<const N: usize>(
    rows: &[Row],
    stride: usize,
    offset: usize,
    first: usize,
    valid: usize,
    fill: Row,
) -> [[Row; LANES]; N] {
    let mut span = [[fill; LANES]; N];
    for lane in 0..valid.min(LANES) {
        let base = (first + lane) * stride + offset;
        if let Some(p) = rows.get(base..base + N) {
            for (layer, row) in span.iter_mut().zip(p) {
                layer[lane] = *row;
            }
        }
    }
    span
}

/// The inverse of [`gather`] for the lanes set in `mask`.
#[inline(always)]
fn scatter<const N: usize>(
    rows: &mut [Row],
    stride: usize,
    offset: usize,
    first: usize,
    mask: u8,
    span: &[[Row; LANES]; N],
) {
    for lane in 0..LANES {
        if mask & (1 << lane) == 0 {
            continue;
        }
        let base = (first + lane) * stride + offset;
        if let Some(p) = rows.get_mut(base..base + N) {
            for (layer, row) in span.iter().zip(p) {
                *row = layer[lane];
            }
        }
    }
}

/// Pixels of a span at pixel index `first` that lie inside a line of `width` pixels from
/// column `x`.
#[inline(always)]
fn lanes_inside(width: u32, x: u32) -> usize {
    (width.saturating_sub(x) as usize).min(LANES)
}

/// An MLAB framebuffer: `width * height` blending arrays of `M` rows over borrowed storage,
/// pixel-major, in the arithmetic `A` ([`Unbiased`] by default, [`Paper`](crate::Paper) for
/// the paper's). Its operations are those of [`Framebuffer`].
#[derive(Debug)]
pub struct MlabFramebuffer<'a, const M: usize, A: Arithmetic = Unbiased> {
    pixels: &'a mut [[Row; M]],
    dims: Dims,
    arithmetic: PhantomData<A>,
}

impl<'a, const M: usize, A: Arithmetic> MlabFramebuffer<'a, M, A> {
    /// Rows of storage needed for `width x height` pixels (`width * height * M`), or
    /// [`FramebufferError::SizeOverflow`].
    pub fn rows_needed(width: u32, height: u32) -> Result<usize, FramebufferError> {
        Dims { width, height }.rows_needed(M)
    }

    /// A view over `storage`, which must hold exactly `width * height * M` rows. The
    /// contents are kept (call [`clear`](Framebuffer::clear) for a new frame): rows from a
    /// previous frame or from arbitrary bytes are valid input.
    pub fn new(storage: &'a mut [Row], width: u32, height: u32) -> Result<Self, FramebufferError> {
        let dims = Dims { width, height };
        dims.check_storage(M, storage.len())?;
        let () = mlab::AtLeastOne::<M>::OK;
        let actual = storage.len();
        // Cannot fail: the length is a multiple of M >= 1 and the alignment is Row's.
        let pixels: &mut [[Row; M]] =
            bytemuck::try_cast_slice_mut(storage).map_err(|_| FramebufferError::StorageLength {
                expected: actual,
                actual,
            })?;
        Ok(MlabFramebuffer {
            pixels,
            dims,
            arithmetic: PhantomData,
        })
    }

    /// [`new`](Self::new), then [`clear`](Framebuffer::clear).
    pub fn new_cleared(storage: &'a mut [Row], width: u32, height: u32) -> Result<Self, FramebufferError> {
        let mut fb = Self::new(storage, width, height)?;
        fb.clear();
        Ok(fb)
    }

    /// The blending array of pixel `(x, y)`.
    pub fn pixel(&self, x: u32, y: u32) -> Result<&[Row; M], FramebufferError> {
        let i = self.dims.index(x, y)?;
        self.pixels.get(i).ok_or(self.dims.out_of_bounds(x, y))
    }

    /// The blending array of pixel `(x, y)`, mutable.
    pub fn pixel_mut(&mut self, x: u32, y: u32) -> Result<&mut [Row; M], FramebufferError> {
        let i = self.dims.index(x, y)?;
        let d = self.dims;
        self.pixels.get_mut(i).ok_or(d.out_of_bounds(x, y))
    }

    /// The 8 pixels from `(x, y)` when all of them are inside.
    #[inline(always)]
    fn whole_span(&self, x: u32, y: u32) -> Option<&[[Row; M]; LANES]> {
        if lanes_inside(self.dims.width, x) < LANES {
            return None;
        }
        let first = y as usize * self.dims.width as usize + x as usize;
        self.pixels
            .get(first..first + LANES)
            .and_then(|px| <&[[Row; M]; LANES]>::try_from(px).ok())
    }

    /// The 8 pixels from `(x, y)` as a layer-major span, for an edge span (where
    /// `whole_span` said no): the pixels inside gathered one by one, the others empty.
    fn edge_span_rows(&self, x: u32, y: u32) -> [[Row; LANES]; M] {
        let first = y as usize * self.dims.width as usize + x as usize;
        gather::<M>(self.flat(), M, 0, first, lanes_inside(self.dims.width, x), Row::EMPTY)
    }

    fn flat(&self) -> &[Row] {
        bytemuck::cast_slice(self.pixels)
    }
}

impl<'a, const M: usize, A: Arithmetic> Framebuffer for MlabFramebuffer<'a, M, A> {
    type Arith = A;
    type Band<'b>
        = MlabFramebuffer<'b, M, A>
    where
        Self: 'b;

    fn width(&self) -> u32 {
        self.dims.width
    }

    fn height(&self) -> u32 {
        self.dims.height
    }

    fn rows_per_pixel(&self) -> usize {
        M
    }

    fn clear(&mut self) {
        self.pixels.fill([Row::EMPTY; M]);
    }

    #[inline]
    fn insert_row(&mut self, x: u32, y: u32, row: Row) -> Result<(), FramebufferError> {
        let i = self.dims.index(x, y)?;
        if let Some(p) = self.pixels.get_mut(i) {
            mlab::insert_with::<A, M>(p, row);
        }
        Ok(())
    }

    /// Gathers the 8 pixels into a layer-major span, inserts in lanes, scatters back the
    /// lanes that are on.
    #[inline]
    fn insert_span(&mut self, x: u32, y: u32, rows: &[Row; LANES], mask: u8) -> Result<(), FramebufferError> {
        let first = self.dims.check_span(x, y, mask)?;
        if mask == 0 {
            return Ok(());
        }
        let valid = lanes_inside(self.dims.width, x);
        let flat: &mut [Row] = bytemuck::cast_slice_mut(self.pixels);
        let mut span = gather::<M>(flat, M, 0, first, valid, Row::EMPTY);
        lanes::mlab_insert_with::<A, M>(&mut span, rows, mask);
        scatter::<M>(flat, M, 0, first, mask, &span);
        Ok(())
    }

    fn resolve(&self, x: u32, y: u32) -> Result<Resolved, FramebufferError> {
        self.pixel(x, y).map(|p| resolve_rows(p))
    }

    #[inline]
    fn resolve_span(&self, span: u32, y: u32) -> Option<ResolvedLanes> {
        let x = span
            .checked_mul(LANES as u32)
            .filter(|&x| x < self.dims.width && y < self.dims.height)?;
        Some(match self.whole_span(x, y) {
            Some(px) => lanes::mlab_resolve_pixel_major(px),
            None => lanes::mlab_resolve(&self.edge_span_rows(x, y)),
        })
    }

    #[inline]
    fn resolve_span_rgba8(&self, span: u32, y: u32, background: Background) -> [[u8; 4]; LANES] {
        let Some(x) = span
            .checked_mul(LANES as u32)
            .filter(|&x| x < self.dims.width && y < self.dims.height)
        else {
            return [to_rgba8(Resolved::CLEAR.pixel(background)); LANES];
        };
        match self.whole_span(x, y) {
            Some(px) => lanes::mlab_resolve_pixel_major_rgba8(px, background),
            None => lanes::mlab_resolve_rgba8(&self.edge_span_rows(x, y), background),
        }
    }

    /// Line by line, the whole spans straight from the pixel slice (no per-span bounds
    /// check, the lanes resolve inlined), the partial last span as
    /// [`resolve_span_rgba8`](Framebuffer::resolve_span_rgba8).
    fn resolve_rgba8(&self, out: &mut [[u8; 4]], background: Background) -> Result<(), FramebufferError> {
        let (width, height) = (self.dims.width, self.dims.height);
        let mut lines = self.pixels.chunks_exact(width.max(1) as usize);
        write_lines(
            width,
            height,
            out,
            |_, spans| {
                let pixels = lines.next().unwrap_or(&[]);
                for (o, px) in spans.iter_mut().zip(pixels.as_chunks::<LANES>().0) {
                    *o = lanes::mlab_resolve_pixel_major_rgba8(px, background);
                }
            },
            |s, y| self.resolve_span_rgba8(s, y, background),
        )
    }

    fn as_rows(&self) -> &[Row] {
        self.flat()
    }

    fn reborrow(&mut self) -> MlabFramebuffer<'_, M, A> {
        MlabFramebuffer {
            pixels: self.pixels,
            dims: self.dims,
            arithmetic: PhantomData,
        }
    }

    fn split_lines(self, lines: u32) -> (Self, Self) {
        let lines = lines.min(self.dims.height);
        let (a, b) = self.pixels.split_at_mut(lines as usize * self.dims.width as usize);
        let band = |pixels, height| MlabFramebuffer {
            pixels,
            dims: Dims { height, ..self.dims },
            arithmetic: PhantomData,
        };
        (band(a, lines), band(b, self.dims.height - lines))
    }
}

/// A Hybrid Transparency framebuffer: per pixel `K` head rows then one tail slot
/// (`K + 1` row-sized slots, `8 * (K + 1)` bytes) over borrowed storage, pixel-major, in
/// the arithmetic `A` (which picks the tail layout: [`Tail`](crate::Tail) by default). Its
/// operations are those of [`Framebuffer`].
#[derive(Debug)]
pub struct HybridFramebuffer<'a, const K: usize, A: Arithmetic = Unbiased> {
    rows: &'a mut [Row],
    dims: Dims,
    arithmetic: PhantomData<A>,
}

impl<'a, const K: usize, A: Arithmetic> HybridFramebuffer<'a, K, A> {
    /// Rows of storage needed for `width x height` pixels (`width * height * (K + 1)`).
    pub fn rows_needed(width: u32, height: u32) -> Result<usize, FramebufferError> {
        Dims { width, height }.rows_needed(K + 1)
    }

    /// A view over `storage`, which must hold exactly `width * height * (K + 1)` rows.
    /// Contents are kept. **Storage filled with [`Row::EMPTY`] is not a cleared HT
    /// framebuffer**: the tail slots would hold an empty row's bytes, which are not an empty
    /// [`Tail`](crate::Tail). Use [`new_cleared`](Self::new_cleared) (or
    /// [`clear`](Framebuffer::clear)) to start a frame.
    pub fn new(storage: &'a mut [Row], width: u32, height: u32) -> Result<Self, FramebufferError> {
        let dims = Dims { width, height };
        dims.check_storage(K + 1, storage.len())?;
        Ok(HybridFramebuffer {
            rows: storage,
            dims,
            arithmetic: PhantomData,
        })
    }

    /// [`new`](Self::new), then [`clear`](Framebuffer::clear): the way to start a frame.
    pub fn new_cleared(storage: &'a mut [Row], width: u32, height: u32) -> Result<Self, FramebufferError> {
        let mut fb = Self::new(storage, width, height)?;
        fb.clear();
        Ok(fb)
    }

    fn split(pixel: &[Row]) -> ([Row; K], A::Tail) {
        let mut head = [Row::EMPTY; K];
        let mut tail = A::Tail::EMPTY;
        if let Some((t, h)) = pixel.split_last() {
            head.copy_from_slice(&h[..K.min(h.len())]);
            tail = A::Tail::from_bytes(t.to_bytes());
        }
        (head, tail)
    }

    fn pixel_slots(&self, x: u32, y: u32) -> Result<&[Row], FramebufferError> {
        let i = self.dims.index(x, y)?;
        self.rows
            .get(i * (K + 1)..(i + 1) * (K + 1))
            .ok_or(self.dims.out_of_bounds(x, y))
    }

    /// Head rows and tail of pixel `(x, y)`.
    pub fn pixel(&self, x: u32, y: u32) -> Result<([Row; K], A::Tail), FramebufferError> {
        self.pixel_slots(x, y).map(Self::split)
    }

    /// Head layers and tails of the 8 pixels from pixel index `first` (`valid` inside).
    #[inline(always)]
    fn gather_span(&self, first: usize, valid: usize) -> ([[Row; LANES]; K], [A::Tail; LANES]) {
        let empty = Row::from_bytes(A::Tail::EMPTY.to_bytes());
        // A whole span inside (the common case): a transpose with constant indices, no
        // fill first (`get` cannot fail there; it keeps the code free of panics).
        if valid >= LANES
            && let Some(px) = self.rows.get(first * (K + 1)..(first + LANES) * (K + 1))
        {
            let at = |lane: usize, slot: usize| px.get(lane * (K + 1) + slot).copied().unwrap_or(empty);
            let head = core::array::from_fn(|layer| core::array::from_fn(|lane| at(lane, layer)));
            let tails: [Row; LANES] = core::array::from_fn(|lane| at(lane, K));
            return (head, bytemuck::cast(tails));
        }
        let mut head = [[Row::EMPTY; LANES]; K];
        let mut tails = [empty; LANES];
        // One pass over the pixels' slots (contiguous): head rows, then the tail slot.
        if let Some(px) = self.rows.get(first * (K + 1)..(first + valid.min(LANES)) * (K + 1)) {
            for (lane, p) in px.chunks_exact(K + 1).enumerate() {
                if let (Some((t, h)), Some(tail)) = (p.split_last(), tails.get_mut(lane)) {
                    for (layer, row) in head.iter_mut().zip(h) {
                        layer[lane] = *row;
                    }
                    *tail = *t;
                }
            }
        }
        (head, bytemuck::cast(tails))
    }

    fn span_start(&self, span: u32, y: u32) -> Option<(usize, usize)> {
        let x = span
            .checked_mul(LANES as u32)
            .filter(|&x| x < self.dims.width && y < self.dims.height)?;
        Some((
            y as usize * self.dims.width as usize + x as usize,
            lanes_inside(self.dims.width, x),
        ))
    }
}

impl<'a, const K: usize, A: Arithmetic> Framebuffer for HybridFramebuffer<'a, K, A> {
    type Arith = A;
    type Band<'b>
        = HybridFramebuffer<'b, K, A>
    where
        Self: 'b;

    /// Per-pixel HT inserts are faster than span inserts here: see the trait's docs.
    const SPAN_INSERTS_PAY: bool = false;

    fn width(&self) -> u32 {
        self.dims.width
    }

    fn height(&self) -> u32 {
        self.dims.height
    }

    fn rows_per_pixel(&self) -> usize {
        K + 1
    }

    fn clear(&mut self) {
        for p in self.rows.chunks_exact_mut(K + 1) {
            if let Some((t, h)) = p.split_last_mut() {
                h.fill(Row::EMPTY);
                *t = Row::from_bytes(A::Tail::EMPTY.to_bytes());
            }
        }
    }

    #[inline]
    fn insert_row(&mut self, x: u32, y: u32, row: Row) -> Result<(), FramebufferError> {
        let i = self.dims.index(x, y)?;
        if let Some(p) = self.rows.get_mut(i * (K + 1)..(i + 1) * (K + 1))
            && let Some((t, h)) = p.split_last_mut()
            && let Ok(head) = <&mut [Row; K]>::try_from(h)
        {
            let mut tail = A::Tail::from_bytes(t.to_bytes());
            hybrid::insert(head, &mut tail, row);
            *t = Row::from_bytes(tail.to_bytes());
        }
        Ok(())
    }

    /// Gathers the 8 pixels' heads and tails, inserts in lanes, scatters back the lanes
    /// that are on.
    #[inline]
    fn insert_span(&mut self, x: u32, y: u32, rows: &[Row; LANES], mask: u8) -> Result<(), FramebufferError> {
        let first = self.dims.check_span(x, y, mask)?;
        if mask == 0 {
            return Ok(());
        }
        let (mut head, mut tails) = self.gather_span(first, lanes_inside(self.dims.width, x));
        lanes::hybrid_insert_parts(&mut head, &mut tails, rows, mask);
        scatter::<K>(self.rows, K + 1, 0, first, mask, &head);
        let tails: [Row; LANES] = bytemuck::cast(tails);
        scatter::<1>(self.rows, K + 1, K, first, mask, &[tails]);
        Ok(())
    }

    fn resolve(&self, x: u32, y: u32) -> Result<Resolved, FramebufferError> {
        self.pixel(x, y).map(|(h, t)| hybrid::resolve(&h, t))
    }

    #[inline]
    fn resolve_span(&self, span: u32, y: u32) -> Option<ResolvedLanes> {
        let (first, valid) = self.span_start(span, y)?;
        let (head, tails) = self.gather_span(first, valid);
        Some(lanes::hybrid_resolve_parts(&head, &tails))
    }

    #[inline(always)]
    fn resolve_span_rgba8(&self, span: u32, y: u32, background: Background) -> [[u8; 4]; LANES] {
        let Some((first, valid)) = self.span_start(span, y) else {
            return [to_rgba8(Resolved::CLEAR.pixel(background)); LANES];
        };
        let (head, tails) = self.gather_span(first, valid);
        lanes::hybrid_resolve_parts_rgba8(&head, &tails, background)
    }

    /// Line by line, each whole span gathered and resolved in place (no per-span bounds
    /// check), the partial last span as [`resolve_span_rgba8`](Framebuffer::resolve_span_rgba8).
    /// Without AVX2 and above `K = 4` the span by span default is kept: the inlined resolve
    /// took 11 % longer there (SSE2, `K = 8`: 304 against 273 us in `benches/batch.rs`).
    fn resolve_rgba8(&self, out: &mut [[u8; 4]], background: Background) -> Result<(), FramebufferError> {
        if K > 4 && !cfg!(target_feature = "avx2") {
            return write_spans(self.dims.width, self.dims.height, out, |s, y| {
                self.resolve_span_rgba8(s, y, background)
            });
        }
        let width = self.dims.width as usize;
        write_lines(
            self.dims.width,
            self.dims.height,
            out,
            |y, spans| {
                for (s, o) in spans.iter_mut().enumerate() {
                    let (head, tails) = self.gather_span(y * width + s * LANES, LANES);
                    *o = lanes::hybrid_resolve_parts_rgba8(&head, &tails, background);
                }
            },
            |s, y| self.resolve_span_rgba8(s, y, background),
        )
    }

    fn as_rows(&self) -> &[Row] {
        self.rows
    }

    fn reborrow(&mut self) -> HybridFramebuffer<'_, K, A> {
        HybridFramebuffer {
            rows: self.rows,
            dims: self.dims,
            arithmetic: PhantomData,
        }
    }

    fn split_lines(self, lines: u32) -> (Self, Self) {
        let lines = lines.min(self.dims.height);
        let (a, b) = self
            .rows
            .split_at_mut(lines as usize * self.dims.width as usize * (K + 1));
        let band = |rows, height| HybridFramebuffer {
            rows,
            dims: Dims { height, ..self.dims },
            arithmetic: PhantomData,
        };
        (band(a, lines), band(b, self.dims.height - lines))
    }
}

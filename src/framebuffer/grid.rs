//! [`Grid`]: one framebuffer type over caller-owned rows, generic over what a pixel holds
//! ([`Pixel`]: [`Mlab`](super::Mlab), [`Ht`](super::Ht)) and how pixels are laid out
//! ([`Arrangement`]: [`PixelMajor`], [`Spans`]). The arrangements own the index maths,
//! bounds, span rotation and line splits, written once for both kinds; the kinds' leaves
//! (`pixel.rs`) are the only code that knows `M`, `K` or the tail.

use core::fmt::Debug;
use core::marker::PhantomData;

use super::pixel::Pixel;
use super::{CLEAR_LANES, Dims, Framebuffer, FramebufferError, write_lines, write_spans};
use crate::lanes::{self, LANES, LANES_U32, ResolvedLanes};
use crate::mlab::row_hash;
use crate::resolve::{Background, Resolved, int, to_rgba16f};
use crate::row::Row;
use glam::Vec4;
use half::f16;

impl crate::sealed::Sealed for PixelMajor {}
impl crate::sealed::Sealed for Spans {}

/// Pixel-major storage: pixel `(x, y)` owns the rows
/// `[(y * width + x) * R, (y * width + x + 1) * R)`, `R` = [`Pixel::ROWS`] (an HT pixel's last slot holds its tail's bytes).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct PixelMajor;

/// 8-pixel spans, layer-major: slot `j` of pixel `(x, y)` is row
/// `((y * spans + x / 8) * R + j) * 8 + x % 8`, `spans = ceil(width / 8)`; for HT the `K`
/// head layers come first, then the 8 tails. Lanes past the right edge are padding (kept empty).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Spans;

/// How the pixels of a [`Grid`] are laid out: [`PixelMajor`] or [`Spans`] (sealed). The
/// hidden items are the storage layer's index maths.
// `Dims` is the crate's own: the trait is sealed, no other crate implements or calls it.
#[allow(private_interfaces)]
pub trait Arrangement: crate::sealed::Sealed + Copy + Debug + Default + Send + Sync + 'static {
    /// Whether pixels are stored in 8-pixel layer-major spans.
    const SPANS: bool;
    #[doc(hidden)]
    fn line_rows(d: Dims, rows: usize) -> Option<usize>;
    /// Storage index of slot `j` of pixel `(x, y)` (checked before), `n` slots per pixel.
    #[doc(hidden)]
    fn slot(d: Dims, n: usize, x: u32, y: u32, j: usize) -> usize;
    /// Which slot of its pixel storage index `i` holds, `n` slots per pixel.
    #[doc(hidden)]
    fn slot_of(i: usize, n: usize) -> usize;
    #[doc(hidden)]
    fn insert<P: Pixel>(rows: &mut [Row], d: Dims, x: u32, y: u32, row: Row, h: u32);
    #[doc(hidden)]
    fn insert_span<P: Pixel>(
        rows: &mut [Row],
        d: Dims,
        x: u32,
        y: u32,
        span: &[Row; LANES],
        hashes: &[u32; LANES],
        mask: u8,
    );
    /// The storage of span `span` of line `y` (1 to 8 consecutive pixels, or one stored
    /// span), if it exists.
    #[doc(hidden)]
    fn span_unit(rows: &[Row], d: Dims, rows_per_pixel: usize, span: u32, y: u32) -> Option<&[Row]>;
}

/// Unit `i` of `n` rows.
#[inline(always)]
fn unit(rows: &[Row], i: usize, n: usize) -> Option<&[Row]> {
    rows.get(i * n..(i + 1) * n)
}

/// Unit `i` of `n` rows, mutable.
#[inline(always)]
fn unit_mut(rows: &mut [Row], i: usize, n: usize) -> Option<&mut [Row]> {
    rows.get_mut(i * n..(i + 1) * n)
}

/// The lanes of a span insert, rotated so that lane `i` sits at `(i + shift) % 8`.
fn rotate<T: Copy>(rows: &[T; LANES], shift: usize) -> [T; LANES] {
    let mut r = *rows;
    r.rotate_right(shift);
    r
}

/// `out[i] = f(unit i of line)`, for the whole 8-pixel units of a line's rows.
#[inline(always)]
fn units<P: Pixel, T>(line: &[Row], out: &mut [[T; LANES]], f: impl Fn(&[Row]) -> [T; LANES]) {
    for (o, u) in out.iter_mut().zip(line.chunks_exact(LANES * P::ROWS)) {
        *o = f(u);
    }
}

#[allow(private_interfaces)]
impl Arrangement for PixelMajor {
    const SPANS: bool = false;

    fn line_rows(d: Dims, rows: usize) -> Option<usize> {
        (d.width as usize).checked_mul(rows)
    }

    fn slot(d: Dims, n: usize, x: u32, y: u32, j: usize) -> usize {
        d.index_unchecked(x, y) * n + j
    }

    fn slot_of(i: usize, n: usize) -> usize {
        i % n
    }

    #[inline(always)]
    fn insert<P: Pixel>(rows: &mut [Row], d: Dims, x: u32, y: u32, row: Row, h: u32) {
        if let Some(px) = unit_mut(rows, d.index_unchecked(x, y), P::ROWS) {
            P::pm_insert(px, row, h);
        }
    }

    #[inline(always)]
    fn insert_span<P: Pixel>(
        rows: &mut [Row],
        d: Dims,
        x: u32,
        y: u32,
        span: &[Row; LANES],
        hashes: &[u32; LANES],
        mask: u8,
    ) {
        let first = d.index_unchecked(x, y);
        let valid = d.lanes_inside(x);
        if let Some(px) = rows.get_mut(first * P::ROWS..(first + valid) * P::ROWS) {
            P::insert_unit::<Self>(px, span, hashes, mask);
        }
    }

    #[inline(always)]
    fn span_unit(rows: &[Row], d: Dims, n: usize, span: u32, y: u32) -> Option<&[Row]> {
        let x = span.checked_mul(LANES_U32).filter(|&x| x < d.width && y < d.height)?;
        let first = d.index_unchecked(x, y);
        rows.get(first * n..(first + d.lanes_inside(x)) * n)
    }
}

#[allow(private_interfaces)]
impl Arrangement for Spans {
    const SPANS: bool = true;

    fn line_rows(d: Dims, rows: usize) -> Option<usize> {
        d.spans.checked_mul(LANES)?.checked_mul(rows)
    }

    fn slot(d: Dims, n: usize, x: u32, y: u32, j: usize) -> usize {
        let (i, lane) = d.span_lane(x, y);
        (i * n + j) * LANES + lane
    }

    fn slot_of(i: usize, n: usize) -> usize {
        i / LANES % n
    }

    #[inline(always)]
    fn insert<P: Pixel>(rows: &mut [Row], d: Dims, x: u32, y: u32, row: Row, h: u32) {
        let (i, lane) = d.span_lane(x, y);
        if let Some(s) = unit_mut(rows, i, LANES * P::ROWS) {
            P::span_insert(s, lane, row, h);
        }
    }

    /// A span at `x` not a multiple of 8 touches two stored spans: lane `i` lands on lane
    /// `(i + x % 8) % 8`, of the first if `i + x % 8 < 8`, of the next one otherwise.
    #[inline(always)]
    #[expect(
        clippy::cast_possible_truncation,
        reason = "the two bytes of the mask shifted into 16 bits"
    )]
    fn insert_span<P: Pixel>(
        rows: &mut [Row],
        d: Dims,
        x: u32,
        y: u32,
        span: &[Row; LANES],
        hashes: &[u32; LANES],
        mask: u8,
    ) {
        let (i, shift) = d.span_lane(x, y);
        let wide = (mask as u16) << shift;
        let (m0, m1) = (wide as u8, (wide >> 8) as u8);
        let (span, hashes) = if shift == 0 {
            (*span, *hashes)
        } else {
            (rotate(span, shift), rotate(hashes, shift))
        };
        if m0 != 0
            && let Some(s) = unit_mut(rows, i, LANES * P::ROWS)
        {
            P::insert_unit::<Self>(s, &span, &hashes, m0);
        }
        if m1 != 0
            && let Some(s) = unit_mut(rows, i + 1, LANES * P::ROWS)
        {
            P::insert_unit::<Self>(s, &span, &hashes, m1);
        }
    }

    #[inline(always)]
    fn span_unit(rows: &[Row], d: Dims, n: usize, span: u32, y: u32) -> Option<&[Row]> {
        unit(rows, d.span_index(span, y)?, LANES * n)
    }
}

/// A framebuffer over caller-owned rows: `width x height` pixels of the kind `P` ([`Mlab`](super::Mlab) or
/// [`Ht`](super::Ht), with their size and arithmetic) in the arrangement `L` ([`PixelMajor`] or
/// [`Spans`]). Usually named by its aliases: [`MlabFramebuffer`](super::MlabFramebuffer),
/// [`HybridFramebuffer`](super::HybridFramebuffer), [`SpanFramebuffer`](super::SpanFramebuffer),
/// [`HybridSpanFramebuffer`](super::HybridSpanFramebuffer). Its operations are those of
/// [`Framebuffer`]; the storage layouts are specified in `docs/layout.md`.
///
/// ```
/// use mlab::{Framebuffer, HybridFramebuffer, HybridSpanFramebuffer, Row};
/// let mut a = vec![Row::EMPTY; HybridSpanFramebuffer::<3>::rows_needed(10, 2)?];
/// let mut spans = HybridSpanFramebuffer::<3>::new_cleared(&mut a, 10, 2)?;
/// spans.insert_row(9, 1, Row::new([10, 20, 30], 128, 2.0))?;
/// // The same pixels, pixel-major (to upload, or to read pixel by pixel).
/// let mut b = vec![Row::EMPTY; HybridFramebuffer::<3>::rows_needed(10, 2)?];
/// let mut pixels = HybridFramebuffer::<3>::new(&mut b, 10, 2)?;
/// pixels.copy_from(&spans)?;
/// assert_eq!(pixels.pixel(9, 1)?, spans.pixel(9, 1)?);
/// assert_eq!(pixels.pixel(9, 1)?.0[0], Row::new([10, 20, 30], 128, 2.0));
/// # Ok::<(), mlab::Error>(())
/// ```
#[derive(Debug)]
pub struct Grid<'a, P: Pixel, L: Arrangement> {
    rows: &'a mut [Row],
    dims: Dims,
    /// The id of pixel `(0, 0)`: 0, or the first line's in a band (`line * width`), so that a
    /// band hashes its fragments as the whole framebuffer does ([`Fragment::hash`](crate::Fragment::hash)).
    first: u32,
    kind: PhantomData<(P, L)>,
}

impl<'a, P: Pixel, L: Arrangement> Grid<'a, P, L> {
    /// Rows of storage for `width x height` pixels: `width * height * R` pixel-major,
    /// `ceil(width / 8) * 8 * height * R` in spans (`R` = [`Pixel::ROWS`]).
    pub fn rows_needed(width: u32, height: u32) -> Result<usize, FramebufferError> {
        let d = Dims::new(width, height);
        L::line_rows(d, P::ROWS)
            .and_then(|r| r.checked_mul(height as usize))
            .ok_or(FramebufferError::SizeOverflow)
    }

    /// A view over `storage`, which must hold exactly [`rows_needed`](Self::rows_needed)
    /// rows. The contents are kept (a previous frame, a GPU read-back). **Storage filled with
    /// [`Row::EMPTY`] is not a cleared HT framebuffer** (an empty row's bytes are not an empty
    /// tail): start a frame with [`new_cleared`](Self::new_cleared).
    pub fn new(storage: &'a mut [Row], width: u32, height: u32) -> Result<Self, FramebufferError> {
        let expected = Self::rows_needed(width, height)?;
        if storage.len() != expected {
            return Err(FramebufferError::StorageLength {
                expected,
                actual: storage.len(),
            });
        }
        Ok(Grid {
            rows: storage,
            dims: Dims::new(width, height),
            first: 0,
            kind: PhantomData,
        })
    }

    /// [`new`](Self::new), then [`clear`](Framebuffer::clear): the way to start a frame.
    pub fn new_cleared(storage: &'a mut [Row], width: u32, height: u32) -> Result<Self, FramebufferError> {
        let mut fb = Self::new(storage, width, height)?;
        fb.clear();
        Ok(fb)
    }

    /// This view with `first` as the id of its pixel `(0, 0)`
    /// ([`first_pixel`](Framebuffer::first_pixel)), so that it hashes its fragments as the
    /// band of a larger framebuffer that it is: `first = first_line * width` (wrapping) for
    /// lines `first_line..` of a whole framebuffer. For a band rebuilt from its rows alone,
    /// where the whole framebuffer is not at hand to split (a band passed across an FFI
    /// boundary, as the C API's `mlab_framebuffer_band`); [`bands_mut`](Framebuffer::bands_mut)
    /// and [`split_lines`](Framebuffer::split_lines) set it themselves. Only the dithers of
    /// [`Unbiased`](crate::Unbiased) depend on it.
    ///
    /// ```
    /// use mlab::glam::Vec3;
    /// use mlab::{Fragment, Framebuffer, Row, SpanFramebuffer};
    /// let (w, h) = (13, 4);
    /// let f = Fragment::straight(Vec3::ONE, 0.02, 5.0)?.with_key(9); // faint: dithered
    /// let mut whole = vec![Row::EMPTY; SpanFramebuffer::<2>::rows_needed(w, h)?];
    /// let mut fb = SpanFramebuffer::<2>::new_cleared(&mut whole, w, h)?;
    /// fb.insert(3, 2, &f)?;
    /// // Lines 2..4 as a band of their own rows: pixel (3, 0) of the band is (3, 2).
    /// let mut rows = vec![Row::EMPTY; SpanFramebuffer::<2>::rows_needed(w, 2)?];
    /// let mut band = SpanFramebuffer::<2>::new_cleared(&mut rows, w, 2)?.with_first_pixel(2 * w);
    /// assert_eq!(band.pixel_id(3, 0), fb.pixel_id(3, 2));
    /// band.insert(3, 0, &f)?;
    /// assert_eq!(band.as_rows(), &fb.as_rows()[fb.as_rows().len() / 2..]);
    /// # Ok::<(), mlab::Error>(())
    /// ```
    #[inline(always)]
    #[must_use]
    pub fn with_first_pixel(self, first: u32) -> Self {
        Grid { first, ..self }
    }

    /// The contents of pixel `(x, y)`: `[Row; M]` for MLAB, `([Row; K], tail)` for HT.
    pub fn pixel(&self, x: u32, y: u32) -> Result<P::Value, FramebufferError> {
        self.dims.check(x, y)?;
        Ok(self.get(x, y))
    }

    /// Overwrite every pixel with those of `other` (same kind and size, any arrangement):
    /// between pixel-major and spans, losslessly.
    pub fn copy_from<L2: Arrangement>(&mut self, other: &Grid<'_, P, L2>) -> Result<(), FramebufferError> {
        if (other.dims.width, other.dims.height) != (self.dims.width, self.dims.height) {
            return Err(FramebufferError::SizeMismatch);
        }
        for y in 0..self.dims.height {
            for x in 0..self.dims.width {
                let (d, rows) = (self.dims, &mut *self.rows);
                P::to_slots(other.get(x, y), |j, r| {
                    if let Some(slot) = rows.get_mut(L::slot(d, P::ROWS, x, y, j)) {
                        *slot = r;
                    }
                });
            }
        }
        Ok(())
    }

    /// Pixels whose HT tail has a field at its maximum (its sums no longer grow); 0 for MLAB.
    pub fn saturated_pixels(&self) -> usize {
        let d = self.dims;
        (0..d.height)
            .flat_map(|y| (0..d.width).map(move |x| (x, y)))
            .filter(|&(x, y)| P::saturated(&self.get(x, y)))
            .count()
    }
}

impl<P: Pixel, L: Arrangement> Grid<'_, P, L> {
    /// The contents of pixel `(x, y)` (checked before).
    fn get(&self, x: u32, y: u32) -> P::Value {
        let d = self.dims;
        P::from_slots(|j| {
            self.rows
                .get(L::slot(d, P::ROWS, x, y, j))
                .copied()
                .unwrap_or(Row::EMPTY)
        })
    }

    /// Span `span` of line `y` resolved, clear where it does not exist.
    fn lanes(&self, span: u32, y: u32) -> ResolvedLanes {
        self.resolve_span(span, y).unwrap_or(CLEAR_LANES)
    }

    /// Write a whole-frame resolve: whole spans by `whole` from their line's rows (no
    /// per-span index maths or bounds checks), partial last spans by `edge`.
    #[inline(always)]
    fn write<T: Copy>(
        &self,
        out: &mut [T],
        whole: impl Fn(&[Row], &mut [[T; LANES]]),
        edge: impl Fn(u32, u32) -> [T; LANES],
    ) -> Result<(), FramebufferError> {
        if !(L::SPANS || P::PIXEL_MAJOR_LINE_LOOP) {
            return write_spans(self.dims, out, edge);
        }
        let line_rows = L::line_rows(self.dims, P::ROWS).unwrap_or(0);
        write_lines(self.dims, out, self.rows, line_rows, whole, edge)
    }
}

impl<'a, P: Pixel, L: Arrangement> Framebuffer for Grid<'a, P, L> {
    type Arith = P::Arith;
    type Band<'b>
        = Grid<'b, P, L>
    where
        Self: 'b;

    const SPAN_INSERTS_PAY: bool = L::SPANS || P::PIXEL_MAJOR_SPAN_INSERTS_PAY;
    const MERGES: bool = P::MERGES;

    fn width(&self) -> u32 {
        self.dims.width
    }

    fn height(&self) -> u32 {
        self.dims.height
    }

    fn layers(&self) -> super::Layers {
        P::LAYERS
    }

    fn clear(&mut self) {
        for (i, r) in self.rows.iter_mut().enumerate() {
            *r = P::empty_slot(L::slot_of(i, P::ROWS));
        }
    }

    #[inline(always)]
    fn insert_row(&mut self, x: u32, y: u32, row: Row) -> Result<(), FramebufferError> {
        let h = if P::MERGES {
            row_hash(row, self.pixel_id(x, y))
        } else {
            0
        };
        self.insert_hashed(x, y, row, h)
    }

    #[inline(always)]
    fn insert_span(&mut self, x: u32, y: u32, rows: &[Row; LANES], mask: u8) -> Result<(), FramebufferError> {
        let hashes = if P::MERGES {
            lanes::row_hashes(rows, self.pixel_id(x, y))
        } else {
            [0; LANES]
        };
        self.insert_span_hashed(x, y, rows, &hashes, mask)
    }

    #[inline(always)]
    fn first_pixel(&self) -> u32 {
        self.first
    }

    #[inline(always)]
    fn insert_hashed(&mut self, x: u32, y: u32, row: Row, h: u32) -> Result<(), FramebufferError> {
        self.dims.check(x, y)?;
        L::insert::<P>(self.rows, self.dims, x, y, row, h);
        Ok(())
    }

    #[inline(always)]
    fn insert_span_hashed(
        &mut self,
        x: u32,
        y: u32,
        rows: &[Row; LANES],
        hashes: &[u32; LANES],
        mask: u8,
    ) -> Result<(), FramebufferError> {
        self.dims.check_span(x, y, mask)?;
        if mask != 0 {
            L::insert_span::<P>(self.rows, self.dims, x, y, rows, hashes, mask);
        }
        Ok(())
    }

    fn resolve(&self, x: u32, y: u32) -> Result<Resolved, FramebufferError> {
        self.pixel(x, y).map(|v| P::resolve(&v))
    }

    #[inline]
    fn resolve_span(&self, span: u32, y: u32) -> Option<ResolvedLanes> {
        L::span_unit(self.rows, self.dims, P::ROWS, span, y).map(P::resolve_unit::<L>)
    }

    #[inline]
    fn resolve_span_rgba8(&self, span: u32, y: u32, background: Background) -> [[u8; 4]; LANES] {
        match L::span_unit(self.rows, self.dims, P::ROWS, span, y) {
            Some(u) => P::resolve_unit_rgba8::<L>(u, int::background(background)),
            None => P::clear_rgba8(background),
        }
    }

    fn resolve_into(&self, out: &mut [Vec4], bg: Background) -> Result<(), FramebufferError> {
        let whole =
            |line: &[Row], o: &mut [[Vec4; LANES]]| units::<P, _>(line, o, |u| P::resolve_unit::<L>(u).pixels(bg));
        self.write(out, whole, |s, y| self.lanes(s, y).pixels(bg))
    }

    fn resolve_rgba8(&self, out: &mut [[u8; 4]], bg: Background) -> Result<(), FramebufferError> {
        let ibg = int::background(bg);
        let whole = |line: &[Row], o: &mut [[[u8; 4]; LANES]]| P::resolve_line_rgba8::<L>(line, o, ibg);
        self.write(out, whole, |s, y| self.resolve_span_rgba8(s, y, bg))
    }

    fn resolve_rgba16f(&self, out: &mut [[f16; 4]], bg: Background) -> Result<(), FramebufferError> {
        // Large stored spans convert through a call of their own: inlined into their
        // whole-span loop, the 32 conversions ran 6-7 % more instructions (HT K = 4, MLAB
        // M = 8 spans; smaller ones and pixel-major lose with the call; callgrind x86-64-v3).
        let px = |r: ResolvedLanes| {
            if L::SPANS && P::ROWS >= 5 {
                rgba16f_lanes(&r, bg)
            } else {
                r.pixels(bg).map(to_rgba16f)
            }
        };
        let whole = |line: &[Row], o: &mut [[[f16; 4]; LANES]]| units::<P, _>(line, o, |u| px(P::resolve_unit::<L>(u)));
        self.write(out, whole, |s, y| px(self.lanes(s, y)))
    }

    fn as_rows(&self) -> &[Row] {
        self.rows
    }

    fn reborrow(&mut self) -> Grid<'_, P, L> {
        Grid {
            rows: self.rows,
            dims: self.dims,
            first: self.first,
            kind: PhantomData,
        }
    }

    fn split_lines(self, lines: u32) -> (Self, Self) {
        let lines = lines.min(self.dims.height);
        let line_rows = L::line_rows(self.dims, P::ROWS).unwrap_or(0);
        let at = (lines as usize * line_rows).min(self.rows.len());
        let (a, b) = self.rows.split_at_mut(at);
        let band = |rows, height, first| Grid {
            rows,
            dims: Dims { height, ..self.dims },
            first,
            kind: PhantomData,
        };
        let second = self.first.wrapping_add(lines.wrapping_mul(self.dims.width));
        (band(a, lines, self.first), band(b, self.dims.height - lines, second))
    }
}

/// The 8 pixels of a resolved span as RGBA16F, not inlined (see `Grid::resolve_rgba16f`).
#[inline(never)]
fn rgba16f_lanes(r: &ResolvedLanes, bg: Background) -> [[f16; 4]; LANES] {
    r.pixels(bg).map(to_rgba16f)
}

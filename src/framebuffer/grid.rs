//! [`Grid`]: one framebuffer type over caller-owned rows, generic over what a pixel holds
//! ([`Pixel`]: [`Mlab`](super::Mlab), [`Ht`](super::Ht)) and how pixels are laid out
//! ([`Arrangement`]: [`PixelMajor`](super::PixelMajor), [`Spans`](super::Spans)): its
//! constructors, pixel reads, copies and the [`Framebuffer`] impl, each written once. The
//! geometry and checks are [`Dims`]'s, the layouts the arrangements', the per-kind leaves
//! the kinds' (`pixel.rs`), the formats [`Output`]'s.

use core::marker::PhantomData;

use super::arrangement::{Arrangement, InsertUnit, SpanRows};
use super::dims::{Dims, SpanAt};
use super::output::Output;
use super::pixel::Pixel;
use super::write::write_lines;
use super::{Framebuffer, FramebufferError};
use crate::lanes::{self, LANES, ResolvedLanes};
use crate::mlab::row_hash;
use crate::resolve::{Background, Resolved};
use crate::row::Row;

/// A framebuffer over caller-owned rows: `width x height` pixels of the kind `P` ([`Mlab`](super::Mlab) or
/// [`Ht`](super::Ht), with their size and arithmetic) in the arrangement `L` ([`PixelMajor`](super::PixelMajor) or
/// [`Spans`](super::Spans)). Usually named by its aliases: [`MlabFramebuffer`](super::MlabFramebuffer),
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
        d.rows_needed(L::line_rows(d, P::ROWS))
    }

    /// A view over `storage`, which must hold exactly [`rows_needed`](Self::rows_needed)
    /// rows. The contents are kept (a previous frame, a GPU read-back). **Storage filled with
    /// [`Row::EMPTY`] is not a cleared HT framebuffer** (an empty row's bytes are not an empty
    /// tail): start a frame with [`new_cleared`](Self::new_cleared).
    pub fn new(storage: &'a mut [Row], width: u32, height: u32) -> Result<Self, FramebufferError> {
        Dims::check_storage(Self::rows_needed(width, height)?, storage.len())?;
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
    /// between pixel-major and spans, losslessly. The whole storage is written: padding
    /// lanes of span storage as [`clear`](Framebuffer::clear) writes them, so that the rows
    /// are those of a cleared framebuffer into which the pixels were inserted, whatever the
    /// storage held before.
    pub fn copy_from<L2: Arrangement>(&mut self, other: &Grid<'_, P, L2>) -> Result<(), FramebufferError> {
        self.dims.check_same(other.dims)?;
        self.copy_pixels(|x, y| other.get(x, y));
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

    /// Clear (the padding too), then write every pixel `(x, y)` as `value(x, y)`.
    fn copy_pixels(&mut self, value: impl Fn(u32, u32) -> P::Value) {
        self.clear();
        let d = self.dims;
        for y in 0..d.height {
            for x in 0..d.width {
                let rows = &mut *self.rows;
                P::to_slots(value(x, y), |j, r| {
                    if let Some(slot) = rows.get_mut(L::slot(d, P::ROWS, x, y, j)) {
                        *slot = r;
                    }
                });
            }
        }
    }

    /// [`copy_from`](Grid::copy_from) of a grid of the same kind in the arrangement `L2`
    /// given by its size and rows.
    pub(crate) fn copy_from_rows<L2: Arrangement>(
        &mut self,
        width: u32,
        height: u32,
        src: &[Row],
    ) -> Result<(), FramebufferError> {
        let d = Dims::new(width, height);
        self.dims.check_same(d)?;
        self.copy_pixels(|x, y| {
            P::from_slots(|j| src.get(L2::slot(d, P::ROWS, x, y, j)).copied().unwrap_or(Row::EMPTY))
        });
        Ok(())
    }

    /// Span `span` of line `y` in the format `O` (`b`: `bg` prepared), empty pixels where it
    /// does not exist.
    #[inline(always)]
    fn span_as<O: Output>(&self, span: u32, y: u32, bg: Background, b: O::Bg) -> [O; LANES] {
        match L::span_unit(self.rows, self.dims, P::ROWS, span, y) {
            Some(u) => O::unit::<P, L>(u, b),
            None => O::clear::<P>(bg),
        }
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
        P::insert_pixel::<L>(self.rows, self.dims, x, y, row, h);
        Ok(())
    }

    #[inline(always)]
    fn insert_span_rows(&mut self, x: u32, y: u32, span: SpanRows<'_>) -> Result<(), FramebufferError> {
        self.dims.check_span(x, y, span.mask)?;
        if span.mask != 0 {
            L::insert_span::<KindInsert<P, L>>(self.rows, self.dims, P::ROWS, self.dims.span_at(x, y), span);
        }
        Ok(())
    }

    #[inline(always)]
    fn insert_span_at(&mut self, at: SpanAt, span: SpanRows<'_>) -> Result<(), FramebufferError> {
        L::insert_aligned::<KindInsert<P, L>>(self.rows, self.dims, P::ROWS, at, span);
        Ok(())
    }

    fn resolve(&self, x: u32, y: u32) -> Result<Resolved, FramebufferError> {
        self.pixel(x, y).map(|v| P::resolve(&v))
    }

    #[inline]
    fn resolve_span(&self, span: u32, y: u32) -> Option<ResolvedLanes> {
        L::span_unit(self.rows, self.dims, P::ROWS, span, y).map(P::resolve_f32::<L>)
    }

    #[inline]
    fn resolve_span_rgba8(&self, span: u32, y: u32, background: Background) -> [[u8; 4]; LANES] {
        self.span_as::<[u8; 4]>(span, y, background, <[u8; 4]>::background(background))
    }

    /// Whole spans from their line's rows (no per-span index maths or bounds checks), the
    /// partial last spans through `span_as`.
    fn resolve_as<O: Output>(&self, out: &mut [O], bg: Background) -> Result<(), FramebufferError> {
        let b = O::background(bg);
        let edge = |s, y| self.span_as::<O>(s, y, bg, b);
        let line_rows = L::line_rows(self.dims, P::ROWS).unwrap_or(0);
        let whole = |line: &[Row], o: &mut [[O; LANES]]| O::line::<P, L>(line, o, b);
        write_lines(self.dims, out, self.rows, line_rows, whole, edge)
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

/// The kind's span insert on one unit of storage in the arrangement `L`.
struct KindInsert<P, L>(PhantomData<(P, L)>);

impl<P: Pixel, L: Arrangement> InsertUnit for KindInsert<P, L> {
    #[inline(always)]
    fn insert(unit: &mut [Row], span: SpanRows<'_>) {
        P::insert_span::<L>(unit, span);
    }
}

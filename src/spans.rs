//! Framebuffers in the lanes' arrangement: 8-pixel spans, layer-major.
//!
//! Each line of `width` pixels is cut into `ceil(width / 8)` spans of 8 pixels. A span of an
//! MLAB framebuffer is `M` layers of 8 rows (`[[Row; 8]; M]`, layer `j` of the 8 pixels is
//! 64 contiguous bytes); a span of an HT framebuffer is `K` head layers and then the 8 tails
//! (in 8 row-sized slots). Spans follow each other along the line, lines top to bottom:
//!
//! ```text
//! row index of (x, y, layer j) = ((y * spans_per_line + x / 8) * R + j) * 8 + x % 8
//! ```
//!
//! with `R = M` (MLAB) or `K + 1` (HT). Lanes past the right edge (when `width % 8 != 0`) are
//! padding: kept empty by [`clear`](SpanFramebuffer::clear), never written by an insert.
//! In this arrangement the lane kernels load and store whole registers; `docs/performance.md`
//! measures it against the pixel-major [`MlabFramebuffer`](crate::MlabFramebuffer) (which
//! needs a transpose around every span insert). [`SpanFramebuffer::to_pixel_major`] and
//! [`SpanFramebuffer::from_pixel_major`] convert losslessly between the two.
//!
//! Span operations take the pixel `(x, y)` of lane 0 and a mask; lane `i` is the pixel
//! `(x + i, y)`. `x` need not be a multiple of 8 (the span is then split across two stored
//! spans), and a lane whose pixel is outside the framebuffer must be off in the mask
//! (otherwise [`FramebufferError::OutOfBounds`] is returned and nothing changes).
//!
//! ```
//! use mlab::lanes::FragmentLanes;
//! use mlab::{Background, Framebuffer, Row, SpanFramebuffer};
//! let (w, h) = (13, 2); // not a multiple of 8: two spans per line, the second partial
//! let mut storage = vec![Row::EMPTY; SpanFramebuffer::<4>::rows_needed(w, h)?];
//! let mut fb = SpanFramebuffer::<4>::new_cleared(&mut storage, w, h)?;
//! let frags = FragmentLanes { color: [[0.4; 8], [0.0; 8], [0.0; 8]], alpha: [0.6; 8], depth: [1.0; 8] };
//! // Pixels 9..13 of line 1: the partial span at the right edge (lanes 0..4 on).
//! let invalid = fb.insert_span_fragments(9, 1, &frags, 0b0000_1111)?;
//! assert_eq!(invalid, 0);
//! assert!(fb.insert_span_fragments(9, 1, &frags, 0b0001_1111).is_err()); // lane 4 is x = 13
//! let mut out = vec![[0u8; 4]; (w * h) as usize];
//! fb.resolve_rgba8(&mut out, Background::Opaque(mlab::glam::Vec3::ZERO))?;
//! assert_eq!(out[13 + 9], [102, 0, 0, 255]);
//! assert_eq!(out[13 + 8], [0, 0, 0, 255]);
//! # Ok::<(), mlab::Error>(())
//! ```
//!
//! Bands for threads ([`Framebuffer::bands_mut`]):
//!
//! ```
//! use mlab::{Framebuffer, Row, SpanFramebuffer};
//! let mut storage = vec![Row::EMPTY; SpanFramebuffer::<2>::rows_needed(20, 10)?];
//! let mut fb = SpanFramebuffer::<2>::new_cleared(&mut storage, 20, 10)?;
//! let bands: Vec<_> = fb.bands_mut(4).collect();
//! assert_eq!(bands.iter().map(|b| b.height()).collect::<Vec<_>>(), [4, 4, 2]);
//! std::thread::scope(|s| {
//!     for mut band in bands {
//!         s.spawn(move || band.insert_row(19, 0, Row::new([9, 9, 9], 0, 1.0)));
//!     }
//! });
//! assert_eq!(fb.pixel(19, 8)?[0], Row::new([9, 9, 9], 0, 1.0));
//! # Ok::<(), mlab::Error>(())
//! ```

use core::marker::PhantomData;

use crate::arith::{Arithmetic, Unbiased};
use crate::framebuffer::{Dims, Framebuffer, FramebufferError};
use crate::hybrid::TailFormat;
use crate::lanes::{self, LANES, MlabSpan, ResolvedLanes};
use crate::resolve::{Background, Resolved, to_rgba8};
use crate::row::Row;

/// Geometry shared by both span framebuffers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct SpanDims {
    width: u32,
    height: u32,
    /// Spans per line: `ceil(width / 8)`.
    spans: usize,
}

impl SpanDims {
    fn new(width: u32, height: u32) -> SpanDims {
        SpanDims {
            width,
            height,
            spans: (width as usize).div_ceil(LANES),
        }
    }

    /// Rows of storage for `rows_per_pixel` rows per pixel, or an overflow error.
    fn rows_needed(self, rows_per_pixel: usize) -> Result<usize, FramebufferError> {
        self.spans
            .checked_mul(self.height as usize)
            .and_then(|s| s.checked_mul(LANES))
            .and_then(|s| s.checked_mul(rows_per_pixel))
            .ok_or(FramebufferError::SizeOverflow)
    }

    /// The pixel dimensions, for the checks shared with the pixel-major views.
    fn plain(self) -> Dims {
        Dims {
            width: self.width,
            height: self.height,
        }
    }

    fn out_of_bounds(self, x: u32, y: u32) -> FramebufferError {
        self.plain().out_of_bounds(x, y)
    }

    /// Span index and lane of pixel `(x, y)`.
    fn locate(self, x: u32, y: u32) -> Result<(usize, usize), FramebufferError> {
        if x >= self.width || y >= self.height {
            return Err(self.out_of_bounds(x, y));
        }
        Ok((y as usize * self.spans + x as usize / LANES, x as usize % LANES))
    }

    /// The one or two stored spans touched by a span operation at `(x, y)` with `mask`:
    /// `(span, shift, mask_in_first, mask_in_second)`. Lane `i` lands on lane `(i + shift) % 8`,
    /// of the first span if `i + shift < 8`, of the next one otherwise.
    #[inline(always)]
    fn split(self, x: u32, y: u32, mask: u8) -> Result<(usize, usize, u8, u8), FramebufferError> {
        self.plain().check_span(x, y, mask)?;
        if mask == 0 {
            return Ok((0, 0, 0, 0));
        }
        let shift = x as usize % LANES;
        let span = y as usize * self.spans + x as usize / LANES;
        let wide = (mask as u16) << shift;
        Ok((span, shift, wide as u8, (wide >> 8) as u8))
    }

    /// Stored span index of span `span` of line `y`, if both are inside.
    fn index(self, span: u32, y: u32) -> Option<usize> {
        ((span as usize) < self.spans && y < self.height).then(|| y as usize * self.spans + span as usize)
    }
}

/// Run `f` on the rows of one lane of `N` layers (one pixel of a span), gathered into an
/// array and scattered back: a pixel insert in scalar code on span storage.
#[inline(always)]
fn with_lane<const N: usize>(layers: &mut [[Row; LANES]; N], lane: usize, f: impl FnOnce(&mut [Row; N])) {
    let mut px: [Row; N] = core::array::from_fn(|j| layers[j].get(lane).copied().unwrap_or(Row::EMPTY));
    f(&mut px);
    for (layer, r) in layers.iter_mut().zip(px) {
        if let Some(slot) = layer.get_mut(lane) {
            *slot = r;
        }
    }
}

/// The lanes of a span insert, rotated so that lane `i` sits at `(i + shift) % 8`.
fn rotate(rows: &[Row; LANES], shift: usize) -> [Row; LANES] {
    let mut r = *rows;
    r.rotate_right(shift);
    r
}

/// An MLAB framebuffer in 8-pixel layer-major spans over borrowed storage (see the
/// [module docs](self) for the arrangement), in the arithmetic `A` ([`Unbiased`] by
/// default). Its operations are those of [`Framebuffer`].
#[derive(Debug)]
pub struct SpanFramebuffer<'a, const M: usize, A: Arithmetic = Unbiased> {
    spans: &'a mut [MlabSpan<M>],
    dims: SpanDims,
    arithmetic: PhantomData<A>,
}

impl<'a, const M: usize, A: Arithmetic> SpanFramebuffer<'a, M, A> {
    /// Rows of storage for `width x height` pixels: `ceil(width / 8) * 8 * height * M`.
    pub fn rows_needed(width: u32, height: u32) -> Result<usize, FramebufferError> {
        SpanDims::new(width, height).rows_needed(M)
    }

    /// A view over `storage` ([`rows_needed`](Self::rows_needed) rows exactly). The contents
    /// are kept (rows from a previous frame or a GPU buffer); use
    /// [`new_cleared`](Self::new_cleared) to start a frame.
    pub fn new(storage: &'a mut [Row], width: u32, height: u32) -> Result<Self, FramebufferError> {
        let () = crate::mlab::AtLeastOne::<M>::OK;
        let dims = SpanDims::new(width, height);
        let expected = dims.rows_needed(M)?;
        if storage.len() != expected {
            return Err(FramebufferError::StorageLength {
                expected,
                actual: storage.len(),
            });
        }
        let spans = bytemuck::try_cast_slice_mut(storage).map_err(|_| FramebufferError::StorageLength {
            expected,
            actual: expected,
        })?;
        Ok(SpanFramebuffer {
            spans,
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

    /// The blending array of pixel `(x, y)`.
    pub fn pixel(&self, x: u32, y: u32) -> Result<[Row; M], FramebufferError> {
        let (span, lane) = self.dims.locate(x, y)?;
        let s = self.spans.get(span).ok_or(self.dims.out_of_bounds(x, y))?;
        Ok(core::array::from_fn(|j| s[j][lane]))
    }

    /// Copy into the pixel-major arrangement of [`MlabFramebuffer`](crate::MlabFramebuffer)
    /// (`width * height * M` rows); padding lanes are dropped.
    pub fn to_pixel_major(&self, out: &mut [Row]) -> Result<(), FramebufferError> {
        let d = self.dims;
        let out: &mut [[Row; M]] = pixel_major_slice(out, d, M)?;
        crate::framebuffer::write_spans(d.width, d.height, out, |s, y| {
            d.index(s, y)
                .and_then(|i| self.spans.get(i))
                .map_or([[Row::EMPTY; M]; LANES], lanes::to_pixel_major)
        })
    }

    /// Overwrite from the pixel-major arrangement (`width * height * M` rows); padding lanes
    /// become empty.
    pub fn from_pixel_major(&mut self, pixels: &[Row]) -> Result<(), FramebufferError> {
        let d = self.dims;
        let expected = (d.width as usize) * (d.height as usize) * M;
        let pixels: &[[Row; M]] = bytemuck::try_cast_slice(pixels)
            .ok()
            .filter(|p: &&[[Row; M]]| p.len() * M == expected)
            .ok_or(FramebufferError::StorageLength {
                expected,
                actual: pixels.len(),
            })?;
        for (i, span) in self.spans.iter_mut().enumerate() {
            let (y, sx) = (i / d.spans, (i % d.spans) * LANES);
            let mut px = [[Row::EMPTY; M]; LANES];
            for (lane, p) in px.iter_mut().enumerate() {
                if sx + lane < d.width as usize {
                    *p = pixels[y * d.width as usize + sx + lane];
                }
            }
            *span = lanes::from_pixel_major(&px);
        }
        Ok(())
    }
}

impl<'a, const M: usize, A: Arithmetic> Framebuffer for SpanFramebuffer<'a, M, A> {
    type Arith = A;
    type Band<'b>
        = SpanFramebuffer<'b, M, A>
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

    /// Every row empty (padding lanes included).
    fn clear(&mut self) {
        self.spans.fill([[Row::EMPTY; LANES]; M]);
    }

    /// With AVX, a span insert of one lane; without, the pixel's rows (one per layer of its
    /// span) gathered, Listing 1 in scalar code, scattered back. Callgrind, `benches/batch.rs`
    /// mesh, M = 4, instructions per fragment: SSE2 606 (one lane) against 241 (scalar);
    /// x86-64-v3 198 against 231. The same rows either way.
    fn insert_row(&mut self, x: u32, y: u32, row: Row) -> Result<(), FramebufferError> {
        let (i, lane) = self.dims.locate(x, y)?;
        if cfg!(target_feature = "avx") {
            return self.insert_span(x - lane as u32, y, &[row; LANES], 1 << lane);
        }
        if let Some(s) = self.spans.get_mut(i) {
            with_lane(s, lane, |px| crate::mlab::insert_with::<A, M>(px, row));
        }
        Ok(())
    }

    #[inline]
    fn insert_span(&mut self, x: u32, y: u32, rows: &[Row; LANES], mask: u8) -> Result<(), FramebufferError> {
        let (span, shift, m0, m1) = self.dims.split(x, y, mask)?;
        let rows = if shift == 0 { *rows } else { rotate(rows, shift) };
        if m0 != 0
            && let Some(s) = self.spans.get_mut(span)
        {
            lanes::mlab_insert_with::<A, M>(s, &rows, m0);
        }
        if m1 != 0
            && let Some(s) = self.spans.get_mut(span + 1)
        {
            lanes::mlab_insert_with::<A, M>(s, &rows, m1);
        }
        Ok(())
    }

    fn resolve(&self, x: u32, y: u32) -> Result<Resolved, FramebufferError> {
        self.pixel(x, y).map(|p| crate::resolve_rows(&p))
    }

    #[inline]
    fn resolve_span(&self, span: u32, y: u32) -> Option<ResolvedLanes> {
        self.dims
            .index(span, y)
            .and_then(|i| self.spans.get(i))
            .map(lanes::mlab_resolve)
    }

    #[inline]
    fn resolve_span_rgba8(&self, span: u32, y: u32, background: Background) -> [[u8; 4]; LANES] {
        match self.dims.index(span, y).and_then(|i| self.spans.get(i)) {
            Some(s) => lanes::mlab_resolve_rgba8(s, background),
            None => [to_rgba8(Resolved::CLEAR.pixel(background)); LANES],
        }
    }

    fn as_rows(&self) -> &[Row] {
        bytemuck::cast_slice(self.spans)
    }

    fn reborrow(&mut self) -> SpanFramebuffer<'_, M, A> {
        SpanFramebuffer {
            spans: self.spans,
            dims: self.dims,
            arithmetic: PhantomData,
        }
    }

    fn split_lines(self, lines: u32) -> (Self, Self) {
        let lines = lines.min(self.dims.height);
        let (a, b) = self.spans.split_at_mut(lines as usize * self.dims.spans);
        let band = |spans, height| SpanFramebuffer {
            spans,
            dims: SpanDims { height, ..self.dims },
            arithmetic: PhantomData,
        };
        (band(a, lines), band(b, self.dims.height - lines))
    }
}

/// `out` as `width * height` pixels of `r` rows.
fn pixel_major_slice<const M: usize>(
    out: &mut [Row],
    d: SpanDims,
    r: usize,
) -> Result<&mut [[Row; M]], FramebufferError> {
    let expected = (d.width as usize) * (d.height as usize) * r;
    let actual = out.len();
    if actual != expected {
        return Err(FramebufferError::StorageLength { expected, actual });
    }
    bytemuck::try_cast_slice_mut(out).map_err(|_| FramebufferError::StorageLength { expected, actual })
}

/// Head layers and tails of one stored HT span.
type SpanParts<'s, const K: usize, T> = (&'s [[Row; LANES]; K], &'s [T; LANES]);
/// Head layers and tails of one stored HT span, mutable.
type SpanPartsMut<'s, const K: usize, T> = (&'s mut [[Row; LANES]; K], &'s mut [T; LANES]);

/// A Hybrid Transparency framebuffer in 8-pixel spans: per span, `K` head layers of 8 rows,
/// then the 8 tails in 8 row-sized slots (see the [module docs](self)). Its operations are
/// those of [`Framebuffer`].
#[derive(Debug)]
pub struct HybridSpanFramebuffer<'a, const K: usize, A: Arithmetic = Unbiased> {
    rows: &'a mut [Row],
    dims: SpanDims,
    arithmetic: PhantomData<A>,
}

impl<'a, const K: usize, A: Arithmetic> HybridSpanFramebuffer<'a, K, A> {
    const SPAN_ROWS: usize = (K + 1) * LANES;

    /// Rows of storage: `ceil(width / 8) * 8 * height * (K + 1)`.
    pub fn rows_needed(width: u32, height: u32) -> Result<usize, FramebufferError> {
        SpanDims::new(width, height).rows_needed(K + 1)
    }

    /// A view over `storage` (exactly [`rows_needed`](Self::rows_needed) rows); contents
    /// are kept. **Storage filled with [`Row::EMPTY`] is not a cleared HT framebuffer** (an
    /// empty row's bytes are not an empty tail): use [`new_cleared`](Self::new_cleared).
    pub fn new(storage: &'a mut [Row], width: u32, height: u32) -> Result<Self, FramebufferError> {
        let dims = SpanDims::new(width, height);
        let expected = dims.rows_needed(K + 1)?;
        if storage.len() != expected {
            return Err(FramebufferError::StorageLength {
                expected,
                actual: storage.len(),
            });
        }
        Ok(HybridSpanFramebuffer {
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

    /// Head layers and tails of stored span `i`.
    fn parts_mut(&mut self, i: usize) -> Option<SpanPartsMut<'_, K, A::Tail>> {
        let span = self.rows.get_mut(i * Self::SPAN_ROWS..(i + 1) * Self::SPAN_ROWS)?;
        let (head, tails) = span.split_at_mut(K * LANES);
        let head: &mut [[Row; LANES]] = bytemuck::try_cast_slice_mut(head).ok()?;
        let tails: &mut [Row; LANES] = tails.try_into().ok()?;
        Some((head.try_into().ok()?, bytemuck::cast_mut(tails)))
    }

    fn parts(span: &[Row]) -> Option<SpanParts<'_, K, A::Tail>> {
        let (head, tails) = span.split_at_checked(K * LANES)?;
        let head: &[[Row; LANES]] = bytemuck::try_cast_slice(head).ok()?;
        let tails: &[Row; LANES] = tails.try_into().ok()?;
        Some((head.try_into().ok()?, bytemuck::cast_ref(tails)))
    }

    /// Head rows and tail of pixel `(x, y)`.
    pub fn pixel(&self, x: u32, y: u32) -> Result<([Row; K], A::Tail), FramebufferError> {
        let (span, lane) = self.dims.locate(x, y)?;
        let (head, tails) = self.span(span).ok_or(self.dims.out_of_bounds(x, y))?;
        Ok((core::array::from_fn(|j| head[j][lane]), tails[lane]))
    }

    fn span(&self, i: usize) -> Option<SpanParts<'_, K, A::Tail>> {
        self.rows
            .get(i * Self::SPAN_ROWS..(i + 1) * Self::SPAN_ROWS)
            .and_then(Self::parts)
    }
}

impl<'a, const K: usize, A: Arithmetic> Framebuffer for HybridSpanFramebuffer<'a, K, A> {
    type Arith = A;
    type Band<'b>
        = HybridSpanFramebuffer<'b, K, A>
    where
        Self: 'b;

    fn width(&self) -> u32 {
        self.dims.width
    }

    fn height(&self) -> u32 {
        self.dims.height
    }

    fn rows_per_pixel(&self) -> usize {
        K + 1
    }

    /// Empty head rows and empty tails everywhere.
    fn clear(&mut self) {
        let empty_tail = Row::from_bytes(A::Tail::EMPTY.to_bytes());
        for span in self.rows.chunks_exact_mut(Self::SPAN_ROWS) {
            let (head, tails) = span.split_at_mut(K * LANES);
            head.fill(Row::EMPTY);
            tails.fill(empty_tail);
        }
    }

    /// The pixel's head rows and tail gathered, Listing 2 in scalar code, scattered back:
    /// one pixel does not pay for eight lanes (callgrind, `benches/batch.rs` mesh, K = 3,
    /// instructions per fragment: SSE2 548 with a one-lane span insert against 196,
    /// x86-64-v3 259 against 186).
    fn insert_row(&mut self, x: u32, y: u32, row: Row) -> Result<(), FramebufferError> {
        let (i, lane) = self.dims.locate(x, y)?;
        if let Some((head, tails)) = self.parts_mut(i)
            && let Some(tail) = tails.get_mut(lane)
        {
            with_lane(head, lane, |px| crate::hybrid::insert(px, tail, row));
        }
        Ok(())
    }

    #[inline]
    fn insert_span(&mut self, x: u32, y: u32, rows: &[Row; LANES], mask: u8) -> Result<(), FramebufferError> {
        let (span, shift, m0, m1) = self.dims.split(x, y, mask)?;
        let rows = if shift == 0 { *rows } else { rotate(rows, shift) };
        for (i, m) in [(span, m0), (span + 1, m1)] {
            if m != 0
                && let Some((head, tails)) = self.parts_mut(i)
            {
                lanes::hybrid_insert_parts(head, tails, &rows, m);
            }
        }
        Ok(())
    }

    fn resolve(&self, x: u32, y: u32) -> Result<Resolved, FramebufferError> {
        self.pixel(x, y).map(|(h, t)| crate::hybrid::resolve(&h, t))
    }

    #[inline]
    fn resolve_span(&self, span: u32, y: u32) -> Option<ResolvedLanes> {
        let (h, t) = self.dims.index(span, y).and_then(|i| self.span(i))?;
        Some(lanes::hybrid_resolve_parts(h, t))
    }

    #[inline]
    fn resolve_span_rgba8(&self, span: u32, y: u32, background: Background) -> [[u8; 4]; LANES] {
        match self.dims.index(span, y).and_then(|i| self.span(i)) {
            Some((h, t)) => lanes::hybrid_resolve_parts_rgba8(h, t, background),
            None => [to_rgba8(Resolved::CLEAR.pixel(background)); LANES],
        }
    }

    /// The storage as rows (tail slots hold [`Tail`](crate::Tail) bytes).
    fn as_rows(&self) -> &[Row] {
        self.rows
    }

    fn reborrow(&mut self) -> HybridSpanFramebuffer<'_, K, A> {
        HybridSpanFramebuffer {
            rows: self.rows,
            dims: self.dims,
            arithmetic: PhantomData,
        }
    }

    fn split_lines(self, lines: u32) -> (Self, Self) {
        let lines = lines.min(self.dims.height);
        let (a, b) = self
            .rows
            .split_at_mut(lines as usize * self.dims.spans * Self::SPAN_ROWS);
        let band = |rows, height| HybridSpanFramebuffer {
            rows,
            dims: SpanDims { height, ..self.dims },
            arithmetic: PhantomData,
        };
        (band(a, lines), band(b, self.dims.height - lines))
    }
}

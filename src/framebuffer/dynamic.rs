//! Run-time layer counts: [`DynFramebuffer`] is a span [`Grid`] whose method (MLAB or HT)
//! and size are chosen at run time ([`Layers`]), with the same [`Framebuffer`] operations:
//! each call is one `match` to the monomorphized grid (per span insert or per resolved span,
//! not per pixel of a resolve).
//!
//! ```
//! use mlab::{DynFramebuffer, Framebuffer, Layers, Row};
//! let quality = Layers::Mlab(6); // from a settings menu
//! let mut storage = vec![Row::EMPTY; quality.rows_needed(64, 16)?];
//! let mut fb: DynFramebuffer = DynFramebuffer::new_cleared(quality, &mut storage, 64, 16)?;
//! fb.insert_row(3, 2, Row::new([10, 0, 0], 200, 1.0))?;
//! assert_eq!(fb.layers(), Layers::Mlab(6));
//! assert!(Layers::Mlab(9).rows_needed(64, 16).is_err()); // not one of Layers::SIZES
//! # Ok::<(), mlab::Error>(())
//! ```

use super::arrangement::SpanRows;
use super::arrangement::{PixelMajor, Spans};
use super::dims::SpanAt;
use super::grid::Grid;
use super::output::Output;
use super::pixel::{Ht, Mlab, Pixel};
use super::{Framebuffer, FramebufferError};
use crate::arith::{Arithmetic, Unbiased};
use crate::fragment::Fragment;
use crate::hybrid::TailFormat;
use crate::lanes::{LANES, ResolvedLanes};
use crate::resolve::{Background, Resolved};
use crate::row::Row;

/// A method and its size, chosen at run time.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Layers {
    /// MLAB with this many rows per pixel (`M`).
    Mlab(usize),
    /// Hybrid Transparency with this many head rows (`K`; one more slot holds the tail).
    Hybrid(usize),
}

impl Layers {
    /// The sizes offered at run time, for both methods.
    pub const SIZES: [usize; 8] = [1, 2, 3, 4, 5, 6, 7, 8];

    /// Rows of storage of a [`DynFramebuffer`] of `width x height` pixels, or
    /// [`FramebufferError::UnsupportedLayers`] for a size not in [`SIZES`](Self::SIZES).
    pub fn rows_needed(self, width: u32, height: u32) -> Result<usize, FramebufferError> {
        let rows = match self {
            Layers::Mlab(m) | Layers::Hybrid(m) => m,
        };
        if !Layers::SIZES.contains(&rows) {
            return Err(FramebufferError::UnsupportedLayers { rows });
        }
        Grid::<Mlab<1>, Spans>::rows_needed(width, height)?
            .checked_mul(self.rows_per_pixel())
            .ok_or(FramebufferError::SizeOverflow)
    }

    /// Rows (8-byte slots) per pixel, `R`: `M` for MLAB, `K + 1` for HT (the `K` head rows,
    /// then the tail in the last slot).
    ///
    /// Part of the storage contract a port relies on (`docs/layout.md`): pixel-major storage
    /// gives pixel `p` the slots `p * R .. (p + 1) * R`; span storage gives slot `j` of pixel
    /// `(x, y)` the index `((y * ceil(width / 8) + x / 8) * R + j) * 8 + x % 8`.
    ///
    /// ```
    /// use mlab::Layers;
    /// assert_eq!(Layers::Mlab(4).rows_per_pixel(), 4);
    /// assert_eq!(Layers::Hybrid(4).rows_per_pixel(), 5);
    /// ```
    pub const fn rows_per_pixel(self) -> usize {
        match self {
            Layers::Mlab(m) => m,
            Layers::Hybrid(k) => k + 1,
        }
    }
}

/// The grids a [`DynFramebuffer`] can be, with `$each!` dispatching over all of them.
macro_rules! variants {
    ($($v:ident: $p:ident<$n:literal>,)*) => {
        #[derive(Debug)]
        enum Inner<'a, A: Arithmetic> {
            $($v(Grid<'a, $p<$n, A>, Spans>),)*
        }

        impl<'a, A: Arithmetic> Inner<'a, A> {
            fn new(layers: Layers, storage: &'a mut [Row], width: u32, height: u32) -> Result<Self, FramebufferError> {
                $(if layers == <$p<$n, A> as Pixel>::LAYERS {
                    return Grid::new(storage, width, height).map(Inner::$v);
                })*
                let (Layers::Mlab(rows) | Layers::Hybrid(rows)) = layers;
                Err(FramebufferError::UnsupportedLayers { rows })
            }
        }

        /// `$body` with `$f` bound to the grid inside `$self`, and `$v` (in the second form)
        /// to the variant's constructor, for results that are grids again.
        macro_rules! each {
            ($self:expr, $f:ident => $body:expr) => {
                match $self { $(Inner::$v($f) => $body,)* }
            };
            ($self:expr, $f:ident, $c:ident => $body:expr) => {
                match $self { $(Inner::$v($f) => { let $c = Inner::$v; $body })* }
            };
        }
    };
}

variants! {
    M1: Mlab<1>, M2: Mlab<2>, M3: Mlab<3>, M4: Mlab<4>, M5: Mlab<5>, M6: Mlab<6>, M7: Mlab<7>, M8: Mlab<8>,
    H1: Ht<1>, H2: Ht<2>, H3: Ht<3>, H4: Ht<4>, H5: Ht<5>, H6: Ht<6>, H7: Ht<7>, H8: Ht<8>,
}

/// Trait methods that call the grid's own with one `match`: `ref fn` takes `&self`,
/// `mut fn` takes `&mut self`.
macro_rules! forward {
    ($($kind:ident fn $name:ident($($arg:ident: $ty:ty),*) $(-> $ret:ty)?;)*) => {$(
        forward!(@one $kind $name ($($arg: $ty),*) ($($ret)?));
    )*};
    (@one ref $name:ident ($($arg:ident: $ty:ty),*) ($($ret:ty)?)) => {
        #[inline]
        fn $name(&self $(, $arg: $ty)*) $(-> $ret)? {
            each!(&self.0, f => f.$name($($arg),*))
        }
    };
    (@one mut $name:ident ($($arg:ident: $ty:ty),*) ($($ret:ty)?)) => {
        // Always: inlined into a caller's loop, the match on a variant that the loop does not
        // change can be taken out of it (a call per insert cost 1.1-1.2x the typed grid).
        #[inline(always)]
        fn $name(&mut self $(, $arg: $ty)*) $(-> $ret)? {
            each!(&mut self.0, f => f.$name($($arg),*))
        }
    };
}

/// A span framebuffer of a method and size chosen at run time ([`Layers`]), in the
/// arithmetic `A` ([`Unbiased`] by default).
///
/// Name the arithmetic where nothing else fixes it: a type's default parameter does not drive
/// inference in Rust, so `DynFramebuffer::new(..)` alone is E0283 ("type annotations
/// needed"). Write `let fb: DynFramebuffer = DynFramebuffer::new(..)`, or
/// `DynFramebuffer::<Unbiased>::new(..)`, or `DynFramebuffer::<Paper>::new(..)` for the
/// paper's arithmetic ([`Paper`](crate::Paper)).
#[derive(Debug)]
pub struct DynFramebuffer<'a, A: Arithmetic = Unbiased>(Inner<'a, A>);

impl<'a, A: Arithmetic> DynFramebuffer<'a, A> {
    /// A view over `storage` ([`Layers::rows_needed`] rows exactly); contents are kept, as in
    /// [`Grid::new`].
    pub fn new(layers: Layers, storage: &'a mut [Row], width: u32, height: u32) -> Result<Self, FramebufferError> {
        Inner::new(layers, storage, width, height).map(DynFramebuffer)
    }

    /// [`new`](Self::new), then [`clear`](Framebuffer::clear): the way to start a frame.
    pub fn new_cleared(
        layers: Layers,
        storage: &'a mut [Row],
        width: u32,
        height: u32,
    ) -> Result<Self, FramebufferError> {
        let mut fb = Self::new(layers, storage, width, height)?;
        fb.clear();
        Ok(fb)
    }

    /// Writes every pixel into `out` in pixel-major order (as [`Grid::copy_from`] into a
    /// [`PixelMajor`] grid of the same kind and size): pixel `p = y * width + x` owns
    /// `out[p * R .. (p + 1) * R]`, `R` = [`Layers::rows_per_pixel`], the same rows as its
    /// span slots (the padding lanes are not copied). `out` must hold `width * height * R`
    /// rows ([`FramebufferError::StorageLength`] otherwise); it is the order of
    /// `MlabFramebuffer` and `HybridFramebuffer`, and of a port that stores pixels one after
    /// another (`mlab-gpu`'s `Layout::PixelMajor`).
    ///
    /// ```
    /// use mlab::{DynFramebuffer, Framebuffer, Layers, Row};
    /// let layers = Layers::Mlab(2);
    /// let mut storage = vec![Row::EMPTY; layers.rows_needed(3, 2)?];
    /// let mut fb: DynFramebuffer = DynFramebuffer::new_cleared(layers, &mut storage, 3, 2)?;
    /// let row = Row::new([10, 0, 0], 200, 1.0);
    /// fb.insert_row(2, 1, row)?;
    /// let mut pixels = vec![Row::EMPTY; 3 * 2 * layers.rows_per_pixel()];
    /// fb.copy_to_pixel_major(&mut pixels)?;
    /// assert_eq!(pixels[(1 * 3 + 2) * 2], row); // pixel (2, 1), its first slot
    /// # Ok::<(), mlab::Error>(())
    /// ```
    pub fn copy_to_pixel_major(&self, out: &mut [Row]) -> Result<(), FramebufferError> {
        let (width, height) = (self.width(), self.height());
        each!(&self.0, f => Grid::<_, PixelMajor>::new(out, width, height)?.copy_from(f))
    }

    /// The contents of pixel `(x, y)` ([`Grid::pixel`] of the grid inside): its rows and,
    /// for HT, its tail.
    ///
    /// ```
    /// use mlab::{DynFramebuffer, Framebuffer, Layers, Row, Tail, TailFormat};
    /// let layers = Layers::Hybrid(2);
    /// let mut storage = vec![Row::EMPTY; layers.rows_needed(9, 1)?];
    /// let mut fb: DynFramebuffer = DynFramebuffer::new_cleared(layers, &mut storage, 9, 1)?;
    /// let row = Row::new([10, 0, 0], 200, 1.0);
    /// fb.insert_row(8, 0, row)?;
    /// let px = fb.pixel(8, 0)?;
    /// assert_eq!(px.layers(), layers);
    /// assert_eq!(px.rows(), &[row, Row::EMPTY]);
    /// assert_eq!(px.tail(), Some(Tail::EMPTY));
    /// assert!(fb.pixel(9, 0).is_err());
    /// # Ok::<(), mlab::Error>(())
    /// ```
    pub fn pixel(&self, x: u32, y: u32) -> Result<DynPixel<A>, FramebufferError> {
        each!(&self.0, f => DynPixel::read(f, x, y))
    }

    /// Overwrite every pixel with those of `other` (the same [`Layers`] and size, otherwise
    /// [`FramebufferError::SizeMismatch`]), as [`Grid::copy_from`]: the whole storage is
    /// written, padding lanes as cleared.
    ///
    /// ```
    /// use mlab::{DynFramebuffer, Framebuffer, Layers, Row};
    /// let layers = Layers::Mlab(3);
    /// let (mut a, mut b) = (vec![Row::EMPTY; layers.rows_needed(5, 2)?], vec![Row::EMPTY; layers.rows_needed(5, 2)?]);
    /// let mut src: DynFramebuffer = DynFramebuffer::new_cleared(layers, &mut a, 5, 2)?;
    /// src.insert_row(4, 1, Row::new([1, 2, 3], 100, 2.0))?;
    /// let mut dst: DynFramebuffer = DynFramebuffer::new(layers, &mut b, 5, 2)?;
    /// dst.copy_from(&src)?;
    /// assert_eq!(dst.as_rows(), src.as_rows());
    /// # Ok::<(), mlab::Error>(())
    /// ```
    pub fn copy_from(&mut self, other: &DynFramebuffer<'_, A>) -> Result<(), FramebufferError> {
        if other.layers() != self.layers() {
            return Err(FramebufferError::SizeMismatch);
        }
        let (width, height, rows) = (other.width(), other.height(), other.as_rows());
        each!(&mut self.0, f => f.copy_from_rows::<Spans>(width, height, rows))
    }

    /// Pixels whose HT tail has a field at its maximum ([`Grid::saturated_pixels`]); 0 for MLAB.
    pub fn saturated_pixels(&self) -> usize {
        each!(&self.0, f => f.saturated_pixels())
    }
}

/// One pixel of a [`DynFramebuffer`] ([`DynFramebuffer::pixel`]): its `M` rows (MLAB) or
/// its `K` head rows and its tail (HT), in the arithmetic `A`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DynPixel<A: Arithmetic = Unbiased> {
    layers: Layers,
    rows: [Row; 8],
    tail: Option<A::Tail>,
}

impl<A: Arithmetic> DynPixel<A> {
    /// Pixel `(x, y)` of a grid of the kind `P`.
    fn read<P: Pixel<Arith = A>>(grid: &Grid<'_, P, Spans>, x: u32, y: u32) -> Result<Self, FramebufferError> {
        let (Layers::Mlab(n) | Layers::Hybrid(n)) = P::LAYERS;
        let (mut rows, mut tail) = ([Row::EMPTY; 8], None);
        P::to_slots(grid.pixel(x, y)?, |j, r| match rows.get_mut(j).filter(|_| j < n) {
            Some(s) => *s = r,
            None => tail = Some(A::Tail::from_bytes(r.to_bytes())),
        });
        Ok(DynPixel {
            layers: P::LAYERS,
            rows,
            tail,
        })
    }

    /// The method and size of the framebuffer it was read from.
    pub fn layers(&self) -> Layers {
        self.layers
    }

    /// Its rows: the `M` rows of an MLAB pixel, the `K` head rows of an HT pixel.
    pub fn rows(&self) -> &[Row] {
        let (Layers::Mlab(n) | Layers::Hybrid(n)) = self.layers;
        self.rows.get(..n).unwrap_or(&self.rows)
    }

    /// Its HT tail (`None` for MLAB).
    pub fn tail(&self) -> Option<A::Tail> {
        self.tail
    }
}

impl<'a, A: Arithmetic> Framebuffer for DynFramebuffer<'a, A> {
    type Arith = A;
    type Band<'b>
        = DynFramebuffer<'b, A>
    where
        Self: 'b;

    forward! {
        ref fn width() -> u32;
        ref fn height() -> u32;
        ref fn layers() -> Layers;
        mut fn clear();
        mut fn insert(x: u32, y: u32, fragment: &Fragment) -> Result<(), FramebufferError>;
        mut fn insert_row(x: u32, y: u32, row: Row) -> Result<(), FramebufferError>;
        mut fn insert_span(x: u32, y: u32, rows: &[Row; LANES], mask: u8) -> Result<(), FramebufferError>;
        ref fn first_pixel() -> u32;
        mut fn insert_hashed(x: u32, y: u32, row: Row, h: u32) -> Result<(), FramebufferError>;
        mut fn insert_span_rows(x: u32, y: u32, span: SpanRows<'_>) -> Result<(), FramebufferError>;
        ref fn resolve(x: u32, y: u32) -> Result<Resolved, FramebufferError>;
        ref fn resolve_span(span: u32, y: u32) -> Option<ResolvedLanes>;
        ref fn resolve_span_rgba8(span: u32, y: u32, bg: Background) -> [[u8; 4]; LANES];
        ref fn as_rows() -> &[Row];
    }

    // A call per flushed span, not inlined into the batcher: inlined, its 16 arms made the
    // batcher's push a call of its own (HT K = 3 batched 1.24x the instructions, callgrind
    // x86-64-v3).
    #[inline(never)]
    fn insert_span_at(&mut self, at: SpanAt, span: SpanRows<'_>) -> Result<(), FramebufferError> {
        each!(&mut self.0, f => f.insert_span_at(at, span))
    }

    #[inline]
    fn resolve_as<O: Output>(&self, out: &mut [O], bg: Background) -> Result<(), FramebufferError> {
        each!(&self.0, f => f.resolve_as(out, bg))
    }

    fn reborrow(&mut self) -> DynFramebuffer<'_, A> {
        DynFramebuffer(each!(&mut self.0, f, v => v(f.reborrow())))
    }

    fn split_lines(self, lines: u32) -> (Self, Self) {
        each!(self.0, f, v => {
            let (a, b) = f.split_lines(lines);
            (DynFramebuffer(v(a)), DynFramebuffer(v(b)))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::{DynFramebuffer, Framebuffer, FramebufferError, Layers};
    use crate::row::Row;

    /// Pixel-major slot `(y * w + x) * R + j` holds span slot `((y * ceil(w / 8) + x / 8) * R +
    /// j) * 8 + x % 8` (`Layers::rows_per_pixel`'s contract), for MLAB and HT (the tail too).
    #[test]
    fn copy_to_pixel_major_reindexes_every_slot() {
        let (w, h) = (13u32, 3u32);
        for layers in [Layers::Mlab(3), Layers::Hybrid(2)] {
            let r = layers.rows_per_pixel();
            let mut spans = [Row::EMPTY; 144];
            let mut fb: DynFramebuffer =
                DynFramebuffer::new_cleared(layers, &mut spans[..2 * 8 * h as usize * r], w, h).expect("size");
            for i in 0..60u32 {
                let row = Row::new([(i * 7 % 50) as u8, 3, 1], 250 - (i % 90) as u8, (i % 5) as f32);
                fb.insert_row(i * 5 % w, i % h, row).expect("inside");
            }
            let mut pixels = [Row::EMPTY; 117];
            let n = (w * h) as usize * r;
            fb.copy_to_pixel_major(&mut pixels[..n]).expect("length");
            let stored = fb.as_rows();
            for (y, x, j) in
                (0..h as usize).flat_map(|y| (0..w as usize).flat_map(move |x| (0..r).map(move |j| (y, x, j))))
            {
                let span = ((y * 2 + x / 8) * r + j) * 8 + x % 8;
                assert_eq!(
                    pixels[(y * w as usize + x) * r + j],
                    stored[span],
                    "{layers:?} ({x}, {y}) slot {j}"
                );
            }
            assert_eq!(
                fb.copy_to_pixel_major(&mut pixels[..n - 1]),
                Err(FramebufferError::StorageLength {
                    expected: n,
                    actual: n - 1
                })
            );
        }
    }
}

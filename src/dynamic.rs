//! Run-time layer counts: [`DynFramebuffer`] is a span framebuffer whose method (MLAB or
//! HT) and number of rows are chosen at run time, from the sizes in [`Layers::SIZES`], with
//! the same [`Framebuffer`] operations.
//!
//! ```
//! use mlab::{DynFramebuffer, Framebuffer, Layers, Row};
//! let quality = Layers::Mlab(6); // from a settings menu
//! let mut storage = vec![Row::EMPTY; quality.rows_needed(64, 16)?];
//! let mut fb: DynFramebuffer = DynFramebuffer::new_cleared(quality, &mut storage, 64, 16)?;
//! fb.insert_row(3, 2, Row::new([10, 0, 0], 200, 1.0))?;
//! assert_eq!(fb.layers(), Layers::Mlab(6));
//! assert!(Layers::Mlab(5).rows_needed(64, 16).is_err()); // not one of Layers::SIZES
//! # Ok::<(), mlab::Error>(())
//! ```

use crate::arith::{Arithmetic, Unbiased};
use crate::framebuffer::{Framebuffer, FramebufferError};
use crate::lanes::{LANES, ResolvedLanes};
use crate::resolve::{Background, Resolved};
use crate::row::Row;
use crate::spans::{HybridSpanFramebuffer, SpanFramebuffer};

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
    pub const SIZES: [usize; 6] = [1, 2, 3, 4, 6, 8];

    /// Rows of storage of a [`DynFramebuffer`] of `width x height` pixels, or
    /// [`FramebufferError::UnsupportedLayers`] for a size not in [`SIZES`](Self::SIZES).
    pub fn rows_needed(self, width: u32, height: u32) -> Result<usize, FramebufferError> {
        let rows = match self {
            Layers::Mlab(m) | Layers::Hybrid(m) => m,
        };
        if !Layers::SIZES.contains(&rows) {
            return Err(FramebufferError::UnsupportedLayers { rows });
        }
        SpanFramebuffer::<'_, 1, Unbiased>::rows_needed(width, height)?
            .checked_mul(self.rows_per_pixel())
            .ok_or(FramebufferError::SizeOverflow)
    }

    /// Rows (8-byte slots) per pixel: `M`, or `K + 1`.
    pub const fn rows_per_pixel(self) -> usize {
        match self {
            Layers::Mlab(m) => m,
            Layers::Hybrid(k) => k + 1,
        }
    }
}

/// A span framebuffer of a method and size chosen at run time ([`Layers`]), in the
/// arithmetic `A`. Each variant is the compile-time type; [`Framebuffer`] dispatches with
/// one `match` per call (per span insert or per resolved span, not per pixel of a resolve).
#[derive(Debug)]
#[non_exhaustive]
pub enum DynFramebuffer<'a, A: Arithmetic = Unbiased> {
    /// MLAB, `M = 1`.
    Mlab1(SpanFramebuffer<'a, 1, A>),
    /// MLAB, `M = 2`.
    Mlab2(SpanFramebuffer<'a, 2, A>),
    /// MLAB, `M = 3`.
    Mlab3(SpanFramebuffer<'a, 3, A>),
    /// MLAB, `M = 4`.
    Mlab4(SpanFramebuffer<'a, 4, A>),
    /// MLAB, `M = 6`.
    Mlab6(SpanFramebuffer<'a, 6, A>),
    /// MLAB, `M = 8`.
    Mlab8(SpanFramebuffer<'a, 8, A>),
    /// HT, `K = 1`.
    Hybrid1(HybridSpanFramebuffer<'a, 1, A>),
    /// HT, `K = 2`.
    Hybrid2(HybridSpanFramebuffer<'a, 2, A>),
    /// HT, `K = 3`.
    Hybrid3(HybridSpanFramebuffer<'a, 3, A>),
    /// HT, `K = 4`.
    Hybrid4(HybridSpanFramebuffer<'a, 4, A>),
    /// HT, `K = 6`.
    Hybrid6(HybridSpanFramebuffer<'a, 6, A>),
    /// HT, `K = 8`.
    Hybrid8(HybridSpanFramebuffer<'a, 8, A>),
}

/// `$body` with `$f` bound to the framebuffer inside `$self`, whatever the variant, and
/// `$v` (in the second form) to the variant's constructor, for results that are
/// framebuffers again.
macro_rules! each {
    ($self:expr, $f:ident => $body:expr) => {
        each!(@arms $self, $f, [Mlab1, Mlab2, Mlab3, Mlab4, Mlab6, Mlab8, Hybrid1, Hybrid2, Hybrid3, Hybrid4, Hybrid6, Hybrid8] => $body)
    };
    ($self:expr, $f:ident, $v:ident => $body:expr) => {
        each!(@ctor $self, $f, $v, [Mlab1, Mlab2, Mlab3, Mlab4, Mlab6, Mlab8, Hybrid1, Hybrid2, Hybrid3, Hybrid4, Hybrid6, Hybrid8] => $body)
    };
    (@arms $self:expr, $f:ident, [$($var:ident),*] => $body:expr) => {
        match $self {
            $(DynFramebuffer::$var($f) => $body,)*
        }
    };
    (@ctor $self:expr, $f:ident, $v:ident, [$($var:ident),*] => $body:expr) => {
        match $self {
            $(DynFramebuffer::$var($f) => {
                let $v = DynFramebuffer::$var;
                $body
            })*
        }
    };
}

impl<'a, A: Arithmetic> DynFramebuffer<'a, A> {
    /// Rows of storage for `width x height` pixels of `layers`, or
    /// [`FramebufferError::UnsupportedLayers`] for a size not in [`Layers::SIZES`].
    pub fn rows_needed(layers: Layers, width: u32, height: u32) -> Result<usize, FramebufferError> {
        layers.rows_needed(width, height)
    }

    /// A view over `storage` ([`rows_needed`](Self::rows_needed) rows exactly); contents
    /// are kept, as in [`SpanFramebuffer::new`] and [`HybridSpanFramebuffer::new`].
    pub fn new(layers: Layers, storage: &'a mut [Row], width: u32, height: u32) -> Result<Self, FramebufferError> {
        Self::rows_needed(layers, width, height)?;
        Ok(match layers {
            Layers::Mlab(1) => DynFramebuffer::Mlab1(SpanFramebuffer::new(storage, width, height)?),
            Layers::Mlab(2) => DynFramebuffer::Mlab2(SpanFramebuffer::new(storage, width, height)?),
            Layers::Mlab(3) => DynFramebuffer::Mlab3(SpanFramebuffer::new(storage, width, height)?),
            Layers::Mlab(4) => DynFramebuffer::Mlab4(SpanFramebuffer::new(storage, width, height)?),
            Layers::Mlab(6) => DynFramebuffer::Mlab6(SpanFramebuffer::new(storage, width, height)?),
            Layers::Mlab(8) => DynFramebuffer::Mlab8(SpanFramebuffer::new(storage, width, height)?),
            Layers::Hybrid(1) => DynFramebuffer::Hybrid1(HybridSpanFramebuffer::new(storage, width, height)?),
            Layers::Hybrid(2) => DynFramebuffer::Hybrid2(HybridSpanFramebuffer::new(storage, width, height)?),
            Layers::Hybrid(3) => DynFramebuffer::Hybrid3(HybridSpanFramebuffer::new(storage, width, height)?),
            Layers::Hybrid(4) => DynFramebuffer::Hybrid4(HybridSpanFramebuffer::new(storage, width, height)?),
            Layers::Hybrid(6) => DynFramebuffer::Hybrid6(HybridSpanFramebuffer::new(storage, width, height)?),
            Layers::Hybrid(8) => DynFramebuffer::Hybrid8(HybridSpanFramebuffer::new(storage, width, height)?),
            Layers::Mlab(rows) | Layers::Hybrid(rows) => return Err(FramebufferError::UnsupportedLayers { rows }),
        })
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

    /// The method and size.
    pub fn layers(&self) -> Layers {
        match self {
            DynFramebuffer::Mlab1(_) => Layers::Mlab(1),
            DynFramebuffer::Mlab2(_) => Layers::Mlab(2),
            DynFramebuffer::Mlab3(_) => Layers::Mlab(3),
            DynFramebuffer::Mlab4(_) => Layers::Mlab(4),
            DynFramebuffer::Mlab6(_) => Layers::Mlab(6),
            DynFramebuffer::Mlab8(_) => Layers::Mlab(8),
            DynFramebuffer::Hybrid1(_) => Layers::Hybrid(1),
            DynFramebuffer::Hybrid2(_) => Layers::Hybrid(2),
            DynFramebuffer::Hybrid3(_) => Layers::Hybrid(3),
            DynFramebuffer::Hybrid4(_) => Layers::Hybrid(4),
            DynFramebuffer::Hybrid6(_) => Layers::Hybrid(6),
            DynFramebuffer::Hybrid8(_) => Layers::Hybrid(8),
        }
    }
}

impl<'a, A: Arithmetic> Framebuffer for DynFramebuffer<'a, A> {
    type Arith = A;
    type Band<'b>
        = DynFramebuffer<'b, A>
    where
        Self: 'b;

    fn width(&self) -> u32 {
        each!(self, f => f.width())
    }

    fn height(&self) -> u32 {
        each!(self, f => f.height())
    }

    fn rows_per_pixel(&self) -> usize {
        self.layers().rows_per_pixel()
    }

    fn clear(&mut self) {
        each!(self, f => f.clear())
    }

    #[inline]
    fn insert_row(&mut self, x: u32, y: u32, row: Row) -> Result<(), FramebufferError> {
        each!(self, f => f.insert_row(x, y, row))
    }

    #[inline]
    fn insert_span(&mut self, x: u32, y: u32, rows: &[Row; LANES], mask: u8) -> Result<(), FramebufferError> {
        each!(self, f => f.insert_span(x, y, rows, mask))
    }

    fn resolve(&self, x: u32, y: u32) -> Result<Resolved, FramebufferError> {
        each!(self, f => f.resolve(x, y))
    }

    fn resolve_span(&self, span: u32, y: u32) -> Option<ResolvedLanes> {
        each!(self, f => f.resolve_span(span, y))
    }

    fn resolve_span_rgba8(&self, span: u32, y: u32, background: Background) -> [[u8; 4]; LANES] {
        each!(self, f => f.resolve_span_rgba8(span, y, background))
    }

    fn resolve_into(&self, out: &mut [glam::Vec4], background: Background) -> Result<(), FramebufferError> {
        each!(self, f => f.resolve_into(out, background))
    }

    fn resolve_rgba8(&self, out: &mut [[u8; 4]], background: Background) -> Result<(), FramebufferError> {
        each!(self, f => f.resolve_rgba8(out, background))
    }

    fn resolve_rgba16f(&self, out: &mut [[half::f16; 4]], background: Background) -> Result<(), FramebufferError> {
        each!(self, f => f.resolve_rgba16f(out, background))
    }

    fn as_rows(&self) -> &[Row] {
        each!(self, f => f.as_rows())
    }

    fn reborrow(&mut self) -> DynFramebuffer<'_, A> {
        each!(self, f, v => v(f.reborrow()))
    }

    fn split_lines(self, lines: u32) -> (Self, Self) {
        each!(self, f, v => {
            let (a, b) = f.split_lines(lines);
            (v(a), v(b))
        })
    }
}

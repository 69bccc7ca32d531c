//! [`Dims`]: the geometry of a framebuffer (width, height, 8-pixel spans per line) and every
//! bounds and length check of the storage layer, so that a coordinate is checked in one
//! place, once: by the framebuffer's operation, or by the [`SpanBatcher`](crate::SpanBatcher)
//! when a fragment is pushed (its flush then inserts at a [`SpanAt`] without a second check).

use crate::error::FramebufferError;
use crate::lanes::{LANES, LANES_U32};

/// Width, height and spans per line, with the checks shared by every framebuffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Dims {
    pub(crate) width: u32,
    pub(crate) height: u32,
    /// 8-pixel spans per line: `ceil(width / 8)`.
    pub(crate) spans: usize,
}

/// Where an 8-pixel span lies (lane 0 at `(x, y)`), checked once ([`Dims::span_at`]):
/// `index`, the stored span index `y * spans + x / 8` (in span storage, the unit of its
/// lane 0), and the coordinates a pixel-major grid or a framebuffer of another crate
/// inserts at. Public in a private module: a framebuffer of another crate can
/// neither name nor build one, so the insert that takes it is crate-private.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SpanAt {
    pub(crate) index: usize,
    pub(crate) x: u32,
    pub(crate) y: u32,
}

impl Dims {
    pub(crate) fn new(width: u32, height: u32) -> Dims {
        Dims {
            width,
            height,
            spans: (width as usize).div_ceil(LANES),
        }
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

    /// Check that pixel `(x, y)` is inside.
    #[inline(always)]
    pub(crate) fn check(self, x: u32, y: u32) -> Result<(), FramebufferError> {
        if x >= self.width || y >= self.height {
            return Err(self.out_of_bounds(x, y));
        }
        Ok(())
    }

    /// Where the span with lane 0 at `(x, y)` lies (checked before; `x` any column).
    #[inline(always)]
    pub(crate) fn span_at(self, x: u32, y: u32) -> SpanAt {
        SpanAt {
            index: y as usize * self.spans + x as usize / LANES,
            x,
            y,
        }
    }

    /// The aligned span of the key `y << 32 | x / 8` of a pixel `(x, y)` checked before
    /// ([`check`](Self::check)): the [`SpanBatcher`](crate::SpanBatcher)'s pending spans.
    #[inline(always)]
    #[expect(clippy::cast_possible_truncation, reason = "the key packs two u32: y << 32 | x / 8")]
    pub(crate) fn span_at_key(self, key: u64) -> SpanAt {
        self.span_at(key as u32 * LANES_U32, (key >> 32) as u32)
    }

    /// Pixel index of `(x, y)` (checked before).
    #[inline(always)]
    pub(crate) fn index_unchecked(self, x: u32, y: u32) -> usize {
        y as usize * self.width as usize + x as usize
    }

    /// Stored span index of span `span` of line `y`, if both are inside.
    #[inline(always)]
    pub(crate) fn span_index(self, span: u32, y: u32) -> Option<usize> {
        ((span as usize) < self.spans && y < self.height).then(|| y as usize * self.spans + span as usize)
    }

    /// Pixels of a span from column `x` that lie inside the line.
    #[inline(always)]
    pub(crate) fn lanes_inside(self, x: u32) -> usize {
        (self.width.saturating_sub(x) as usize).min(LANES)
    }

    /// Check a span operation at `(x, y)` with `mask`: every lane that is on lies inside (a
    /// zero mask touches no pixel and may lie anywhere on a valid line).
    #[inline(always)]
    #[expect(clippy::cast_possible_truncation, reason = "clamped to u32::MAX first")]
    pub(crate) fn check_span(self, x: u32, y: u32, mask: u8) -> Result<(), FramebufferError> {
        if y >= self.height {
            return Err(self.out_of_bounds(x, y));
        }
        if mask == 0 {
            return Ok(());
        }
        let last = x as u64 + 7 - mask.leading_zeros() as u64;
        if last >= self.width as u64 {
            return Err(self.out_of_bounds(last.min(u32::MAX as u64) as u32, y));
        }
        Ok(())
    }

    /// Check an output slice length: exactly `width * height` pixels.
    pub(crate) fn check_output(self, len: usize) -> Result<(), FramebufferError> {
        let expected = (self.width as usize)
            .checked_mul(self.height as usize)
            .ok_or(FramebufferError::SizeOverflow)?;
        if len != expected {
            return Err(FramebufferError::OutputLength { expected, actual: len });
        }
        Ok(())
    }

    /// Rows of storage for these dimensions, `line_rows` rows per line.
    pub(crate) fn rows_needed(self, line_rows: Option<usize>) -> Result<usize, FramebufferError> {
        line_rows
            .and_then(|r| r.checked_mul(self.height as usize))
            .ok_or(FramebufferError::SizeOverflow)
    }

    /// Check a storage slice length: exactly `expected` rows.
    pub(crate) fn check_storage(expected: usize, len: usize) -> Result<(), FramebufferError> {
        if len != expected {
            return Err(FramebufferError::StorageLength { expected, actual: len });
        }
        Ok(())
    }

    /// Check that two framebuffers have the same size (a copy between them).
    pub(crate) fn check_same(self, other: Dims) -> Result<(), FramebufferError> {
        if (other.width, other.height) != (self.width, self.height) {
            return Err(FramebufferError::SizeMismatch);
        }
        Ok(())
    }
}

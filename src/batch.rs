//! The span batcher: fragments pushed one pixel at a time become 8-pixel span inserts.
//!
//! Rasterizers such as a scanline or tile rasterizer emit one fragment at a time. The lanes
//! insert 8 pixels of a line at once, 3-8x faster per fragment than one pixel at a time
//! (`docs/performance.md`), but only if something gathers the fragments into spans. A
//! [`SpanBatcher`] does, over any [`Framebuffer`]:
//!
//! ```text
//! insert(x, y, row):                        // slot: a direct-mapped table of 256 spans
//!   s = slot of span (x / 8, y)             //   (x / 8) % 8 + 8 * (y % 32): a 64x32-pixel window
//!   if s holds another span, or lane x % 8 is already pending in s: flush s
//!   s.rows[x % 8] = row; s.mask |= 1 << (x % 8)
//!   if s.mask == 0xff: flush s              // a full span goes at once
//! flush s: framebuffer.insert_span(8 * (x / 8), y, s.rows, s.mask); s.mask = 0
//! ```
//!
//! Every pixel keeps its submission order exactly: a pixel has one slot, a slot holds at
//! most one pending fragment per pixel, and it is flushed before a second one for the same
//! pixel, or a fragment of another span, takes its place. Pixels are independent in MLAB
//! and HT, so the framebuffer ends up byte-identical to inserting the fragments one by one
//! (`tests/batch.rs` checks this for random streams, both arithmetics, MLAB and HT, both
//! arrangements). Fragments still pending are not in the framebuffer: the batcher borrows
//! it mutably until [`finish`](SpanBatcher::finish) (or drop) flushes them.
//!
//! Coordinates are checked when a fragment is pushed, so flushes cannot fail.
//!
//! The window: 64 x 32 pixels (256 spans, about 18 KiB). On the mesh of `benches/batch.rs`
//! (the tori of `examples/rasterizer.rs` at 320 x 240, 10 pixels per triangle) it gives
//! 5.8 fragments per span insert; 64 x 8 pixels gave 4.0, 128 x 16 gave 4.5, 64 x 64 gave
//! 6.4 for twice the memory. On the coherent stream (rectangles) every window gives 6.1-6.2.
//!
//! ```
//! use mlab::glam::Vec3;
//! use mlab::{Background, Fragment, Framebuffer, Row, SpanBatcher, SpanFramebuffer};
//! let (w, h) = (32, 4);
//! let mut storage = vec![Row::EMPTY; SpanFramebuffer::<4>::rows_needed(w, h)?];
//! let mut fb = SpanFramebuffer::<4>::new_cleared(&mut storage, w, h)?;
//! let mut batch = SpanBatcher::new(&mut fb);
//! for y in 0..h {
//!     for x in 0..w {
//!         // One fragment per pixel, in the order a rasterizer emits them.
//!         batch.insert(x, y, &Fragment::straight(Vec3::X, 1.0, 1.0)?)?;
//!     }
//! }
//! batch.finish()?; // flush what is pending
//! let mut out = vec![[0u8; 4]; (w * h) as usize];
//! fb.resolve_rgba8(&mut out, Background::Opaque(Vec3::ZERO))?;
//! assert!(out.iter().all(|&px| px == [255, 0, 0, 255]));
//! # Ok::<(), mlab::Error>(())
//! ```

use crate::arith::Arithmetic;
use crate::fragment::Fragment;
use crate::framebuffer::{Framebuffer, FramebufferError};
use crate::lanes::LANES;
use crate::row::Row;

/// log2 of the spans per line of the batcher's window.
const COL_BITS: u32 = 3;
/// log2 of the lines of the batcher's window.
const LINE_BITS: u32 = 5;
/// Pending spans a [`SpanBatcher`] holds: a window of `8 << COL_BITS` x `1 << LINE_BITS` pixels.
pub const BATCH_SLOTS: usize = 1 << (COL_BITS + LINE_BITS);

/// Gathers fragments pushed one pixel at a time into 8-pixel span inserts on a
/// [`Framebuffer`] (see the [module docs](self)). A fixed-size value (about 18 KiB: keep it in a `Box` or a long-lived struct rather than re-creating it per primitive), no
/// allocation; one per thread or band.
#[derive(Debug)]
pub struct SpanBatcher<'f, F: Framebuffer> {
    fb: &'f mut F,
    width: u32,
    height: u32,
    /// `y << 32 | x / 8` of the span pending in each slot (meaningful when its mask is not 0).
    keys: [u64; BATCH_SLOTS],
    masks: [u8; BATCH_SLOTS],
    rows: [[Row; LANES]; BATCH_SLOTS],
}

impl<'f, F: Framebuffer> SpanBatcher<'f, F> {
    /// A batcher over `fb`, nothing pending.
    pub fn new(fb: &'f mut F) -> Self {
        SpanBatcher {
            width: fb.width(),
            height: fb.height(),
            fb,
            keys: [0; BATCH_SLOTS],
            masks: [0; BATCH_SLOTS],
            rows: [[Row::EMPTY; LANES]; BATCH_SLOTS],
        }
    }

    /// Push a fragment for pixel `(x, y)`, quantized by the framebuffer's arithmetic.
    /// [`FramebufferError::OutOfBounds`] (and nothing pushed) if the pixel is outside.
    #[inline]
    pub fn insert(&mut self, x: u32, y: u32, fragment: &Fragment) -> Result<(), FramebufferError> {
        self.insert_row(x, y, <F::Arith as Arithmetic>::quantize(fragment))
    }

    /// Push a quantized row for pixel `(x, y)`.
    #[inline]
    pub fn insert_row(&mut self, x: u32, y: u32, row: Row) -> Result<(), FramebufferError> {
        if x >= self.width || y >= self.height {
            return Err(FramebufferError::OutOfBounds {
                x,
                y,
                width: self.width,
                height: self.height,
            });
        }
        let sx = x / LANES as u32;
        let lane = x as usize % LANES;
        let bit = 1u8 << lane;
        let key = (y as u64) << 32 | sx as u64;
        // In 0..64 by construction: the indexing below cannot fail.
        let s = ((sx & ((1 << COL_BITS) - 1)) | (y & ((1 << LINE_BITS) - 1)) << COL_BITS) as usize;
        let mut mask = self.masks[s];
        if mask != 0 && (self.keys[s] != key || mask & bit != 0) {
            let k = self.keys[s];
            self.fb
                .insert_span((k as u32) * LANES as u32, (k >> 32) as u32, &self.rows[s], mask)?;
            mask = 0;
        }
        self.keys[s] = key;
        self.rows[s][lane] = row;
        mask |= bit;
        if mask == 0xff {
            self.fb.insert_span(sx * LANES as u32, y, &self.rows[s], 0xff)?;
            mask = 0;
        }
        self.masks[s] = mask;
        Ok(())
    }

    /// Insert every pending span into the framebuffer.
    pub fn flush(&mut self) -> Result<(), FramebufferError> {
        for ((mask, key), rows) in self.masks.iter_mut().zip(&self.keys).zip(&self.rows) {
            if *mask != 0 {
                let m = core::mem::take(mask);
                self.fb
                    .insert_span((*key as u32) * LANES as u32, (*key >> 32) as u32, rows, m)?;
            }
        }
        Ok(())
    }

    /// Fragments pushed but not yet in the framebuffer.
    pub fn pending(&self) -> usize {
        self.masks.iter().map(|m| m.count_ones() as usize).sum()
    }

    /// Flush, and end the batch (also done on drop, where an error cannot be reported; none
    /// can occur, since coordinates are checked when pushed).
    pub fn finish(mut self) -> Result<(), FramebufferError> {
        self.flush()
    }

    /// The framebuffer, after a flush (for example to read or resolve it, then go on
    /// batching).
    pub fn framebuffer(&mut self) -> Result<&mut F, FramebufferError> {
        self.flush()?;
        Ok(self.fb)
    }
}

impl<F: Framebuffer> Drop for SpanBatcher<'_, F> {
    fn drop(&mut self) {
        // Cannot fail (coordinates were checked on push); nothing to report it to anyway.
        let _ = self.flush();
    }
}

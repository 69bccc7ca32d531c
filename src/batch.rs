//! The span batcher: fragments pushed one pixel at a time become 8-pixel span inserts.
//!
//! Rasterizers such as a scanline or tile rasterizer emit one fragment at a time. The lanes
//! insert 8 pixels of a line at once, several times faster per fragment than one pixel at a
//! time (`docs/performance.md`), but only if something gathers the fragments into spans. A
//! [`SpanBatcher`] does, over any [`Framebuffer`]:
//!
//! ```text
//! insert(x, y, fragment):                   // slot: a direct-mapped table of 256 spans
//!   s = slot of span (x / 8, y)             //   (x / 8) % 8 + 8 * (y % 32): a 64x32-pixel window
//!   if s holds another span, or lane x % 8 is already pending in s: flush s
//!   s.fragments[x % 8] = fragment (f32); s.mask |= 1 << (x % 8)
//!   (a full span waits for the next push to its slot: flushed at once, its 8-lane loads
//!    would read the f32 stores just made, which the store buffer cannot forward)
//! flush s: rows = quantize the 8 lanes at once (as FragmentLanes::quantize_with, without
//!          its validation: every lane was a validated Fragment), rows pushed as rows kept
//!          framebuffer.insert_span(8 * (x / 8), y, rows, s.mask); s.mask = 0
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
//! What it gains is measured in `docs/performance.md` (`benches/batch.rs`): most for MLAB
//! into a [`SpanFramebuffer`](crate::SpanFramebuffer), whose merge the lanes share; little for
//! HT, whose per-pixel insert has no merge and is cheap already. Into the pixel-major
//! [`HybridFramebuffer`](crate::HybridFramebuffer) span inserts are slower than per-pixel
//! inserts (a gather and a scatter around an insert with nothing to share), so there the
//! batcher passes each fragment straight through ([`Framebuffer::SPAN_INSERTS_PAY`]).
//! [`span_inserts`](SpanBatcher::span_inserts) counts what it sent, to see how full the spans
//! of your stream are.
//!
//! The window: 64 x 32 pixels (256 spans, a fixed-size value: build it once per frame and
//! band). Why this size, against the others tried: `docs/performance.md`.
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

use crate::fragment::Fragment;
use crate::framebuffer::{Dims, Framebuffer, FramebufferError, SpanRows};
use crate::lanes::{FragmentLanes, LANES, LANES_U32};
use crate::row::Row;

/// log2 of the spans per line of the batcher's window.
const COL_BITS: u32 = 3;
/// log2 of the lines of the batcher's window.
const LINE_BITS: u32 = 5;
/// Pending spans a [`SpanBatcher`] holds: a window of `8 << COL_BITS` x `1 << LINE_BITS` pixels.
const BATCH_SLOTS: usize = 1 << (COL_BITS + LINE_BITS);

/// One pending span: the fragments of its lanes as f32 (structure of arrays, quantized 8 at
/// a time when the span is flushed), which lanes are pending, and which of those hold an
/// already quantized row (its two words in the bits of `color[0]` and `color[1]`).
#[derive(Clone, Copy, Debug)]
struct Slot {
    /// The pending fragments, `key` always `Some`: each lane's stable or content key
    /// (`Fragment::hash`).
    fragments: FragmentLanes,
    mask: u8,
    rows: u8,
}

/// Gathers fragments pushed one pixel at a time into 8-pixel span inserts on a
/// [`Framebuffer`] (see the [module docs](self)). A fixed-size value (about 52 KiB: build
/// it once per frame and band, not per primitive), no allocation. Fragments are kept as
/// f32 until their span is flushed, then validated and quantized 8 at a time
/// ([`FragmentLanes::quantize_with`], byte-identical to
/// [`Arithmetic::quantize`](crate::Arithmetic::quantize) per fragment).
#[derive(Debug)]
pub struct SpanBatcher<'f, F: Framebuffer> {
    fb: &'f mut F,
    /// The framebuffer's size: a pushed fragment's one bounds check.
    dims: Dims,
    /// `y << 32 | x / 8` of the span pending in each slot (meaningful when its mask is not
    /// 0), checked when pushed. Not its stored span index and coordinates (`SpanAt`, 16
    /// bytes): kept per slot, they cost 7 instructions more per fragment (`batcher_alone`
    /// 1.09x, callgrind x86-64-v3) and 2 KiB; the flush derives its `SpanAt` from the key
    /// instead ([`Dims::span_at_key`]), once per span.
    keys: [u64; BATCH_SLOTS],
    /// Span inserts sent to the framebuffer so far.
    span_inserts: u64,
    slots: [Slot; BATCH_SLOTS],
}

impl<'f, F: Framebuffer> SpanBatcher<'f, F> {
    /// A batcher over `fb`, nothing pending.
    pub fn new(fb: &'f mut F) -> Self {
        SpanBatcher {
            dims: Dims::new(fb.width(), fb.height()),
            fb,
            keys: [0; BATCH_SLOTS],
            span_inserts: 0,
            slots: [Slot {
                fragments: FragmentLanes {
                    key: Some([0; LANES]),
                    ..FragmentLanes::TRANSPARENT
                },
                mask: 0,
                rows: 0,
            }; BATCH_SLOTS],
        }
    }

    /// Push a fragment for pixel `(x, y)`, quantized (when its span is flushed) by the
    /// framebuffer's arithmetic. [`FramebufferError::OutOfBounds`] (and nothing pushed) if
    /// the pixel is outside.
    // Always: the push in the caller's loop, the flush inlined into it (`flush_inline`).
    // Left to LLVM, a `DynFramebuffer`'s push became a call per fragment (1.25x the
    // instructions), or the Paper batcher's loop 1.12x (callgrind x86-64-v3).
    #[inline(always)]
    pub fn insert(&mut self, x: u32, y: u32, fragment: &Fragment) -> Result<(), FramebufferError> {
        if !F::SPAN_INSERTS_PAY {
            return self.fb.insert(x, y, fragment);
        }
        let c = fragment.color();
        self.push(
            x,
            y,
            [c.x, c.y, c.z, fragment.alpha()],
            fragment.depth(),
            fragment.seed_key(),
            false,
        )
    }

    /// Push a quantized row for pixel `(x, y)`.
    #[inline]
    pub fn insert_row(&mut self, x: u32, y: u32, row: Row) -> Result<(), FramebufferError> {
        if !F::SPAN_INSERTS_PAY {
            return self.fb.insert_row(x, y, row);
        }
        // The row's words travel as the bits of two f32 lanes (moved, never computed with:
        // bit-exact on every target the lanes support, which `tests/batch.rs` checks with
        // arbitrary bytes, NaN patterns included).
        let [w0, w1] = row.words();
        self.push(x, y, [f32::from_bits(w0), f32::from_bits(w1), 0.0, 0.0], 0.0, 0, true)
    }

    #[inline(always)]
    fn push(
        &mut self,
        x: u32,
        y: u32,
        rgba: [f32; 4],
        depth: f32,
        seed: u32,
        is_row: bool,
    ) -> Result<(), FramebufferError> {
        self.dims.check(x, y)?;
        let sx = x / LANES_U32;
        let lane = x as usize % LANES;
        let bit = 1u8 << lane;
        // In 0..BATCH_SLOTS by construction: the indexing below cannot fail.
        let s = ((sx & ((1 << COL_BITS) - 1)) | (y & ((1 << LINE_BITS) - 1)) << COL_BITS) as usize;
        let mask = self.slots[s].mask;
        let key = (y as u64) << 32 | sx as u64;
        // The lane's bit tested before the key: in the other order LLVM's register allocator
        // rotated nine registers and back on the hot path of the Paper MLAB batcher (18 moves
        // per fragment: `client_mesh/mlab4_paper_batcher` 1.14x the instructions of 8f8d933;
        // in this order 1.00x, callgrind x86-64-v3).
        if mask != 0 && (mask & bit != 0 || self.keys[s] != key) {
            Self::flush_inline(self.fb, self.dims, self.keys[s], &mut self.slots[s])?;
            self.span_inserts += 1;
        }
        self.keys[s] = key;
        let slot = &mut self.slots[s];
        let f = &mut slot.fragments;
        f.color[0][lane] = rgba[0];
        f.color[1][lane] = rgba[1];
        f.color[2][lane] = rgba[2];
        f.alpha[lane] = rgba[3];
        f.depth[lane] = depth;
        if let Some(keys) = &mut f.key {
            keys[lane] = seed;
        }
        slot.mask |= bit;
        if is_row {
            slot.rows |= bit;
        }
        Ok(())
    }

    /// Quantize and insert the pending span of the key `key` (its pixels checked when
    /// pushed: no second check), and mark it empty: a call per span, for [`flush`](Self::flush).
    #[inline(never)]
    fn flush_slot(fb: &mut F, dims: Dims, key: u64, slot: &mut Slot) -> Result<(), FramebufferError> {
        Self::flush_inline(fb, dims, key, slot)
    }

    /// [`flush_slot`](Self::flush_slot) inlined into the push: through the call the batchers
    /// ran up to 1.09x the time and 1.04x the instructions (`batcher_alone`, the HT span
    /// batcher; `benches/compare.sh`, `docs/performance.md`).
    #[inline(always)]
    fn flush_inline(fb: &mut F, dims: Dims, key: u64, slot: &mut Slot) -> Result<(), FramebufferError> {
        let at = dims.span_at_key(key);
        let fragments = slot.mask & !slot.rows;
        let first = fb.pixel_id(at.x, at.y);
        // Every lane pushed as a fragment holds a validated `Fragment`: no lane is invalid.
        let mut q = slot
            .fragments
            .quantize_validated_at::<F::Arith>(fragments, first, F::MERGES);
        if slot.rows != 0 {
            for lane in 0..LANES {
                if slot.rows & (1 << lane) != 0 {
                    let bits = |c: usize| slot.fragments.color[c][lane].to_bits();
                    let row = Row::from_words([bits(0), bits(1)]);
                    q.rows[lane] = row;
                    #[expect(clippy::cast_possible_truncation, reason = "lane < 8")]
                    let pixel = first.wrapping_add(lane as u32);
                    q.hashes[lane] = crate::mlab::row_hash(row, pixel);
                }
            }
        }
        let mask = q.valid | slot.rows;
        slot.mask = 0;
        slot.rows = 0;
        fb.insert_span_at(
            at,
            SpanRows {
                rows: &q.rows,
                hashes: &q.hashes,
                mask,
            },
        )
    }

    /// Insert every pending span into the framebuffer.
    pub fn flush(&mut self) -> Result<(), FramebufferError> {
        for (slot, key) in self.slots.iter_mut().zip(&self.keys) {
            if slot.mask != 0 {
                Self::flush_slot(self.fb, self.dims, *key, slot)?;
                self.span_inserts += 1;
            }
        }
        Ok(())
    }

    /// Width of the framebuffer, in pixels.
    pub fn width(&self) -> u32 {
        self.dims.width
    }

    /// Height of the framebuffer, in lines.
    pub fn height(&self) -> u32 {
        self.dims.height
    }

    /// Span inserts sent to the framebuffer so far (fragments pushed divided by this is how
    /// full the spans of the stream are; 0 where fragments pass straight through).
    pub fn span_inserts(&self) -> u64 {
        self.span_inserts
    }

    /// Fragments pushed but not yet in the framebuffer.
    pub fn pending(&self) -> usize {
        self.slots.iter().map(|s| s.mask.count_ones() as usize).sum()
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

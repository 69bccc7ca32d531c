//! Whole frames on every core: band-binned compositing with `rayon`.
//!
//! A frame's fragments arrive scattered over the screen, and a 1280x720 MLAB framebuffer
//! with `M = 4` holds 28 MiB of blending arrays, far more than a core's cache. The frame
//! compositor works in two passes, both parallel:
//!
//! ```text
//! bin:       for each chunk of CHUNK fragments of the stream (in parallel):
//!                for each fragment f, in submission order:
//!                    band = y(f) / band_lines
//!                    lists[chunk][band].push((x, y - band * band_lines), payload(f))
//! composite: for each band b of the framebuffer (bands_mut, in parallel):
//!                clear band b
//!                for chunk in 0..chunks, for entry in lists[chunk][b]:   // submission order
//!                    insert entry (MLAB: each 8-pixel span gathers its fragments in a
//!                    pending span insert, flushed when a lane repeats, when full and at
//!                    the end, so fragments of different primitives share span inserts)
//!                resolve band b into its lines of the output
//! ```
//!
//! Chunks are in stream order and each chunk's lists keep its fragments in stream order, so
//! a band reads its fragments in submission order: every pixel sees its fragments in
//! the order the stream gave them, which MLAB depends on (its merge is order dependent).
//! The result is byte-identical to inserting the whole stream, fragment by fragment, into
//! one framebuffer on one thread (tested in `lab/tests/frame.rs`). A band of `band_lines`
//! full lines is the tile: with `M = 4` and 1280 pixels a line holds 40 KiB of blending
//! arrays, so a band of 16 lines (640 KiB) stays in a core's L2 from its clear through its
//! inserts to its resolve. [`DEFAULT_BAND_LINES`] was picked by measurement
//! (`oit-lab bench --bands`, `docs/frame.md`).
//!
//! The baselines run through the same bins and the same bands, so the comparison is fair:
//! - **A-buffer**: per pixel a linked list of 12-byte nodes (RGBA8 + f32 depth as the
//!   quantized [`Row`], and a 32-bit next index) behind a 4-byte head, as in the paper's
//!   Table 1 note; resolve sorts each list by depth (stable, so on equal depth the later
//!   submission is in front) and composites front to back in f32.
//! - **OVER** (unsorted, `RGBA16F`) and **WBOIT** (eq. 7, `RGBA16F` accumulation + `R8`
//!   revealage): the same arithmetic as [`crate::methods`], targets stored as IEEE half
//!   (8 B/px) and unorm8 (1 B/px); their bins carry the f32 fragment (24 B).
//!
//! Every method writes the displayed RGBA8 frame ([`mlab::to_rgba8`] of the pixel over the
//! opaque background).

// Channel loops `for k in 0..3` index the target and the fragment at once, as in the
// blend equations (as in `methods`).
#![allow(clippy::needless_range_loop)]

use crate::methods::{Weight, r8_blend};
use crate::stream::{Frag, Stream};
use mlab::glam::{Vec3, Vec4};
use mlab::half::f16;
use mlab::lanes::{FragmentLanes, LANES};
use mlab::{Background, Framebuffer, Paper, Row, SpanFramebuffer, to_rgba8};
use rayon::prelude::*;

/// Lines per band when none is given: the fastest on the development machine for MLAB 4 at
/// 1280x720 on HAIR and PARTICLES (`docs/frame.md`).
pub const DEFAULT_BAND_LINES: u32 = 16;

/// Fragments per binning chunk (a unit of parallel binning work) by default.
pub const CHUNK: usize = 1 << 15;

/// Largest frame width and band height: positions are packed as `x | y << 16`.
pub const MAX_EXTENT: u32 = 1 << 16;

/// A binned fragment: its position inside its band and what the band pass needs of it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Entry<T> {
    /// `x | y << 16`, `y` relative to the band's first line.
    pub pos: u32,
    /// The payload ([`Row`] for MLAB and the A-buffer, [`Frag`] for OVER and WBOIT).
    pub data: T,
}

/// `n / d` as a multiply and a shift, exact for `n * d < 2^40` (every pixel index of a frame
/// up to 8192x8192 by any width up to 2^14, and any smaller case).
#[derive(Clone, Copy, Debug)]
struct Divider {
    d: u32,
    m: u64,
}

impl Divider {
    fn new(d: u32) -> Divider {
        let d = d.max(1);
        Divider {
            d,
            m: (1u64 << 40).div_ceil(d as u64),
        }
    }

    #[inline(always)]
    fn div(self, n: u32) -> u32 {
        ((n as u64 * self.m) >> 40) as u32
    }

    /// Whether [`div`](Self::div) is exact for every `n < limit`.
    fn exact_below(self, limit: u64) -> bool {
        limit.saturating_mul(self.d as u64) <= 1 << 40
    }
}

/// A stream's fragments binned by band, in submission order inside each band. The lists are
/// kept between frames (cleared, not freed): after the first frame binning allocates nothing.
#[derive(Debug, Default)]
pub struct Bins<T> {
    width: u32,
    height: u32,
    band_lines: u32,
    bands: usize,
    chunks: usize,
    /// Chunk-major: `lists[chunk * bands + band]`.
    lists: Vec<Vec<Entry<T>>>,
}

impl<T: Copy + Send + Sync> Bins<T> {
    /// No bins.
    pub fn new() -> Bins<T> {
        Bins {
            width: 0,
            height: 0,
            band_lines: 1,
            bands: 0,
            chunks: 0,
            lists: Vec::new(),
        }
    }

    /// Bin `stream` into bands of `band_lines` lines, in chunks of `chunk` fragments (the
    /// unit of parallel work; [`CHUNK`] unless testing). `payload` maps up to 8 consecutive
    /// fragments of the stream to their payloads and a mask of invalid ones; the first
    /// invalid fragment stops binning with an error naming it.
    pub fn fill<P>(&mut self, stream: &Stream, band_lines: u32, chunk: usize, payload: P) -> Result<(), String>
    where
        P: Fn(&[Frag]) -> ([T; LANES], u8) + Sync,
    {
        let (w, h) = (stream.width, stream.height);
        if w == 0 || h == 0 || w >= MAX_EXTENT || band_lines == 0 || band_lines >= MAX_EXTENT {
            return Err(format!(
                "frame {w}x{h} with bands of {band_lines} lines: width and band lines must be in 1..{MAX_EXTENT}"
            ));
        }
        let (by_width, by_band) = (Divider::new(w), Divider::new(band_lines));
        let pixels = stream.pixels() as u64;
        if !by_width.exact_below(pixels) || !by_band.exact_below(h as u64) {
            return Err(format!("frame {w}x{h} is too large to bin"));
        }
        let bands = h.div_ceil(band_lines) as usize;
        let chunk = chunk.max(1);
        let chunks = stream.frags.len().div_ceil(chunk);
        (self.width, self.height, self.band_lines, self.bands, self.chunks) = (w, h, band_lines, bands, chunks);
        if self.lists.len() < chunks * bands {
            self.lists.resize_with(chunks * bands, Vec::new);
        }
        let lists = &mut self.lists[..chunks * bands];
        let result = lists
            .par_chunks_mut(bands)
            .zip(stream.frags.par_chunks(chunk))
            .enumerate()
            .try_for_each(|(c, (lists, frags))| {
                for l in lists.iter_mut() {
                    l.clear();
                }
                for (g, group) in frags.chunks(LANES).enumerate() {
                    let (data, invalid) = payload(group);
                    if invalid != 0 {
                        return Err(c * chunk + g * LANES + invalid.trailing_zeros() as usize);
                    }
                    for (j, (f, d)) in group.iter().zip(data).enumerate() {
                        if f.pixel as u64 >= pixels {
                            return Err(c * chunk + g * LANES + j);
                        }
                        let y = by_width.div(f.pixel);
                        let x = f.pixel - y * w;
                        let band = by_band.div(y);
                        let pos = x | (y - band * band_lines) << 16;
                        if let Some(l) = lists.get_mut(band as usize) {
                            l.push(Entry { pos, data: d });
                        }
                    }
                }
                Ok(())
            });
        result.map_err(|i| match stream.frags.get(i) {
            Some(f) if f.pixel as u64 >= pixels => format!("fragment {i}: pixel {} outside the frame", f.pixel),
            Some(f) => match f.to_kernel() {
                Err(e) => format!("fragment {i}: {e}"),
                Ok(_) => format!("fragment {i}: refused"),
            },
            None => format!("fragment {i}: refused"),
        })
    }

    /// Number of bands.
    pub fn bands(&self) -> usize {
        self.bands
    }

    /// Lines per band.
    pub fn band_lines(&self) -> u32 {
        self.band_lines
    }

    /// The fragments of band `b`, in submission order.
    pub fn band(&self, b: usize) -> impl Iterator<Item = &Entry<T>> + '_ {
        (0..self.chunks)
            .filter_map(move |c| self.lists.get(c * self.bands + b))
            .flatten()
    }

    /// Number of fragments in band `b`.
    pub fn band_len(&self, b: usize) -> usize {
        (0..self.chunks)
            .filter_map(|c| self.lists.get(c * self.bands + b))
            .map(Vec::len)
            .sum()
    }
}

/// Quantize up to 8 consecutive fragments with the kernel's lanes (validation and rounding
/// identical to [`mlab::Fragment::premultiplied`] then [`mlab::Fragment::row`]).
pub fn quantize_rows(group: &[Frag]) -> ([Row; LANES], u8) {
    let mut lanes = FragmentLanes {
        color: [[0.0; LANES]; 3],
        alpha: [0.0; LANES],
        depth: [0.0; LANES],
    };
    for (i, f) in group.iter().enumerate().take(LANES) {
        lanes.color[0][i] = f.color[0];
        lanes.color[1][i] = f.color[1];
        lanes.color[2][i] = f.color[2];
        lanes.alpha[i] = f.alpha;
        lanes.depth[i] = f.depth;
    }
    let mask = (((1u16 << group.len().min(LANES)) - 1) & 0xff) as u8;
    let q = lanes.quantize_with::<Paper>(mask);
    (q.rows, q.invalid)
}

/// The fragments themselves (OVER and WBOIT blend the f32 fragment).
pub fn copy_frags(group: &[Frag]) -> ([Frag; LANES], u8) {
    let mut out = [Frag {
        pixel: 0,
        depth: 0.0,
        color: [0.0; 3],
        alpha: 0.0,
    }; LANES];
    for (o, f) in out.iter_mut().zip(group) {
        *o = *f;
    }
    (out, 0)
}

/// The frame-level methods.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameMethod {
    /// MLAB with `M = 4` through the lanes kernel ([`SpanFramebuffer`]).
    Mlab4,
    /// The A-buffer: per-pixel linked lists, sorted at resolve.
    ABuffer,
    /// WBOIT, weight eq. 7.
    Wboit,
    /// OVER in submission order, unsorted.
    Over,
}

impl FrameMethod {
    /// All four, in table order.
    pub const ALL: [FrameMethod; 4] = [
        FrameMethod::Mlab4,
        FrameMethod::ABuffer,
        FrameMethod::Wboit,
        FrameMethod::Over,
    ];

    /// Display name.
    pub fn name(self) -> &'static str {
        match self {
            FrameMethod::Mlab4 => "MLAB 4 lanes",
            FrameMethod::ABuffer => "A-buffer",
            FrameMethod::Wboit => "WBOIT eq.7",
            FrameMethod::Over => "OVER unsorted",
        }
    }

    /// Bytes of the method's per-frame storage for `pixels` pixels and `fragments`
    /// fragments (the paper's Table 1 accounting: MLAB 8 B per row, the A-buffer 12 B per
    /// fragment plus a 4 B head per pixel, WBOIT `RGBA16F` + `R8`, OVER `RGBA16F`).
    pub fn frame_bytes(self, pixels: usize, fragments: usize) -> usize {
        match self {
            FrameMethod::Mlab4 => 32 * pixels,
            FrameMethod::ABuffer => 4 * pixels + 12 * fragments,
            FrameMethod::Wboit => 9 * pixels,
            FrameMethod::Over => 8 * pixels,
        }
    }
}

/// A frame compositor: the bins and the per-frame storage of every method, kept between
/// frames. Work runs on the current `rayon` pool (`ThreadPool::install` chooses the thread
/// count).
#[derive(Debug)]
pub struct Compositor {
    /// Lines per band.
    pub band_lines: u32,
    /// Fragments per binning chunk.
    pub chunk: usize,
    rows: Bins<Row>,
    frags: Bins<Frag>,
    mlab: Vec<Row>,
    heads: Vec<u32>,
    nodes: Vec<(Row, u32)>,
    half: Vec<[f16; 4]>,
    reveal: Vec<u8>,
}

impl Default for Compositor {
    fn default() -> Self {
        Compositor::new(DEFAULT_BAND_LINES)
    }
}

/// "No next node" in the A-buffer's lists.
const NIL: u32 = u32::MAX;

fn resize<T: Clone>(v: &mut Vec<T>, n: usize, fill: T) {
    v.clear();
    v.resize(n, fill);
}

impl Compositor {
    /// A compositor with bands of `band_lines` lines.
    pub fn new(band_lines: u32) -> Compositor {
        Compositor {
            band_lines,
            chunk: CHUNK,
            rows: Bins::new(),
            frags: Bins::new(),
            mlab: Vec::new(),
            heads: Vec::new(),
            nodes: Vec::new(),
            half: Vec::new(),
            reveal: Vec::new(),
        }
    }

    /// Composite `stream` with `method` into `out` (`width * height` RGBA8 pixels, row major),
    /// binning included.
    pub fn render(&mut self, method: FrameMethod, stream: &Stream, out: &mut [[u8; 4]]) -> Result<(), String> {
        if out.len() != stream.pixels() {
            return Err(format!(
                "output has {} pixels, the frame {}",
                out.len(),
                stream.pixels()
            ));
        }
        match method {
            FrameMethod::Mlab4 => self.mlab::<4>(stream, out),
            FrameMethod::ABuffer => self.abuffer(stream, out),
            FrameMethod::Wboit => self.wboit(stream, out),
            FrameMethod::Over => self.over(stream, out),
        }
    }

    /// The MLAB framebuffer of the last [`mlab`](Self::mlab) frame (span arrangement).
    pub fn mlab_rows(&self) -> &[Row] {
        &self.mlab
    }

    /// MLAB's binning alone (quantization included), for the bench's breakdown.
    pub fn bin_rows(&mut self, stream: &Stream) -> Result<(), String> {
        self.rows.fill(stream, self.band_lines, self.chunk, quantize_rows)
    }

    /// MLAB with `M` rows: bin, then per band (in parallel) clear, span inserts, resolve.
    pub fn mlab<const M: usize>(&mut self, stream: &Stream, out: &mut [[u8; 4]]) -> Result<(), String> {
        self.rows.fill(stream, self.band_lines, self.chunk, quantize_rows)?;
        let (w, h, lines) = (stream.width, stream.height, self.band_lines);
        let n = SpanFramebuffer::<M, Paper>::rows_needed(w, h).map_err(|e| e.to_string())?;
        if self.mlab.len() != n {
            resize(&mut self.mlab, n, Row::EMPTY);
        }
        let mut fb = SpanFramebuffer::<M, Paper>::new(&mut self.mlab, w, h).map_err(|e| e.to_string())?;
        let bg = Background::Opaque(Vec3::from(stream.background));
        let bins = &self.rows;
        let work: Vec<_> = fb
            .bands_mut(lines)
            .zip(out.chunks_mut((w * lines) as usize))
            .enumerate()
            .collect();
        work.into_par_iter().try_for_each(|(b, (mut band, out))| {
            band.clear();
            mlab_band(&mut band, bins.band(b)).map_err(|e| e.to_string())?;
            band.resolve_rgba8(out, bg).map_err(|e| e.to_string())
        })
    }

    /// The A-buffer: bin, then per band (in parallel) build the lists and resolve.
    pub fn abuffer(&mut self, stream: &Stream, out: &mut [[u8; 4]]) -> Result<(), String> {
        self.rows.fill(stream, self.band_lines, self.chunk, quantize_rows)?;
        let (w, lines) = (stream.width as usize, self.band_lines as usize);
        if self.heads.len() != stream.pixels() {
            resize(&mut self.heads, stream.pixels(), NIL);
        }
        if self.nodes.len() < stream.frags.len() {
            resize(&mut self.nodes, stream.frags.len(), (Row::EMPTY, NIL));
        }
        let bg = Vec3::from(stream.background);
        let bins = &self.rows;
        // Each band's node pool: as many nodes as the band has fragments.
        let mut pools = Vec::with_capacity(bins.bands());
        let mut rest = &mut self.nodes[..];
        for b in 0..bins.bands() {
            let (pool, r) = rest.split_at_mut(bins.band_len(b));
            pools.push(pool);
            rest = r;
        }
        let work: Vec<_> = self
            .heads
            .chunks_mut(w * lines)
            .zip(out.chunks_mut(w * lines))
            .zip(pools)
            .enumerate()
            .collect();
        work.into_par_iter().for_each(|(b, ((heads, out), nodes))| {
            heads.fill(NIL);
            for (i, e) in bins.band(b).enumerate() {
                let p = (e.pos & 0xffff) as usize + (e.pos >> 16) as usize * w;
                if let (Some(head), Some(node)) = (heads.get_mut(p), nodes.get_mut(i)) {
                    *node = (e.data, *head);
                    *head = i as u32;
                }
            }
            let mut list: Vec<Row> = Vec::new();
            for (head, o) in heads.iter().zip(out.iter_mut()) {
                list.clear();
                let mut i = *head;
                while let Some(&(row, next)) = nodes.get(i as usize) {
                    list.push(row);
                    i = next;
                }
                // Lists run newest first; a stable sort keeps the later submission in front
                // on equal depth.
                list.sort_by(|a, b| a.depth().total_cmp(&b.depth()));
                let (mut c, mut t) = (Vec3::ZERO, 1.0f32);
                for r in &list {
                    let [cr, cg, cb, tr] = r.rgbt();
                    c += t * Vec3::new(cr as f32, cg as f32, cb as f32) * (1.0 / 255.0);
                    t *= tr as f32 * (1.0 / 255.0);
                }
                *o = to_rgba8((c + t * bg).extend(1.0));
            }
        });
        Ok(())
    }

    /// WBOIT eq. 7 into `RGBA16F` + `R8` targets, per band in parallel.
    pub fn wboit(&mut self, stream: &Stream, out: &mut [[u8; 4]]) -> Result<(), String> {
        self.frags.fill(stream, self.band_lines, self.chunk, copy_frags)?;
        let (w, lines) = (stream.width as usize, self.band_lines as usize);
        if self.half.len() != stream.pixels() || self.reveal.len() != stream.pixels() {
            resize(&mut self.half, stream.pixels(), [f16::ZERO; 4]);
            resize(&mut self.reveal, stream.pixels(), 255u8);
        }
        let bg = stream.background;
        let bins = &self.frags;
        let work: Vec<_> = self
            .half
            .chunks_mut(w * lines)
            .zip(self.reveal.chunks_mut(w * lines))
            .zip(out.chunks_mut(w * lines))
            .enumerate()
            .collect();
        work.into_par_iter().for_each(|(b, ((acc, reveal), out))| {
            acc.fill([f16::ZERO; 4]);
            reveal.fill(255);
            for e in bins.band(b) {
                let p = (e.pos & 0xffff) as usize + (e.pos >> 16) as usize * w;
                let f = &e.data;
                let (Some(a), Some(r)) = (acc.get_mut(p), reveal.get_mut(p)) else {
                    continue;
                };
                let wt = Weight::Eq7.eval(f.color, f.alpha, f.depth, 0.0);
                for k in 0..3 {
                    a[k] = f16::from_f32(a[k].to_f32() + f.color[k] * wt);
                }
                a[3] = f16::from_f32(a[3].to_f32() + f.alpha * wt);
                *r = r8_blend(*r, 1.0 - f.alpha);
            }
            for ((a, r), o) in acc.iter().zip(reveal.iter()).zip(out.iter_mut()) {
                let rv = *r as f32 / 255.0;
                let d = a[3].to_f32().max(1e-5);
                let c: [f32; 3] = std::array::from_fn(|k| finite_or_zero(a[k].to_f32() / d * (1.0 - rv) + bg[k] * rv));
                *o = to_rgba8(Vec4::new(c[0], c[1], c[2], 1.0));
            }
        });
        Ok(())
    }

    /// OVER in submission order into an `RGBA16F` target, per band in parallel.
    pub fn over(&mut self, stream: &Stream, out: &mut [[u8; 4]]) -> Result<(), String> {
        self.frags.fill(stream, self.band_lines, self.chunk, copy_frags)?;
        let (w, lines) = (stream.width as usize, self.band_lines as usize);
        let bg = stream.background.map(f16::from_f32);
        if self.half.len() != stream.pixels() {
            resize(&mut self.half, stream.pixels(), [f16::ZERO; 4]);
        }
        let bins = &self.frags;
        let work: Vec<_> = self
            .half
            .chunks_mut(w * lines)
            .zip(out.chunks_mut(w * lines))
            .enumerate()
            .collect();
        work.into_par_iter().for_each(|(b, (target, out))| {
            target.fill([bg[0], bg[1], bg[2], f16::ONE]);
            for e in bins.band(b) {
                let p = (e.pos & 0xffff) as usize + (e.pos >> 16) as usize * w;
                let f = &e.data;
                let Some(c) = target.get_mut(p) else { continue };
                for k in 0..3 {
                    c[k] = f16::from_f32(f.color[k] + c[k].to_f32() * (1.0 - f.alpha));
                }
                c[3] = f16::from_f32(c[3].to_f32() * (1.0 - f.alpha));
            }
            for (c, o) in target.iter().zip(out.iter_mut()) {
                *o = to_rgba8(Vec4::new(c[0].to_f32(), c[1].to_f32(), c[2].to_f32(), 1.0));
            }
        });
        Ok(())
    }
}

/// MLAB without bins, on the calling thread: the whole stream in submission order into one
/// framebuffer over `storage` (consecutive fragments of one span grouped as in the bands),
/// then the lanes resolve. The comparison point for binning: fragments land all over the
/// 28 MiB framebuffer.
pub fn mlab_unbinned<const M: usize>(
    stream: &Stream,
    storage: &mut Vec<Row>,
    out: &mut [[u8; 4]],
) -> Result<(), String> {
    let (w, h) = (stream.width, stream.height);
    if w >= MAX_EXTENT || h >= MAX_EXTENT {
        return Err(format!("frame {w}x{h} too large"));
    }
    let n = SpanFramebuffer::<M, Paper>::rows_needed(w, h).map_err(|e| e.to_string())?;
    if storage.len() != n {
        resize(storage, n, Row::EMPTY);
    }
    let mut fb = SpanFramebuffer::<M, Paper>::new_cleared(storage, w, h).map_err(|e| e.to_string())?;
    let by_width = Divider::new(w);
    if !by_width.exact_below(stream.pixels() as u64) {
        return Err(format!("frame {w}x{h} too large"));
    }
    let mut pending = Pending::new(&fb);
    for (g, group) in stream.frags.chunks(LANES).enumerate() {
        let (rows, invalid) = quantize_rows(group);
        if invalid != 0 {
            return Err(format!(
                "fragment {}: invalid",
                g * LANES + invalid.trailing_zeros() as usize
            ));
        }
        for (f, r) in group.iter().zip(rows) {
            let y = by_width.div(f.pixel);
            let e = Entry {
                pos: (f.pixel - y * w) | y << 16,
                data: r,
            };
            pending.push(&mut fb, &e).map_err(|e| e.to_string())?;
        }
    }
    pending.flush_all(&mut fb).map_err(|e| e.to_string())?;
    fb.resolve_rgba8(out, Background::Opaque(Vec3::from(stream.background)))
        .map_err(|e| e.to_string())
}

/// Non-finite results (a half target that overflowed) are shown black, as in the lab.
fn finite_or_zero(x: f32) -> f32 {
    if x.is_finite() { x } else { 0.0 }
}

/// Pending span inserts, one per 8-pixel span of a framebuffer: each span collects fragments
/// (one row per lane) and goes into the framebuffer as one span insert when a fragment arrives
/// for a lane that is already pending (so each pixel still sees its fragments in submission
/// order), when all 8 lanes are pending, and at [`Pending::flush_all`]. Different pixels are
/// independent in MLAB, so fragments of different primitives share span inserts and the
/// result is byte-identical to inserting the stream fragment by fragment.
struct Pending {
    spans_per_line: usize,
    slots: Vec<([Row; LANES], u8)>,
}

impl Pending {
    fn new<const M: usize>(fb: &SpanFramebuffer<'_, M, Paper>) -> Pending {
        let spans_per_line = fb.width().div_ceil(LANES as u32) as usize;
        Pending {
            spans_per_line,
            slots: vec![([Row::EMPTY; LANES], 0u8); spans_per_line * fb.height() as usize],
        }
    }

    fn flush<const M: usize>(
        spans_per_line: usize,
        fb: &mut SpanFramebuffer<'_, M, Paper>,
        s: usize,
        rows: &[Row; LANES],
        mask: u8,
    ) -> Result<(), mlab::FramebufferError> {
        let (y, sx) = (s / spans_per_line, s % spans_per_line);
        fb.insert_span((sx * LANES) as u32, y as u32, rows, mask)
    }

    fn push<const M: usize>(
        &mut self,
        fb: &mut SpanFramebuffer<'_, M, Paper>,
        e: &Entry<Row>,
    ) -> Result<(), mlab::FramebufferError> {
        let (x, y) = ((e.pos & 0xffff) as usize, (e.pos >> 16) as usize);
        let (s, lane) = (y * self.spans_per_line + x / LANES, x % LANES);
        let Some((rows, mask)) = self.slots.get_mut(s) else {
            return Err(mlab::FramebufferError::OutOfBounds {
                x: x as u32,
                y: y as u32,
                width: fb.width(),
                height: fb.height(),
            });
        };
        if *mask & (1 << lane) != 0 {
            Self::flush(self.spans_per_line, fb, s, rows, *mask)?;
            *mask = 0;
        }
        rows[lane] = e.data;
        *mask |= 1 << lane;
        if *mask == 0xff {
            Self::flush(self.spans_per_line, fb, s, rows, 0xff)?;
            *mask = 0;
        }
        Ok(())
    }

    fn flush_all<const M: usize>(
        &mut self,
        fb: &mut SpanFramebuffer<'_, M, Paper>,
    ) -> Result<(), mlab::FramebufferError> {
        for (s, (rows, mask)) in self.slots.iter_mut().enumerate() {
            if *mask != 0 {
                Self::flush(self.spans_per_line, fb, s, rows, *mask)?;
                *mask = 0;
            }
        }
        Ok(())
    }
}

/// Insert one band's fragments through [`Pending`] span inserts.
fn mlab_band<'e, const M: usize>(
    band: &mut SpanFramebuffer<'_, M, Paper>,
    entries: impl Iterator<Item = &'e Entry<Row>>,
) -> Result<(), mlab::FramebufferError> {
    let mut pending = Pending::new(band);
    for e in entries {
        pending.push(band, e)?;
    }
    pending.flush_all(band)
}

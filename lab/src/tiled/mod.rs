//! Whole frames without storing fragments: the scene's primitives are binned by their screen
//! bounds into bands of lines, each band's into tiles of columns, and each worker (a `rayon`
//! task per band) takes the band's tiles one by one: it clears its own tile-sized target,
//! rasterizes the tile's primitives in submission order straight into it (for MLAB: span
//! inserts of the kernel's [`SpanFramebuffer`], fragments live in the rasterizer's lanes
//! only), and resolves the tile into its part of the output:
//!
//! ```text
//! bin:   for each primitive p, in submission order: push p to every band its box meets
//! band:  (in parallel, one task per band b)
//!        bin band b's primitives into its tiles (whole lines: one tile)
//!        for each tile t of band b:
//!            clear the worker's target (tile-sized, reused)
//!            for p in t's list (submission order): rasterize p clipped to t
//!                for each 8-pixel span: quantize the lanes, insert the span
//!            resolve the target into t's pixels of the output
//! ```
//!
//! Each pixel sees its fragments in submission order whatever the tile size and thread
//! count, so the frame is byte-identical to one tile over the whole frame on one thread
//! (tested in `lab/tests/tiled.rs`, also against the scalar kernel over the stream).
//! Memory: one tile-sized target per worker, the output, the primitives and their bins;
//! nothing grows with the fragment count except the A-buffer's per-tile fragment arrays, and
//! the blending arrays do not grow with the frame size.

mod abuffer;
mod bins;

pub use bins::PrimBins;

use crate::methods::{Arith, Method, Weight, over_step, wboit_resolve, wboit_step};
use crate::scenes::{Clip, Primitives, SpanLanes};
use mlab::glam::{Vec3, Vec4};
use mlab::half::f16;
use mlab::lanes::LANES;
use mlab::{Arithmetic, Background, Framebuffer, Paper, Row, SpanFramebuffer, Unbiased, to_rgba8};
use rayon::prelude::*;
use std::sync::Mutex;

/// Lines per band when none is given (`oit-lab bench --band-lines`, `docs/frame.md`).
pub const DEFAULT_BAND_LINES: u32 = 16;

/// Columns per tile when none is given: 0, whole lines (`oit-lab bench --tile-width`,
/// `docs/frame.md`).
pub const DEFAULT_TILE_WIDTH: u32 = 0;

/// A tile size: `lines` lines per band, `width` columns per tile (0: whole lines, a band is
/// one tile). Written `L` (whole lines) or `WxL`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TileSize {
    /// Columns per tile, rounded up to a multiple of 8 when used; 0: whole lines.
    pub width: u32,
    /// Lines per band (at least 1 when used).
    pub lines: u32,
}

impl TileSize {
    /// Whole-line bands of `lines` lines.
    pub fn band(lines: u32) -> TileSize {
        TileSize { width: 0, lines }
    }
}

impl Default for TileSize {
    fn default() -> TileSize {
        TileSize {
            width: DEFAULT_TILE_WIDTH,
            lines: DEFAULT_BAND_LINES,
        }
    }
}

impl std::fmt::Display for TileSize {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}x{}", self.width, self.lines)
    }
}

impl std::str::FromStr for TileSize {
    type Err = String;

    /// `L` (whole-line bands of `L` lines) or `WxL` (`W` 0: whole lines).
    fn from_str(s: &str) -> Result<TileSize, String> {
        let bad = || format!("tile size '{s}': expected L or WxL (W columns, 0 for whole lines; L lines >= 1)");
        let (w, l) = match s.split_once('x') {
            Some((w, l)) => (w.parse().map_err(|_| bad())?, l.parse().map_err(|_| bad())?),
            None => (0, s.parse().map_err(|_| bad())?),
        };
        if l == 0 {
            return Err(bad());
        }
        Ok(TileSize { width: w, lines: l })
    }
}

/// The methods of the tiled renderer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TiledMethod {
    /// MLAB with `M = 4`, span inserts, the kernel's default arithmetic ([`Unbiased`]).
    Mlab4,
    /// MLAB with `M = 4`, span inserts, the paper's arithmetic ([`Paper`]).
    Mlab4Paper,
    /// The A-buffer: per band a fragment array, counting sort by pixel, insertion sort by
    /// depth (stable; on equal depth the later submission in front), f32 front to back.
    ABuffer,
    /// WBOIT, weight eq. 7, `RGBA16F` + `R8` targets.
    Wboit,
    /// OVER in submission order, unsorted, `RGBA16F` target.
    Over,
}

impl TiledMethod {
    /// Every method, in table order.
    pub const ALL: [TiledMethod; 5] = [
        TiledMethod::Mlab4,
        TiledMethod::Mlab4Paper,
        TiledMethod::ABuffer,
        TiledMethod::Wboit,
        TiledMethod::Over,
    ];

    /// Display name.
    pub fn name(self) -> &'static str {
        match self {
            TiledMethod::Mlab4 => "MLAB 4",
            TiledMethod::Mlab4Paper => "MLAB 4 Paper",
            TiledMethod::ABuffer => "A-buffer",
            TiledMethod::Wboit => "WBOIT eq.7",
            TiledMethod::Over => "OVER unsorted",
        }
    }

    /// Short name for the command line (`mlab4`, `mlab4-paper`, `abuffer`, `wboit`, `over`).
    pub fn key(self) -> &'static str {
        match self {
            TiledMethod::Mlab4 => "mlab4",
            TiledMethod::Mlab4Paper => "mlab4-paper",
            TiledMethod::ABuffer => "abuffer",
            TiledMethod::Wboit => "wboit",
            TiledMethod::Over => "over",
        }
    }

    /// The method with this short name.
    pub fn from_key(s: &str) -> Option<TiledMethod> {
        TiledMethod::ALL.into_iter().find(|m| m.key() == s)
    }
}

/// Bytes of a method's per-frame target for `pixels` pixels, `fragments` fragments, and the
/// RGBA8 output: the lab's one memory accounting, [`Method::storage`], of the same method (the
/// A-buffer as the paper's Table 1 counts it: 12 B per fragment + a 4 B head per pixel). The
/// tiled renderer holds a tile's target per worker, not the frame's: pass the tile's pixels
/// (and, for the A-buffer, [`TiledRenderer::abuffer_peak_fragments`]).
pub fn storage_bytes(method: TiledMethod, pixels: usize, fragments: usize) -> usize {
    let same = match method {
        TiledMethod::Mlab4 => Method::Mlab(4),
        TiledMethod::Mlab4Paper => Method::MlabWith(4, Arith::Paper),
        TiledMethod::ABuffer => Method::Reference,
        TiledMethod::Wboit => Method::Wboit(Weight::Eq7),
        TiledMethod::Over => Method::Over,
    };
    same.storage().bytes(pixels, fragments) + 4 * pixels
}

/// A worker's tile-sized targets and tile lists, reused from tile to tile and frame to frame.
#[derive(Debug, Default)]
struct Worker {
    /// Per tile of the current band, its primitives in submission order.
    tiles: Vec<Vec<u32>>,
    target: Target,
}

#[derive(Debug, Default)]
struct Target {
    mlab: Vec<Row>,
    half: Vec<[f16; 4]>,
    reveal: Vec<u8>,
    abuffer: abuffer::Scratch,
    /// The most fragments one A-buffer tile held since the last frame began.
    abuffer_peak: usize,
    /// A tile's RGBA8 pixels when the tile is narrower than the frame.
    pixels: Vec<[u8; 4]>,
}

impl Target {
    fn bytes(&self) -> usize {
        self.mlab.capacity() * std::mem::size_of::<Row>()
            + self.half.capacity() * 8
            + self.reveal.capacity()
            + self.abuffer.bytes()
            + self.pixels.capacity() * 4
    }
}

/// The tiled renderer: primitive bins and one tile-sized target per worker, kept between
/// frames. Work runs on the current `rayon` pool (`ThreadPool::install` chooses the thread
/// count).
#[derive(Debug, Default)]
pub struct TiledRenderer {
    /// Lines per band (and per tile).
    pub band_lines: u32,
    /// Columns per tile, rounded up to a multiple of 8; 0: whole lines (a band is one tile).
    pub tile_width: u32,
    bins: PrimBins,
    workers: Vec<Mutex<Worker>>,
}

fn grow<T: Clone>(v: &mut Vec<T>, n: usize, fill: T) {
    if v.len() < n {
        v.resize(n, fill);
    }
}

/// The id of frame pixel `(x, y)` in the hashes that seed the kernel's dithers
/// ([`mlab::Fragment::hash`]): `y * width + x` of the whole frame, so that a tile's target (a
/// framebuffer of the tile's size) quantizes and merges each fragment as the whole frame's
/// framebuffer would: the spans are quantized at [`frame_pixel`] and inserted with their
/// hashes ([`Framebuffer::insert_span_hashed`]).
fn frame_pixel(scene: &Primitives, x: u32, y: u32) -> u32 {
    y.wrapping_mul(scene.width).wrapping_add(x)
}

/// Per span, the fragments `popcount(mask)`.
fn count(mask: u8) -> u64 {
    mask.count_ones() as u64
}

/// The tiles of band `b` (lines `y0..y1`) of a `width`-wide frame with tiles of `tile_width`
/// columns (0: one tile): their clips, and each tile's primitives from the band's list
/// `prims`, in submission order, into `lists` (reused).
fn tiles_of_band<'l>(
    scene: &Primitives,
    prims: &'l [u32],
    (y0, y1): (u32, u32),
    tile_width: u32,
    lists: &'l mut Vec<Vec<u32>>,
) -> impl Iterator<Item = (Clip, &'l [u32])> {
    let width = scene.width;
    let tw = tile_columns(tile_width, width);
    let n = width.div_ceil(tw.max(1)) as usize;
    let whole = n <= 1;
    if !whole {
        if lists.len() < n {
            lists.resize_with(n, Vec::new);
        }
        for l in &mut lists[..n] {
            l.clear();
        }
        for &i in prims {
            let p = &scene.prims[i as usize];
            let (t0, t1) = ((p.x0 / tw) as usize, ((p.x1 - 1) / tw) as usize);
            for l in lists.iter_mut().take((t1 + 1).min(n)).skip(t0) {
                l.push(i);
            }
        }
    }
    let lists: &'l [Vec<u32>] = lists;
    (0..n.max(1)).map(move |t| {
        let x0 = t as u32 * tw;
        let clip = Clip {
            x0,
            y0,
            x1: (x0 + tw).min(width),
            y1,
        };
        (clip, if whole { prims } else { lists[t].as_slice() })
    })
}

/// Columns per tile for `tile_width` (0: the frame's width) in a `width`-wide frame: a
/// multiple of 8, at least 8.
fn tile_columns(tile_width: u32, width: u32) -> u32 {
    let w = if tile_width == 0 { width } else { tile_width.min(width) };
    w.max(1).next_multiple_of(LANES as u32)
}

/// Run `f` on a tile's RGBA8 pixels (`clip`'s width x height, row major) and copy them into
/// the band's output `out` (lines of `stride` pixels from the band's first line); a tile as
/// wide as the frame writes straight into `out`.
fn with_tile_pixels<R>(
    pixels: &mut Vec<[u8; 4]>,
    out: &mut [[u8; 4]],
    stride: usize,
    clip: Clip,
    f: impl FnOnce(&mut [[u8; 4]]) -> R,
) -> R {
    let (tw, th) = ((clip.x1 - clip.x0) as usize, (clip.y1 - clip.y0) as usize);
    if clip.x0 == 0 && tw == stride {
        return f(&mut out[..tw * th]);
    }
    grow(pixels, tw * th, [0; 4]);
    let r = f(&mut pixels[..tw * th]);
    for (src, dst) in pixels.chunks_exact(tw).zip(out.chunks_mut(stride)).take(th) {
        dst[clip.x0 as usize..clip.x0 as usize + tw].copy_from_slice(src);
    }
    r
}

impl TiledRenderer {
    /// A renderer with bands of `band_lines` lines, each one tile (whole lines).
    pub fn new(band_lines: u32) -> TiledRenderer {
        TiledRenderer {
            band_lines: band_lines.max(1),
            ..TiledRenderer::default()
        }
    }

    /// A renderer with tiles of `tile.width` columns (rounded up to a multiple of 8; 0: whole
    /// lines) and `tile.lines` lines.
    pub fn tiled(tile: TileSize) -> TiledRenderer {
        TiledRenderer {
            tile_width: tile.width,
            ..TiledRenderer::new(tile.lines)
        }
    }

    /// The bins of the last frame.
    pub fn bins(&self) -> &PrimBins {
        &self.bins
    }

    /// Bytes of the renderer's storage held now (the workers' targets and tile lists, the
    /// bins; as allocated).
    pub fn held_bytes(&self) -> usize {
        let workers: usize = self
            .workers
            .iter()
            .map(|w| {
                let w = w.lock().unwrap_or_else(|e| e.into_inner());
                w.target.bytes()
                    + w.tiles.capacity() * std::mem::size_of::<Vec<u32>>()
                    + w.tiles.iter().map(|l| l.capacity() * 4).sum::<usize>()
            })
            .sum();
        self.bins.bytes() + workers
    }

    /// The most fragments one tile of the last A-buffer frame held.
    pub fn abuffer_peak_fragments(&self) -> usize {
        self.workers
            .iter()
            .map(|w| w.lock().unwrap_or_else(|e| e.into_inner()).target.abuffer_peak)
            .max()
            .unwrap_or(0)
    }

    /// Render `scene` with `method` into `out` (`width * height` RGBA8 pixels, row major),
    /// binning included; returns the number of fragments.
    pub fn render(&mut self, method: TiledMethod, scene: &Primitives, out: &mut [[u8; 4]]) -> Result<u64, String> {
        let pixels = scene.width as usize * scene.height as usize;
        if out.len() != pixels {
            return Err(format!("output has {} pixels, the frame {pixels}", out.len()));
        }
        self.bins.fill(scene, self.band_lines);
        let threads = rayon::current_num_threads().max(1);
        if self.workers.len() < threads {
            self.workers.resize_with(threads, Mutex::default);
        }
        for w in &self.workers {
            w.lock().unwrap_or_else(|e| e.into_inner()).target.abuffer_peak = 0;
        }
        let tile = |t: &mut Target, prims: &[u32], clip: Clip, out: &mut [[u8; 4]]| match method {
            TiledMethod::Mlab4 => mlab_tile::<Unbiased>(t, scene, prims, clip, out),
            TiledMethod::Mlab4Paper => mlab_tile::<Paper>(t, scene, prims, clip, out),
            TiledMethod::ABuffer => abuffer_tile(t, scene, prims, clip, out),
            TiledMethod::Wboit => wboit_tile(t, scene, prims, clip, out),
            TiledMethod::Over => over_tile(t, scene, prims, clip, out),
        };
        let (w, h, lines) = (scene.width, scene.height, self.bins.band_lines());
        let (bins, workers, tile_width) = (&self.bins, &self.workers, self.tile_width);
        out.par_chunks_mut((w * lines) as usize)
            .enumerate()
            // One band per task: rayon's adaptive split would hand a thread runs of bands
            // that another thread cannot take once it is idle (docs/frame.md).
            .with_max_len(1)
            .map(|(b, out)| {
                let i = rayon::current_thread_index().unwrap_or(0) % workers.len();
                let mut guard = workers[i].lock().unwrap_or_else(|e| e.into_inner());
                let Worker { tiles, target } = &mut *guard;
                let y0 = b as u32 * lines;
                let mut n = 0;
                for (clip, prims) in tiles_of_band(scene, bins.band(b), (y0, (y0 + lines).min(h)), tile_width, tiles) {
                    n += tile(target, prims, clip, out)?;
                }
                Ok(n)
            })
            .sum()
    }
}

/// The rows of the worker's MLAB target for `clip`, as a cleared span framebuffer of the
/// tile's size.
fn mlab_target<'t, A: Arithmetic>(rows: &'t mut Vec<Row>, clip: Clip) -> Result<SpanFramebuffer<'t, 4, A>, String> {
    let (tw, th) = (clip.x1 - clip.x0, clip.y1 - clip.y0);
    let n = SpanFramebuffer::<4, A>::rows_needed(tw, th).map_err(|e| e.to_string())?;
    grow(rows, n, Row::EMPTY);
    SpanFramebuffer::<4, A>::new_cleared(&mut rows[..n], tw, th).map_err(|e| e.to_string())
}

/// Resolve a tile's MLAB target into the band's output (`out`: lines of `stride` pixels from
/// the tile's first line).
fn mlab_resolve<A: Arithmetic>(
    fb: &SpanFramebuffer<'_, 4, A>,
    bg: Background,
    out: &mut [[u8; 4]],
    stride: usize,
    x0: u32,
) {
    let tw = fb.width() as usize;
    for (y, line) in out.chunks_mut(stride).take(fb.height() as usize).enumerate() {
        let Some(line) = line.get_mut(x0 as usize..x0 as usize + tw) else {
            continue;
        };
        for (s, o) in line.chunks_mut(LANES).enumerate() {
            let px = fb.resolve_span_rgba8(s as u32, y as u32, bg);
            o.copy_from_slice(&px[..o.len()]);
        }
    }
}

/// One MLAB 4 tile: rasterize `prims` clipped to `clip` straight into span inserts, resolve
/// into `out` (the band's output); returns the fragment count.
fn mlab_tile<A: Arithmetic>(
    t: &mut Target,
    scene: &Primitives,
    prims: &[u32],
    clip: Clip,
    out: &mut [[u8; 4]],
) -> Result<u64, String> {
    let mut fb = mlab_target::<A>(&mut t.mlab, clip)?;
    let (mut n, mut invalid, mut err) = (0u64, 0u8, None);
    for &i in prims {
        scene.prims[i as usize].raster(clip, &mut |x, y, mask, l: &SpanLanes| {
            let q = l.quantize_at::<A>(mask, frame_pixel(scene, x, y));
            invalid |= q.invalid;
            n += count(mask);
            if let Err(e) = fb.insert_span_hashed(x - clip.x0, y - clip.y0, &q.rows, &q.hashes, q.valid) {
                err.get_or_insert(e);
            }
        });
    }
    if let Some(e) = err {
        return Err(e.to_string());
    }
    if invalid != 0 {
        return Err("a primitive emitted an invalid fragment".into());
    }
    let bg = Background::Opaque(Vec3::from(scene.background));
    mlab_resolve(&fb, bg, out, scene.width as usize, clip.x0);
    Ok(n)
}

/// Rasterize `prims` clipped to `clip` and call `f(i, lane, lanes)` for every fragment, `i`
/// its pixel in the tile (row major), `lane` its lane in `lanes`; returns the fragment count.
fn each_fragment(scene: &Primitives, prims: &[u32], clip: Clip, mut f: impl FnMut(usize, usize, &SpanLanes)) -> u64 {
    let tw = (clip.x1 - clip.x0) as usize;
    let mut n = 0;
    for &i in prims {
        scene.prims[i as usize].raster(clip, &mut |x, y, mask, l: &SpanLanes| {
            n += count(mask);
            let row = (y - clip.y0) as usize * tw + (x - clip.x0) as usize;
            for lane in (0..LANES).filter(|&lane| mask & (1 << lane) != 0) {
                f(row + lane, lane, l);
            }
        });
    }
    n
}

/// One OVER tile (unsorted, `RGBA16F` target).
fn over_tile(
    t: &mut Target,
    scene: &Primitives,
    prims: &[u32],
    clip: Clip,
    out: &mut [[u8; 4]],
) -> Result<u64, String> {
    let (tw, th) = ((clip.x1 - clip.x0) as usize, (clip.y1 - clip.y0) as usize);
    grow(&mut t.half, tw * th, [f16::ZERO; 4]);
    let target = &mut t.half[..tw * th];
    let bg = scene.background.map(f16::from_f32);
    target.fill([bg[0], bg[1], bg[2], f16::ONE]);
    let n = each_fragment(scene, prims, clip, |i, lane, l| {
        let Some(px) = target.get_mut(i) else { return };
        let mut c = [px[0].to_f32(), px[1].to_f32(), px[2].to_f32()];
        let mut t = px[3].to_f32();
        let color = [l.color[0][lane], l.color[1][lane], l.color[2][lane]];
        over_step(&mut c, &mut t, color, l.alpha[lane]);
        *px = [c[0], c[1], c[2], t].map(f16::from_f32);
    });
    with_tile_pixels(&mut t.pixels, out, scene.width as usize, clip, |px| {
        for (c, o) in target.iter().zip(px.iter_mut()) {
            *o = to_rgba8(Vec4::new(c[0].to_f32(), c[1].to_f32(), c[2].to_f32(), 1.0));
        }
    });
    Ok(n)
}

/// One WBOIT tile (weight eq. 7, `RGBA16F` + `R8` targets).
fn wboit_tile(
    t: &mut Target,
    scene: &Primitives,
    prims: &[u32],
    clip: Clip,
    out: &mut [[u8; 4]],
) -> Result<u64, String> {
    let (tw, th) = ((clip.x1 - clip.x0) as usize, (clip.y1 - clip.y0) as usize);
    grow(&mut t.half, tw * th, [f16::ZERO; 4]);
    grow(&mut t.reveal, tw * th, 255u8);
    let (acc, reveal) = (&mut t.half[..tw * th], &mut t.reveal[..tw * th]);
    acc.fill([f16::ZERO; 4]);
    reveal.fill(255);
    let n = each_fragment(scene, prims, clip, |i, lane, l| {
        let (Some(a), Some(r)) = (acc.get_mut(i), reveal.get_mut(i)) else {
            return;
        };
        let color = [l.color[0][lane], l.color[1][lane], l.color[2][lane]];
        let (alpha, depth) = (l.alpha[lane], l.depth[lane]);
        let wt = Weight::Eq7.eval(color, alpha, depth, 0.0);
        let mut v = a.map(f16::to_f32);
        wboit_step(&mut v, r, color, alpha, wt);
        *a = v.map(f16::from_f32);
    });
    let bg = scene.background;
    with_tile_pixels(&mut t.pixels, out, scene.width as usize, clip, |px| {
        for ((a, r), o) in acc.iter().zip(reveal.iter()).zip(px.iter_mut()) {
            let c = wboit_resolve(a.map(f16::to_f32), *r, bg);
            *o = to_rgba8(Vec4::new(c[0], c[1], c[2], 1.0));
        }
    });
    Ok(n)
}

/// One A-buffer tile: a fragment array, counting sort by pixel, sort by depth, composite.
fn abuffer_tile(
    t: &mut Target,
    scene: &Primitives,
    prims: &[u32],
    clip: Clip,
    out: &mut [[u8; 4]],
) -> Result<u64, String> {
    let (tw, th) = ((clip.x1 - clip.x0) as usize, (clip.y1 - clip.y0) as usize);
    let scratch = &mut t.abuffer;
    scratch.begin(tw * th);
    let mut invalid = 0u8;
    for &i in prims {
        scene.prims[i as usize].raster(clip, &mut |x, y, mask, l: &SpanLanes| {
            let q = l.quantize_at::<Unbiased>(mask, frame_pixel(scene, x, y));
            invalid |= q.invalid;
            let row = ((y - clip.y0) as usize * tw + (x - clip.x0) as usize) as u32;
            scratch.push_span(row, &q.rows, q.valid);
        });
    }
    if invalid != 0 {
        return Err("a primitive emitted an invalid fragment".to_string());
    }
    let n = scratch.len();
    t.abuffer_peak = t.abuffer_peak.max(n);
    let bg = Vec3::from(scene.background);
    with_tile_pixels(&mut t.pixels, out, scene.width as usize, clip, |px| {
        scratch.resolve(px, bg)
    });
    Ok(n as u64)
}

/// One recorded span insert (tile-relative column and line).
#[derive(Clone, Copy, Debug)]
pub struct RecordedSpan {
    /// First column inside the tile (a multiple of 8).
    pub x: u32,
    /// Line inside the tile.
    pub y: u32,
    /// Lanes on.
    pub mask: u8,
    /// The quantized rows.
    pub rows: [Row; LANES],
    /// Their hashes in their frame pixels (what their merges are seeded with).
    pub hashes: [u32; LANES],
}

/// The kernel-only replay bound: per tile (bands of `band_lines` lines, tiles of
/// `tile_width` columns as in [`TiledRenderer`]), the span inserts the MLAB 4 frame makes
/// are recorded once (rasterized and quantized, untimed), then `warmup + reps` times the
/// tile's target is cleared, the spans are replayed into it and it is resolved into the
/// output, the last `reps` timed, on the calling thread. Returns per rep the sum over tiles
/// of the replay time (seconds), the mean CPU seconds per rep by `cpu_clock` (read around
/// each tile's timed reps), and the fragment count. One tile's spans are held at a time.
pub fn replay_mlab4(
    scene: &Primitives,
    tile: TileSize,
    warmup: usize,
    reps: usize,
    cpu_clock: impl Fn() -> f64,
) -> Result<(Vec<f64>, f64, u64), String> {
    let (w, h) = (scene.width, scene.height);
    let mut bins = PrimBins::default();
    bins.fill(scene, tile.lines);
    let lines = bins.band_lines();
    let mut target = Target::default();
    let mut lists = Vec::new();
    let mut out = vec![[0u8; 4]; w as usize * h as usize];
    let bg = Background::Opaque(Vec3::from(scene.background));
    let reps = reps.max(1);
    let mut sums = vec![0.0f64; reps];
    let (mut n, mut cpu) = (0u64, 0.0f64);
    let mut spans: Vec<RecordedSpan> = Vec::new();
    for (b, out) in out.chunks_mut((w * lines) as usize).enumerate() {
        let y0 = b as u32 * lines;
        for (clip, prims) in tiles_of_band(scene, bins.band(b), (y0, (y0 + lines).min(h)), tile.width, &mut lists) {
            spans.clear();
            for &i in prims {
                scene.prims[i as usize].raster(clip, &mut |x, y, mask, l: &SpanLanes| {
                    let q = l.quantize_at::<Unbiased>(mask, frame_pixel(scene, x, y));
                    n += count(q.valid);
                    spans.push(RecordedSpan {
                        x: x - clip.x0,
                        y: y - clip.y0,
                        mask: q.valid,
                        rows: q.rows,
                        hashes: q.hashes,
                    });
                });
            }
            let mut c0 = cpu_clock();
            for r in 0..warmup + reps {
                if r == warmup {
                    c0 = cpu_clock();
                }
                let t = std::time::Instant::now();
                let mut fb = mlab_target::<Unbiased>(&mut target.mlab, clip)?;
                for s in &spans {
                    fb.insert_span_hashed(s.x, s.y, &s.rows, &s.hashes, s.mask)
                        .map_err(|e| e.to_string())?;
                }
                mlab_resolve(&fb, bg, out, w as usize, clip.x0);
                let dt = t.elapsed().as_secs_f64();
                if r >= warmup {
                    sums[r - warmup] += dt;
                }
            }
            cpu += cpu_clock() - c0;
        }
    }
    Ok((sums, cpu / reps as f64, n))
}

/// The rasterizer alone: every tile's primitives (tiles as in [`TiledRenderer`]) rasterized
/// into spans that are only counted (the lanes pass through [`std::hint::black_box`]), on
/// the calling thread. Returns the fragment count. What the frame pays on top of the replay
/// is this and the quantization.
pub fn raster_only(scene: &Primitives, bins: &mut PrimBins, tile: TileSize) -> u64 {
    bins.fill(scene, tile.lines);
    let mut lists = Vec::new();
    let mut n = 0u64;
    let lines = bins.band_lines();
    for b in 0..bins.bands() {
        let y0 = b as u32 * lines;
        for (clip, prims) in tiles_of_band(
            scene,
            bins.band(b),
            (y0, (y0 + lines).min(scene.height)),
            tile.width,
            &mut lists,
        ) {
            for &i in prims {
                scene.prims[i as usize].raster(clip, &mut |_, _, mask, l: &SpanLanes| {
                    std::hint::black_box(l);
                    n += count(mask);
                });
            }
        }
    }
    n
}

//! Whole frames without storing fragments: the scene's primitives are binned by their screen
//! bounds into full-width bands, and each worker (a `rayon` task per band) clears its band of
//! the target, rasterizes the band's primitives in submission order straight into the
//! method's target (for MLAB: span inserts of the kernel's [`SpanFramebuffer`], fragments
//! live in the rasterizer's lanes only), and resolves the band into the output:
//!
//! ```text
//! bin:   for each primitive p, in submission order: push p to every band its box meets
//! band:  (in parallel) clear band b of the target
//!        for p in bins[b] (submission order): rasterize p clipped to band b
//!            for each 8-pixel span: quantize the lanes, insert the span
//!        resolve band b into its lines of the output
//! ```
//!
//! Each pixel sees its fragments in submission order whatever the band height and thread
//! count, so the frame is byte-identical to one band over the whole frame on one thread
//! (tested in `lab/tests/tiled.rs`, also against the scalar kernel over the stream).
//! Memory: the target, the output, the primitives and their bins; nothing grows with the
//! fragment count except the A-buffer's per-band fragment arrays.

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

/// Lines per band when none is given (`oit-lab bench --bands`, `docs/frame.md`).
pub const DEFAULT_BAND_LINES: u32 = 16;

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
/// A-buffer as the paper's Table 1 counts it: 12 B per fragment + a 4 B head per pixel; the
/// tiled A-buffer holds only a band's fragments at a time, see
/// [`TiledRenderer::abuffer_peak_fragments`]).
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

/// The tiled renderer: primitive bins and each method's target, kept between frames. Work
/// runs on the current `rayon` pool (`ThreadPool::install` chooses the thread count).
#[derive(Debug, Default)]
pub struct TiledRenderer {
    /// Lines per band.
    pub band_lines: u32,
    bins: PrimBins,
    mlab: Vec<Row>,
    half: Vec<[f16; 4]>,
    reveal: Vec<u8>,
    abuffer_peak: usize,
}

fn resize<T: Clone>(v: &mut Vec<T>, n: usize, fill: T) {
    if v.len() != n {
        v.clear();
        v.resize(n, fill);
    }
}

/// Per span, the fragments `popcount(mask)`.
fn count(mask: u8) -> u64 {
    mask.count_ones() as u64
}

impl TiledRenderer {
    /// A renderer with bands of `band_lines` lines.
    pub fn new(band_lines: u32) -> TiledRenderer {
        TiledRenderer {
            band_lines: band_lines.max(1),
            ..TiledRenderer::default()
        }
    }

    /// The bins of the last frame.
    pub fn bins(&self) -> &PrimBins {
        &self.bins
    }

    /// Bytes of the method's storage held now (targets and bins, as allocated).
    pub fn held_bytes(&self) -> usize {
        self.bins.bytes()
            + self.mlab.capacity() * std::mem::size_of::<Row>()
            + self.half.capacity() * 8
            + self.reveal.capacity()
    }

    /// The most fragments one band of the last A-buffer frame held.
    pub fn abuffer_peak_fragments(&self) -> usize {
        self.abuffer_peak
    }

    /// Render `scene` with `method` into `out` (`width * height` RGBA8 pixels, row major),
    /// binning included; returns the number of fragments.
    pub fn render(&mut self, method: TiledMethod, scene: &Primitives, out: &mut [[u8; 4]]) -> Result<u64, String> {
        let pixels = scene.width as usize * scene.height as usize;
        if out.len() != pixels {
            return Err(format!("output has {} pixels, the frame {pixels}", out.len()));
        }
        self.bins.fill(scene, self.band_lines);
        match method {
            TiledMethod::Mlab4 => self.mlab::<Unbiased>(scene, out),
            TiledMethod::Mlab4Paper => self.mlab::<Paper>(scene, out),
            TiledMethod::ABuffer => self.abuffer(scene, out),
            TiledMethod::Wboit => self.wboit(scene, out),
            TiledMethod::Over => self.over(scene, out),
        }
    }

    fn mlab<A: Arithmetic>(&mut self, scene: &Primitives, out: &mut [[u8; 4]]) -> Result<u64, String> {
        let (w, h, lines) = (scene.width, scene.height, self.bins.band_lines());
        let n = SpanFramebuffer::<4, A>::rows_needed(w, h).map_err(|e| e.to_string())?;
        resize(&mut self.mlab, n, Row::EMPTY);
        let mut fb = SpanFramebuffer::<4, A>::new(&mut self.mlab, w, h).map_err(|e| e.to_string())?;
        let bg = Background::Opaque(Vec3::from(scene.background));
        let bins = &self.bins;
        let work: Vec<_> = fb
            .bands_mut(lines)
            .zip(out.chunks_mut((w * lines) as usize))
            .enumerate()
            .collect();
        work.into_par_iter().with_max_len(1)
            .map(|(b, (mut band, out))| {
                band.clear();
                let y0 = b as u32 * lines;
                let n = mlab_band(&mut band, scene, bins.band(b), y0)?;
                band.resolve_rgba8(out, bg).map_err(|e| e.to_string())?;
                Ok(n)
            })
            .sum()
    }

    fn over(&mut self, scene: &Primitives, out: &mut [[u8; 4]]) -> Result<u64, String> {
        let (w, h, lines) = (scene.width as usize, scene.height, self.bins.band_lines());
        resize(&mut self.half, w * h as usize, [f16::ZERO; 4]);
        let bg = scene.background.map(f16::from_f32);
        let bins = &self.bins;
        let work: Vec<_> = self
            .half
            .chunks_mut(w * lines as usize)
            .zip(out.chunks_mut(w * lines as usize))
            .enumerate()
            .collect();
        work.into_par_iter().with_max_len(1)
            .map(|(b, (target, out))| {
                target.fill([bg[0], bg[1], bg[2], f16::ONE]);
                let y0 = b as u32 * lines;
                let clip = band_clip(scene, y0, lines);
                let mut n = 0;
                for &i in bins.band(b) {
                    scene.prims[i as usize].raster(clip, &mut |x, y, mask, l: &SpanLanes| {
                        n += count(mask);
                        let row = (y - y0) as usize * w + x as usize;
                        for lane in 0..LANES {
                            if mask & (1 << lane) == 0 {
                                continue;
                            }
                            let Some(px) = target.get_mut(row + lane) else { continue };
                            let mut c = [px[0].to_f32(), px[1].to_f32(), px[2].to_f32()];
                            let mut t = px[3].to_f32();
                            let color = [l.color[0][lane], l.color[1][lane], l.color[2][lane]];
                            over_step(&mut c, &mut t, color, l.alpha[lane]);
                            *px = [c[0], c[1], c[2], t].map(f16::from_f32);
                        }
                    });
                }
                for (c, o) in target.iter().zip(out.iter_mut()) {
                    *o = to_rgba8(Vec4::new(c[0].to_f32(), c[1].to_f32(), c[2].to_f32(), 1.0));
                }
                Ok(n)
            })
            .sum()
    }

    fn wboit(&mut self, scene: &Primitives, out: &mut [[u8; 4]]) -> Result<u64, String> {
        let (w, h, lines) = (scene.width as usize, scene.height, self.bins.band_lines());
        resize(&mut self.half, w * h as usize, [f16::ZERO; 4]);
        resize(&mut self.reveal, w * h as usize, 255u8);
        let bg = scene.background;
        let bins = &self.bins;
        let work: Vec<_> = self
            .half
            .chunks_mut(w * lines as usize)
            .zip(self.reveal.chunks_mut(w * lines as usize))
            .zip(out.chunks_mut(w * lines as usize))
            .enumerate()
            .collect();
        work.into_par_iter().with_max_len(1)
            .map(|(b, ((acc, reveal), out))| {
                acc.fill([f16::ZERO; 4]);
                reveal.fill(255);
                let y0 = b as u32 * lines;
                let clip = band_clip(scene, y0, lines);
                let mut n = 0;
                for &i in bins.band(b) {
                    scene.prims[i as usize].raster(clip, &mut |x, y, mask, l: &SpanLanes| {
                        n += count(mask);
                        let row = (y - y0) as usize * w + x as usize;
                        for lane in 0..LANES {
                            if mask & (1 << lane) == 0 {
                                continue;
                            }
                            let (Some(a), Some(r)) = (acc.get_mut(row + lane), reveal.get_mut(row + lane)) else {
                                continue;
                            };
                            let color = [l.color[0][lane], l.color[1][lane], l.color[2][lane]];
                            let (alpha, depth) = (l.alpha[lane], l.depth[lane]);
                            let wt = Weight::Eq7.eval(color, alpha, depth, 0.0);
                            let mut v = a.map(f16::to_f32);
                            wboit_step(&mut v, r, color, alpha, wt);
                            *a = v.map(f16::from_f32);
                        }
                    });
                }
                for ((a, r), o) in acc.iter().zip(reveal.iter()).zip(out.iter_mut()) {
                    let c = wboit_resolve(a.map(f16::to_f32), *r, bg);
                    *o = to_rgba8(Vec4::new(c[0], c[1], c[2], 1.0));
                }
                Ok(n)
            })
            .sum()
    }

    fn abuffer(&mut self, scene: &Primitives, out: &mut [[u8; 4]]) -> Result<u64, String> {
        let (w, lines) = (scene.width as usize, self.bins.band_lines());
        let bins = &self.bins;
        let bg = Vec3::from(scene.background);
        let results: Vec<Result<(u64, usize), String>> = out
            .par_chunks_mut(w * lines as usize)
            .enumerate()
            .with_max_len(1)
            .map_init(abuffer::Scratch::default, |scratch, (b, out)| {
                let y0 = b as u32 * lines;
                let clip = band_clip(scene, y0, lines);
                scratch.begin(out.len());
                let mut invalid = 0u8;
                for &i in bins.band(b) {
                    scene.prims[i as usize].raster(clip, &mut |x, y, mask, l: &SpanLanes| {
                        let q = l.quantize_with::<Unbiased>(mask);
                        invalid |= q.invalid;
                        let row = ((y - y0) as usize * w + x as usize) as u32;
                        scratch.push_span(row, &q.rows, q.valid);
                    });
                }
                if invalid != 0 {
                    return Err("a primitive emitted an invalid fragment".to_string());
                }
                let n = scratch.len();
                scratch.resolve(out, bg);
                Ok((n as u64, n))
            })
            .collect();
        let mut total = 0;
        self.abuffer_peak = 0;
        for r in results {
            let (n, len) = r?;
            total += n;
            self.abuffer_peak = self.abuffer_peak.max(len);
        }
        Ok(total)
    }
}

/// Band `b`'s clip rectangle (the last band may be shorter).
fn band_clip(scene: &Primitives, y0: u32, lines: u32) -> Clip {
    Clip {
        x0: 0,
        y0,
        x1: scene.width,
        y1: (y0 + lines).min(scene.height),
    }
}

/// Rasterize a band's primitives straight into span inserts; returns the fragment count.
fn mlab_band<A: Arithmetic>(
    band: &mut SpanFramebuffer<'_, 4, A>,
    scene: &Primitives,
    prims: &[u32],
    y0: u32,
) -> Result<u64, String> {
    let clip = Clip {
        x0: 0,
        y0,
        x1: band.width(),
        y1: y0 + band.height(),
    };
    let (mut n, mut invalid, mut err) = (0u64, 0u8, None);
    for &i in prims {
        scene.prims[i as usize].raster(clip, &mut |x, y, mask, l: &SpanLanes| {
            let q = l.quantize_with::<A>(mask);
            invalid |= q.invalid;
            n += count(mask);
            if let Err(e) = band.insert_span(x, y - y0, &q.rows, q.valid) {
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
    Ok(n)
}

/// One recorded span insert (band-relative line).
#[derive(Clone, Copy, Debug)]
pub struct RecordedSpan {
    /// First column (a multiple of 8).
    pub x: u32,
    /// Line inside the band.
    pub y: u32,
    /// Lanes on.
    pub mask: u8,
    /// The quantized rows.
    pub rows: [Row; LANES],
}

/// The kernel-only replay bound: per band, the span inserts the MLAB 4 frame makes are
/// recorded once (rasterized and quantized, untimed), then `reps` times cleared, replayed into
/// the band of a framebuffer and resolved, timed, on the calling thread. Returns per rep the
/// sum over bands of the replay time (seconds), the mean CPU seconds per rep by `cpu_clock`
/// (read around each band's timed reps), and the fragment count. One band's spans are held
/// at a time.
pub fn replay_mlab4(
    scene: &Primitives,
    band_lines: u32,
    warmup: usize,
    reps: usize,
    cpu_clock: impl Fn() -> f64,
) -> Result<(Vec<f64>, f64, u64), String> {
    let (w, h) = (scene.width, scene.height);
    let mut bins = PrimBins::default();
    bins.fill(scene, band_lines);
    let lines = bins.band_lines();
    let mut storage = vec![Row::EMPTY; SpanFramebuffer::<4>::rows_needed(w, h).map_err(|e| e.to_string())?];
    let mut fb = SpanFramebuffer::<4>::new(&mut storage, w, h).map_err(|e| e.to_string())?;
    let mut out = vec![[0u8; 4]; w as usize * h as usize];
    let bg = Background::Opaque(Vec3::from(scene.background));
    let reps = reps.max(1);
    let mut sums = vec![0.0f64; reps];
    let (mut n, mut cpu) = (0u64, 0.0f64);
    let mut spans: Vec<RecordedSpan> = Vec::new();
    for (b, (mut band, out)) in fb
        .bands_mut(lines)
        .zip(out.chunks_mut((w * lines) as usize))
        .enumerate()
    {
        let y0 = b as u32 * lines;
        spans.clear();
        let clip = band_clip(scene, y0, lines);
        for &i in bins.band(b) {
            scene.prims[i as usize].raster(clip, &mut |x, y, mask, l: &SpanLanes| {
                let q = l.quantize_with::<Unbiased>(mask);
                n += count(q.valid);
                spans.push(RecordedSpan {
                    x,
                    y: y - y0,
                    mask: q.valid,
                    rows: q.rows,
                });
            });
        }
        let mut c0 = cpu_clock();
        for r in 0..warmup + reps {
            if r == warmup {
                c0 = cpu_clock();
            }
            let t = std::time::Instant::now();
            band.clear();
            for s in &spans {
                band.insert_span(s.x, s.y, &s.rows, s.mask).map_err(|e| e.to_string())?;
            }
            band.resolve_rgba8(out, bg).map_err(|e| e.to_string())?;
            let dt = t.elapsed().as_secs_f64();
            if r >= warmup {
                sums[r - warmup] += dt;
            }
        }
        cpu += cpu_clock() - c0;
    }
    Ok((sums, cpu / reps as f64, n))
}

/// The rasterizer alone: every band's primitives rasterized into spans that are only
/// counted (the lanes pass through [`std::hint::black_box`]), on the calling thread. Returns
/// the fragment count. What the frame pays on top of the replay is this and the
/// quantization.
pub fn raster_only(scene: &Primitives, bins: &mut PrimBins, band_lines: u32) -> u64 {
    bins.fill(scene, band_lines);
    let mut n = 0u64;
    for b in 0..bins.bands() {
        let clip = band_clip(scene, b as u32 * bins.band_lines(), bins.band_lines());
        for &i in bins.band(b) {
            scene.prims[i as usize].raster(clip, &mut |_, _, mask, l: &SpanLanes| {
                std::hint::black_box(l);
                n += count(mask);
            });
        }
    }
    n
}

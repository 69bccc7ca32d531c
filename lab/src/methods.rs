//! The compositing methods, each a function from a frame's fragment stream to an image.
//!
//! Every method sees the same [`Frame`]: the stream in submission order, the fragments
//! grouped per pixel in submission order ([`Frame::bins`]) and sorted front to back
//! ([`Frame::sorted`], what an application that sorts would submit). Render targets are
//! emulated at their storage precision: `RGBA16F` rounds every blend result to IEEE half
//! ([`f16r`]), `R8` rounds to the nearest of 256 levels after every blend ([`r8_blend`]).
//!
//! MLAB and HT run in the kernel (`mlab`) through its framebuffer views, fragment by
//! fragment in submission order, as a pixel shader would. A lane (SIMD) variant of the
//! kernel becomes one more [`Method`] variant whose `render` calls it; see
//! [`Method::standard_list`].

// Channel loops `for k in 0..3` index several arrays at once (target, fragment, weight);
// written as in the blend equations.
#![allow(clippy::needless_range_loop)]

use crate::stream::{Bins, Stream};
use mlab::glam::Vec3;
use mlab::half::f16;
use mlab::lanes::{self, HybridSpan, LANES, ResolvedLanes};
use mlab::{
    Arithmetic, Fragment, Framebuffer, HybridFramebuffer, MlabFramebuffer, Paper, Resolved, Row, TailFormat, Unbiased,
};
use mlab_reference::Layer;

/// A rendered image: linear RGB per pixel (not clamped; additive light may exceed 1) and the
/// visibility of the background (the product of transmittances the method ends up with).
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Linear RGB, row major.
    pub rgb: Vec<[f32; 3]>,
    /// Background visibility in `[0, 1]` (Meshkin's is `1 - sum(alpha)`, negative past full
    /// opacity).
    pub vis: Vec<f32>,
}

/// A stream prepared for compositing.
pub struct Frame<'a> {
    /// The stream.
    pub stream: &'a Stream,
    /// Fragment indices per pixel, in submission order.
    pub bins: Bins,
    /// Fragment indices per pixel, front to back (later submission first on equal depth).
    pub sorted: Bins,
    /// Seconds spent sorting (part of the A-buffer's cost).
    pub sort_seconds: f64,
    /// Near and far depth for the window-space depth of WBOIT's Eq. 10: the stream's
    /// depth range widened by 10% on each side.
    pub near_far: (f32, f32),
}

impl<'a> Frame<'a> {
    /// Group and sort the stream. The stream must be valid ([`Stream::validate`]);
    /// otherwise rendering with the kernel methods returns an error.
    pub fn new(stream: &'a Stream) -> Frame<'a> {
        let bins = Bins::new(stream);
        let t = std::time::Instant::now();
        let sorted = bins.sorted(stream);
        let sort_seconds = t.elapsed().as_secs_f64();
        let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
        for f in &stream.frags {
            lo = lo.min(f.depth);
            hi = hi.max(f.depth);
        }
        let near_far = if lo > 0.0 && hi.is_finite() {
            (lo / 1.1, hi * 1.1)
        } else {
            (0.0, 1.0)
        };
        Frame {
            stream,
            bins,
            sorted,
            sort_seconds,
            near_far,
        }
    }

    fn bg(&self) -> [f32; 3] {
        self.stream.background
    }
}

/// IEEE half rounding of one stored value (an `RGBA16F` channel after a blend).
#[inline]
pub fn f16r(x: f32) -> f32 {
    f16::from_f32(x).to_f32()
}

/// One blend into an `R8` (unorm8) target: `dst * factor`, rounded to the nearest level.
#[inline]
pub fn r8_blend(dst: u8, factor: f32) -> u8 {
    (dst as f32 / 255.0 * factor * 255.0 + 0.5).floor().clamp(0.0, 255.0) as u8
}

/// OVER, one fragment, into an `RGBA16F` target: `C = c + C * (1 - a)`, `T = T * (1 - a)`,
/// each result rounded to half (the one copy of the formula: [`crate::tiled`] uses it too).
#[inline]
pub fn over_step(c: &mut [f32; 3], t: &mut f32, color: [f32; 3], alpha: f32) {
    for k in 0..3 {
        c[k] = f16r(color[k] + c[k] * (1.0 - alpha));
    }
    *t = f16r(*t * (1.0 - alpha));
}

/// WBOIT, one fragment of weight `w`: `acc += (c * w, a * w)` in half, `r *= 1 - a` in
/// unorm8 (the one copy of the formula: [`crate::tiled`] uses it too).
#[inline]
pub fn wboit_step(acc: &mut [f32; 4], r: &mut u8, color: [f32; 3], alpha: f32, w: f32) {
    for k in 0..3 {
        acc[k] = f16r(acc[k] + color[k] * w);
    }
    acc[3] = f16r(acc[3] + alpha * w);
    *r = r8_blend(*r, 1.0 - alpha);
}

/// WBOIT's resolve: `C = acc.rgb / max(acc.a, 1e-5) * (1 - r) + bg * r`, non-finite shown
/// black.
#[inline]
pub fn wboit_resolve(acc: [f32; 4], r: u8, bg: [f32; 3]) -> [f32; 3] {
    let rv = r as f32 / 255.0;
    let d = acc[3].max(1e-5);
    std::array::from_fn(|k| finite_or_zero(acc[k] / d * (1.0 - rv) + bg[k] * rv))
}

/// The WBOIT weight functions of McGuire & Bavoil (2013), Eq. 7-10, and the color-aware
/// variant of seed 001 (LearnOpenGL).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Weight {
    /// `alpha * clamp(10 / (1e-5 + (|z|/5)^2 + (|z|/200)^6), 1e-2, 3e3)`
    Eq7,
    /// `alpha * clamp(10 / (1e-5 + (|z|/10)^3 + (|z|/200)^6), 1e-2, 3e3)`
    Eq8,
    /// `alpha * clamp(0.03 / (1e-5 + (|z|/200)^4), 1e-2, 3e3)`
    Eq9,
    /// `alpha * max(1e-2, 3e3 * (1 - d)^3)`, `d` the window-space depth.
    Eq10,
    /// `max(min(1, max(C.rgb) * alpha), alpha) * clamp(0.03 / (1e-5 + (z/200)^4), 1e-2, 3e3)`
    /// (seed 001; `max(C.rgb) * alpha` is the largest premultiplied channel).
    Color,
}

impl Weight {
    /// All five.
    pub const ALL: [Weight; 5] = [Weight::Eq7, Weight::Eq8, Weight::Eq9, Weight::Eq10, Weight::Color];

    /// The weight of a fragment with premultiplied color `c`, alpha `a`, view depth `z`,
    /// window-space depth `d`.
    pub fn eval(self, c: [f32; 3], a: f32, z: f32, d: f32) -> f32 {
        let z = z.abs();
        match self {
            Weight::Eq7 => a * (10.0 / (1e-5 + (z / 5.0).powi(2) + (z / 200.0).powi(6))).clamp(1e-2, 3e3),
            Weight::Eq8 => a * (10.0 / (1e-5 + (z / 10.0).powi(3) + (z / 200.0).powi(6))).clamp(1e-2, 3e3),
            Weight::Eq9 => a * (0.03 / (1e-5 + (z / 200.0).powi(4))).clamp(1e-2, 3e3),
            Weight::Eq10 => a * (3e3 * (1.0 - d).powi(3)).max(1e-2),
            Weight::Color => {
                let m = c[0].max(c[1]).max(c[2]);
                m.min(1.0).max(a) * (0.03 / (1e-5 + (z / 200.0).powi(4))).clamp(1e-2, 3e3)
            }
        }
    }

    fn label(self) -> &'static str {
        match self {
            Weight::Eq7 => "WBOIT eq.7",
            Weight::Eq8 => "WBOIT eq.8",
            Weight::Eq9 => "WBOIT eq.9",
            Weight::Eq10 => "WBOIT eq.10",
            Weight::Color => "WBOIT color",
        }
    }
}

/// UNDER blending stops taking fragments once the transmittance is below this.
pub const UNDER_THRESHOLD: f32 = 0.01;

/// The kernel's arithmetic (issue 9): how MLAB's merge rounds its unorm8 products, how a
/// fragment is quantized to a row, and the HT tail's layout: `mlab::Paper` or
/// `mlab::Unbiased`. The lab turns it into the kernel's type in one place, the `*_with`
/// functions of this module ([`mlab_with`], [`hybrid_with`], ...).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Arith {
    /// The paper's: products and fragments rounded to nearest, the 3 x 10-bit tail.
    Paper,
    /// The unbiased one: dithered rounding, a tail that does not saturate on dense content.
    Unbiased,
}

impl Arith {
    /// Both, paper first.
    pub const ALL: [Arith; 2] = [Arith::Paper, Arith::Unbiased];

    /// `"paper"` or `"unbiased"`.
    pub fn name(self) -> &'static str {
        match self {
            Arith::Paper => "paper",
            Arith::Unbiased => "unbiased",
        }
    }
}

/// MLAB row counts the lab can run (const generics are instantiated for these).
pub const MLAB_SIZES: [usize; 10] = [1, 2, 3, 4, 5, 6, 7, 8, 12, 16];
/// HT head sizes the lab can run.
pub const HT_SIZES: [usize; 10] = [0, 1, 2, 3, 4, 5, 6, 7, 11, 15];

/// A compositing method.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// Exact: every fragment kept, sorted per pixel, composited front to back in f64.
    Reference,
    /// MLAB (kernel, scalar) with `M` rows.
    Mlab(usize),
    /// MLAB (kernel, scalar) with `M` rows, fed each pixel's fragments front to back (the
    /// sorted stream): no fragment ever lands between merged rows, so what is left is the
    /// 8-bit quantization (a check of the paper's claim about the merge).
    MlabSorted(usize),
    /// Hybrid Transparency (kernel, scalar) with `K` head rows and a tail.
    Hybrid(usize),
    /// MLAB (kernel, scalar) with `M` rows and the given arithmetic ([`Method::Mlab`] is the
    /// kernel's default arithmetic).
    MlabWith(usize, Arith),
    /// HT (kernel, scalar) with `K` head rows and the given arithmetic (its tail included).
    HybridWith(usize, Arith),
    /// MLAB with `M` rows through the kernel's 8-pixel lanes (`mlab::lanes`); must give the
    /// same image as [`Method::Mlab`] bit for bit.
    MlabLanes(usize),
    /// HT with `K` head rows through the kernel's 8-pixel lanes.
    HybridLanes(usize),
    /// OVER in submission order into an `RGBA16F` target (unsorted alpha blending, "AB").
    Over,
    /// UNDER, front to back over the sorted stream, `RGBA16F`, transmittance thresholding.
    Under,
    /// Weighted Blended OIT with a weight function: `RGBA16F` accumulation + `R8` revealage.
    Wboit(Weight),
    /// Bavoil-Myers weighted average: `RGBA16F` sums + `R32F` count.
    BavoilMyers,
    /// Meshkin's sort-independent blend (first-order terms): `RGBA16F` sums.
    Meshkin,
    /// Adaptive Transparency with `N` visibility nodes, two passes.
    Adaptive(usize),
}

impl Method {
    /// The methods of the main job, in table order. A lanes variant of the kernel goes here
    /// as one more entry per size (for example `Method::MlabLanes(m)` after `Method::Mlab(m)`).
    pub fn standard_list() -> Vec<Method> {
        let mut v = vec![Method::Over, Method::Under];
        for m in [1, 2, 4, 8] {
            v.push(Method::Mlab(m));
        }
        for m in [1, 2, 4, 8] {
            v.push(Method::Hybrid(m - 1));
        }
        v.push(Method::MlabLanes(4));
        v.push(Method::HybridLanes(3));
        v.push(Method::MlabSorted(1));
        v.push(Method::MlabSorted(4));
        for n in [2, 4, 8] {
            v.push(Method::Adaptive(n));
        }
        v.extend(Weight::ALL.map(Method::Wboit));
        v.push(Method::BavoilMyers);
        v.push(Method::Meshkin);
        v
    }

    /// Display name.
    pub fn name(self) -> String {
        match self {
            Method::Reference => "A-buffer".into(),
            Method::Mlab(m) => format!("MLAB {m}"),
            Method::MlabSorted(m) => format!("MLAB {m} sorted"),
            Method::MlabLanes(m) => format!("MLAB {m} lanes"),
            Method::HybridLanes(k) => format!("HT {k} lanes"),
            Method::Hybrid(k) => format!("HT {k}"),
            Method::MlabWith(m, a) => format!("MLAB {m} {}", a.name()),
            Method::HybridWith(k, a) => format!("HT {k} {}", a.name()),
            Method::Over => "OVER unsorted".into(),
            Method::Under => "UNDER sorted".into(),
            Method::Wboit(w) => w.label().into(),
            Method::BavoilMyers => "Bavoil-Myers".into(),
            Method::Meshkin => "Meshkin".into(),
            Method::Adaptive(n) => format!("AT {n}"),
        }
    }

    /// A file-name friendly name.
    pub fn slug(self) -> String {
        self.name()
            .to_ascii_lowercase()
            .replace([' ', '.'], "_")
            .replace("__", "_")
    }

    /// Memory per pixel in bytes. For the A-buffer: 12 bytes per stored fragment (RGBA8,
    /// f32 depth, 32-bit next pointer) plus a 4-byte head pointer, averaged over the frame.
    pub fn bytes_per_pixel(self, frame: &Frame) -> f64 {
        match self {
            Method::Reference => 4.0 + 12.0 * frame.stream.frags.len() as f64 / frame.stream.pixels().max(1) as f64,
            Method::Mlab(m) | Method::MlabSorted(m) | Method::MlabLanes(m) | Method::MlabWith(m, _) => 8.0 * m as f64,
            Method::Hybrid(k) | Method::HybridLanes(k) | Method::HybridWith(k, _) => 8.0 * (k + 1) as f64,
            Method::Over | Method::Under | Method::Meshkin => 8.0,
            Method::Wboit(_) => 9.0,
            Method::BavoilMyers => 12.0,
            Method::Adaptive(n) => 8.0 * n as f64 + 8.0,
        }
    }

    /// Render the frame. Errors only for a stream the kernel refuses or an unsupported size.
    pub fn render(self, frame: &Frame) -> Result<Image, String> {
        match self {
            Method::Reference => Ok(reference(frame)),
            Method::Mlab(m) => mlab_with(m, Arith::DEFAULT, frame),
            Method::MlabSorted(m) => mlab_sorted_with(m, Arith::DEFAULT, frame),
            Method::MlabLanes(m) => mlab_lanes_with(m, Arith::DEFAULT, frame),
            Method::HybridLanes(k) => hybrid_lanes_with(k, Arith::DEFAULT, frame),
            Method::Hybrid(k) => hybrid_with(k, Arith::DEFAULT, frame).map(|(image, _)| image),
            Method::MlabWith(m, a) => mlab_with(m, a, frame),
            Method::HybridWith(k, a) => hybrid_with(k, a, frame).map(|(image, _)| image),
            Method::Over => Ok(over(frame)),
            Method::Under => Ok(under(frame)),
            Method::Wboit(w) => Ok(wboit(frame, w)),
            Method::BavoilMyers => Ok(bavoil_myers(frame)),
            Method::Meshkin => Ok(meshkin(frame)),
            Method::Adaptive(0) => Err("AT needs at least one node".into()),
            Method::Adaptive(n) => Ok(adaptive(frame, n)),
        }
    }
}

/// Run `f` for every pixel, on all cores, and collect the image.
fn per_pixel<F>(frame: &Frame, f: F) -> Image
where
    F: Fn(usize) -> ([f32; 3], f32) + Sync,
{
    let s = frame.stream;
    let n = s.pixels();
    let mut rgb = vec![[0.0f32; 3]; n];
    let mut vis = vec![0.0f32; n];
    let threads = std::thread::available_parallelism().map_or(1, |t| t.get()).clamp(1, 16);
    let chunk = n.div_ceil(threads * 8).max(1024);
    let work: Vec<_> = rgb.chunks_mut(chunk).zip(vis.chunks_mut(chunk)).enumerate().collect();
    let work = std::sync::Mutex::new(work);
    std::thread::scope(|scope| {
        let (f, work) = (&f, &work);
        for _ in 0..threads {
            scope.spawn(move || {
                loop {
                    let item = work.lock().map(|mut w| w.pop()).ok().flatten();
                    let Some((ci, (rc, vc))) = item else { break };
                    for (j, (r, v)) in rc.iter_mut().zip(vc.iter_mut()).enumerate() {
                        (*r, *v) = f(ci * chunk + j);
                    }
                }
            });
        }
    });
    Image {
        width: s.width,
        height: s.height,
        rgb,
        vis,
    }
}

fn over_bg(c: [f32; 3], t: f32, bg: [f32; 3]) -> [f32; 3] {
    [c[0] + bg[0] * t, c[1] + bg[1] * t, c[2] + bg[2] * t]
}

/// The exact reference: `mlab_reference::oracle::composite`, the oracle the kernel's tests
/// and fuzz targets use, over each pixel's fragments as the A-buffer sorted them
/// ([`Frame::sorted`]: front to back, later submission first on equal depth, the oracle's
/// order; the sort is timed apart as `sort_seconds`): in f64 `C += T * c`, `T *= 1 - a`,
/// then `C + T * bg`.
fn reference(frame: &Frame) -> Image {
    let (frags, bg) = (&frame.stream.frags, frame.bg().map(f64::from));
    per_pixel(frame, |p| {
        let layers = frame.sorted.of(p).iter().map(|&i| {
            let f = &frags[i as usize];
            Layer {
                color: f.color,
                alpha: f.alpha,
                depth: f.depth,
            }
        });
        let (c, t) = mlab_reference::oracle::composite(layers, bg);
        (c.map(|x| x as f32), t as f32)
    })
}

fn kernel_image(frame: &Frame, resolve: impl Fn(u32, u32) -> Result<Resolved, String>) -> Result<Image, String> {
    let s = frame.stream;
    let bg = Vec3::from(s.background);
    let mut rgb = Vec::with_capacity(s.pixels());
    let mut vis = Vec::with_capacity(s.pixels());
    for y in 0..s.height {
        for x in 0..s.width {
            let r = resolve(x, y)?;
            rgb.push(r.over(bg).to_array());
            vis.push(r.transmittance);
        }
    }
    Ok(Image {
        width: s.width,
        height: s.height,
        rgb,
        vis,
    })
}

fn err(e: impl std::fmt::Display) -> String {
    e.to_string()
}

/// MLAB with the kernel's framebuffer view in arithmetic `A`, in submission order (or, when
/// `sorted`, each pixel's fragments front to back).
pub fn run_mlab<const M: usize, A: Arithmetic>(frame: &Frame, sorted: bool) -> Result<Image, String> {
    let s = frame.stream;
    let mut storage = vec![Row::EMPTY; MlabFramebuffer::<M, A>::rows_needed(s.width, s.height).map_err(err)?];
    let mut fb = MlabFramebuffer::<M, A>::new(&mut storage, s.width, s.height).map_err(err)?;
    fb.clear();
    let insert = |fb: &mut MlabFramebuffer<M, A>, i: usize| -> Result<(), String> {
        let f = &s.frags[i];
        let frag = f.to_kernel().map_err(|e| format!("fragment {i}: {e}"))?;
        fb.insert(f.pixel % s.width, f.pixel / s.width, &frag).map_err(err)
    };
    if sorted {
        for &i in &frame.sorted.index {
            insert(&mut fb, i as usize)?;
        }
    } else {
        for i in 0..s.frags.len() {
            insert(&mut fb, i)?;
        }
    }
    kernel_image(frame, |x, y| fb.resolve(x, y).map_err(err))
}

/// Hybrid Transparency with the kernel's framebuffer view in arithmetic `A` (which picks the
/// tail), in submission order; also the number of pixels whose tail has a field at its
/// maximum (`saturated`).
pub fn run_hybrid<const K: usize, A: Arithmetic>(frame: &Frame) -> Result<(Image, usize), String> {
    let s = frame.stream;
    let mut storage = vec![Row::EMPTY; HybridFramebuffer::<K, A>::rows_needed(s.width, s.height).map_err(err)?];
    let mut fb = HybridFramebuffer::<K, A>::new(&mut storage, s.width, s.height).map_err(err)?;
    // The tail slot of `Row::EMPTY` bytes is not an empty tail: clear for a new frame.
    fb.clear();
    for (i, f) in s.frags.iter().enumerate() {
        let frag = f.to_kernel().map_err(|e| format!("fragment {i}: {e}"))?;
        fb.insert(f.pixel % s.width, f.pixel / s.width, &frag).map_err(err)?;
    }
    let mut saturated = 0;
    for y in 0..s.height {
        for x in 0..s.width {
            saturated += usize::from(fb.pixel(x, y).map_err(err)?.1.saturated());
        }
    }
    Ok((kernel_image(frame, |x, y| fb.resolve(x, y).map_err(err))?, saturated))
}

/// A kernel through its 8-pixel lanes: the frame is cut into spans of 8 pixels of a row;
/// consecutive fragments of the stream that fall in one span on distinct lanes are inserted
/// with one call (a rasterizer's span of a primitive), which keeps each pixel's submission
/// order. Fragments are quantized with `quantize` (the arithmetic's).
fn run_lanes<S: Clone>(
    frame: &Frame,
    empty: S,
    quantize: fn(&Fragment) -> Row,
    insert: fn(&mut S, &[Row; LANES], u8),
    resolve: fn(&S) -> ResolvedLanes,
) -> Result<Image, String> {
    let s = frame.stream;
    let spans_x = (s.width as usize).div_ceil(LANES);
    let mut spans = vec![empty; spans_x * s.height as usize];
    let (mut cur, mut rows, mut mask) = (0usize, [Row::EMPTY; LANES], 0u8);
    for (i, f) in s.frags.iter().enumerate() {
        let row = quantize(&f.to_kernel().map_err(|e| format!("fragment {i}: {e}"))?);
        let (x, y) = ((f.pixel % s.width) as usize, (f.pixel / s.width) as usize);
        let (span, lane) = (y * spans_x + x / LANES, x % LANES);
        if mask != 0 && (span != cur || mask & (1 << lane) != 0) {
            insert(&mut spans[cur], &rows, mask);
            (rows, mask) = ([Row::EMPTY; LANES], 0);
        }
        cur = span;
        rows[lane] = row;
        mask |= 1 << lane;
    }
    if mask != 0 {
        insert(&mut spans[cur], &rows, mask);
    }
    let bg = Vec3::from(s.background);
    let mut rgb = Vec::with_capacity(s.pixels());
    let mut vis = Vec::with_capacity(s.pixels());
    for y in 0..s.height as usize {
        for sx in 0..spans_x {
            let r = resolve(&spans[y * spans_x + sx]);
            for lane in 0..LANES.min(s.width as usize - sx * LANES) {
                let p = r.get(lane).ok_or("lane out of range")?;
                rgb.push(p.over(bg).to_array());
                vis.push(p.transmittance);
            }
        }
    }
    Ok(Image {
        width: s.width,
        height: s.height,
        rgb,
        vis,
    })
}

fn mlab_dyn<A: Arithmetic>(m: usize, frame: &Frame, sorted: bool) -> Result<Image, String> {
    match m {
        1 => run_mlab::<1, A>(frame, sorted),
        2 => run_mlab::<2, A>(frame, sorted),
        3 => run_mlab::<3, A>(frame, sorted),
        4 => run_mlab::<4, A>(frame, sorted),
        5 => run_mlab::<5, A>(frame, sorted),
        6 => run_mlab::<6, A>(frame, sorted),
        7 => run_mlab::<7, A>(frame, sorted),
        8 => run_mlab::<8, A>(frame, sorted),
        12 => run_mlab::<12, A>(frame, sorted),
        16 => run_mlab::<16, A>(frame, sorted),
        _ => Err(format!("MLAB {m}: supported row counts are {MLAB_SIZES:?}")),
    }
}

fn hybrid_dyn<A: Arithmetic>(k: usize, frame: &Frame) -> Result<(Image, usize), String> {
    match k {
        0 => run_hybrid::<0, A>(frame),
        1 => run_hybrid::<1, A>(frame),
        2 => run_hybrid::<2, A>(frame),
        3 => run_hybrid::<3, A>(frame),
        4 => run_hybrid::<4, A>(frame),
        5 => run_hybrid::<5, A>(frame),
        6 => run_hybrid::<6, A>(frame),
        7 => run_hybrid::<7, A>(frame),
        11 => run_hybrid::<11, A>(frame),
        15 => run_hybrid::<15, A>(frame),
        _ => Err(format!("HT {k}: supported head sizes are {HT_SIZES:?}")),
    }
}

fn mlab_lanes<A: Arithmetic>(m: usize, frame: &Frame) -> Result<Image, String> {
    let q: fn(&Fragment) -> Row = A::quantize;
    match m {
        1 => run_lanes(
            frame,
            [[Row::EMPTY; LANES]; 1],
            q,
            lanes::mlab_insert_with::<A, 1>,
            lanes::mlab_resolve::<1>,
        ),
        2 => run_lanes(
            frame,
            [[Row::EMPTY; LANES]; 2],
            q,
            lanes::mlab_insert_with::<A, 2>,
            lanes::mlab_resolve::<2>,
        ),
        4 => run_lanes(
            frame,
            [[Row::EMPTY; LANES]; 4],
            q,
            lanes::mlab_insert_with::<A, 4>,
            lanes::mlab_resolve::<4>,
        ),
        8 => run_lanes(
            frame,
            [[Row::EMPTY; LANES]; 8],
            q,
            lanes::mlab_insert_with::<A, 8>,
            lanes::mlab_resolve::<8>,
        ),
        _ => Err(format!("MLAB {m} lanes: supported row counts are 1, 2, 4, 8")),
    }
}

fn hybrid_lanes<A: Arithmetic>(k: usize, frame: &Frame) -> Result<Image, String> {
    let q: fn(&Fragment) -> Row = A::quantize;
    match k {
        0 => run_lanes(
            frame,
            HybridSpan::<0, A>::new(),
            q,
            lanes::hybrid_insert::<0, A>,
            lanes::hybrid_resolve::<0, A>,
        ),
        1 => run_lanes(
            frame,
            HybridSpan::<1, A>::new(),
            q,
            lanes::hybrid_insert::<1, A>,
            lanes::hybrid_resolve::<1, A>,
        ),
        3 => run_lanes(
            frame,
            HybridSpan::<3, A>::new(),
            q,
            lanes::hybrid_insert::<3, A>,
            lanes::hybrid_resolve::<3, A>,
        ),
        7 => run_lanes(
            frame,
            HybridSpan::<7, A>::new(),
            q,
            lanes::hybrid_insert::<7, A>,
            lanes::hybrid_resolve::<7, A>,
        ),
        _ => Err(format!("HT {k} lanes: supported head sizes are 0, 1, 3, 7")),
    }
}

// The one place where the lab's `Arith` picks the kernel's arithmetic type.

/// MLAB `m` with arithmetic `arith` (scalar kernel), in submission order.
pub fn mlab_with(m: usize, arith: Arith, frame: &Frame) -> Result<Image, String> {
    match arith {
        Arith::Paper => mlab_dyn::<Paper>(m, frame, false),
        Arith::Unbiased => mlab_dyn::<Unbiased>(m, frame, false),
    }
}

/// MLAB `m` with arithmetic `arith`, fed each pixel's fragments front to back.
pub fn mlab_sorted_with(m: usize, arith: Arith, frame: &Frame) -> Result<Image, String> {
    match arith {
        Arith::Paper => mlab_dyn::<Paper>(m, frame, true),
        Arith::Unbiased => mlab_dyn::<Unbiased>(m, frame, true),
    }
}

/// HT `k` with arithmetic `arith` (scalar kernel): the image and the number of pixels with a
/// saturated tail.
pub fn hybrid_with(k: usize, arith: Arith, frame: &Frame) -> Result<(Image, usize), String> {
    match arith {
        Arith::Paper => hybrid_dyn::<Paper>(k, frame),
        Arith::Unbiased => hybrid_dyn::<Unbiased>(k, frame),
    }
}

/// MLAB `m` (1, 2, 4 or 8) with arithmetic `arith` through the kernel's 8-pixel lanes.
pub fn mlab_lanes_with(m: usize, arith: Arith, frame: &Frame) -> Result<Image, String> {
    match arith {
        Arith::Paper => mlab_lanes::<Paper>(m, frame),
        Arith::Unbiased => mlab_lanes::<Unbiased>(m, frame),
    }
}

/// HT `k` (0, 1, 3 or 7) with arithmetic `arith` through the kernel's 8-pixel lanes.
pub fn hybrid_lanes_with(k: usize, arith: Arith, frame: &Frame) -> Result<Image, String> {
    match arith {
        Arith::Paper => hybrid_lanes::<Paper>(k, frame),
        Arith::Unbiased => hybrid_lanes::<Unbiased>(k, frame),
    }
}

impl Arith {
    /// The kernel's default arithmetic (what `MlabFramebuffer::<M>` and the other kernel
    /// types use when none is named), which [`Method::Mlab`] and the other kernel methods
    /// without an arithmetic run.
    pub const DEFAULT: Arith = Arith::Unbiased;

    /// A validated fragment quantized to a row as this arithmetic quantizes it.
    pub fn quantize(self, fragment: &Fragment) -> Row {
        match self {
            Arith::Paper => Paper::quantize(fragment),
            Arith::Unbiased => Unbiased::quantize(fragment),
        }
    }
}

/// OVER in submission order: `C = c + C * (1 - a)`, `T = T * (1 - a)`, every result
/// rounded to half; the target starts as the background with `T = 1`.
fn over(frame: &Frame) -> Image {
    let (frags, bg) = (&frame.stream.frags, frame.bg());
    per_pixel(frame, |p| {
        let (mut c, mut t) = (bg.map(f16r), 1.0f32);
        for &i in frame.bins.of(p) {
            let f = &frags[i as usize];
            over_step(&mut c, &mut t, f.color, f.alpha);
        }
        (c, t)
    })
}

/// UNDER front to back over the sorted fragments (seed 004): `C = C + T * c`,
/// `T = T * (1 - a)`, rounded to half; a fragment arriving when `T < UNDER_THRESHOLD` is
/// discarded. The background is composited last with the remaining `T`.
fn under(frame: &Frame) -> Image {
    let (frags, bg) = (&frame.stream.frags, frame.bg());
    per_pixel(frame, |p| {
        let (mut c, mut t) = ([0.0f32; 3], 1.0f32);
        for &i in frame.sorted.of(p) {
            if t < UNDER_THRESHOLD {
                break;
            }
            let f = &frags[i as usize];
            for k in 0..3 {
                c[k] = f16r(c[k] + t * f.color[k]);
            }
            t = f16r(t * (1.0 - f.alpha));
        }
        (over_bg(c, t, bg), t)
    })
}

/// Window-space depth of a perspective projection with the frame's near and far planes.
fn window_depth(z: f32, (near, far): (f32, f32)) -> f32 {
    if near > 0.0 {
        (far * (z - near) / (z * (far - near))).clamp(0.0, 1.0)
    } else {
        z.clamp(0.0, 1.0)
    }
}

/// Non-finite results (a half target that overflowed: inf / inf) are shown black.
fn finite_or_zero(x: f32) -> f32 {
    if x.is_finite() { x } else { 0.0 }
}

/// WBOIT: `acc += (c * w, a * w)` in half, `r *= 1 - a` in unorm8;
/// `C = acc.rgb / max(acc.a, 1e-5) * (1 - r) + bg * r`.
fn wboit(frame: &Frame, weight: Weight) -> Image {
    let (frags, bg, nf) = (&frame.stream.frags, frame.bg(), frame.near_far);
    per_pixel(frame, |p| {
        let (mut acc, mut r) = ([0.0f32; 4], 255u8);
        for &i in frame.bins.of(p) {
            let f = &frags[i as usize];
            let w = weight.eval(f.color, f.alpha, f.depth, window_depth(f.depth, nf));
            wboit_step(&mut acc, &mut r, f.color, f.alpha, w);
        }
        (wboit_resolve(acc, r, bg), r as f32 / 255.0)
    })
}

/// Bavoil-Myers (seed 004, as in HT's tail): `n` fragments, `S_c`, `S_a` sums;
/// `T = (1 - S_a / n)^n`, `C = S_c / S_a * (1 - T) + bg * T` (`S_c + bg` when `S_a = 0`).
fn bavoil_myers(frame: &Frame) -> Image {
    let (frags, bg) = (&frame.stream.frags, frame.bg());
    per_pixel(frame, |p| {
        let (mut acc, mut n) = ([0.0f32; 4], 0.0f32);
        for &i in frame.bins.of(p) {
            let f = &frags[i as usize];
            for k in 0..3 {
                acc[k] = f16r(acc[k] + f.color[k]);
            }
            acc[3] = f16r(acc[3] + f.alpha);
            n += 1.0;
        }
        if n == 0.0 {
            return (bg, 1.0);
        }
        let mean = (acc[3] / n).min(1.0);
        let t = (1.0 - mean).powi(n as i32);
        let g = if acc[3] > 0.0 { (1.0 - t) / acc[3] } else { 1.0 };
        (std::array::from_fn(|k| finite_or_zero(acc[k] * g + bg[k] * t)), t)
    })
}

/// Meshkin (seed 003) as its "Simpler is better" slide writes it (lines 219-229):
/// `FinalColor = D0 + sum(A_n C_n) - D0 sum(A_n)`, that is `sum(a c) + bg (1 - sum(a))` with
/// `c` premultiplied; the sums in an RGBA16F target (line 320: "Use 16 bits per component"),
/// the final pass in f32. There is no clamp: once `sum(a)` passes 1 the background term goes
/// negative and the image darkens (seed 003, line 278: "Completely inaccurate with higher
/// alpha values"); the visibility returned is `1 - sum(a)`, negative then too.
fn meshkin(frame: &Frame) -> Image {
    let (frags, bg) = (&frame.stream.frags, frame.bg());
    per_pixel(frame, |p| {
        let mut acc = [0.0f32; 4];
        for &i in frame.bins.of(p) {
            let f = &frags[i as usize];
            for k in 0..3 {
                acc[k] = f16r(acc[k] + f.color[k]);
            }
            acc[3] = f16r(acc[3] + f.alpha);
        }
        let t = 1.0 - acc[3];
        (std::array::from_fn(|k| finite_or_zero(acc[k] + bg[k] * t)), t)
    })
}

/// Adaptive Transparency's visibility function: nodes `(z, T)` sorted front to back, where
/// `T` is the visibility just behind `z` (seed 002: "a sorted (front-to-back) sequence of
/// nodes stored into a fixed-size array", the first node `(0, 1)` implicit).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Visibility {
    /// The nodes, front to back.
    pub nodes: Vec<(f32, f32)>,
}

/// The first node AT may remove when it keeps `n` nodes: Intel's published AOIT code
/// protects the front half of the nodes from removal when `n >= 8` ("to bias our compression
/// scheme in order to favor the closest nodes to the eye we skip the first 50%"), and
/// otherwise only node 0.
///
/// Source: GameTechDev/AOIT-Update, `OIT_DX11/AOIT Technique/DXAOIT.hlsl` (commit 7a637f28,
/// the two-pass AT of the sample: fragment lists, then a visibility function per pixel),
/// lines 24-27 (`AOIT_DONT_COMPRESS_FIRST_HALF` for `OIT_NODE_COUNT >= 8`) and 219-225
/// (`startRemovalIdx = removalCandidateCount / 2`, else 1, with `removalCandidateCount = N`).
/// The sample builds only multiples of 4 nodes (`OIT_RT_COUNT = N / 4`, line 20); AT 1 and
/// AT 2 here follow the same rule (start at node 1).
pub fn at_first_removable(n: usize) -> usize {
    if n >= 8 { n / 2 } else { 1 }
}

impl Visibility {
    /// Insert a fragment of alpha `a` at depth `z` and compress, as the published AOIT code
    /// does (DXAOIT.hlsl `AOITInsertFragment`, lines 173-267; see [`at_first_removable`]):
    ///
    /// - every fragment is inserted, alpha 0 included (a purely additive one makes a node
    ///   that keeps the visibility of the node in front), in front of the nodes at its depth
    ///   (`fragmentDepth <= depth[i]` ends the search, lines 145-163); the nodes behind it
    ///   are attenuated by `1 - a` (lines 196-211);
    /// - with `n + 1` nodes (line 214), the node `i` in `at_first_removable(n)..n` with the
    ///   smallest area variation `(z_i - z_(i-1)) * (T_(i-1) - T_i)` is removed, the front
    ///   one on ties (lines 217-245): the last node, the farthest, is never a candidate;
    /// - node `i - 1` takes `T_i` and node `i` goes (lines 247-257): visibility is
    ///   underestimated, never overestimated.
    pub fn insert(&mut self, z: f32, a: f32, n: usize) {
        let n = n.max(1);
        let pos = self
            .nodes
            .iter()
            .position(|&(nz, _)| nz >= z)
            .unwrap_or(self.nodes.len());
        let before = if pos == 0 { 1.0 } else { self.nodes[pos - 1].1 };
        let t = 1.0 - a;
        self.nodes.insert(pos, (z, t * before));
        for node in &mut self.nodes[pos + 1..] {
            node.1 *= t;
        }
        while self.nodes.len() > n {
            let last = self.nodes.len() - 1;
            let area = |i: usize| (self.nodes[i].0 - self.nodes[i - 1].0) * (self.nodes[i - 1].1 - self.nodes[i].1);
            // The sample starts from the first candidate and keeps it unless a later one is
            // strictly smaller (with one node, no candidate: node 1, the last, goes).
            let mut best = at_first_removable(n);
            if best < last {
                let mut best_area = area(best);
                for i in best + 1..last {
                    let ai = area(i);
                    if ai < best_area {
                        best_area = ai;
                        best = i;
                    }
                }
            }
            self.nodes[best - 1].1 = self.nodes[best].1;
            self.nodes.remove(best);
        }
    }

    /// Visibility at depth `z`: `T` of the last node strictly in front of `z`, else 1 (the
    /// published resolve, DX_Resolve.hlsl lines 62-63).
    pub fn at(&self, z: f32) -> f32 {
        self.nodes
            .iter()
            .take_while(|&&(nz, _)| nz < z)
            .last()
            .map_or(1.0, |&(_, t)| t)
    }

    /// Visibility behind everything (of the background).
    pub fn total(&self) -> f32 {
        self.nodes.last().map_or(1.0, |&(_, t)| t)
    }
}

/// Adaptive Transparency, two passes, as the published resolve (GameTechDev/AOIT-Update,
/// `OIT_DX11/AOIT Technique/DX_Resolve.hlsl`, commit 7a637f28, lines 25-71): build the
/// visibility function with `n` nodes over the pixel's fragments in submission order, then
/// `C = sum(c * vis(z))` in f32 registers, written once to an RGBA16F target, plus
/// `bg * vis(inf)`. The departures from the sample: fragments keep their f32 color and alpha
/// (the sample reads them back from RGBA8 fragment lists), and `n` may be 1 or 2.
fn adaptive(frame: &Frame, n: usize) -> Image {
    let (frags, bg) = (&frame.stream.frags, frame.bg());
    per_pixel(frame, |p| {
        let mut v = Visibility {
            nodes: Vec::with_capacity(n + 1),
        };
        for &i in frame.bins.of(p) {
            let f = &frags[i as usize];
            v.insert(f.depth, f.alpha, n);
        }
        let mut c = [0.0f32; 3];
        for &i in frame.bins.of(p) {
            let f = &frags[i as usize];
            let vis = v.at(f.depth);
            for k in 0..3 {
                c[k] += f.color[k] * vis;
            }
        }
        let t = v.total();
        (over_bg(c.map(f16r), t, bg), t)
    })
}

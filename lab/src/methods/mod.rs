//! The compositing methods, each a function from a frame's fragment stream to an image.
//!
//! Every method sees the same [`BinnedStream`]: the stream in submission order, the fragments
//! grouped per pixel in submission order ([`BinnedStream::bins`]) and sorted front to back
//! ([`BinnedStream::sorted`], what an application that sorts would submit). Render targets are
//! emulated at their storage precision: `RGBA16F` rounds every blend result to IEEE half
//! ([`f16r`]), `R8` rounds to the nearest of 256 levels after every blend ([`r8_blend`]).
//!
//! MLAB and HT run in the kernel (`mlab`) through its framebuffer views, fragment by
//! fragment in submission order, as a pixel shader would. A lane (SIMD) variant of the
//! kernel becomes one more [`Method`] variant whose `render` calls it; see
//! [`catalog::main_job`].
//!
//! The files: [`reference`](mod@reference) the exact A-buffer; [`kernel`] MLAB and HT
//! through the kernel's pixel-major framebuffers, and the lab's [`Arith`]; [`lanes`] the same
//! kernels through the kernel's span batcher and span framebuffers; [`baselines`] OVER, UNDER,
//! WBOIT, Bavoil-Myers and Meshkin with the render-target formulas they share with
//! [`crate::tiled`]; [`adaptive`] Adaptive Transparency; [`moments`] moment-based OIT;
//! [`kclosest`] K-closest layered OIT. Everything public of those is re-exported here
//! (`oit_lab::methods::over_step`, ...). Used by path: [`catalog`], the sizes the lab runs and
//! every study's method list; [`depth`](mod@depth), fragments per covered pixel.

/// `$f::<N, $a>($args)` for the `N` of `$sizes` that equals `$n` (const generics need a literal
/// per size), else `$none`: the lab runs the kernel's framebuffers at these sizes only.
macro_rules! by_size {
    ($n:expr, [$($size:literal),*], $f:ident::<_, $a:ty> $args:tt, $none:expr) => {
        match $n {
            $($size => $f::<$size, $a> $args,)*
            _ => $none,
        }
    };
}

pub mod adaptive;
pub mod baselines;
pub mod catalog;
pub mod depth;
pub mod kclosest;
pub mod kernel;
pub mod lanes;
pub mod moments;
pub mod reference;

pub use adaptive::{Visibility, at_first_removable};
pub use baselines::{UNDER_THRESHOLD, Weight, f16r, over_step, r8_blend, wboit_resolve, wboit_step};
pub use kclosest::Layers;
pub use kernel::{Arith, hybrid_with, mlab_sorted_with, mlab_with, quantize, run_hybrid, run_mlab};
pub use lanes::{hybrid_lanes_with, mlab_lanes_with};
pub use moments::{MomentKind, MomentState, Moments};

use crate::stream::{PixelBins, Stream};
use adaptive::adaptive;
use baselines::{bavoil_myers, meshkin, mlab_f32, over, under, wboit};
use reference::reference;

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

/// A stream prepared for compositing: its fragments grouped per pixel ([`PixelBins`]), in
/// submission order and front to back. (Not a frame of the tiled renderer, [`crate::tiled`],
/// which stores no fragments.)
pub struct BinnedStream<'a> {
    /// The stream.
    pub stream: &'a Stream,
    /// Fragment indices per pixel, in submission order.
    pub bins: PixelBins,
    /// Fragment indices per pixel, front to back (later submission first on equal depth).
    pub sorted: PixelBins,
    /// Seconds spent sorting (part of the A-buffer's cost).
    pub sort_seconds: f64,
    /// Near and far depth for the window-space depth of WBOIT's Eq. 10: the stream's
    /// depth range widened by 10% on each side.
    pub near_far: (f32, f32),
}

impl<'a> BinnedStream<'a> {
    /// Group and sort the stream. The stream must be valid ([`Stream::validate`]);
    /// otherwise rendering with the kernel methods returns an error.
    pub fn new(stream: &'a Stream) -> BinnedStream<'a> {
        let bins = PixelBins::new(stream);
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
        BinnedStream {
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

/// Bytes a method stores for a frame ([`Method::storage`]): so much per pixel and so much
/// per fragment (only the A-buffer's and AT's grow with the fragments).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Storage {
    /// Bytes per pixel.
    pub per_pixel: usize,
    /// Bytes per fragment.
    pub per_fragment: usize,
}

impl Storage {
    /// Bytes for `pixels` pixels and `fragments` fragments.
    pub fn bytes(self, pixels: usize, fragments: usize) -> usize {
        self.per_pixel * pixels + self.per_fragment * fragments
    }
}

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
    /// Moment-based OIT (Münstermann et al. 2018), two additive passes.
    Mboit(Moments),
    /// K-closest layered OIT (Diligent Engine Tutorial 29) with `K` layers and a tail.
    KClosest(usize),
    /// MLAB with `M` rows of f32 (color, transmittance, depth: 20 bytes a row, never
    /// quantized) and the default arithmetic's merged depth: the ceiling of the 8-byte row,
    /// what is left being the `M`-row approximation itself (issue 30).
    MlabF32(usize),
}

impl Method {
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
            Method::Mboit(m) => m.name(),
            Method::KClosest(k) => format!("K-closest {k}"),
            Method::MlabF32(m) => format!("MLAB {m} f32 rows"),
        }
    }

    /// A file-name friendly name.
    pub fn slug(self) -> String {
        self.name()
            .to_ascii_lowercase()
            .replace([' ', '.'], "_")
            .replace("__", "_")
    }

    /// What the method stores for a frame: the one memory accounting of the lab, used by the
    /// quality tables ([`bytes_per_pixel`](Self::bytes_per_pixel)) and by the tiled frame
    /// renderer's storage table (`tiled::storage_bytes`). A row of MLAB or HT is 8 bytes;
    /// `RGBA16F` 8, `R8` 1, `R32F` 4. The A-buffer as the paper's Table 1 counts it: 12 bytes
    /// per stored fragment (RGBA8, f32 depth, 32-bit next pointer) and a 4-byte head pointer
    /// per pixel. AT stores what the A-buffer stores: the AOIT code it follows keeps every
    /// fragment in per-pixel lists and builds the visibility function in registers at the
    /// resolve (as the MLAB paper's Table 1 and the AOIT slides count it). MBOIT: `b_0` and
    /// the moments plus the RGBA16F target of its second pass ([`Moments::bytes_per_pixel`]);
    /// K-closest: 4 bytes per layer and the 4-byte RGBA8 tail.
    pub fn storage(self) -> Storage {
        let per_pixel = |per_pixel| Storage {
            per_pixel,
            per_fragment: 0,
        };
        match self {
            Method::Reference | Method::Adaptive(_) => Storage {
                per_pixel: 4,
                per_fragment: 12,
            },
            Method::Mlab(m) | Method::MlabSorted(m) | Method::MlabLanes(m) | Method::MlabWith(m, _) => per_pixel(8 * m),
            Method::Hybrid(k) | Method::HybridLanes(k) | Method::HybridWith(k, _) => per_pixel(8 * (k + 1)),
            Method::Over | Method::Under | Method::Meshkin => per_pixel(8),
            Method::Wboit(_) => per_pixel(9),
            Method::BavoilMyers => per_pixel(12),
            Method::Mboit(m) => per_pixel(m.bytes_per_pixel()),
            Method::KClosest(k) => per_pixel(4 * k + 4),
            Method::MlabF32(m) => per_pixel(20 * m),
        }
    }

    /// Memory per pixel in bytes on this stream ([`storage`](Self::storage); the A-buffer's
    /// fragments averaged over the frame).
    pub fn bytes_per_pixel(self, binned: &BinnedStream) -> f64 {
        let s = self.storage();
        let frags = binned.stream.frags.len() as f64;
        s.per_pixel as f64 + s.per_fragment as f64 * frags / binned.stream.pixels().max(1) as f64
    }

    /// Render the frame. Errors only for a stream the kernel refuses or an unsupported size.
    pub fn render(self, binned: &BinnedStream) -> Result<Image, String> {
        match self {
            Method::Reference => Ok(reference(binned)),
            Method::Mlab(m) => mlab_with(m, Arith::default(), binned),
            Method::MlabSorted(m) => mlab_sorted_with(m, Arith::default(), binned),
            Method::MlabLanes(m) => mlab_lanes_with(m, Arith::default(), binned),
            Method::HybridLanes(k) => hybrid_lanes_with(k, Arith::default(), binned),
            Method::Hybrid(k) => hybrid_with(k, Arith::default(), binned).map(|(image, _)| image),
            Method::MlabWith(m, a) => mlab_with(m, a, binned),
            Method::HybridWith(k, a) => hybrid_with(k, a, binned).map(|(image, _)| image),
            Method::Over => Ok(over(binned)),
            Method::Under => Ok(under(binned)),
            Method::Wboit(w) => Ok(wboit(binned, w)),
            Method::BavoilMyers => Ok(bavoil_myers(binned)),
            Method::Meshkin => Ok(meshkin(binned)),
            Method::Adaptive(0) => Err("AT needs at least one node".into()),
            Method::Adaptive(n) => Ok(adaptive(binned, n)),
            Method::Mboit(m) => Ok(moments::mboit(binned, m)),
            Method::KClosest(k) if (1..=kclosest::KCLOSEST_MAX).contains(&k) => Ok(kclosest::kclosest(binned, k)),
            Method::KClosest(k) => Err(format!(
                "K-closest needs 1 to {} layers, not {k}",
                kclosest::KCLOSEST_MAX
            )),
            Method::MlabF32(0) => Err("MLAB needs at least one row".into()),
            Method::MlabF32(m) => Ok(mlab_f32(binned, m)),
        }
    }
}

/// Run `f` for every pixel, on all cores, and collect the image.
fn per_pixel<F>(binned: &BinnedStream, f: F) -> Image
where
    F: Fn(usize) -> ([f32; 3], f32) + Sync,
{
    let s = binned.stream;
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

/// Non-finite results (a half target that overflowed: inf / inf) are shown black.
fn finite_or_zero(x: f32) -> f32 {
    if x.is_finite() { x } else { 0.0 }
}

//! Quality metrics of an image against the reference.
//!
//! Color metrics are computed on what a display shows: linear RGB clamped to `[0, 1]`
//! (additive light above 1 saturates). FLIP (NVIDIA's perceptual difference, LDR variant,
//! through the `nv-flip` crate) takes both images sRGB-encoded to 8 bits, at the default
//! 67 pixels per degree. [`compare_covered`] restricts the error and the visibility bias to
//! the pixels the reference covers.

use crate::methods::Image;

/// The metrics of one image against the reference.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quality {
    /// Root mean square error over every pixel and channel (linear, clamped).
    pub rmse: f64,
    /// `20 log10(1 / rmse)` in dB (infinite for identical images).
    pub psnr: f64,
    /// Largest absolute channel error.
    pub max_abs: f64,
    /// Mean FLIP error in `[0, 1]`, when computed.
    pub flip: Option<f64>,
    /// Mean signed channel error `test - reference` (negative: darker than the reference).
    pub mean_signed: f64,
    /// Mean of `vis(method) - vis(reference)`: positive means the background shows through
    /// too much.
    pub vis_bias: f64,
}

/// sRGB encoding of a linear value, clamped, to 8 bits.
pub fn srgb8(x: f32) -> u8 {
    let x = if x.is_finite() { x.clamp(0.0, 1.0) } else { 0.0 };
    let e = if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    };
    (e * 255.0 + 0.5).floor().clamp(0.0, 255.0) as u8
}

/// The image as sRGB8, row major, 3 bytes per pixel.
pub fn to_srgb8(img: &Image) -> Vec<u8> {
    img.rgb.iter().flat_map(|p| p.map(srgb8)).collect()
}

fn display(x: f32) -> f64 {
    if x.is_finite() { x.clamp(0.0, 1.0) as f64 } else { 0.0 }
}

/// RMSE, PSNR, max error and visibility bias of `test` against `reference` (same size);
/// FLIP when `with_flip`.
pub fn compare(reference: &Image, test: &Image, with_flip: bool) -> Quality {
    assert_eq!((reference.width, reference.height), (test.width, test.height));
    let n = reference.rgb.len().max(1);
    let (mut se, mut max_abs, mut vb, mut sd) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for (a, b) in reference.rgb.iter().zip(&test.rgb) {
        for k in 0..3 {
            let d = display(a[k]) - display(b[k]);
            se += d * d;
            sd -= d;
            max_abs = max_abs.max(d.abs());
        }
    }
    for (a, b) in reference.vis.iter().zip(&test.vis) {
        vb += *b as f64 - *a as f64;
    }
    let rmse = (se / (3 * n) as f64).sqrt();
    let psnr = if rmse > 0.0 {
        20.0 * (1.0 / rmse).log10()
    } else {
        f64::INFINITY
    };
    let flip = with_flip.then(|| flip_mean(reference, test));
    Quality {
        rmse,
        psnr,
        max_abs,
        flip,
        mean_signed: sd / (3 * n) as f64,
        vis_bias: vb / n as f64,
    }
}

/// Mean FLIP of `test` against `reference`.
pub fn flip_mean(reference: &Image, test: &Image) -> f64 {
    let r = nv_flip::FlipImageRgb8::with_data(reference.width, reference.height, &to_srgb8(reference));
    let t = nv_flip::FlipImageRgb8::with_data(test.width, test.height, &to_srgb8(test));
    let err = nv_flip::flip(r, t, nv_flip::DEFAULT_PIXELS_PER_DEGREE);
    nv_flip::FlipPool::from_image(&err).mean() as f64
}

/// Metrics over the covered pixels only (pixels where the reference has at least one
/// fragment): what a transparency method can get wrong. Uncovered pixels show the
/// background in every method and would dilute the whole-image PSNR.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Covered {
    /// Number of covered pixels.
    pub pixels: usize,
    /// RMSE over the covered pixels and their channels (linear, clamped to `[0, 1]`).
    pub rmse: f64,
    /// `20 log10(1 / rmse)` in dB (infinite when they agree exactly, or no pixel is covered).
    pub psnr: f64,
    /// Mean over covered pixels of `vis(method) - vis(reference)`, where `vis(reference)` is
    /// the exact product of `1 - alpha` over the pixel's fragments: positive means the
    /// background shows through too much. 0 when no pixel is covered.
    pub vis_bias: f64,
    /// The signed `vis(method) - vis(reference)` of largest magnitude over covered pixels
    /// (the first one found on ties; 0 when no pixel is covered).
    pub vis_worst: f64,
    /// Mean over covered pixels of `|vis(method) - vis(reference)|`: with `vis_bias` near 0,
    /// the typical size of a noise (a dither) rather than a bias. 0 when no pixel is covered.
    pub vis_abs: f64,
    /// The high-frequency part of the error (noise, as a dither adds): RMS over covered pixels
    /// and channels of `e(p) - mean(e over the covered pixels of the 3x3 block around p)`,
    /// `e = test - reference` on the display values. A constant error gives 0; an isolated
    /// error `d` at one interior pixel of a covered area gives `8 d / 9` there. 0 when no pixel
    /// is covered.
    pub noise: f64,
}

/// [`Covered`] metrics of `test` against `reference` (same size) over the pixels where
/// `covered` is true (`covered` has one entry per pixel).
pub fn compare_covered(reference: &Image, test: &Image, covered: &[bool]) -> Covered {
    assert_eq!((reference.width, reference.height), (test.width, test.height));
    assert_eq!(covered.len(), reference.rgb.len());
    let (mut pixels, mut se, mut vb, mut worst, mut va) = (0usize, 0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for p in (0..covered.len()).filter(|&p| covered[p]) {
        pixels += 1;
        for k in 0..3 {
            let d = display(reference.rgb[p][k]) - display(test.rgb[p][k]);
            se += d * d;
        }
        let v = test.vis[p] as f64 - reference.vis[p] as f64;
        vb += v;
        va += v.abs();
        if v.abs() > worst.abs() {
            worst = v;
        }
    }
    let rmse = if pixels > 0 {
        (se / (3 * pixels) as f64).sqrt()
    } else {
        0.0
    };
    let noise = high_pass_rms(reference, test, covered);
    Covered {
        pixels,
        rmse,
        psnr: if rmse > 0.0 {
            20.0 * (1.0 / rmse).log10()
        } else {
            f64::INFINITY
        },
        vis_bias: if pixels > 0 { vb / pixels as f64 } else { 0.0 },
        vis_worst: worst,
        vis_abs: if pixels > 0 { va / pixels as f64 } else { 0.0 },
        noise,
    }
}

/// See [`Covered::noise`].
fn high_pass_rms(reference: &Image, test: &Image, covered: &[bool]) -> f64 {
    let (w, h) = (reference.width as usize, reference.height as usize);
    let err = |p: usize, k: usize| display(test.rgb[p][k]) - display(reference.rgb[p][k]);
    let (mut sum, mut n) = (0.0f64, 0usize);
    for y in 0..h {
        for x in 0..w {
            let p = y * w + x;
            if !covered[p] {
                continue;
            }
            let mut local = [0.0f64; 3];
            let mut count = 0usize;
            for yy in y.saturating_sub(1)..(y + 2).min(h) {
                for xx in x.saturating_sub(1)..(x + 2).min(w) {
                    let q = yy * w + xx;
                    if covered[q] {
                        count += 1;
                        for (k, l) in local.iter_mut().enumerate() {
                            *l += err(q, k);
                        }
                    }
                }
            }
            for (k, l) in local.iter().enumerate() {
                let d = err(p, k) - l / count as f64;
                sum += d * d;
            }
            n += 3;
        }
    }
    if n > 0 { (sum / n as f64).sqrt() } else { 0.0 }
}

/// Mean of `values` over the entries where `mask` is true (0 when none is).
pub fn mean_where<T: Copy + Into<f64>>(values: &[T], mask: &[bool]) -> f64 {
    assert_eq!(values.len(), mask.len());
    let (mut s, mut n) = (0.0f64, 0usize);
    for (v, _) in values.iter().zip(mask).filter(|(_, m)| **m) {
        s += (*v).into();
        n += 1;
    }
    if n > 0 { s / n as f64 } else { 0.0 }
}

/// The per-pixel FLIP error map of `test` against `reference` (nv-flip, LDR, both images
/// sRGB-encoded to 8 bits, 67 pixels per degree): one value in `[0, 1]` per pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct FlipMap {
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// Error per pixel, row major.
    pub values: Vec<f32>,
}

impl FlipMap {
    /// FLIP of `test` against `reference` (same size).
    pub fn new(reference: &Image, test: &Image) -> FlipMap {
        assert_eq!((reference.width, reference.height), (test.width, test.height));
        let r = nv_flip::FlipImageRgb8::with_data(reference.width, reference.height, &to_srgb8(reference));
        let t = nv_flip::FlipImageRgb8::with_data(test.width, test.height, &to_srgb8(test));
        let err = nv_flip::flip(r, t, nv_flip::DEFAULT_PIXELS_PER_DEGREE);
        FlipMap {
            width: reference.width,
            height: reference.height,
            values: err.to_vec(),
        }
    }

    /// Mean over every pixel.
    pub fn mean(&self) -> f64 {
        mean_where(&self.values, &vec![true; self.values.len()])
    }

    /// Mean over the pixels where `mask` is true (the covered pixels): 0 when none is.
    pub fn mean_where(&self, mask: &[bool]) -> f64 {
        mean_where(&self.values, mask)
    }

    /// The map through nv-flip's own color map (`magma_lut`, what the FLIP tool writes):
    /// RGB bytes, row major.
    pub fn magma(&self) -> Vec<u8> {
        let map = nv_flip::FlipImageFloat::with_data(self.width, self.height, &self.values);
        map.apply_color_lut(&nv_flip::magma_lut()).to_vec()
    }
}

/// SSIM constants of Wang, Bovik, Sheikh & Simoncelli, "Image quality assessment: from error
/// visibility to structural similarity", IEEE Trans. Image Processing 13(4), 600-612, 2004,
/// section III-C: `K1 = 0.01`, `K2 = 0.03`, dynamic range `L = 1` (display values in [0, 1]),
/// an 11x11 circular-symmetric Gaussian window of standard deviation 1.5 normalized to sum 1.
pub const SSIM_K1: f64 = 0.01;
/// See [`SSIM_K1`].
pub const SSIM_K2: f64 = 0.03;
/// Gaussian window radius (11 taps) and standard deviation; see [`SSIM_K1`].
pub const SSIM_RADIUS: usize = 5;
/// See [`SSIM_RADIUS`].
pub const SSIM_SIGMA: f64 = 1.5;

/// sRGB encoding of a linear value clamped to `[0, 1]`, not quantized.
fn srgb_encode(x: f32) -> f64 {
    let x = display(x);
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// The SSIM window's 1D weights (the 2D window is their outer product), normalized to sum 1.
fn ssim_kernel() -> [f64; 2 * SSIM_RADIUS + 1] {
    let mut k = [0.0f64; 2 * SSIM_RADIUS + 1];
    for (i, v) in k.iter_mut().enumerate() {
        let d = i as f64 - SSIM_RADIUS as f64;
        *v = (-d * d / (2.0 * SSIM_SIGMA * SSIM_SIGMA)).exp();
    }
    let sum: f64 = k.iter().sum();
    k.map(|v| v / sum)
}

/// The Gaussian-weighted local mean of a `w x h` plane: separable, the window cut to the image
/// and renormalized near the border (the cut 2D window is the product of the two cut 1D ones).
fn ssim_blur(src: &[f64], w: usize, h: usize) -> Vec<f64> {
    let k = ssim_kernel();
    let r = SSIM_RADIUS;
    // Renormalized weights for the cut window at position `i` of `n`.
    let cut = |i: usize, n: usize| -> (usize, usize, f64) {
        let (lo, hi) = (i.saturating_sub(r), (i + r + 1).min(n));
        let sum: f64 = (lo..hi).map(|j| k[j + r - i]).sum();
        (lo, hi, sum)
    };
    let mut tmp = vec![0.0f64; w * h];
    for y in 0..h {
        let row = &src[y * w..(y + 1) * w];
        let out = &mut tmp[y * w..(y + 1) * w];
        for x in 0..w {
            if x >= r && x + r < w {
                let win = &row[x - r..=x + r];
                out[x] = win.iter().zip(&k).map(|(a, b)| a * b).sum();
            } else {
                let (lo, hi, sum) = cut(x, w);
                out[x] = (lo..hi).map(|j| k[j + r - x] * row[j]).sum::<f64>() / sum;
            }
        }
    }
    let mut out = vec![0.0f64; w * h];
    for y in 0..h {
        let (lo, hi, sum) = cut(y, h);
        let o = &mut out[y * w..(y + 1) * w];
        for j in lo..hi {
            let kj = k[j + r - y] / sum;
            for (a, b) in o.iter_mut().zip(&tmp[j * w..(j + 1) * w]) {
                *a += kj * b;
            }
        }
    }
    out
}

/// The reference's side of SSIM (its encoded channels and their local means), computed once
/// and compared with many test images ([`SsimReference::map`]).
#[derive(Clone, Debug)]
pub struct SsimReference {
    width: u32,
    height: u32,
    /// Per channel: encoded values, local mean, local mean of squares.
    planes: Vec<[Vec<f64>; 3]>,
}

impl SsimReference {
    /// Prepare `reference`.
    pub fn new(reference: &Image) -> SsimReference {
        let (w, h) = (reference.width as usize, reference.height as usize);
        let planes = (0..3)
            .map(|k| {
                let x: Vec<f64> = reference.rgb.iter().map(|p| srgb_encode(p[k])).collect();
                let xx: Vec<f64> = x.iter().map(|v| v * v).collect();
                let (mx, mxx) = (ssim_blur(&x, w, h), ssim_blur(&xx, w, h));
                [x, mx, mxx]
            })
            .collect();
        SsimReference {
            width: reference.width,
            height: reference.height,
            planes,
        }
    }

    /// The SSIM map of `test` against the prepared reference; see [`ssim_map`].
    pub fn map(&self, test: &Image) -> Vec<f64> {
        assert_eq!((self.width, self.height), (test.width, test.height));
        let (w, h) = (self.width as usize, self.height as usize);
        let n = w * h;
        let (c1, c2) = ((SSIM_K1 * 1.0).powi(2), (SSIM_K2 * 1.0).powi(2));
        let mut map = vec![0.0f64; n];
        for (k, [x, mx, mxx]) in self.planes.iter().enumerate() {
            let y: Vec<f64> = test.rgb.iter().map(|p| srgb_encode(p[k])).collect();
            let yy: Vec<f64> = y.iter().map(|v| v * v).collect();
            let xy: Vec<f64> = x.iter().zip(&y).map(|(a, b)| a * b).collect();
            let (my, myy, mxy) = (ssim_blur(&y, w, h), ssim_blur(&yy, w, h), ssim_blur(&xy, w, h));
            for p in 0..n {
                // Weighted variances as E[x^2] - mu^2 (the sums of Eq. 15), not below 0.
                let vx = (mxx[p] - mx[p] * mx[p]).max(0.0);
                let vy = (myy[p] - my[p] * my[p]).max(0.0);
                let cxy = mxy[p] - mx[p] * my[p];
                let s = (2.0 * mx[p] * my[p] + c1) * (2.0 * cxy + c2)
                    / ((mx[p] * mx[p] + my[p] * my[p] + c1) * (vx + vy + c2));
                map[p] += s / 3.0;
            }
        }
        map
    }
}

/// The per-pixel SSIM of `test` against `reference` (same size), mean of the three channels,
/// each channel on the sRGB-encoded display values (what SSIM was designed on: gamma-encoded
/// pixel values), with the constants of [`SSIM_K1`]. At each pixel, with the Gaussian window
/// `w` centred there, `mu = sum w x`, `sigma^2 = sum w (x - mu)^2`, `sigma_xy = sum w (x - mu_x)
/// (y - mu_y)` and `SSIM = (2 mu_x mu_y + C1)(2 sigma_xy + C2) / ((mu_x^2 + mu_y^2 + C1)
/// (sigma_x^2 + sigma_y^2 + C2))`, `C1 = (K1 L)^2`, `C2 = (K2 L)^2` (Eq. 13 with the weighted
/// statistics of Eq. 14-16). Near the border the window is cut to the image and renormalized
/// (Wang et al. drop the border instead; a map needs a value at every pixel, so that it can be
/// averaged over the covered ones). 1 for identical images.
pub fn ssim_map(reference: &Image, test: &Image) -> Vec<f64> {
    SsimReference::new(reference).map(test)
}

/// Every metric of one image against the reference: whole image and covered pixels.
#[derive(Clone, Debug, PartialEq)]
pub struct Scores {
    /// Whole-image metrics ([`compare`]); its `flip` is the mean of [`Scores::flip_map`].
    pub whole: Quality,
    /// Metrics over the covered pixels ([`compare_covered`]).
    pub covered: Covered,
    /// Mean FLIP over the covered pixels, when FLIP was computed.
    pub flip_covered: Option<f64>,
    /// Mean SSIM over every pixel ([`ssim_map`]).
    pub ssim: f64,
    /// Mean SSIM over the covered pixels.
    pub ssim_covered: f64,
    /// The FLIP error map, when computed.
    pub flip_map: Option<FlipMap>,
}

/// [`Scores`] of `test` against `reference`, covered pixels where `covered` is true.
pub fn score(reference: &Image, test: &Image, covered: &[bool], with_flip: bool) -> Scores {
    Scorer::new(reference, covered).score(test, with_flip)
}

/// A reference prepared for [`Scores`] of many test images.
pub struct Scorer<'a> {
    reference: &'a Image,
    covered: &'a [bool],
    ssim: SsimReference,
}

impl<'a> Scorer<'a> {
    /// Prepare `reference`, covered pixels where `covered` is true.
    pub fn new(reference: &'a Image, covered: &'a [bool]) -> Scorer<'a> {
        Scorer {
            reference,
            covered,
            ssim: SsimReference::new(reference),
        }
    }

    /// [`Scores`] of `test`.
    pub fn score(&self, test: &Image, with_flip: bool) -> Scores {
        score_prepared(self.reference, &self.ssim, test, self.covered, with_flip)
    }
}

fn score_prepared(reference: &Image, sref: &SsimReference, test: &Image, covered: &[bool], with_flip: bool) -> Scores {
    let mut whole = compare(reference, test, false);
    let flip_map = with_flip.then(|| FlipMap::new(reference, test));
    whole.flip = flip_map.as_ref().map(FlipMap::mean);
    let ssim = sref.map(test);
    Scores {
        whole,
        covered: compare_covered(reference, test, covered),
        flip_covered: flip_map.as_ref().map(|m| m.mean_where(covered)),
        ssim: mean_where(&ssim, &vec![true; ssim.len()]),
        ssim_covered: mean_where(&ssim, covered),
        flip_map,
    }
}

/// How much an image changes between two submission orders of the same primitives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Change {
    /// Share of the covered pixels (in `[0, 1]`) where a displayed 8-bit sRGB channel differs
    /// by more than [`CHANGE_LEVELS`] levels.
    pub share: f64,
    /// Largest change of a displayed 8-bit sRGB channel, in levels (0-255).
    pub max_levels: u8,
    /// Mean FLIP of one image against the other over the covered pixels, when computed.
    pub flip: Option<f64>,
}

/// A displayed channel "changes" when its 8-bit sRGB value moves by more than this (2/255).
pub const CHANGE_LEVELS: u8 = 2;

/// [`Change`] between `a` and `b` (same size) over the pixels where `covered` is true.
pub fn change(a: &Image, b: &Image, covered: &[bool], with_flip: bool) -> Change {
    assert_eq!((a.width, a.height), (b.width, b.height));
    assert_eq!(covered.len(), a.rgb.len());
    let (mut n, mut moved, mut max_levels) = (0usize, 0usize, 0u8);
    for p in (0..covered.len()).filter(|&p| covered[p]) {
        n += 1;
        let d = (0..3)
            .map(|k| srgb8(a.rgb[p][k]).abs_diff(srgb8(b.rgb[p][k])))
            .max()
            .unwrap_or(0);
        max_levels = max_levels.max(d);
        moved += usize::from(d > CHANGE_LEVELS);
    }
    Change {
        share: if n > 0 { moved as f64 / n as f64 } else { 0.0 },
        max_levels,
        flip: with_flip.then(|| FlipMap::new(a, b).mean_where(covered)),
    }
}

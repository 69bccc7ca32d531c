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

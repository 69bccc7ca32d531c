//! The baselines over the per-pixel bins: OVER, UNDER, WBOIT, Bavoil-Myers and Meshkin, with
//! the render-target formulas ([`over_step`], [`wboit_step`], [`wboit_resolve`]) that the
//! tiled frame renderer ([`crate::tiled`]) uses too.

// Channel loops `for k in 0..3` index several arrays at once (target, fragment, weight);
// written as in the blend equations.
#![allow(clippy::needless_range_loop)]

use super::{BinnedStream, Image, finite_or_zero, over_bg, per_pixel};
use mlab::half::f16;

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

    pub(super) fn label(self) -> &'static str {
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

/// OVER in submission order: `C = c + C * (1 - a)`, `T = T * (1 - a)`, every result
/// rounded to half; the target starts as the background with `T = 1`.
pub(super) fn over(binned: &BinnedStream) -> Image {
    let (frags, bg) = (&binned.stream.frags, binned.bg());
    per_pixel(binned, |p| {
        let (mut c, mut t) = (bg.map(f16r), 1.0f32);
        for &i in binned.bins.of(p) {
            let f = &frags[i as usize];
            over_step(&mut c, &mut t, f.color, f.alpha);
        }
        (c, t)
    })
}

/// MLAB with `m` rows of f32 (no quantization; issue 30's ceiling of the 8-byte row): Listing 1
/// in submission order, `merge(front, back) = (A_f + A_b T_f, T_f T_b, z)` with the default
/// arithmetic's merged depth in real numbers, `z = z_f + (z_b - z_f) w`,
/// `w = T_f (1 - T_b) / (1 - T_f T_b)` where `T_f >= 160/255` (else `z_f`), then Eq. 5 and 6.
pub(super) fn mlab_f32(binned: &BinnedStream, m: usize) -> Image {
    let (frags, bg) = (&binned.stream.frags, binned.bg());
    per_pixel(binned, |p| {
        // (color, transmittance, depth), front to back.
        let mut rows: Vec<([f32; 3], f32, f32)> = Vec::with_capacity(m + 1);
        for &i in binned.bins.of(p) {
            let f = &frags[i as usize];
            let at = rows.iter().position(|r| f.depth <= r.2).unwrap_or(rows.len());
            rows.insert(at, (f.color, 1.0 - f.alpha, f.depth));
            if rows.len() > m {
                let (cb, tb, zb) = rows.pop().expect("m + 1 rows");
                let (cf, tf, zf) = rows.pop().expect("m >= 1");
                let c = [cf[0] + cb[0] * tf, cf[1] + cb[1] * tf, cf[2] + cb[2] * tf];
                let opacity = 1.0 - tf * tb;
                let z = if tf >= 160.0 / 255.0 && opacity > 0.0 && zb > zf {
                    zf + (zb - zf) * (tf * (1.0 - tb) / opacity)
                } else {
                    zf
                };
                rows.push((c, tf * tb, z));
            }
        }
        let (mut c, mut t) = ([0.0f32; 3], 1.0f32);
        for (rc, rt, _) in rows {
            for k in 0..3 {
                c[k] += rc[k] * t;
            }
            t *= rt;
        }
        (over_bg(c, t, bg), t)
    })
}

/// UNDER front to back over the sorted fragments (seed 004): `C = C + T * c`,
/// `T = T * (1 - a)`, rounded to half; a fragment arriving when `T < UNDER_THRESHOLD` is
/// discarded. The background is composited last with the remaining `T`.
pub(super) fn under(binned: &BinnedStream) -> Image {
    let (frags, bg) = (&binned.stream.frags, binned.bg());
    per_pixel(binned, |p| {
        let (mut c, mut t) = ([0.0f32; 3], 1.0f32);
        for &i in binned.sorted.of(p) {
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

/// Window-space depth of a perspective projection with the frame's near and far planes
/// (WBOIT eq. 10 and K-closest layered OIT use it).
pub fn window_depth(z: f32, (near, far): (f32, f32)) -> f32 {
    if near > 0.0 {
        (far * (z - near) / (z * (far - near))).clamp(0.0, 1.0)
    } else {
        z.clamp(0.0, 1.0)
    }
}

/// WBOIT: `acc += (c * w, a * w)` in half, `r *= 1 - a` in unorm8;
/// `C = acc.rgb / max(acc.a, 1e-5) * (1 - r) + bg * r`.
pub(super) fn wboit(binned: &BinnedStream, weight: Weight) -> Image {
    let (frags, bg, nf) = (&binned.stream.frags, binned.bg(), binned.near_far);
    per_pixel(binned, |p| {
        let (mut acc, mut r) = ([0.0f32; 4], 255u8);
        for &i in binned.bins.of(p) {
            let f = &frags[i as usize];
            let w = weight.eval(f.color, f.alpha, f.depth, window_depth(f.depth, nf));
            wboit_step(&mut acc, &mut r, f.color, f.alpha, w);
        }
        (wboit_resolve(acc, r, bg), r as f32 / 255.0)
    })
}

/// Bavoil-Myers (seed 004, as in HT's tail): `n` fragments, `S_c`, `S_a` sums;
/// `T = (1 - S_a / n)^n`, `C = S_c / S_a * (1 - T) + bg * T` (`S_c + bg` when `S_a = 0`).
pub(super) fn bavoil_myers(binned: &BinnedStream) -> Image {
    let (frags, bg) = (&binned.stream.frags, binned.bg());
    per_pixel(binned, |p| {
        let (mut acc, mut n) = ([0.0f32; 4], 0.0f32);
        for &i in binned.bins.of(p) {
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
pub(super) fn meshkin(binned: &BinnedStream) -> Image {
    let (frags, bg) = (&binned.stream.frags, binned.bg());
    per_pixel(binned, |p| {
        let mut acc = [0.0f32; 4];
        for &i in binned.bins.of(p) {
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

//! Moment-based OIT (Münstermann, Krumpen, Klein & Peters, "Moment-Based Order-Independent
//! Transparency", Proc. ACM CGIT 1(1), I3D 2018): a first additive pass sums, per pixel, the
//! absorbance `A = -ln(1 - a)` of every fragment (`b_0`) and its power or trigonometric
//! moments over a warped depth; the second pass reconstructs each fragment's transmittance
//! from them (the paper's moment bound with its bias and overestimation), sums `c T` and
//! `a T` additively, and the composite normalizes: `C = sum(c T) / sum(a T) (1 - e^-b0) +
//! bg e^-b0`.
//!
//! Written from the paper and checked line by line against the authors' shader code (CC0,
//! momentsingraphics.de; the HLSL `MomentOIT.hlsli`, `MomentMath.hlsli`,
//! `TrigonometricMomentMath.hlsli`), as stored in the public GLSL port
//! chrismile/PixelSyncOIT (commit feacb29b), `Data/Shaders/MBOIT/`:
//!
//! - generation, `MomentOIT.glsl` lines 108-176 (power; the 16-bit branch un-normalizes the
//!   stored moments by `b_0`, adds the new moments quantized, renormalizes and offsets,
//!   lines 141-170) and 178-262 (trigonometric; 16-bit: `b = (2 s - 1) b_0`, add, `s = b / b_0
//!   / 2 + 1/2`); the phase of a trigonometric moment `depth * wz.y + wz.y`, line 194;
//! - resolve, lines 441-546: pixels with `b_0 < 0.00100050033` are skipped (line 450),
//!   the moments normalized by `b_0` (32-bit) or dequantized (16-bit), and the bias vectors
//!   `(0, 0.375, 0, 0.375)` (4 power, 32-bit, line 479), `(0, 0.628, 0, 0.628)` (16-bit, line
//!   488), `(0, 0.48, 0, 0.451, 0, 0.45)` (6 power, 32-bit, line 534),
//!   `(0, 0.5566, 0, 0.489, 0, 0.47869382)` (16-bit, line 543);
//! - the quantization of 16-bit power moments, `MomentMath.glsl` lines 156-207 (4 and 6);
//!   the reconstruction from 4 power moments lines 246-301, from 6 lines 305-385;
//! - `TrigonometricMomentMath.glsl` lines 25-39 (`circleToParameter`, the root weights with
//!   the wrapping zone), 43-111 (2 trigonometric moments), 115-208 (3);
//! - `src/OIT/OIT_MBOIT_Utils.cpp` lines 22-54: the wrapping zone parameters for the angle
//!   `0.1 pi`; `src/OIT/OIT_MBOIT.cpp` lines 193-221: the bias per variant, the paper's values
//!   in the comments (the port multiplies the 16-bit ones by 10): power 4 `5e-7` / `6e-5`
//!   (32 / 16 bit), power 6 `5e-6` / `6e-4`, trigonometric 2 `4e-7` / `4e-4`, trigonometric 3
//!   `8e-7` / `6.5e-4`. The overestimation is the paper's 0.25 (the port's default is 0.1).
//!
//! Depth is warped as in the port (`MBOITHeader.glsl` lines 27-31, `OIT_MBOIT.cpp` lines
//! 333-341): `2 (ln z - ln near) / (ln far - ln near) - 1`, near and far the stream's depth
//! range widened by 10 % (the lab's `near_far`).
//!
//! Memory: the paper counts `b_0` and the moments at 32 or 16 bits each (the project page
//! cg.ivd.kit.edu/english/mboit.php: "6 power moments, 112 bits", "3 trigonometric moments,
//! 224 bits"), so the 16-bit variants keep `b_0` in 16 bits too: the lab stores it as a half
//! float there (the shader's `RasterizerOrderedTexture2DArray<float>` with a 16-bit float
//! format), f32 in the 32-bit variants. The lab adds the second pass's RGBA16F target (8 B),
//! as it counts WBOIT's accumulation target: [`Moments::bytes_per_pixel`].
//!
//! Departures, each named:
//! - the reconstruction runs in f64 (the shaders: f32), by Gaussian elimination of the Hankel
//!   or Toeplitz system instead of the shaders' hand-unrolled Cholesky, and the roots by closed
//!   forms (real quadratic; real cubic by the trigonometric form, as `SolveCubic`; complex
//!   quadratic) or, for the complex cubic of 3 trigonometric moments, by Durand-Kerner
//!   iteration instead of Blinn's closed form; negative discriminants from rounding are
//!   clamped to 0. The same roots and weights, more precisely computed: the bias is the
//!   paper's all the same. Storage is emulated at its precision (f32 sums in submission order;
//!   16-bit: unorm16 rounding after every read-modify-write, in submission order as the
//!   rasterizer ordered view does);
//! - the absorbance of one fragment is clamped to 10 (`ABSORBANCE_MAX_VALUE`, the port's
//!   `MomentOIT.glsl` lines 41 and 119-121; the HLSL has no clamp, and an alpha of 1 gives an
//!   infinite `b_0`);
//! - the composite divides by `max(sum(a T), 1e-5)`, as the lab's WBOIT resolve does (the
//!   shader divides by `sum(a T)` unguarded);
//! - 8 power moments and 4 trigonometric moments are not run (issue 25 asks for 4 and 6 power,
//!   2 and 3 trigonometric).

// Index loops over several arrays at once (stored, offset, new moments; matrix rows and
// columns), written as the formulas.
#![allow(clippy::needless_range_loop)]

mod solve;

pub use solve::{C64, Field, Lu};

use super::{BinnedStream, Image, f16r, finite_or_zero, per_pixel};
use solve::{complex_roots, interpolate, real_roots};

/// Which moments.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MomentKind {
    /// 4 power moments `z, z^2, z^3, z^4`.
    Power4,
    /// 6 power moments.
    Power6,
    /// 2 trigonometric moments `e^(i phi), e^(2 i phi)` (4 real values).
    Trig2,
    /// 3 trigonometric moments (6 real values).
    Trig3,
}

/// A moment-based OIT variant: the moments and their storage.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Moments {
    /// Which moments.
    pub kind: MomentKind,
    /// 16-bit unorm moments (quantized; a rasterizer ordered view), else 32-bit float sums.
    pub half: bool,
}

/// The paper's overestimation weight.
pub const OVERESTIMATION: f64 = 0.25;

/// The wrapping zone angle of the trigonometric moments (`OIT_MBOIT_Utils.cpp` line 41).
pub const WRAPPING_ZONE_ANGLE: f64 = 0.1 * std::f64::consts::PI;

/// Pixels whose `b_0` is below this are left to the background (resolve, line 450).
pub const B0_MIN: f32 = 0.001_000_500_3;

/// The absorbance clamp of one fragment (see the module's departures).
pub const ABSORBANCE_MAX: f32 = 10.0;

impl Moments {
    /// Every variant the lab runs, in table order.
    pub const ALL: [Moments; 8] = [
        Moments::new(MomentKind::Power4, true),
        Moments::new(MomentKind::Power4, false),
        Moments::new(MomentKind::Power6, true),
        Moments::new(MomentKind::Power6, false),
        Moments::new(MomentKind::Trig2, true),
        Moments::new(MomentKind::Trig2, false),
        Moments::new(MomentKind::Trig3, true),
        Moments::new(MomentKind::Trig3, false),
    ];

    /// A variant.
    pub const fn new(kind: MomentKind, half: bool) -> Moments {
        Moments { kind, half }
    }

    /// Real values stored besides `b_0`.
    pub fn values(self) -> usize {
        match self.kind {
            MomentKind::Power4 | MomentKind::Trig2 => 4,
            MomentKind::Power6 | MomentKind::Trig3 => 6,
        }
    }

    /// Trigonometric moments.
    pub fn trig(self) -> bool {
        matches!(self.kind, MomentKind::Trig2 | MomentKind::Trig3)
    }

    /// Bits per pixel as the paper counts them: `b_0` and the moments, 32 or 16 bits each
    /// (6 power moments at 16 bit: 112 bits; 3 trigonometric at 32: 224).
    pub fn paper_bits(self) -> usize {
        (self.values() + 1) * if self.half { 16 } else { 32 }
    }

    /// Bytes per pixel as the lab counts them: the paper's plus the RGBA16F target of the
    /// second pass.
    pub fn bytes_per_pixel(self) -> usize {
        self.paper_bits() / 8 + 8
    }

    /// The paper's moment bias for this variant (see the module).
    pub fn bias(self) -> f64 {
        match (self.kind, self.half) {
            (MomentKind::Power4, false) => 5e-7,
            (MomentKind::Power4, true) => 6e-5,
            (MomentKind::Power6, false) => 5e-6,
            (MomentKind::Power6, true) => 6e-4,
            (MomentKind::Trig2, false) => 4e-7,
            (MomentKind::Trig2, true) => 4e-4,
            (MomentKind::Trig3, false) => 8e-7,
            (MomentKind::Trig3, true) => 6.5e-4,
        }
    }

    /// Display name, e.g. `MBOIT 6 power 16-bit`.
    pub fn name(self) -> String {
        let (n, k) = match self.kind {
            MomentKind::Power4 => (4, "power"),
            MomentKind::Power6 => (6, "power"),
            MomentKind::Trig2 => (2, "trig"),
            MomentKind::Trig3 => (3, "trig"),
        };
        format!("MBOIT {n} {k} {}-bit", if self.half { 16 } else { 32 })
    }
}

/// The wrapping zone parameters `(angle, pi - angle / 2, 1 / (end - begin), 1 - end / (end -
/// begin))`, `begin` and `end` the circle parameters of `2 pi - angle` and the largest one (7).
pub fn wrapping_zone() -> [f64; 4] {
    let a = WRAPPING_ZONE_ANGLE;
    let angle = 2.0 * std::f64::consts::PI - a;
    let begin = circle_parameter(angle.cos(), angle.sin());
    let end = 7.0;
    [
        a,
        std::f64::consts::PI - 0.5 * a,
        1.0 / (end - begin),
        1.0 - end / (end - begin),
    ]
}

/// `circleToParameter`: grows monotonically with the angle of `(x, y)` over `[0, 2 pi)`.
pub fn circle_parameter(x: f64, y: f64) -> f64 {
    let r = y.abs() - x.abs();
    let r = if x < 0.0 { 2.0 - r } else { r };
    if y < 0.0 { 6.0 - r } else { r }
}

/// The moment vector of one fragment at warped depth `z` (in `[-1, 1]`), before weighting by
/// its absorbance: `z, z^2, ..` or `cos, sin` of `k phi`, in f32 as the shader computes it.
pub fn features(m: Moments, z: f32) -> [f32; 6] {
    let mut f = [0.0f32; 6];
    if m.trig() {
        // wz.y = pi - angle / 2 (wrapping_zone()[1]).
        let wy = (std::f64::consts::PI - 0.5 * WRAPPING_ZONE_ANGLE) as f32;
        let phase = z * wy + wy;
        let (s, c) = phase.sin_cos();
        let (mut re, mut im) = (c, s);
        for k in 0..m.values() / 2 {
            f[2 * k] = re;
            f[2 * k + 1] = im;
            (re, im) = (re * c - im * s, re * s + im * c);
        }
    } else {
        let mut p = z;
        for v in f.iter_mut().take(m.values()) {
            *v = p;
            p *= z;
        }
    }
    f
}

// 16-bit power moments: `q_j = sum_i v_i G_i[j]` over the odd moments `(z, z^3, z^5)` and the
// even ones `(z^2, z^4, z^6)` separately (MomentMath.glsl lines 161-165, 180-192; the matrices
// as the HLSL writes them, row i multiplying moment i), then offsets (lines 156-159, 174-178).
const SQRT3: f32 = 1.732_050_8;
const Q4_ODD: [[f32; 2]; 2] = [[1.5, SQRT3 * 0.5], [-2.0, -SQRT3 * 2.0 / 9.0]];
const Q4_EVEN: [[f32; 2]; 2] = [[4.0, 0.5], [-4.0, 0.5]];
const D4_ODD: [[f32; 2]; 2] = [[-1.0 / 3.0, -0.75], [SQRT3, 0.75 * SQRT3]];
const D4_EVEN: [[f32; 2]; 2] = [[0.125, -0.125], [1.0, 1.0]];
const Q6_ODD: [[f32; 3]; 3] = [
    [2.5, -1.874_998_6, 1.265_830_4],
    [-10.0, 4.207_575_4, -1.476_448_8],
    [8.0, -1.832_576_8, 0.710_616_6],
];
const Q6_EVEN: [[f32; 3]; 3] = [
    [4.0, 9.0, -0.577_598_06],
    [-4.0, -24.0, 4.619_366_5],
    [0.0, 16.0, -3.079_539],
];
const D6_ODD: [[f32; 3]; 3] = [
    [-0.028_777_892, 0.099_952_36, 0.258_933_54],
    [0.476_355_5, 0.845_325_8, 0.907_796_2],
    [1.552_428_1, 1.054_725_7, 0.833_273_36],
];
const D6_EVEN: [[f32; 3]; 3] = [
    [0.000_012_530_44, -0.249_987_47, -0.374_988_25],
    [0.166_684_94, 0.166_684_94, 0.218_767_13],
    [0.866_025_4, 0.866_025_4, 0.811_898_8],
];

fn mat<const N: usize>(v: [f32; N], g: &[[f32; N]; N]) -> [f32; N] {
    std::array::from_fn(|j| (0..N).map(|i| v[i] * g[i][j]).sum())
}

/// Apply the matrices `odd` (to `b1, b3, ..`) and `even` (to `b2, b4, ..`) to the moment
/// vector `b = (b1, b2, ...)`.
fn split_apply<const N: usize>(b: [f32; 6], odd: &[[f32; N]; N], even: &[[f32; N]; N]) -> [f32; 6] {
    let o = mat::<N>(std::array::from_fn(|i| b[2 * i]), odd);
    let e = mat::<N>(std::array::from_fn(|i| b[2 * i + 1]), even);
    let mut out = [0.0f32; 6];
    for i in 0..N {
        out[2 * i] = o[i];
        out[2 * i + 1] = e[i];
    }
    out
}

/// The 16-bit quantization of power moments `(b1, b2, ...)` (no offset).
pub fn quantize(m: Moments, b: [f32; 6]) -> [f32; 6] {
    match m.kind {
        MomentKind::Power4 => split_apply(b, &Q4_ODD, &Q4_EVEN),
        _ => split_apply(b, &Q6_ODD, &Q6_EVEN),
    }
}

/// The inverse of [`quantize`].
pub fn dequantize(m: Moments, q: [f32; 6]) -> [f32; 6] {
    match m.kind {
        MomentKind::Power4 => split_apply(q, &D4_ODD, &D4_EVEN),
        _ => split_apply(q, &D6_ODD, &D6_EVEN),
    }
}

/// The offsets added to the quantized power moments before they are stored as unorm16
/// (`offsetMoments`): 0.5 on the odd ones, and 0.018888946 on `b6`'s slot for 6 moments.
pub fn offsets(m: Moments) -> [f32; 6] {
    match m.kind {
        MomentKind::Power4 => [0.5, 0.0, 0.5, 0.0, 0.0, 0.0],
        _ => [0.5, 0.0, 0.5, 0.0, 0.5, 0.018_888_946],
    }
}

fn unorm16(x: f32) -> f32 {
    (x.clamp(0.0, 1.0) * 65535.0).round() / 65535.0
}

/// One pixel's moments as stored: `b_0` (f32; half in the 16-bit variants) and the moments (32-bit: the sums; 16-bit: the
/// normalized, quantized and offset unorm16 values as read back).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MomentState {
    /// Total absorbance.
    pub b0: f32,
    /// The stored moments.
    pub b: [f32; 6],
}

impl MomentState {
    /// The first pass for one fragment of transmittance `t` at warped depth `z`.
    pub fn add(&mut self, m: Moments, z: f32, t: f32) {
        if t > 0.999_999_9 {
            return;
        }
        let a = (-t.ln()).min(ABSORBANCE_MAX);
        let f = features(m, z);
        let n = m.values();
        if !m.half {
            self.b0 += a;
            for (b, f) in self.b.iter_mut().zip(f).take(n) {
                *b += f * a;
            }
            return;
        }
        if m.trig() {
            let b0 = self.b0;
            self.b0 = f16r(self.b0 + a);
            for i in 0..n {
                let v = (self.b[i] * 2.0 - 1.0) * b0 + f[i] * a;
                self.b[i] = unorm16(v / self.b0 * 0.5 + 0.5);
            }
            return;
        }
        let off = offsets(m);
        let fq = quantize(m, f);
        let b0 = self.b0;
        self.b0 = f16r(self.b0 + a);
        for i in 0..n {
            let v = (self.b[i] - off[i]) * b0 + fq[i] * a;
            self.b[i] = unorm16(v / self.b0 + off[i]);
        }
    }

    /// The normalized moments the resolve reconstructs from (`b_k / b_0`, or dequantized).
    pub fn normalized(&self, m: Moments) -> [f64; 6] {
        let n = m.values();
        let mut v = [0.0f32; 6];
        if !m.half {
            for i in 0..n {
                v[i] = self.b[i] / self.b0;
            }
        } else if m.trig() {
            for i in 0..n {
                v[i] = self.b[i] * 2.0 - 1.0;
            }
        } else {
            let off = offsets(m);
            let mut q = [0.0f32; 6];
            for i in 0..n {
                q[i] = self.b[i] - off[i];
            }
            v = dequantize(m, q);
        }
        v.map(f64::from)
    }

    /// The second pass's reconstruction for this pixel.
    pub fn resolver(&self, m: Moments) -> Resolver {
        let b = self.normalized(m);
        let b0 = self.b0 as f64;
        if m.trig() {
            return Resolver::trig(b0, &b[..m.values()], m.bias(), OVERESTIMATION);
        }
        let bias_vector: &[f64] = match (m.kind, m.half) {
            (MomentKind::Power4, false) => &[0.0, 0.375, 0.0, 0.375],
            (MomentKind::Power4, true) => &[0.0, 0.628, 0.0, 0.628],
            (_, false) => &[0.0, 0.48, 0.0, 0.451, 0.0, 0.45],
            (_, true) => &[0.0, 0.5566, 0.0, 0.489, 0.0, 0.478_693_82],
        };
        Resolver::power(b0, &b[..m.values()], bias_vector, m.bias(), OVERESTIMATION)
    }

    /// The reconstructed transmittance at warped depth `z` ([`Resolver::at`]); see
    /// [`transmittance`].
    pub fn transmittance_at(&self, m: Moments, z: f32) -> f32 {
        transmittance(&self.resolver(m), z)
    }
}

/// The reconstructed transmittance at warped depth `z`. Where the f64 reconstruction meets a
/// root exactly at `z` (0 / 0 in the divided differences: one fragment, or all at one depth)
/// it is evaluated `1e-7` behind `z` instead (the shaders' f32 rounding never lands exactly
/// there); still not finite: 0 (HLSL `saturate(NaN)`).
pub fn transmittance(r: &Resolver, z: f32) -> f32 {
    let t = r.at(z as f64);
    if t.is_finite() {
        return t as f32;
    }
    let t = r.at(z as f64 + 1e-7);
    if t.is_finite() { t as f32 } else { 0.0 }
}

/// The second pass of one pixel: its biased moments and the factored system, evaluated per
/// fragment depth ([`Resolver::at`]).
#[derive(Clone, Copy, Debug)]
pub enum Resolver {
    /// Power moments: `b_0`, the biased moments `(1, b1, b2, ...)`, the Hankel system.
    Power {
        /// Total absorbance.
        b0: f64,
        /// `mom[k]` is the biased `b_k` (`mom[0] = 1`).
        mom: [f64; 7],
        /// The Hankel matrix `B_ij = b_(i+j)`, factored.
        lu: Lu<f64>,
        /// The overestimation weight.
        overestimation: f64,
    },
    /// Trigonometric moments: `b_0`, the scaled moments, the Toeplitz system.
    Trig {
        /// Total absorbance.
        b0: f64,
        /// `mom[k]` is the scaled `b_k` (`mom[0] = 1`).
        mom: [C64; 4],
        /// The Toeplitz matrix `M_ij = b_(i-j)`, `b_(-k) = conj(b_k)`, factored.
        lu: Lu<C64>,
        /// The overestimation weight.
        overestimation: f64,
        /// The wrapping zone parameters.
        wz: [f64; 4],
    },
}

impl Resolver {
    /// From normalized power moments `b = (b1, ..)` and `b_0`: the moments biased towards
    /// `bias_vector` by `bias`, the Hankel matrix factored.
    pub fn power(b0: f64, b: &[f64], bias_vector: &[f64], bias: f64, overestimation: f64) -> Resolver {
        let mut mom = [0.0f64; 7];
        mom[0] = 1.0;
        for (k, (&x, &v)) in b.iter().zip(bias_vector).enumerate() {
            mom[k + 1] = x * (1.0 - bias) + v * bias;
        }
        let m = b.len() / 2 + 1;
        let mut h = [[0.0f64; 4]; 4];
        for (i, row) in h.iter_mut().enumerate().take(m) {
            row[..m].copy_from_slice(&mom[i..i + m]);
        }
        Resolver::Power {
            b0,
            mom,
            lu: Lu::new(h, m),
            overestimation,
        }
    }

    /// From normalized trigonometric moments `b = (re b1, im b1, ..)` and `b_0`: the moments
    /// scaled by `1 - bias`, the Toeplitz matrix factored.
    pub fn trig(b0: f64, b: &[f64], bias: f64, overestimation: f64) -> Resolver {
        let n = b.len() / 2;
        let s = 1.0 - bias;
        let mut mom = [C64::ZERO; 4];
        mom[0] = C64(1.0, 0.0);
        for k in 1..=n {
            mom[k] = C64(b[2 * k - 2] * s, b[2 * k - 1] * s);
        }
        let mut mt = [[C64::ZERO; 4]; 4];
        for i in 0..=n {
            for j in 0..=n {
                mt[i][j] = if i >= j { mom[i - j] } else { mom[j - i].conj() };
            }
        }
        Resolver::Trig {
            b0,
            mom,
            lu: Lu::new(mt, n + 1),
            overestimation,
            wz: wrapping_zone(),
        }
    }

    /// The transmittance at warped depth `z`.
    ///
    /// Power: `B c = (1, z, z^2, ..)`, the roots of `sum c_k x^k`, the weights
    /// (`overestimation` at `z`, 1 at roots in front of `z`, 0 behind), the interpolating
    /// polynomial `p`, `T = clamp(exp(-b_0 sum p_k b_k), 0, 1)`.
    ///
    /// Trigonometric: `M c = (1, u, u^2, ..)` with `u = e^(i phase)`, the roots of
    /// `sum conj(c_k) x^k`, the weights through `circleToParameter` and the wrapping zone, the
    /// interpolating polynomial `p`, `T = exp(-b_0 Re(sum b_k p_k))` (not clamped, as the shader).
    pub fn at(&self, z: f64) -> f64 {
        match *self {
            Resolver::Power {
                b0,
                mom,
                lu,
                overestimation,
            } => {
                let m = lu.n;
                let mut y = [0.0f64; 4];
                let mut zp = 1.0;
                for yi in y.iter_mut().take(m) {
                    *yi = zp;
                    zp *= z;
                }
                let c = lu.solve(y);
                let (roots, nr) = real_roots(&c[..m]);
                let mut pts = [z; 4];
                let mut f = [overestimation; 4];
                for k in 0..nr {
                    pts[k + 1] = roots[k];
                    f[k + 1] = if roots[k] < z { 1.0 } else { 0.0 };
                }
                let p = interpolate(&pts[..=nr], &f[..=nr]);
                let absorbance: f64 = (0..m).map(|k| p[k] * mom[k]).sum();
                let t = (-b0 * absorbance).exp();
                if t.is_nan() { t } else { t.clamp(0.0, 1.0) }
            }
            Resolver::Trig {
                b0,
                mom,
                lu,
                overestimation,
                wz,
            } => {
                let n = lu.n - 1;
                let phase = z * wz[1] + wz[1];
                let u = C64(phase.cos(), phase.sin());
                let mut y = [C64::ZERO; 4];
                let mut up = C64(1.0, 0.0);
                for yi in y.iter_mut().take(n + 1) {
                    *yi = up;
                    up = up.mul(u);
                }
                let c = lu.solve(y);
                let mut coeffs = [C64::ZERO; 4];
                for k in 0..=n {
                    coeffs[k] = c[k].conj();
                }
                let (roots, nr) = complex_roots(&coeffs[..=n]);
                let depth_parameter = circle_parameter(u.0, u.1);
                let mut pts = [u; 4];
                let mut f = [overestimation; 4];
                for k in 0..nr {
                    let rp = circle_parameter(roots[k].0, roots[k].1);
                    let binary = if rp < depth_parameter { 1.0 } else { 0.0 };
                    pts[k + 1] = roots[k];
                    f[k + 1] = binary + (rp * wz[2] + wz[3]).clamp(0.0, 1.0);
                }
                let p = interpolate(&pts[..=nr], &f[..=nr]);
                let absorbance: f64 = (0..=n).map(|k| mom[k].mul(p[k]).0).sum();
                (-b0 * absorbance).exp()
            }
        }
    }
}

/// The depth warp: `2 (ln z - ln near) / (ln far - ln near) - 1` (linear `2 z - 1` when
/// `near <= 0`).
pub fn warp(z: f32, (near, far): (f32, f32)) -> f32 {
    if near > 0.0 && far > near {
        let (ln, lf) = ((near as f64).ln(), (far as f64).ln());
        (((z as f64).max(1e-30).ln() - ln) / (lf - ln) * 2.0 - 1.0) as f32
    } else {
        z * 2.0 - 1.0
    }
}

/// Moment-based OIT, both passes, over the pixel's fragments in submission order.
pub(super) fn mboit(binned: &BinnedStream, m: Moments) -> Image {
    let (frags, bg, nf) = (&binned.stream.frags, binned.bg(), binned.near_far);
    per_pixel(binned, |p| {
        let mut st = MomentState::default();
        for &i in binned.bins.of(p) {
            let f = &frags[i as usize];
            st.add(m, warp(f.depth, nf), 1.0 - f.alpha);
        }
        if st.b0 < B0_MIN {
            return (bg, 1.0);
        }
        let resolver = st.resolver(m);
        let mut acc = [0.0f32; 4];
        for &i in binned.bins.of(p) {
            let f = &frags[i as usize];
            let t = transmittance(&resolver, warp(f.depth, nf));
            for k in 0..3 {
                acc[k] = f16r(acc[k] + f.color[k] * t);
            }
            acc[3] = f16r(acc[3] + f.alpha * t);
        }
        let total = (-st.b0).exp();
        let d = acc[3].max(1e-5);
        (
            std::array::from_fn(|k| finite_or_zero(acc[k] / d * (1.0 - total) + bg[k] * total)),
            total,
        )
    })
}

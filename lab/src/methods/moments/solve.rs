//! The numerics of the moment bound's reconstruction, in f64 or complex f64 ([`Field`]): an LU
//! solve of the Hankel or Toeplitz system ([`Lu`]), the interpolation polynomial through the
//! roots and the real and complex roots of the kernel polynomial, by closed forms. Apart from
//! [`super`] (what the moments are; this file knows nothing of them).

/// An LU factorization with partial pivoting of an `n x n` matrix (n <= 4): factored once per
/// pixel, solved once per fragment.
#[derive(Clone, Copy, Debug)]
pub struct Lu<T> {
    lu: [[T; 4]; 4],
    perm: [usize; 4],
    pub(super) n: usize,
}

impl<T: Field> Lu<T> {
    pub(super) fn new(mut a: [[T; 4]; 4], n: usize) -> Lu<T> {
        let mut perm = [0, 1, 2, 3];
        for col in 0..n {
            let mut p = col;
            for r in col + 1..n {
                if a[r][col].norm() > a[p][col].norm() {
                    p = r;
                }
            }
            a.swap(col, p);
            perm.swap(col, p);
            let d = a[col][col];
            for r in col + 1..n {
                let f = a[r][col].div(d);
                a[r][col] = f;
                for c in col + 1..n {
                    a[r][c] = a[r][c].sub(f.mul(a[col][c]));
                }
            }
        }
        Lu { lu: a, perm, n }
    }

    pub(super) fn solve(&self, y: [T; 4]) -> [T; 4] {
        let n = self.n;
        let mut x = [T::ZERO; 4];
        for r in 0..n {
            let mut s = y[self.perm[r]];
            for c in 0..r {
                s = s.sub(self.lu[r][c].mul(x[c]));
            }
            x[r] = s;
        }
        for r in (0..n).rev() {
            let mut s = x[r];
            for c in r + 1..n {
                s = s.sub(self.lu[r][c].mul(x[c]));
            }
            x[r] = s.div(self.lu[r][r]);
        }
        x
    }
}

/// The arithmetic [`Lu`] and the divided differences need (f64 and complex).
pub trait Field: Copy {
    /// Zero.
    const ZERO: Self;
    /// `self - o`.
    fn sub(self, o: Self) -> Self;
    /// `self * o`.
    fn mul(self, o: Self) -> Self;
    /// `self / o`.
    fn div(self, o: Self) -> Self;
    /// The magnitude (pivoting).
    fn norm(self) -> f64;
}

impl Field for f64 {
    const ZERO: f64 = 0.0;
    fn sub(self, o: f64) -> f64 {
        self - o
    }
    fn mul(self, o: f64) -> f64 {
        self * o
    }
    fn div(self, o: f64) -> f64 {
        self / o
    }
    fn norm(self) -> f64 {
        self.abs()
    }
}

/// A complex number (the trigonometric moments).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct C64(pub f64, pub f64);

impl C64 {
    pub(super) fn conj(self) -> C64 {
        C64(self.0, -self.1)
    }
    pub(super) fn add(self, o: C64) -> C64 {
        C64(self.0 + o.0, self.1 + o.1)
    }
    pub(super) fn scale(self, s: f64) -> C64 {
        C64(self.0 * s, self.1 * s)
    }
    pub(super) fn sqrt(self) -> C64 {
        let r = (self.0 * self.0 + self.1 * self.1).sqrt();
        let re = ((r + self.0) * 0.5).max(0.0).sqrt();
        let im = ((r - self.0) * 0.5).max(0.0).sqrt();
        C64(re, if self.1 < 0.0 { -im } else { im })
    }
}

impl Field for C64 {
    const ZERO: C64 = C64(0.0, 0.0);
    fn sub(self, o: C64) -> C64 {
        C64(self.0 - o.0, self.1 - o.1)
    }
    fn mul(self, o: C64) -> C64 {
        C64(self.0 * o.0 - self.1 * o.1, self.0 * o.1 + self.1 * o.0)
    }
    fn div(self, o: C64) -> C64 {
        let d = o.0 * o.0 + o.1 * o.1;
        C64((self.0 * o.0 + self.1 * o.1) / d, (self.1 * o.0 - self.0 * o.1) / d)
    }
    fn norm(self) -> f64 {
        (self.0 * self.0 + self.1 * self.1).sqrt()
    }
}

/// The interpolation polynomial through `(z_i, f_i)` (Newton's divided differences, as the
/// shaders), in the monomial basis: `p[k]` multiplies `z^k`.
pub(super) fn interpolate<T: Field + From1>(z: &[T], f: &[f64]) -> [T; 4] {
    let n = z.len();
    let mut d = [T::ZERO; 4];
    for (di, &v) in d.iter_mut().zip(f) {
        *di = T::from1(v);
    }
    for level in 1..n {
        for i in (level..n).rev() {
            d[i] = d[i].sub(d[i - 1]).div(z[i].sub(z[i - level]));
        }
    }
    // Horner from the highest divided difference down: p = d[n-1]; p = p (x - z_i) + d[i].
    let mut p = [T::ZERO; 4];
    p[0] = d[n - 1];
    for i in (0..n - 1).rev() {
        // p <- p * (x - z_i) + d[i]
        let mut q = [T::ZERO; 4];
        for k in 0..n {
            if k + 1 < 4 {
                q[k + 1] = q[k + 1].add1(p[k]);
            }
            q[k] = q[k].sub(p[k].mul(z[i]));
        }
        q[0] = q[0].add1(d[i]);
        p = q;
    }
    p
}

/// Conversions and additions for [`interpolate`].
pub(super) trait From1: Sized {
    fn from1(v: f64) -> Self;
    fn add1(self, o: Self) -> Self;
}

impl From1 for f64 {
    fn from1(v: f64) -> f64 {
        v
    }
    fn add1(self, o: f64) -> f64 {
        self + o
    }
}

impl From1 for C64 {
    fn from1(v: f64) -> C64 {
        C64(v, 0.0)
    }
    fn add1(self, o: C64) -> C64 {
        self.add(o)
    }
}

/// The real roots of `c0 + c1 x + c2 x^2 (+ c3 x^3)` (two or three real roots assumed, as
/// the shaders assume): the roots and their count.
pub(super) fn real_roots(c: &[f64]) -> ([f64; 3], usize) {
    if c.len() == 3 {
        let (p, q) = (c[1] / c[2], c[0] / c[2]);
        let r = (p * p * 0.25 - q).max(0.0).sqrt();
        return ([-p * 0.5 - r, -p * 0.5 + r, 0.0], 2);
    }
    let (a, b, cc) = (c[2] / c[3], c[1] / c[3], c[0] / c[3]);
    let p = b - a * a / 3.0;
    let q = 2.0 * a * a * a / 27.0 - a * b / 3.0 + cc;
    let shift = -a / 3.0;
    if p >= 0.0 {
        // One real root (a degenerate case the shaders do not handle): repeat it.
        let disc = (q * q / 4.0 + p * p * p / 27.0).max(0.0).sqrt();
        let t = (-q / 2.0 + disc).cbrt() + (-q / 2.0 - disc).cbrt();
        return ([t + shift; 3], 3);
    }
    let m = 2.0 * (-p / 3.0).sqrt();
    let arg = (3.0 * q / (p * m)).clamp(-1.0, 1.0);
    let theta = arg.acos() / 3.0;
    let third = 2.0 * std::f64::consts::PI / 3.0;
    (std::array::from_fn(|k| m * (theta - third * k as f64).cos() + shift), 3)
}

/// A cube root of a complex number (the principal one).
pub(super) fn cbrt_c(z: C64) -> C64 {
    let r = z.norm().cbrt();
    let a = z.1.atan2(z.0) / 3.0;
    C64(r * a.cos(), r * a.sin())
}

/// The complex roots of `sum c_k x^k` (degree 2 or 3, closed forms: the quadratic formula,
/// Cardano's for the cubic, each cubic root polished by two Newton steps).
pub(super) fn complex_roots(c: &[C64]) -> ([C64; 3], usize) {
    let n = c.len() - 1;
    let lead = c[n];
    let mut monic = [C64::ZERO; 4];
    for k in 0..=n {
        monic[k] = c[k].div(lead);
    }
    if n == 2 {
        let half_b = monic[1].scale(0.5);
        let disc = half_b.mul(half_b).sub(monic[0]).sqrt();
        return (
            [
                C64::ZERO.sub(half_b).sub(disc),
                C64::ZERO.sub(half_b).add(disc),
                C64::ZERO,
            ],
            2,
        );
    }
    let (a, b, cc) = (monic[2], monic[1], monic[0]);
    let a3 = a.scale(1.0 / 3.0);
    // x = t - a/3: t^3 + p t + q.
    let p = b.sub(a.mul(a3));
    let q = a3.mul(a3).mul(a3).scale(2.0).sub(a3.mul(b)).add(cc);
    let half_q = q.scale(0.5);
    let disc = half_q.mul(half_q).add(p.mul(p).mul(p).scale(1.0 / 27.0)).sqrt();
    let mut u3 = C64::ZERO.sub(half_q).add(disc);
    if u3.norm() < 1e-300 {
        u3 = C64::ZERO.sub(half_q).sub(disc);
    }
    let u = cbrt_c(u3);
    let w = C64(-0.5, 0.75f64.sqrt());
    let mut roots = [C64::ZERO; 3];
    let mut uk = u;
    for r in &mut roots {
        let t = if uk.norm() < 1e-300 {
            C64::ZERO
        } else {
            uk.sub(p.div(uk.scale(3.0)))
        };
        let mut x = t.sub(a3);
        for _ in 0..2 {
            let f = x.mul(x).mul(x).add(a.mul(x).mul(x)).add(b.mul(x)).add(cc);
            let d = x.mul(x).scale(3.0).add(a.mul(x).scale(2.0)).add(b);
            if d.norm() > 1e-300 {
                x = x.sub(f.div(d));
            }
        }
        *r = x;
        uk = uk.mul(w);
    }
    (roots, 3)
}

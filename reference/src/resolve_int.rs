//! The integer RGBA8 resolve, written from `docs/layout.md` ("Integer resolve") alone, in
//! `u64` with plain division (the kernel uses `u32` and shifts), and its error bound against
//! the exact composite of the rows (the derivation is in `docs/layout.md`).

use mlab::{Background, Row};

/// `round(x * y / 32768)`, halves up: `(x y + 16384) / 32768`.
pub fn q15(x: u64, y: u64) -> u64 {
    (x * y + 16384) / 32768
}

/// A background channel as the resolve takes it: clamped to `[0, 1]` (NaN to 0), then
/// `floor(b * 32640 + 0.5)`, the multiply and the add each rounded to f32.
pub fn background_channel(b: f32) -> u64 {
    let b = if b.is_nan() { 0.0 } else { b.clamp(0.0, 1.0) };
    let x = b * 32640.0;
    let x = x + 0.5;
    x.floor() as u64
}

/// The resolve's state after the rows: the three color accumulators and the visibility,
/// and the visibility after each row (`vis[j]` in front of row `j`; `vis[M]` the last).
pub fn state(rows: &[Row]) -> ([u64; 3], Vec<u64>) {
    let mut acc = [64u64; 3];
    let mut vis = vec![32767u64];
    for r in rows {
        let [cr, cg, cb, t] = r.to_bytes()[..4].try_into().map(|b: [u8; 4]| b.map(u64::from)).unwrap();
        let v = *vis.last().unwrap();
        for (a, c) in acc.iter_mut().zip([cr, cg, cb]) {
            *a = (*a + q15(128 * c, v)).min(32767);
        }
        vis.push(q15(257 * t / 2, v));
    }
    (acc, vis)
}

/// The integer RGBA8 resolve of one pixel's rows, front to back.
pub fn rgba8(rows: &[Row], bg: Background) -> [u8; 4] {
    let (acc, vis) = state(rows);
    pixel(acc, *vis.last().unwrap(), bg)
}

/// The pixel from the accumulators and the visibility.
fn pixel(acc: [u64; 3], v: u64, bg: Background) -> [u8; 4] {
    match bg {
        Background::Opaque(c) => {
            let b = c.to_array().map(background_channel);
            let ch = |i: usize| ((acc[i] + q15(b[i], v)).min(32767) / 128) as u8;
            [ch(0), ch(1), ch(2), 255]
        }
        Background::Transparent => {
            let a = (q15(32767 - v, 32640) + 64) / 128;
            [
                (acc[0] / 128) as u8,
                (acc[1] / 128) as u8,
                (acc[2] / 128) as u8,
                a as u8,
            ]
        }
    }
}

/// The HT tail's `(T, g)` in Q16 (`docs/layout.md`, "Integer resolve of HT"), written from the
/// docs in `u64`: the tables as the formulas that give them, the Horner sums as loops over
/// those, the divisions as `/`.
pub fn ht_tail(alpha: u64, count: u64) -> (u64, u64) {
    let rnd = |x: f64| (x + 0.5).floor() as u64;
    let h_c: Vec<u64> = (0..8).map(|k| rnd(16_777_216.0 / (255.0 * (k as f64 + 1.0)))).collect();
    let fact = |k: u64| (1..=k).product::<u64>() as f64;
    let exp_c: Vec<u64> = (0..7).map(|k| rnd(65536.0 * (-0.5f64).exp() / fact(k))).collect();
    let bits_c: Vec<u64> = (0..6).map(|i| rnd(65536.0 * (-(2f64.powi(i)) / 2.0).exp())).collect();
    let psi_c: Vec<u64> = (0..6).map(|k| rnd(65536.0 / fact(k + 1))).collect();
    let q16 = |x: u64, y: u64| (x * y + 32768) / 65536;
    let horner = |c: &[u64], x: u64| c.iter().rev().skip(1).fold(c[c.len() - 1], |a, &ck| ck + q16(a, x));
    let n = count.max(1);
    let m = 257 * alpha / n;
    let route_a = m <= 16384;
    let h = horner(&h_c, m.min(16384));
    let u = (alpha.min(4095) * h + 128) / 256;
    let j = u / 32768;
    let e_r = horner(&exp_c, 32768 - u % 32768);
    let zero = if route_a { u >= 786_432 } else { n >= 64 };
    let t = if zero {
        0
    } else if route_a {
        // e^(-u) = e^(-r) times the factor of each set bit of j = floor(2 u).
        (0..6)
            .filter(|i| (j >> i) & 1 == 1)
            .fold(e_r, |p, i| q16(p, bits_c[i as usize]))
    } else {
        // x^n by the bits of n, x = 1 - m.
        let mut b = 65535 - m.min(65535);
        let mut p = 65536;
        for i in 0..6 {
            if (n >> i) & 1 == 1 {
                p = q16(p, b);
            }
            b = q16(b, b);
        }
        p
    }
    .min(65536);
    let g = if route_a && u < 32768 {
        let psi = horner(&psi_c, u);
        let phi = ((t / 2) * psi + 16384) / 32768;
        phi + ((((h - h_c[0]) * phi + 128) / 256) * 255 + 32768) / 65536
    } else {
        (65536 - t) * 255 / alpha.max(1)
    };
    (t, g.min(65536))
}

/// The integer RGBA8 resolve of one HT pixel: the MLAB integer resolve's state over the head
/// rows, the tail's light and transmittance, then the MLAB pixel.
pub fn ht_rgba8<T: mlab::TailFormat>(head: &[Row], tail: T, bg: Background) -> [u8; 4] {
    let (mut acc, vis) = state(head);
    let v = *vis.last().unwrap();
    let (t, g) = ht_tail(u64::from(tail.alpha_sum()), u64::from(tail.count()));
    for (a, s) in acc.iter_mut().zip(tail.color_sum()) {
        let l = (u64::from(s) * g + 256) / 512;
        *a = (*a + l / 32768 * v + q15(l % 32768, v)).min(32767);
    }
    let v = (t * v + 32768) / 65536;
    pixel(acc, v, bg)
}

/// The exact composite of the rows in bytes (f64): `255 (C + bg V)` per channel over an
/// opaque background (the f32 background widened exactly), `255 C` and `255 (1 - V)`
/// premultiplied; each clamped to `[0, 255]`, as the output is.
pub fn exact(rows: &[Row], bg: Background) -> [f64; 4] {
    let (c, v) = crate::model::composite_rows_f64(rows);
    let clamp = |x: f64| x.clamp(0.0, 255.0);
    match bg {
        Background::Opaque(b) => {
            let b = b.to_array();
            [0, 1, 2]
                .map(|i| clamp(255.0 * (c[i] + f64::from(b[i]) * v)))
                .into_iter()
                .chain([255.0])
                .collect::<Vec<_>>()
                .try_into()
                .unwrap()
        }
        Background::Transparent => [
            clamp(255.0 * c[0]),
            clamp(255.0 * c[1]),
            clamp(255.0 * c[2]),
            clamp(255.0 * (1.0 - v)),
        ],
    }
}

/// The derived bound (`docs/layout.md`, "Integer resolve: error bound") on
/// `|rgba8 - exact|` per channel, in bytes, for a background in `[0, 1]`: half a step of
/// output rounding plus the accumulated error of the products, in 1/128 byte.
///
/// With `V_j` the exact visibility in front of row `j`, `P(i, j)` the product of `t_k / 255`
/// for `i < k < j`, and `F_i = eps(t_i) + 1/2` the largest fresh error of the visibility step
/// of row `i` (`eps(t) = 32768 t / 255 - floor(257 t / 2)`, in `[0, 1]`):
///
/// ```text
/// E_0 = 0,  E_(j+1) = (t_j / 255) E_j + F_j                 (|v_j - 32767 V_j| <= E_j)
/// color: sum_j (1/2 + c_j V_j / 256) + sum_i F_i R_i  [+ k V_M + 1/2 + 0.504]
///         R_i = sum_(j>i) (c_j / 256) P(i, j)  [+ k P(i, M)],  k = 32640 bg / 32768
/// alpha: 1/2 + (32640 / 32768) (1 - V_M + E_M)
/// ```
pub fn bound(rows: &[Row], bg: Background) -> [f64; 4] {
    let m = rows.len();
    let bytes: Vec<[f64; 4]> = rows
        .iter()
        .map(|r| {
            let [c0, c1, c2, t, ..] = r.to_bytes();
            [c0, c1, c2, t].map(f64::from)
        })
        .collect();
    let eps = |t: f64| 32768.0 * t / 255.0 - (257.0 * t / 2.0).floor();
    let f: Vec<f64> = bytes.iter().map(|b| eps(b[3]) + 0.5).collect();
    // Exact visibilities in front of each row, and the a-priori bound on the error of v.
    let mut vis = vec![1.0f64];
    let mut e = vec![0.0f64];
    for (j, b) in bytes.iter().enumerate() {
        vis.push(vis[j] * b[3] / 255.0);
        e.push(b[3] / 255.0 * e[j] + f[j]);
    }
    // P(i, j) = prod_(i<k<j) t_k / 255.
    let p = |i: usize, j: usize| ((i + 1)..j).map(|k| bytes[k][3] / 255.0).product::<f64>();
    let k = match bg {
        Background::Opaque(b) => Some(b.to_array().map(|x| 32640.0 * f64::from(x) / 32768.0)),
        Background::Transparent => None,
    };
    let mut out = [0.0f64; 4];
    for ch in 0..3 {
        let mut steps = 0.0;
        for (b, v) in bytes.iter().zip(&vis) {
            steps += 0.5 + b[ch] / 256.0 * v;
        }
        for (i, fi) in f.iter().enumerate() {
            let mut r: f64 = ((i + 1)..m).map(|j| bytes[j][ch] / 256.0 * p(i, j)).sum();
            if let Some(k) = k {
                r += k[ch] * p(i, m);
            }
            steps += fi * r;
        }
        if let Some(k) = k {
            steps += k[ch] * vis[m] + 0.5 + 0.504;
        }
        out[ch] = 0.5 + steps / 128.0;
    }
    out[3] = match k {
        Some(_) => 0.0,
        None => 0.5 + (0.5 + 32640.0 / 32768.0 * (1.0 - vis[m] + e[m])) / 128.0,
    };
    out
}

/// The bound of `|T - 65536 T_exact|` of [`ht_tail`] in units of `2^-16` (`docs/layout.md`,
/// "Integer resolve of HT": the sum of the step budgets).
pub const HT_T_BOUND: f64 = 4.0;

/// The exact tail in f64: `(T, g)` for `n = max(count, 1)`, `m = min(1, S_a / (255 n))`.
pub fn ht_tail_exact(alpha: u32, count: u32) -> (f64, f64) {
    let n = f64::from(count.max(1));
    let s = f64::from(alpha) / 255.0;
    let m = (s / n).min(1.0);
    let t = if m >= 1.0 { 0.0 } else { (n * (-m).ln_1p()).exp() };
    let g = if alpha == 0 { 1.0 } else { (1.0 - t) / s };
    (t, g)
}

/// The exact composite of an HT pixel (head rows, then the tail), in bytes, clamped as the
/// output is.
pub fn ht_exact<T: mlab::TailFormat>(head: &[Row], tail: T, bg: Background) -> [f64; 4] {
    let (c, v) = crate::model::composite_rows_f64(head);
    let (t, g) = ht_tail_exact(tail.alpha_sum(), tail.count());
    let s = tail.color_sum();
    let col: [f64; 3] = core::array::from_fn(|i| c[i] + v * f64::from(s[i]) / 255.0 * g);
    let v = v * t;
    let clamp = |x: f64| x.clamp(0.0, 255.0);
    match bg {
        Background::Opaque(b) => {
            let b = b.to_array();
            let ch = |i: usize| clamp(255.0 * (col[i] + f64::from(b[i]) * v));
            [ch(0), ch(1), ch(2), 255.0]
        }
        Background::Transparent => [
            clamp(255.0 * col[0]),
            clamp(255.0 * col[1]),
            clamp(255.0 * col[2]),
            clamp(255.0 * (1.0 - v)),
        ],
    }
}

/// The derived bound (`docs/layout.md`, "Integer resolve of HT") on `|ht_rgba8 - ht_exact|`
/// per channel, in bytes, for a background in `[0, 1]`: the MLAB bound of the head rows with
/// the tail as one more row of color `c_t = S_c g` bytes (which may exceed 255) and
/// transmittance `T`, whose visibility step has the fresh error `D_T / 2 + 1/2` and whose
/// color term the error `1 + c_t V / 256 + (S_c D_g / 512) (V + E / 32768)`, with
/// `D_g = 4 + 255 D_T / S_a` the bound of `|g - 65536 g_exact|`.
pub fn ht_bound<T: mlab::TailFormat>(head: &[Row], tail: T, bg: Background) -> [f64; 4] {
    let k_rows = head.len();
    let bytes: Vec<[f64; 4]> = head
        .iter()
        .map(|r| {
            let [c0, c1, c2, t, ..] = r.to_bytes();
            [c0, c1, c2, t].map(f64::from)
        })
        .collect();
    let (t_tail, g) = ht_tail_exact(tail.alpha_sum(), tail.count());
    let sc = tail.color_sum().map(f64::from);
    let d_g = 4.0 + 255.0 * HT_T_BOUND / f64::from(tail.alpha_sum().max(1));
    let eps = |t: f64| 32768.0 * t / 255.0 - (257.0 * t / 2.0).floor();
    let f: Vec<f64> = bytes.iter().map(|b| eps(b[3]) + 0.5).collect();
    let f_tail = HT_T_BOUND / 2.0 + 0.5;
    let mut vis = vec![1.0f64];
    let mut e = vec![0.0f64];
    for (j, b) in bytes.iter().enumerate() {
        vis.push(vis[j] * b[3] / 255.0);
        e.push(b[3] / 255.0 * e[j] + f[j]);
    }
    let v_head = vis[k_rows];
    let e_final = t_tail * e[k_rows] + f_tail;
    let p = |i: usize, j: usize| ((i + 1)..j).map(|k| bytes[k][3] / 255.0).product::<f64>();
    let kb = match bg {
        Background::Opaque(b) => Some(b.to_array().map(|x| 32640.0 * f64::from(x) / 32768.0)),
        Background::Transparent => None,
    };
    let mut out = [0.0f64; 4];
    for ch in 0..3 {
        let ct = sc[ch] * (g + d_g / 65536.0); // the tail's color in bytes, its error included
        let mut steps = 0.0;
        for (b, v) in bytes.iter().zip(&vis) {
            steps += 0.5 + b[ch] / 256.0 * v;
        }
        // The tail's own term: scale, roundings of L and of the product, the error of g.
        steps += 1.0 + ct * v_head / 256.0 + sc[ch] * d_g / 512.0 * (v_head + e[k_rows] / 32768.0);
        for (i, fi) in f.iter().enumerate() {
            let mut r: f64 = ((i + 1)..k_rows).map(|j| bytes[j][ch] / 256.0 * p(i, j)).sum();
            r += (ct / 256.0 + 1.0 / 65536.0) * p(i, k_rows);
            if let Some(kb) = kb {
                r += kb[ch] * p(i, k_rows) * t_tail;
            }
            steps += fi * r;
        }
        if let Some(kb) = kb {
            steps += kb[ch] * vis[k_rows] * t_tail + kb[ch] * f_tail + 0.5 + 0.504;
        }
        out[ch] = 0.5 + steps / 128.0;
    }
    out[3] = match kb {
        Some(_) => 0.0,
        None => 0.5 + (0.5 + 32640.0 / 32768.0 * (1.0 - v_head * t_tail + e_final)) / 128.0,
    };
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use mlab::glam::Vec3;

    #[test]
    fn documented_examples() {
        // docs/layout.md: an empty pixel is the background, a byte background exactly.
        for k in 0..=255u8 {
            let b = f32::from(k) / 255.0;
            assert_eq!(rgba8(&[], Background::Opaque(Vec3::splat(b))), [k, k, k, 255]);
        }
        assert_eq!(rgba8(&[Row::EMPTY; 3], Background::Transparent), [0, 0, 0, 0]);
        // One opaque row: its bytes, whatever the background.
        let r = Row::new([200, 7, 0], 0, 1.0);
        assert_eq!(rgba8(&[r], Background::Opaque(Vec3::ONE)), [200, 7, 0, 255]);
        assert_eq!(rgba8(&[r], Background::Transparent), [200, 7, 0, 255]);
        assert_eq!(background_channel(f32::NAN), 0);
        assert_eq!(background_channel(2.0), 32640);
    }
}

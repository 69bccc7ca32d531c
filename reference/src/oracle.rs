//! The exact per-pixel oracle: every fragment kept, sorted front to back, composited in
//! f64 (`docs/algorithm.md`, Eq. 5 with every layer exact), and the bounds that relate it
//! to the kernel's quantized result.
//!
//! **Order.** By depth with IEEE comparison (`-0.0 == 0.0`), and on equal depth the later
//! submission in front: Listing 1 inserts a row before the first row whose depth is not
//! smaller (`z <= slot z`), so a later fragment of equal depth lands in front of the
//! earlier one, as OVER in submission order would put it. A NaN depth panics (valid
//! fragments have finite depths).
//!
//! **Composite.** Front to back, `C += V c_i`, `V *= 1 - a_i`, then `C + V background`,
//! with the f32 inputs widened to f64 exactly.

use mlab::Fragment;

/// One fragment as the oracle reads it: premultiplied color, alpha and depth, as the
/// kernel's [`Fragment`] holds them (f32).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Layer {
    /// Premultiplied color.
    pub color: [f32; 3],
    /// Alpha (coverage), `1 - transmittance`.
    pub alpha: f32,
    /// Depth (smaller is nearer).
    pub depth: f32,
}

impl From<Fragment> for Layer {
    fn from(f: Fragment) -> Layer {
        Layer {
            color: f.color().to_array(),
            alpha: f.alpha(),
            depth: f.depth(),
        }
    }
}

impl From<&Fragment> for Layer {
    fn from(f: &Fragment) -> Layer {
        Layer::from(*f)
    }
}

impl From<([f32; 3], f32, f32)> for Layer {
    /// `(premultiplied color, alpha, depth)`.
    fn from((color, alpha, depth): ([f32; 3], f32, f32)) -> Layer {
        Layer { color, alpha, depth }
    }
}

/// Indices of `depths` (in submission order) in compositing order: front to back, the later
/// submission first on equal depths (`-0.0 == 0.0`). Panics on a NaN depth.
pub fn front_to_back(depths: &[f32]) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..depths.len()).collect();
    idx.sort_by(|&a, &b| {
        depths[a]
            .partial_cmp(&depths[b])
            .expect("valid fragments have finite depth")
            .then(b.cmp(&a))
    });
    idx
}

/// Indices of a stream in compositing order ([`front_to_back`] of its depths).
pub fn order<L: Copy + Into<Layer>>(stream: &[L]) -> Vec<usize> {
    let depths: Vec<f32> = stream.iter().map(|&l| l.into().depth).collect();
    front_to_back(&depths)
}

/// The exact composite of a stream (in submission order) over an opaque `background`:
/// `(color, background visibility)`, the visibility being the product of `1 - alpha`.
/// A black background gives the premultiplied color of the transparent layers alone.
pub fn oracle<L: Copy + Into<Layer>>(stream: &[L], background: [f64; 3]) -> ([f64; 3], f64) {
    composite(order(stream).into_iter().map(|i| stream[i]), background)
}

/// The composite half of [`oracle`], for layers already in compositing order (front to
/// back, as [`order`] gives them): `C += V c_i`, `V *= 1 - a_i`, then `C + V background`,
/// in f64. For a caller that sorts once and times its sort apart (the lab's A-buffer);
/// the order is then the caller's to get right.
pub fn composite<L: Into<Layer>>(front_to_back: impl IntoIterator<Item = L>, background: [f64; 3]) -> ([f64; 3], f64) {
    let mut c = [0.0f64; 3];
    let mut v = 1.0f64;
    for l in front_to_back {
        let l: Layer = l.into();
        for (ch, &p) in c.iter_mut().zip(&l.color) {
            *ch += f64::from(p) * v;
        }
        v *= 1.0 - f64::from(l.alpha);
    }
    (core::array::from_fn(|ch| c[ch] + v * background[ch]), v)
}

/// One unorm8 rounding: the largest error a single quantization or a single
/// `round(a*b/255)` can introduce, plus f32 slack (f32 multiply before rounding, f32 resolve).
pub const DELTA: f64 = 0.5 / 255.0 + 1e-6;

/// The same for the unbiased arithmetic: a dithered quantization `floor(x + u)` with `u` in
/// `[1/512, 511/512]` and a dithered product `floor((p + d) / 255)` with `d` in `0..=254`
/// are each off by less than one unit (`q - x` lies in `(-1, 1)`), twice the paper's bound.
pub const DELTA_UNBIASED: f64 = 1.0 / 255.0 + 1e-6;

/// The oracle ([`oracle`]), plus the quantization bound per channel for an MLAB array with
/// `M >= n` rows (or an HT head with `K >= n`), for a rounding bound `delta` per
/// quantization and per product ([`DELTA`], [`DELTA_UNBIASED`]): composing quantized
/// fragments `(p + dp, t + dt)` with `|dp|, |dt| <= delta` front to back gives, by
/// telescoping `C_j' - C_j = dp_j + dt_j * C_(j+1) + t_j' * (C_(j+1)' - C_(j+1))`,
/// `|error| <= delta * sum_j (1 + C_(j+1))`, where `C_(j+1)` is the exact composite behind
/// fragment j (background included). For fragments whose color does not exceed alpha and a
/// background in [0, 1], `C_(j+1) <= 1`, so the bound is at most `2 n delta`.
pub fn oracle_with_bound<L: Copy + Into<Layer>>(
    stream: &[L],
    background: [f64; 3],
    delta: f64,
) -> ([f64; 3], f64, [f64; 3]) {
    let (color, v) = oracle(stream, background);
    // Back to front: C = p + (1 - a) * C_behind, accumulating the bound.
    let mut behind = background;
    let mut bound = [0.0f64; 3];
    for i in order(stream).into_iter().rev() {
        let l: Layer = stream[i].into();
        let t = 1.0 - f64::from(l.alpha);
        for ch in 0..3 {
            bound[ch] += delta * (1.0 + behind[ch]);
            behind[ch] = f64::from(l.color[ch]) + t * behind[ch];
        }
    }
    (color, v, bound)
}

/// Bound on a resolved pixel of fragments stored without any merge (MLAB with `n <= M`,
/// HT with `n <= K`), all with premultiplied color not above alpha, against [`oracle`]
/// over a black background, each channel and the transmittance; `quant` are the fragments'
/// quantization errors in steps of `1/255` ([`crate::Model::quant_error`]).
///
/// The composite `C = sum_i c_i prod_(j<i) t_j` is multilinear in the colors `c_i` and
/// transmittances `t_j`. Where `c_i <= 1 - t_i` for every `i` (true of the exact values,
/// and of the quantized bytes, so on the whole segment between them),
/// `|dC/dc_i| = prod_(j<i) t_j <= 1` and
/// `|dC/dt_j| = prod_(k<j) t_k * sum_(i>j) c_i prod_(j<k<i) t_k
///  <= sum_(i>j) (1 - t_i) prod_(j<k<i) t_k = 1 - prod_(k>j) t_k <= 1`.
/// So the color moves by at most the sum of the `n` color errors and of the `n - 1`
/// transmittance errors of all fragments but the last, at most `2 sum q_i - min q_i`
/// steps, and the transmittance (a product of `n` factors in `[0, 1]`) by `sum q_i`. No
/// merge is involved. Paper: `(2n - 1) 0.5 / 255`; unbiased: the same unless some
/// fragments are faint (`511/512` each instead of 0.5). Plus `1e-5` for the f32 resolve
/// and the f32 excess of the quantizations (`v * 255` and `+ u` each rounded once near
/// 255: at most `2.3e-5` step each, `6e-6` for 64 fragments).
pub fn multilinear_bound(quant: &[f64]) -> f64 {
    let sum: f64 = quant.iter().sum();
    let min = quant.iter().copied().fold(f64::INFINITY, f64::min);
    let steps = if quant.is_empty() { 0.0 } else { 2.0 * sum - min };
    steps / 255.0 + 1e-5
}

/// Bound on the background visibility of fragments whose quantization errors (in steps,
/// [`crate::Model::quant_error`]) are `quant`, after `merges` merges whose products are
/// each off by less than `merge_error` steps ([`crate::Model::MERGE_ERROR`]), against the
/// exact product of `1 - alpha` ([`oracle`]'s visibility).
///
/// The stored visibility is the product of the rows' `T / 255`. Each quantization moves
/// one factor by at most its error `q_i / 255` (0.5 step to nearest; `511/512` dithered,
/// which the unbiased arithmetic does for faint fragments), and each merge replaces two
/// factors by their rounded product, off by less than `merge_error / 255` (0.5 step for
/// the paper's rounding, 1 step for the dithered one); every other factor lies in
/// `[0, 1]`, so each step moves the product by at most its own error (telescoping):
/// `(sum q_i + merges merge_error) / 255`. Plus `1e-5`: the f32 resolve (a few `2^-24`)
/// and the f32 excess of the quantizations (as in [`multilinear_bound`]).
pub fn visibility_bound(quant: &[f64], merges: usize, merge_error: f64) -> f64 {
    (quant.iter().sum::<f64>() + merges as f64 * merge_error) / 255.0 + 1e-5
}

#[cfg(test)]
mod tests {
    use super::*;

    fn l(c: f32, a: f32, z: f32) -> Layer {
        Layer {
            color: [c; 3],
            alpha: a,
            depth: z,
        }
    }

    #[test]
    fn later_submission_in_front_on_ties_and_signed_zeros_tie() {
        assert_eq!(front_to_back(&[1.0, 0.0, 1.0, -0.0, 0.0]), vec![4, 3, 1, 2, 0]);
        // Red (earlier) and green (later) at the same depth: green in front.
        let red = Layer {
            color: [0.5, 0.0, 0.0],
            alpha: 0.5,
            depth: 1.0,
        };
        let green = Layer {
            color: [0.0, 0.5, 0.0],
            alpha: 0.5,
            depth: 1.0,
        };
        assert_eq!(oracle(&[red, green], [0.0; 3]), ([0.25, 0.5, 0.0], 0.25));
    }

    #[test]
    fn three_layers_over_a_background() {
        // Submitted 3, 7, 1: front to back green-ish 0.25 (z 1), 0.5 (z 3), opaque (z 7).
        let s = [l(0.25, 0.5, 3.0), l(1.0, 1.0, 7.0), l(0.125, 0.25, 1.0)];
        let (c, v) = oracle(&s, [1.0; 3]);
        assert_eq!(v, 0.0);
        assert_eq!(c, [0.125 + 0.75 * 0.25 + 0.375; 3]);
        // Empty: the background, visibility 1.
        assert_eq!(oracle::<Layer>(&[], [0.2, 0.3, 0.4]), ([0.2, 0.3, 0.4], 1.0));
        // The composite half takes the order as given: the same layers front to back.
        let sorted = order(&s).into_iter().map(|i| s[i]);
        assert_eq!(composite(sorted, [1.0; 3]), (c, v));
        assert_ne!(
            composite(s, [1.0; 3]),
            (c, v),
            "submission order is not depth order here"
        );
    }

    #[test]
    fn bounds_by_hand() {
        // One opaque white layer over white: C_behind = 1, so delta * 2 per channel.
        let (_, _, b) = oracle_with_bound(&[l(1.0, 1.0, 0.0)], [1.0; 3], 0.5);
        assert_eq!(b, [1.0; 3]);
        // Two layers of alpha 0.5 and color 0.5 over black: behind the back one 0, behind
        // the front one 0.5: delta (1 + 0) + delta (1 + 0.5).
        let (c, v, b) = oracle_with_bound(&[l(0.5, 0.5, 2.0), l(0.5, 0.5, 1.0)], [0.0; 3], 1.0);
        assert_eq!((c, v, b), ([0.75; 3], 0.25, [2.5; 3]));
        assert_eq!(multilinear_bound(&[]), 1e-5);
        assert_eq!(multilinear_bound(&[0.5, 0.5, 1.0]), 3.5 / 255.0 + 1e-5);
        assert_eq!(visibility_bound(&[0.5, 0.5], 3, 1.0), 4.0 / 255.0 + 1e-5);
    }

    #[test]
    #[should_panic(expected = "finite depth")]
    fn nan_depth_panics() {
        front_to_back(&[1.0, f32::NAN]);
    }
}

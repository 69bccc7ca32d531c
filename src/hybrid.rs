//! Hybrid Transparency (Maule et al. 2013) as in Listing 2 of Salvi & Vaidyanathan (2014):
//! `K` head rows hold the `K` nearest fragments exactly; every fragment pushed out of the
//! head is accumulated into one 8-byte [`Tail`].
//!
//! ```text
//! HT(in Fragment f, inout Fragment B[K], inout Tail T)   // Listing 2
//!   for i in 0..K:                                      // 1-pass bubble sort
//!     if f.z <= B[i].z: swap(B[i], f)
//!   if f carries color or opacity:                      // the paper tests only T != 1,
//!     T.color += f.A; T.alpha += 1 - f.T; T.count += 1  // which would drop additive light
//! ```
//!
//! Resolve (Bavoil-Myers 2008 for the tail, as Maule et al. 2013): with `n = count`,
//! `S_a = sum(alpha)`, `S_c = sum(C)`:
//!
//! ```text
//! T_tail = (1 - S_a / n)^n
//! c_tail = S_c / S_a                                    (the tail's average color)
//! C_tail = c_tail * (1 - T_tail)
//! C      = C_head + T_head * C_tail,  T = T_head * T_tail   (Hybrid::resolve)
//! pixel  = C + C_background * T                         (Resolved::over, Eq. 6)
//! ```
//!
//! The background enters once, behind the whole composite, not inside the tail's term (the
//! two are equal in exact arithmetic, not in f32). The exact f32 program, every step and
//! branch (the all-opaque `1 / (S_a / 255)` one among them), is in `docs/layout.md`
//! ("f32 resolve of HT").
//!
//! `c_tail * (1 - T_tail) = S_c * g` with `g = (1 - T_tail) / S_a`. With `x = 1 - S_a / n`,
//! `g = (1 - x^n) / (n (1 - x)) = (1 + x + ... + x^(n-1)) / n`: the kernel computes this
//! geometric sum alongside `x^n`, which needs no subtraction of nearly equal numbers (the
//! printed form loses most of its digits in f32 when the mean alpha is tiny) and gives
//! `g = 1` for a tail of pure additive light, which then adds its light instead of vanishing
//! (the printed form divides by zero there).
//!
//! Order independence: the head ends up holding the `K` nearest fragments whatever the
//! order (for distinct depths), and the tail holds exact integer sums that saturate;
//! saturating addition of non-negative integers is associative and commutative
//! (`min(a + b, MAX)` composed in any order is `min(sum, MAX)`), so the bytes of a
//! [`Hybrid`] do not depend on submission order.

use crate::arith::{Arithmetic, Unbiased};
use crate::fragment::Fragment;
use crate::resolve::{Resolved, resolve_lanes};
use crate::row::Row;
use crate::vector::{RowLanes, Slot};
use glam::Vec3;

pub use crate::tail::{PaperTail, Tail, TailFormat};

/// Listing 2 on `K` head rows and a tail: insert `row` into the head, accumulate the row
/// pushed out into the tail. `K = 0` is allowed (every fragment goes to the tail). The tail
/// type picks the layout: [`Tail`] (default) or [`PaperTail`].
#[inline]
pub fn insert<T: TailFormat, const K: usize>(head: &mut [Row; K], tail: &mut T, row: Row) {
    insert_lanes::<_, _, _, T, K>(head, tail, row, true);
}

/// Listing 2, written once for every lane width; lanes where `on` is false are untouched.
#[inline(always)]
pub(crate) fn insert_lanes<L: RowLanes, S: Slot<L>, TS: Slot<L::Tail<T>>, T: TailFormat, const K: usize>(
    b: &mut [S; K],
    tail: &mut TS,
    fragment: L,
    on: L::Mask,
) {
    let mut f = fragment;
    // 1-pass bubble sort to insert fragment, one layer at a time.
    for slot in b.iter_mut() {
        let row = slot.load();
        let swap = f.depth_le(row) & on;
        slot.store(L::select(swap, f, row));
        f = L::select(swap, row, f);
    }
    // Update tail if the row pushed out carries color or opacity.
    let t = tail.load();
    tail.store(L::select_tail(on, L::tail_add::<T>(t, f), t));
}

/// [`Hybrid::resolve`] over a head slice and a tail.
#[inline]
pub(crate) fn resolve<T: TailFormat>(head: &[Row], tail: T) -> Resolved {
    let h = crate::resolve::resolve_layers(head.iter().map(crate::resolve::row_bytes));
    let ([r, g, b], t) = resolve_lanes::<f32>(h, tail.color_sum(), tail.alpha_sum(), tail.count());
    Resolved {
        color: Vec3::new(r, g, b),
        transmittance: t,
    }
}

/// A Hybrid Transparency pixel: `K` head rows and a tail, `8 * (K + 1)` bytes, in the
/// arithmetic `A` ([`Unbiased`] by default: the [`Tail`] layout and dithered
/// quantization; [`Paper`](crate::Paper): the paper's [`PaperTail`] and rounding).
///
/// ```
/// use mlab::glam::Vec3;
/// use mlab::{Fragment, Hybrid, TailFormat};
/// let mut h = Hybrid::<1>::new();
/// h.insert(&Fragment::straight(Vec3::X, 0.5, 1.0)?);
/// h.insert(&Fragment::straight(Vec3::Y, 0.5, 2.0)?); // goes to the tail
/// assert_eq!(h.tail().count(), 1);
/// let px = h.resolve().over(Vec3::ZERO);
/// assert!((px - Vec3::new(0.5, 0.25, 0.0)).abs().max_element() < 2.0 / 255.0);
/// # Ok::<(), mlab::FragmentError>(())
/// ```
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[repr(C)]
pub struct Hybrid<const K: usize, A: Arithmetic = Unbiased> {
    head: [Row; K],
    tail: A::Tail,
}

impl<const K: usize, A: Arithmetic> Hybrid<K, A> {
    /// Empty head rows and an empty tail.
    pub const fn new() -> Self {
        Hybrid {
            head: [Row::EMPTY; K],
            tail: A::Tail::EMPTY,
        }
    }

    /// From stored head rows and tail (any bytes are accepted).
    pub const fn from_parts(head: [Row; K], tail: A::Tail) -> Self {
        Hybrid { head, tail }
    }

    /// Head rows, front to back.
    pub const fn head(&self) -> &[Row; K] {
        &self.head
    }

    /// The tail.
    pub const fn tail(&self) -> A::Tail {
        self.tail
    }

    /// Insert a validated fragment with Listing 2 (quantized once, by `A`), as the fragment
    /// of pixel 0 ([`insert_at`](Self::insert_at)).
    #[inline]
    pub fn insert(&mut self, fragment: &Fragment) {
        self.insert_at(fragment, 0);
    }

    /// Insert a validated fragment into the pixel of id `pixel` (any id the caller picks:
    /// a pixel or ray index), quantized with the hash [`Fragment::hash`]`(pixel)`: with a
    /// keyed fragment ([`Fragment::with_key`]) the dither of a faint fragment stays the same
    /// from one frame to the next.
    #[inline]
    pub fn insert_at(&mut self, fragment: &Fragment, pixel: u32) {
        insert(
            &mut self.head,
            &mut self.tail,
            A::quantize(fragment, fragment.hash(pixel)),
        );
    }

    /// Insert an already quantized row with Listing 2.
    #[inline]
    pub fn insert_row(&mut self, row: Row) {
        insert(&mut self.head, &mut self.tail, row);
    }

    /// Resolve head and tail: `C = C_head + T_head * C_tail`, `T = T_head * T_tail`, where
    /// the head is Eq. 5 over its rows and the tail is [`TailFormat::resolve`].
    #[inline]
    pub fn resolve(&self) -> Resolved {
        resolve(&self.head, self.tail)
    }
}

impl<const K: usize, A: Arithmetic> Default for Hybrid<K, A> {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tail_saturates_instead_of_wrapping() {
        let mut t = PaperTail::EMPTY;
        for _ in 0..10 {
            t.add(Row::new([255, 0, 128], 0, 1.0));
        }
        assert_eq!(t.color_sum(), [1023, 0, 1023]);
        assert_eq!(t.alpha_sum(), 2550);
        assert_eq!(t.count(), 10);
        let mut t = PaperTail::from_words([0, 0xffff_ffff]);
        t.add(Row::new([0, 0, 0], 0, 1.0));
        assert_eq!((t.alpha_sum(), t.count()), (65535, 65535));
    }

    #[test]
    fn tail_skips_only_invisible_rows_and_keeps_spare_bits() {
        let mut t = PaperTail::from_words([3 << 30, 0]);
        t.add(Row::EMPTY);
        t.add(Row::new([0, 0, 0], 255, 1.0));
        assert_eq!(t, PaperTail::from_words([3 << 30, 0]));
        t.add(Row::new([9, 0, 0], 255, 1.0)); // additive light is kept
        assert_eq!(
            (t.color_sum(), t.alpha_sum(), t.count(), t.spare()),
            ([9, 0, 0], 0, 1, 3)
        );
    }

    /// Bavoil-Myers in f64 as printed, with the documented handling of arbitrary bytes
    /// (count 0 as count 1, mean alpha clamped to 1).
    fn bavoil_myers(t: PaperTail) -> (f64, f64) {
        let n = t.count().max(1) as f64;
        let s_a = t.alpha_sum() as f64 / 255.0;
        let x = 1.0 - (s_a / n).min(1.0);
        let t_tail = x.powf(n);
        let g = if s_a == 0.0 { 1.0 } else { (1.0 - t_tail) / s_a };
        (t.color_sum()[0] as f64 / 255.0 * g, t_tail)
    }

    #[test]
    fn tail_resolve_matches_bavoil_myers_including_arbitrary_bytes() {
        let cases = [
            (767, 65280, 0), // count 0, mean above 1 (the fuzz finding of the S_n / n rewrite)
            (500, 600, 2),   // mean above 1
            (300, 200, 0),   // count 0, mean below 1
            (1023, 1, 45372),
            (255, 255, 1),
            (1000, 5000, 60),
            (12, 0, 7), // pure additive light
        ];
        for (c, a, n) in cases {
            let t = PaperTail::from_sums([c, 0, 0], a, n);
            let r = t.resolve();
            let (want_c, want_t) = bavoil_myers(t);
            // The documented precision: `1 - mean` is a multiple of 2^-24, so |dT| <= n 2^-24,
            // and the color is within n 2^-23 relative (docs/reliability.md).
            let n = t.count().max(1) as f64;
            let dt = n * 2f64.powi(-24) + 1e-5;
            assert!(
                (r.transmittance as f64 - want_t).abs() <= dt,
                "{t:?}: {r:?} vs T {want_t}"
            );
            let dc = 1e-5 + (n * 2f64.powi(-23) + 1e-5) * want_c;
            assert!((r.color.x as f64 - want_c).abs() <= dc, "{t:?}: {r:?} vs C {want_c}");
        }
    }

    #[test]
    fn additive_tail_adds_its_light() {
        let mut t = PaperTail::EMPTY;
        t.add(Row::new([51, 0, 0], 255, 1.0));
        t.add(Row::new([51, 0, 0], 255, 2.0));
        let r = t.resolve();
        assert_eq!(r.transmittance, 1.0);
        assert!((r.color.x - 102.0 / 255.0).abs() < 1e-6);
    }
}

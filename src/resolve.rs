//! Resolve: paper Eq. 5 and 6, and the pixel writers.
//!
//! ```text
//! A_transp = sum_j A_j * prod_{i<j} T_i          (Eq. 5, rows front to back, T_-1 = 1)
//! A_pixel  = A_opaque * prod_i T_i + A_transp     (Eq. 6)
//! ```
//!
//! Evaluated in f32 in one fixed order (per row, with `v` the visibility so far and bytes
//! as exact f32: `w = v * (1/255)`, `a += byte * w`, `v = T_byte * w`), with separate
//! multiplies and adds, never FMA.
//! The lane kernels evaluate the same expression tree, so their pixels are bit-identical.

use glam::{Vec3, Vec4};
use half::f16;

use crate::lanes::FloatLanes;
use crate::row::Row;

/// `1 / 255` rounded to f32; `255.0 * INV255 == 1.0` exactly (tested).
pub const INV255: f32 = 1.0 / 255.0;

/// A byte as a unorm value: `b as f32 * INV255`.
#[inline(always)]
pub fn unorm(b: u8) -> f32 {
    b as f32 * INV255
}

/// The composite of the transparent layers of one pixel, before the background.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Resolved {
    /// Premultiplied color of the transparent layers, `A_transp` of Eq. 5. May exceed 1
    /// where additive light was accumulated.
    pub color: Vec3,
    /// Visibility of the background, the product of all transmittances (`1 - alpha`).
    pub transmittance: f32,
}

impl Resolved {
    /// Nothing drawn: color 0, background fully visible.
    pub const CLEAR: Resolved = Resolved {
        color: Vec3::ZERO,
        transmittance: 1.0,
    };

    /// Eq. 6: composite over an opaque background, `color + background * transmittance`.
    #[inline]
    pub fn over(self, background: Vec3) -> Vec3 {
        self.color + background * self.transmittance
    }

    /// Premultiplied RGBA for compositing later: `(color, 1 - transmittance)`.
    #[inline]
    pub fn premultiplied(self) -> Vec4 {
        self.color.extend(1.0 - self.transmittance)
    }

    /// The pixel for a [`Background`]: opaque (alpha 1) or premultiplied.
    #[inline]
    pub fn pixel(self, background: Background) -> Vec4 {
        match background {
            Background::Opaque(bg) => self.over(bg).extend(1.0),
            Background::Transparent => self.premultiplied(),
        }
    }
}

/// What the transparent layers are composited onto when writing pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Background {
    /// An opaque color (Eq. 6); the written alpha is 1.
    Opaque(Vec3),
    /// Nothing: write premultiplied RGBA (`alpha = 1 - prod T`) for compositing later.
    Transparent,
}

/// Eq. 5 over rows sorted front to back (any rows are accepted: the result is finite,
/// color channels in `[0, rows.len()]`, transmittance in `[0, 1]`).
#[inline]
pub fn resolve_rows(rows: &[Row]) -> Resolved {
    let ([r, g, b], t) = resolve_layers(rows.iter().map(row_bytes));
    Resolved {
        color: Vec3::new(r, g, b),
        transmittance: t,
    }
}

/// A row's `[R, G, B, T]` bytes as exact f32.
#[inline(always)]
pub(crate) fn row_bytes(row: &Row) -> [f32; 4] {
    row.rgbt().map(|b| b as f32)
}

/// Eq. 5, written once for every lane width (`f32` or `f32x8`), over layers given as byte
/// values `[R, G, B, T]` front to back. Per layer, with `v` the visibility so far:
/// `w = v * INV255`, `a += byte * w` per channel, then `v = T * w`.
#[inline(always)]
pub(crate) fn resolve_layers<F: FloatLanes>(layers: impl Iterator<Item = [F; 4]>) -> ([F; 3], F) {
    let inv = F::splat(INV255);
    let mut a = [F::splat(0.0); 3];
    let mut v = F::splat(1.0);
    for [r, g, b, t] in layers {
        let w = v * inv;
        a = [a[0] + r * w, a[1] + g * w, a[2] + b * w];
        v = t * w;
    }
    (a, v)
}

/// RGBA8 from a pixel: each channel clamped to `[0, 1]`, then `floor(x * 255 + 0.5)`
/// (NaN becomes 0). Byte order R, G, B, A.
#[inline]
pub fn to_rgba8(pixel: Vec4) -> [u8; 4] {
    pixel.to_array().map(|x| {
        // The same steps as the lanes writer: select-based clamp (NaN fails both tests).
        let x = if x > 1.0 { 1.0 } else { x };
        let x = if x >= 0.0 { x } else { 0.0 };
        crate::unorm::quantize(x)
    })
}

/// [`to_rgba8`] for 8 lanes, one channel: the byte in the low 8 bits of each lane.
#[cfg(target_endian = "little")]
#[inline(always)]
pub(crate) fn to_unorm8_lanes(x: wide::f32x8) -> wide::u32x8 {
    let one = wide::f32x8::ONE;
    let x = x.simd_gt(one).select(one, x);
    let x = x.simd_ge(wide::f32x8::ZERO).select(x, wide::f32x8::ZERO);
    let q = x * wide::f32x8::splat(255.0) + wide::f32x8::splat(0.5);
    bytemuck::cast::<wide::i32x8, wide::u32x8>(q.fast_trunc_int()) & wide::u32x8::splat(0xff)
}

/// RGBA16F (IEEE half) from a pixel, rounded to nearest even; values above 1 (additive
/// light) are kept, above 65504 they become infinity.
#[inline]
pub fn to_rgba16f(pixel: Vec4) -> [f16; 4] {
    pixel.to_array().map(f16::from_f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inv255_is_exact_at_255() {
        assert_eq!(255.0 * INV255, 1.0);
        assert_eq!(unorm(255), 1.0);
        assert_eq!(unorm(0), 0.0);
    }

    #[test]
    fn empty_rows_resolve_to_clear() {
        assert_eq!(resolve_rows(&[Row::EMPTY; 4]), Resolved::CLEAR);
    }

    #[test]
    fn writers_clamp_and_round() {
        assert_eq!(to_rgba8(Vec4::new(-1.0, 0.5, 2.0, f32::NAN)), [0, 128, 255, 0]);
        assert_eq!(
            to_rgba16f(Vec4::new(0.0, 0.5, 4.0, 1.0)).map(f16::to_f32),
            [0.0, 0.5, 4.0, 1.0]
        );
    }
}

//! Eight lanes of `f32` for the span rasterizer's 8-wide shading ([`super::prims::Shade8`]).
//!
//! Every helper performs, per lane, exactly the IEEE operations of its scalar counterpart in
//! the same order, so each lane is bit for bit the scalar result: `+ - * /` and `sqrt` are
//! correctly rounded in both (and Rust never contracts to FMA), and the scalar `clamp`,
//! `min` and `max` are written out as compares and selects that agree with them on every
//! input, NaN and -0.0 included (`clamp01_8`, `min_sel`, `max0_8`). Masks leave as bits.

use wide::{f32x8, i32x8};

/// Eight `f32` lanes.
pub type F8 = f32x8;

/// All lanes `v`.
#[inline(always)]
pub fn splat(v: f32) -> F8 {
    f32x8::splat(v)
}

/// The pixel centres `(sx + i) as f32 + 0.5` of the span at column `sx` (`sx + 7 <
/// 2^31`): the integer converts to `f32` rounding to nearest, as `as f32` does, then one add.
#[inline(always)]
pub fn centres(sx: u32) -> F8 {
    let x = i32x8::splat(sx as i32) + i32x8::from([0, 1, 2, 3, 4, 5, 6, 7]);
    f32x8::from_i32x8(x) + splat(0.5)
}

/// Bits of the lanes where `a < b` (false on NaN).
#[inline(always)]
pub fn lt_bits(a: F8, b: F8) -> u8 {
    a.simd_lt(b).to_bitmask() as u8
}

/// `x.clamp(0.0, 1.0)` per lane: `x < 0` gives 0, then `x > 1` gives 1, otherwise `x`
/// itself (NaN and -0.0 pass through, as in `f32::clamp`).
#[inline(always)]
pub fn clamp01_8(x: F8) -> F8 {
    let x = x.simd_lt(splat(0.0)).select(splat(0.0), x);
    x.simd_gt(splat(1.0)).select(splat(1.0), x)
}

/// `x.min(c)` per lane for a constant `c` that is not 0 and not NaN: `x < c ? x : c` (NaN
/// gives `c`, as `f32::min` does; equal values are the same bits since `c` is not a zero).
#[inline(always)]
pub fn min_sel(x: F8, c: f32) -> F8 {
    x.simd_lt(splat(c)).select(x, splat(c))
}

/// `if x > 0 { x } else { 0 }` per lane (the scalar side is [`super::raster`]'s `max0`).
#[inline(always)]
pub fn max0_8(x: F8) -> F8 {
    x.simd_gt(splat(0.0)).select(x, splat(0.0))
}

/// [`super::seg_dist`] at the pixel centres `px` of line `py`: distance to segment `a-b`
/// and the parameter of the closest point, per lane.
#[inline(always)]
pub fn seg_dist8(px: F8, py: f32, a: (f32, f32), b: (f32, f32)) -> (F8, F8) {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let l2 = dx * dx + dy * dy;
    let (ex0, ey0) = (px - splat(a.0), py - a.1);
    let t = if l2 > 0.0 {
        clamp01_8((ex0 * splat(dx) + splat(ey0 * dy)) / splat(l2))
    } else {
        splat(0.0)
    };
    let (ex, ey) = (ex0 - t * splat(dx), splat(ey0) - t * splat(dy));
    ((ex * ex + ey * ey).sqrt(), t)
}

/// [`super::splat_falloff`] per lane: 0 unless `0 <= q < 18`.
#[inline(always)]
pub fn splat_falloff8(q: F8) -> F8 {
    let inside = q.simd_ge(splat(0.0)) & q.simd_lt(splat(18.0));
    let x = splat(1.0) - q / splat(18.0);
    let x2 = x * x;
    let x4 = x2 * x2;
    inside.select(x4 * x4 * x, splat(0.0))
}

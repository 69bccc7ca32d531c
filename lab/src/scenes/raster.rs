//! The span rasterizer: one scan per primitive kind (monomorphized over the kind's shade),
//! over the primitive's box clipped to any rectangle, emitting 8-pixel spans aligned to
//! multiples of 8 columns: a coverage mask and per-lane premultiplied color, alpha and depth,
//! and the primitive's id as every lane's stable key, as [`mlab::lanes::FragmentLanes`] (what
//! the kernel's span insert quantizes).

use super::clamp01;
use super::lanes8::{F8, centres, clamp01_8, lt_bits, max0_8, min_sel, splat};
use super::prims::{Kind, Primitive, Shade, Shade8};
use crate::stream::Frag;
use mlab::lanes::{FragmentLanes, LANES};

/// A clip rectangle in pixels: columns `x0..x1`, lines `y0..y1`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Clip {
    /// First column.
    pub x0: u32,
    /// First line.
    pub y0: u32,
    /// One past the last column.
    pub x1: u32,
    /// One past the last line.
    pub y1: u32,
}

impl Clip {
    /// The whole frame.
    pub fn frame(width: u32, height: u32) -> Clip {
        Clip {
            x0: 0,
            y0: 0,
            x1: width,
            y1: height,
        }
    }
}

/// The lanes of one emitted span (lanes outside the mask hold unspecified values, NaN
/// included: read only the lanes in the mask, as the kernel's quantizer does); `key` is the
/// primitive's id in every lane ([`Primitive::id`]).
pub type SpanLanes = FragmentLanes;

/// Flattening spans back into fragments (the stream of the quality tables).
pub trait PushFrags {
    /// Append the lanes set in `mask` of the span at `(x, y)` as fragments of primitive
    /// `prim`, left to right.
    fn push_frags(&self, width: u32, x: u32, y: u32, mask: u8, prim: u32, out: &mut Vec<Frag>);
}

impl PushFrags for FragmentLanes {
    fn push_frags(&self, width: u32, x: u32, y: u32, mask: u8, prim: u32, out: &mut Vec<Frag>) {
        for i in 0..LANES {
            if mask & (1 << i) != 0 {
                out.push(Frag {
                    pixel: y * width + x + i as u32,
                    depth: self.depth[i],
                    color: [self.color[0][i], self.color[1][i], self.color[2][i]],
                    alpha: self.alpha[i],
                    prim,
                });
            }
        }
    }
}

impl Primitive {
    /// Rasterize over the box clipped to `clip`: `emit(x, y, mask, lanes)` per span that has
    /// a fragment, `x` a multiple of 8, lines top to bottom, spans left to right; the lanes'
    /// `key` is the primitive's id. A fragment
    /// that carries neither opacity nor light (both below 1/1024) is not emitted.
    ///
    /// Strands, sprites, fog slices and splats are shaded eight lanes at once (`shade8`,
    /// bit for bit the scalar `shade` per lane); the other kinds pixel by pixel. The spans
    /// are exactly those of [`Self::raster_scalar`] (tested lane by lane).
    #[inline]
    pub fn raster<E: FnMut(u32, u32, u8, &SpanLanes)>(&self, clip: Clip, emit: &mut E) {
        let all = |_: f32| Some((f32::NEG_INFINITY, f32::INFINITY));
        match &self.kind {
            Kind::Strand(p) => self.scan8(clip, |x, y, w| p.shade8(x, y, w), |y| p.line_range(y), emit),
            Kind::Sprite(p) => self.scan8(clip, |x, y, w| p.shade8(x, y, w), |y| p.line_range(y), emit),
            Kind::FogSlice(p) => self.scan8(clip, |x, y, w| p.shade8(x, y, w), all, emit),
            Kind::Splat(p) => self.scan8(clip, |x, y, w| p.shade8(x, y, w), |y| p.line_range(y), emit),
            _ => self.raster_scalar(clip, emit),
        }
    }

    /// The reference rasterizer: as [`Self::raster`], every pixel shaded on its own by the
    /// kind's scalar `shade`.
    #[inline]
    pub fn raster_scalar<E: FnMut(u32, u32, u8, &SpanLanes)>(&self, clip: Clip, emit: &mut E) {
        let all = |_: f32| Some((f32::NEG_INFINITY, f32::INFINITY));
        match &self.kind {
            Kind::Strand(p) => self.scan(clip, |x, y| p.shade(x, y), |y| p.line_range(y), emit),
            Kind::Sprite(p) => self.scan(clip, |x, y| p.shade(x, y), |y| p.line_range(y), emit),
            Kind::Trunk(p) => self.scan(clip, |x, y| p.shade(x, y), all, emit),
            Kind::Leaf(p) => self.scan(clip, |x, y| p.shade(x, y), all, emit),
            Kind::SphereBand(p) => self.scan(clip, |x, y| p.shade(x, y), all, emit),
            Kind::Panel(p) => self.scan(clip, |x, y| p.shade(x, y), all, emit),
            Kind::FogSlice(p) => self.scan(clip, |x, y| p.shade(x, y), all, emit),
            Kind::Splat(p) => self.scan(clip, |x, y| p.shade(x, y), |y| p.line_range(y), emit),
        }
    }

    /// The lanes a scan fills: every lane keyed by the primitive's id.
    #[inline(always)]
    fn lanes(&self) -> FragmentLanes {
        FragmentLanes {
            key: Some([self.id; LANES]),
            ..FragmentLanes::TRANSPARENT
        }
    }

    /// The box clipped to `clip` (columns, lines), `None` if empty.
    #[inline(always)]
    fn clipped(&self, clip: Clip) -> Option<((u32, u32), (u32, u32))> {
        let (xa, xb) = (self.x0.max(clip.x0), self.x1.min(clip.x1));
        let (ya, yb) = (self.y0.max(clip.y0), self.y1.min(clip.y1));
        (xa < xb && ya < yb).then_some(((xa, xb), (ya, yb)))
    }

    /// Columns `xa..xb` narrowed to the columns whose pixel centre `x + 0.5` lies in the range
    /// `[lo, hi]` on a line (the ranges carry their own slack for rounding).
    #[inline(always)]
    pub(super) fn narrow((xa, xb): (u32, u32), (lo, hi): (f32, f32)) -> (u32, u32) {
        // Float-to-int casts saturate (negative values and NaN give 0, infinities included);
        // the sum saturates too.
        let xa = xa.max((lo - 0.5).ceil() as u32);
        let xb = xb.min(((hi - 0.5).floor() as u32).saturating_add(1));
        (xa, xb)
    }

    #[inline(always)]
    fn scan<S, R, E>(&self, clip: Clip, shade: S, range: R, emit: &mut E)
    where
        S: Fn(f32, f32) -> Option<Shade>,
        R: Fn(f32) -> Option<(f32, f32)>,
        E: FnMut(u32, u32, u8, &SpanLanes),
    {
        let Some((cols, (ya, yb))) = self.clipped(clip) else {
            return;
        };
        let mut lanes = self.lanes();
        for y in ya..yb {
            let py = y as f32 + 0.5;
            // The kind's conservative range on this line (pixel centres `x + 0.5`).
            let Some(r) = range(py) else { continue };
            let (xa, xb) = Self::narrow(cols, r);
            let mut sx = xa & !(LANES as u32 - 1);
            while sx < xb {
                let mut mask = 0u8;
                for i in 0..LANES {
                    let x = sx + i as u32;
                    if x < xa || x >= xb {
                        continue;
                    }
                    let Some(sh) = shade(x as f32 + 0.5, py) else {
                        continue;
                    };
                    let a = clamp01(sh.alpha);
                    let c = [0, 1, 2].map(|k| min1(clamp01(sh.color[k]) * a + max0(sh.light[k])));
                    if a < 1.0 / 1024.0 && c.iter().all(|&v| v < 1.0 / 1024.0) {
                        continue;
                    }
                    lanes.color[0][i] = c[0];
                    lanes.color[1][i] = c[1];
                    lanes.color[2][i] = c[2];
                    lanes.alpha[i] = a;
                    lanes.depth[i] = sh.depth;
                    mask |= 1 << i;
                }
                if mask != 0 {
                    emit(sx, y, mask, &lanes);
                }
                sx += LANES as u32;
            }
        }
    }

    /// [`Self::scan`] with the shading eight lanes at once: the lanes of a span outside
    /// `xa..xb` are shaded too but masked off, as the lanes `shade8` drops and those below
    /// the emission threshold (the same compares as the scalar scan's, per lane).
    #[inline(always)]
    fn scan8<S, R, E>(&self, clip: Clip, shade8: S, range: R, emit: &mut E)
    where
        S: Fn(F8, f32, u8) -> (u8, Shade8),
        R: Fn(f32) -> Option<(f32, f32)>,
        E: FnMut(u32, u32, u8, &SpanLanes),
    {
        let Some((cols, (ya, yb))) = self.clipped(clip) else {
            return;
        };
        let mut lanes = self.lanes();
        let eps = splat(1.0 / 1024.0);
        for y in ya..yb {
            let py = y as f32 + 0.5;
            let Some(r) = range(py) else { continue };
            let (xa, xb) = Self::narrow(cols, r);
            if xa >= xb {
                continue;
            }
            let mut sx = xa & !(LANES as u32 - 1);
            while sx < xb {
                // Lanes `xa - sx ..` up to `xb - sx` (at most 8).
                let (lo, hi) = (xa.saturating_sub(sx), (xb - sx).min(LANES as u32));
                let inside = ((1u32 << hi) - (1u32 << lo)) as u8;
                let (keep, sh) = shade8(centres(sx), py, inside);
                let a = clamp01_8(sh.alpha);
                let c = [0, 1, 2].map(|k| min_sel(clamp01_8(sh.color[k]) * a + max0_8(sh.light[k]), 1.0));
                let faint = lt_bits(a, eps) & lt_bits(c[0], eps) & lt_bits(c[1], eps) & lt_bits(c[2], eps);
                let mask = inside & keep & !faint;
                if mask != 0 {
                    lanes.color = c.map(|v| v.to_array());
                    lanes.alpha = a.to_array();
                    lanes.depth = sh.depth.to_array();
                    emit(sx, y, mask, &lanes);
                }
                sx += LANES as u32;
            }
        }
    }
}

/// `x.max(0.0)`, written out: `x` if `x > 0`, else `+0.0` (NaN and -0.0 give `+0.0`, where
/// `f32::max` leaves the sign of a zero unspecified).
#[inline(always)]
fn max0(x: f32) -> f32 {
    if x > 0.0 { x } else { 0.0 }
}

/// `x.min(1.0)`, written out: `x` if `x < 1`, else 1 (NaN gives 1, as `f32::min` does).
#[inline(always)]
fn min1(x: f32) -> f32 {
    if x < 1.0 { x } else { 1.0 }
}

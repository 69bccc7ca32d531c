//! The primitives of the scenes: one struct per kind, with what its rasterizer evaluates at a
//! pixel centre ([`Shade`]), and the scene's list of them in submission order.

use super::lanes8::{F8, clamp01_8, lt_bits, min_sel, seg_dist8, splat};
use super::{clamp01, lerp3, seg_dist};
use crate::stream::Stream;

/// What a primitive gives at one pixel centre: depth, straight color, alpha (coverage
/// included), and additive light (premultiplied, added on top of `color * alpha`).
#[derive(Clone, Copy, Debug)]
pub struct Shade {
    /// Distance from the viewer.
    pub depth: f32,
    /// Straight color.
    pub color: [f32; 3],
    /// Alpha, coverage included.
    pub alpha: f32,
    /// Additive light, premultiplied.
    pub light: [f32; 3],
}

/// [`Shade`] at the eight pixel centres of a span, lane by lane: lane `i` is bit for bit what
/// the scalar `shade(px[i], py)` gives where bit `i` of the returned mask is set. The mask
/// is the set of lanes where the scalar shade is `Some`, less any lane the caller did not
/// want (`shade8(px, py, want)`); other lanes hold unspecified values.
#[derive(Clone, Copy, Debug)]
pub struct Shade8 {
    /// Depth per lane.
    pub depth: F8,
    /// Straight color per channel and lane.
    pub color: [F8; 3],
    /// Alpha per lane.
    pub alpha: F8,
    /// Additive light per channel and lane.
    pub light: [F8; 3],
}

/// A scene's primitives in submission order, with the frame they are laid out for.
#[derive(Clone, Debug)]
pub struct Primitives {
    /// Frame width in pixels.
    pub width: u32,
    /// Frame height in pixels.
    pub height: u32,
    /// Opaque background color.
    pub background: [f32; 3],
    /// Primitives in submission order.
    pub prims: Vec<Primitive>,
}

impl Primitives {
    /// The fragment stream: every primitive rasterized over the whole frame, in submission
    /// order, each primitive's fragments in scan order (line by line, left to right).
    pub fn stream(&self) -> Stream {
        use super::PushFrags;
        let clip = super::Clip::frame(self.width, self.height);
        let mut frags = Vec::new();
        for p in &self.prims {
            p.raster(clip, &mut |x, y, mask, l| {
                l.push_frags(self.width, x, y, mask, p.id, &mut frags)
            });
        }
        Stream {
            width: self.width,
            height: self.height,
            background: self.background,
            frags,
        }
    }

    /// Bytes held by the primitive list.
    pub fn bytes(&self) -> usize {
        self.prims.capacity() * std::mem::size_of::<Primitive>()
    }
}

/// One primitive: its id, its pixel box (`x0..x1`, `y0..y1`, clamped to the frame) and its
/// kind.
#[derive(Clone, Copy, Debug)]
pub struct Primitive {
    /// The primitive's id: its number in the scene's list as built (0, 1, 2, ...), which
    /// depends on neither the camera nor the frame size, so the same primitive has the same
    /// id in every frame of a camera path and in every submission order (a shuffle of the
    /// list keeps each primitive's id). Every fragment it emits carries it
    /// ([`crate::stream::Frag::prim`]).
    pub id: u32,
    /// First column.
    pub x0: u32,
    /// First line.
    pub y0: u32,
    /// One past the last column.
    pub x1: u32,
    /// One past the last line.
    pub y1: u32,
    /// What it is.
    pub kind: Kind,
}

/// The primitive kinds, each with its own rasterizer (a monomorphized span scan).
#[derive(Clone, Copy, Debug)]
pub enum Kind {
    /// HAIR: one segment of a strand.
    Strand(Strand),
    /// PARTICLES: a soft round sprite.
    Sprite(Sprite),
    /// FOREST: a trunk.
    Trunk(Trunk),
    /// FOREST: a leaf.
    Leaf(Leaf),
    /// TEAPOTS: a band of lines of a sphere's front or back face.
    SphereBand(SphereBand),
    /// GLASS: one face of a panel.
    Panel(Panel),
    /// FOG: a slice.
    FogSlice(FogSlice),
    /// SPLATS: a Gaussian splat.
    Splat(Splat),
}

/// A strand segment `a-b`; a pixel belongs to the nearest segment of its strand (`prev` and
/// `next` are the neighbouring segments' far ends).
#[derive(Clone, Copy, Debug)]
pub struct Strand {
    pub(super) a: (f32, f32),
    pub(super) b: (f32, f32),
    pub(super) prev: Option<(f32, f32)>,
    pub(super) next: Option<(f32, f32)>,
    pub(super) hw: f32,
    pub(super) za: f32,
    pub(super) zb: f32,
    pub(super) tint: f32,
    pub(super) alpha: f32,
}

impl Strand {
    /// What f32 rounding can move a distance here by, with room to spare: 1/16 pixel plus
    /// 2^-16 of the largest magnitude among the coordinates and `hw` (the distances' rounding
    /// errors are below 2^-20 of it). NaN coordinates are skipped: they make every distance
    /// NaN, which neither covers a pixel nor takes it from a neighbour.
    #[inline(always)]
    fn slack(&self) -> f32 {
        let (p, n) = (self.prev.unwrap_or(self.a), self.next.unwrap_or(self.b));
        let m = [self.a, self.b, p, n]
            .iter()
            .fold(self.hw.abs(), |m, &(x, y)| m.max(x.abs()).max(y.abs()));
        1.0 / 16.0 + m * (1.0 / 65536.0)
    }

    /// A conservative range of pixel-centre `x` on line `py` outside which [`Self::shade`] gives
    /// nothing (coverage needs distance `< hw + 0.5` to the segment; the range is the
    /// capsule of radius `hw + 0.5` plus [`Self::slack`]); `None` if the line misses it.
    #[inline(always)]
    pub(super) fn line_range(&self, py: f32) -> Option<(f32, f32)> {
        let r = self.hw + 0.5 + self.slack();
        let (a, b) = (self.a, self.b);
        let dy = b.1 - a.1;
        if dy.abs() < 1e-6 {
            if (a.1 - py).abs() > r {
                return None;
            }
            return Some((lesser(a.0, b.0) - r, greater(a.0, b.0) + r));
        }
        // The part of the segment within `r` of the line, in `x`, widened by `r`. A
        // reciprocal (hoisted out of the line loop): the range need not be bit-exact, only
        // conservative, and the slack covers its rounding.
        let (dx, inv) = (b.0 - a.0, 1.0 / dy);
        let (u, v) = ((py - r - a.1) * inv, (py + r - a.1) * inv);
        let (t0, t1) = (greater(lesser(u, v), 0.0), lesser(greater(u, v), 1.0));
        if t0 > t1 {
            return None;
        }
        let (x0, x1) = (a.0 + t0 * dx, a.0 + t1 * dx);
        // The capsule also lies within `r` of the segment's supporting line, which crosses
        // this line at `xc`: within `r L / |dy|` of it (widened by 2^-12 for rounding).
        let xc = a.0 + (py - a.1) * (dx * inv);
        let w = r * (dx * dx + dy * dy).sqrt() * inv.abs() * (1.0 + 1.0 / 4096.0);
        Some((greater(lesser(x0, x1) - r, xc - w), lesser(greater(x0, x1) + r, xc + w)))
    }

    #[inline(always)]
    pub(super) fn shade(&self, px: f32, py: f32) -> Option<Shade> {
        let (a, b) = (self.a, self.b);
        let (d, t) = seg_dist(px, py, a, b);
        // Owned by the nearest segment (ties to the earlier one).
        if let Some(p) = self.prev
            && seg_dist(px, py, p, a).0 <= d
        {
            return None;
        }
        if let Some(n) = self.next
            && seg_dist(px, py, b, n).0 < d
        {
            return None;
        }
        let cov = clamp01(self.hw + 0.5 - d);
        if cov <= 0.0 {
            return None;
        }
        let z = self.za + (self.zb - self.za) * t;
        let k = clamp01((z - 7.5) / 5.0 + self.tint);
        Some(Shade {
            depth: z,
            color: lerp3([0.95, 0.78, 0.45], [0.22, 0.1, 0.04], k),
            alpha: self.alpha * cov,
            light: [0.0; 3],
        })
    }

    /// [`Self::shade`] at the pixel centres `px` of line `py`, eight lanes at once (the
    /// same operations in the same order per lane, branch-free; see [`Shade8`]); lanes not in
    /// `want` may be dropped.
    #[inline(always)]
    pub(super) fn shade8(&self, px: F8, py: f32, want: u8) -> (u8, Shade8) {
        let (a, b) = (self.a, self.b);
        let (d, t) = seg_dist8(px, py, a, b);
        let cov = clamp01_8(splat(self.hw + 0.5) - d);
        let mut keep = want & !(cov.simd_le(splat(0.0)).to_bitmask() as u8);
        // The neighbours only where the lanes wanted are covered (each condition alone
        // drops a lane, so their order does not matter).
        // A kept lane has `d < hw + 0.5`: a neighbour whose bounding box is farther than
        // that plus the slack from every kept lane cannot take one, and is not evaluated.
        let far = self.hw + 0.5 + self.slack();
        // `seg_dist(p, a) <= d` drops the lane, as does `seg_dist(b, n) < d` (nothing is
        // evaluated when no lane is kept).
        if let Some(p) = self.prev
            && keep & near_box(px, py, p, a, far) != 0
        {
            keep &= !(seg_dist8(px, py, p, a).0.simd_le(d).to_bitmask() as u8);
        }
        if let Some(n) = self.next
            && keep & near_box(px, py, b, n, far) != 0
        {
            keep &= !(lt_bits(seg_dist8(px, py, b, n).0, d));
        }
        let z = splat(self.za) + splat(self.zb - self.za) * t;
        let k = clamp01_8((z - splat(7.5)) / splat(5.0) + splat(self.tint));
        let (c0, c1) = ([0.95f32, 0.78, 0.45], [0.22f32, 0.1, 0.04]);
        let color = [0, 1, 2].map(|i| splat(c0[i]) + splat(c1[i] - c0[i]) * k);
        let zero = splat(0.0);
        (
            keep,
            Shade8 {
                depth: z,
                color,
                alpha: splat(self.alpha) * cov,
                light: [zero; 3],
            },
        )
    }
}

/// `a < b ? a : b` (one `minss`; unlike `f32::min`, not NaN-aware: the line ranges only
/// have to hold for the coordinates a scene can have).
#[inline(always)]
fn lesser(a: f32, b: f32) -> f32 {
    if a < b { a } else { b }
}

/// `a > b ? a : b` (see [`lesser`]).
#[inline(always)]
fn greater(a: f32, b: f32) -> f32 {
    if a > b { a } else { b }
}

/// The lanes whose pixel centre is not farther than `far` from the bounding box of segment
/// `p-q` along `x` or `y` (a lower bound of the distance to the segment). A NaN coordinate
/// may give any answer: the distance to such a segment is NaN, which takes no lane anyway.
#[inline(always)]
fn near_box(px: F8, py: f32, p: (f32, f32), q: (f32, f32), far: f32) -> u8 {
    let (y0, y1) = (p.1.min(q.1), p.1.max(q.1));
    if py - y1 > far || y0 - py > far {
        return 0;
    }
    let (x0, x1) = (p.0.min(q.0), p.0.max(q.0));
    let away = (splat(x0) - px).simd_gt(splat(far)) | (px - splat(x1)).simd_gt(splat(far));
    !(away.to_bitmask() as u8)
}

/// A smoke or fire sprite.
#[derive(Clone, Copy, Debug)]
pub struct Sprite {
    pub(super) cx: f32,
    pub(super) cy: f32,
    pub(super) rad: f32,
    pub(super) z: f32,
    pub(super) fire: bool,
    pub(super) fa: f32,
    pub(super) heat: f32,
    pub(super) grey: f32,
    pub(super) a0: f32,
}

impl Sprite {
    /// A conservative range of pixel-centre `x` on line `py` outside which [`Self::shade`] gives
    /// nothing (inside the disc), with a pixel of margin.
    #[inline(always)]
    pub(super) fn line_range(&self, py: f32) -> Option<(f32, f32)> {
        let dy = py - self.cy;
        if dy.abs() > self.rad + 1.0 {
            return None;
        }
        let half = (self.rad * self.rad - dy * dy).max(0.0).sqrt() + 1.0;
        Some((self.cx - half, self.cx + half))
    }

    #[inline(always)]
    pub(super) fn shade(&self, px: f32, py: f32) -> Option<Shade> {
        let (dx, dy) = ((px - self.cx) / self.rad, (py - self.cy) / self.rad);
        let q = dx * dx + dy * dy;
        if q >= 1.0 {
            return None;
        }
        let fall = (1.0 - q) * (1.0 - q);
        let heat = self.heat;
        if self.fire {
            Some(Shade {
                depth: self.z,
                color: [1.0, 0.5, 0.2],
                alpha: self.fa * fall,
                light: [heat * fall, heat * 0.45 * fall, heat * 0.1 * fall],
            })
        } else {
            let grey = self.grey;
            Some(Shade {
                depth: self.z,
                color: [grey, grey, grey * 1.05],
                alpha: self.a0 * fall,
                light: [0.0; 3],
            })
        }
    }

    /// [`Self::shade`], eight lanes at once (see [`Shade8`]).
    #[inline(always)]
    pub(super) fn shade8(&self, px: F8, py: f32, _want: u8) -> (u8, Shade8) {
        let rad = self.rad;
        let (dx, dy) = ((px - splat(self.cx)) / splat(rad), (py - self.cy) / rad);
        let q = dx * dx + splat(dy * dy);
        let keep = !(q.simd_ge(splat(1.0)).to_bitmask() as u8);
        let one_q = splat(1.0) - q;
        let fall = one_q * one_q;
        let heat = self.heat;
        let sh = if self.fire {
            Shade8 {
                depth: splat(self.z),
                color: [splat(1.0), splat(0.5), splat(0.2)],
                alpha: splat(self.fa) * fall,
                light: [splat(heat) * fall, splat(heat * 0.45) * fall, splat(heat * 0.1) * fall],
            }
        } else {
            let grey = self.grey;
            Shade8 {
                depth: splat(self.z),
                color: [splat(grey), splat(grey), splat(grey * 1.05)],
                alpha: splat(self.a0) * fall,
                light: [splat(0.0); 3],
            }
        };
        (keep, sh)
    }
}

/// A tree trunk from `(bx, by)` to `top`.
#[derive(Clone, Copy, Debug)]
pub struct Trunk {
    pub(super) bx: f32,
    pub(super) by: f32,
    pub(super) top: (f32, f32),
    pub(super) hw: f32,
    pub(super) z: f32,
}

impl Trunk {
    #[inline(always)]
    pub(super) fn shade(&self, px: f32, py: f32) -> Option<Shade> {
        let (d, _) = seg_dist(px, py, (self.bx, self.by), self.top);
        let cov = clamp01(self.hw + 0.5 - d);
        (cov > 0.0).then_some(Shade {
            depth: self.z + 0.5,
            color: [0.3, 0.2, 0.12],
            alpha: 0.9 * cov,
            light: [0.0; 3],
        })
    }
}

/// An alpha-edged elliptical leaf, tilted in depth.
#[derive(Clone, Copy, Debug)]
pub struct Leaf {
    pub(super) cx: f32,
    pub(super) cy: f32,
    pub(super) ax: f32,
    pub(super) ay: f32,
    pub(super) la: f32,
    pub(super) lb: f32,
    pub(super) lz: f32,
    pub(super) tx: f32,
    pub(super) ty: f32,
    pub(super) s: f32,
    pub(super) col: [f32; 3],
    pub(super) edge: f32,
}

impl Leaf {
    #[inline(always)]
    pub(super) fn shade(&self, px: f32, py: f32) -> Option<Shade> {
        let (dx, dy) = (px - self.cx, py - self.cy);
        let (ax, ay) = (self.ax, self.ay);
        let (u, v) = ((dx * ax + dy * ay) / self.la, (dy * ax - dx * ay) / self.lb);
        let q = (u * u + v * v).sqrt();
        let alpha = 0.85 * clamp01((1.0 - q) * self.edge);
        let s = self.s;
        (alpha > 0.0).then_some(Shade {
            depth: self.lz + self.tx * dx / s * 30.0 + self.ty * dy / s * 30.0,
            color: self.col,
            alpha,
            light: [0.0; 3],
        })
    }
}

/// A band of lines of a sphere's front or back face.
#[derive(Clone, Copy, Debug)]
pub struct SphereBand {
    pub(super) cx: f32,
    pub(super) cy: f32,
    pub(super) rad: f32,
    pub(super) zc: f32,
    pub(super) rw: f32,
    pub(super) col: [f32; 3],
    pub(super) a0: f32,
    pub(super) front: bool,
}

impl SphereBand {
    #[inline(always)]
    pub(super) fn shade(&self, px: f32, py: f32) -> Option<Shade> {
        let rad = self.rad;
        let (dx, dy) = ((px - self.cx) / rad, (py - self.cy) / rad);
        let q = dx * dx + dy * dy;
        let dist = q.sqrt();
        let cov = clamp01((1.0 - dist) * rad + 0.5);
        if cov <= 0.0 {
            return None;
        }
        // At the anti-aliased rim the faces would meet: keep them apart.
        let h = (1.0 - q.min(1.0)).sqrt().max(0.05);
        let q2 = q.min(1.0) * q.min(1.0);
        let shade = if self.front { 1.0 } else { 0.7 };
        let (zc, rw, a0) = (self.zc, self.rw, self.a0);
        Some(Shade {
            depth: if self.front { zc - rw * h } else { zc + rw * h },
            color: self.col.map(|c| c * shade),
            alpha: (a0 + (0.9 - a0) * q2) * cov,
            light: [0.0; 3],
        })
    }
}

/// One face of a tinted glass panel.
#[derive(Clone, Copy, Debug)]
pub struct Panel {
    pub(super) cx: f32,
    pub(super) cy: f32,
    pub(super) hx: f32,
    pub(super) hy: f32,
    pub(super) z: f32,
    pub(super) sx: f32,
    pub(super) sy: f32,
    pub(super) thick: f32,
    pub(super) tint: [f32; 3],
    pub(super) alpha: f32,
    pub(super) front: bool,
}

impl Panel {
    #[inline(always)]
    pub(super) fn shade(&self, px: f32, py: f32) -> Option<Shade> {
        let (cx, cy, hx, hy) = (self.cx, self.cy, self.hx, self.hy);
        let cov = clamp01(hx + 0.5 - (px - cx).abs()) * clamp01(hy + 0.5 - (py - cy).abs());
        if cov <= 0.0 {
            return None;
        }
        let zf = self.z + self.sx * (px - cx) + self.sy * (py - cy);
        Some(Shade {
            depth: if self.front { zf } else { zf + self.thick },
            color: if self.front {
                self.tint
            } else {
                self.tint.map(|c| c * 0.6)
            },
            alpha: self.alpha * cov,
            light: [0.0; 3],
        })
    }
}

/// A faint fog slice.
#[derive(Clone, Copy, Debug)]
pub struct FogSlice {
    pub(super) z: f32,
    pub(super) c: (f32, f32),
    pub(super) h: (f32, f32),
    pub(super) peak: f32,
    pub(super) puffs: [(f32, f32, f32); 3],
    pub(super) base: [f32; 3],
    pub(super) s: f32,
    pub(super) amin: f32,
}

impl FogSlice {
    #[inline(always)]
    pub(super) fn shade(&self, px: f32, py: f32) -> Option<Shade> {
        let (u, v) = ((px - self.c.0) / self.h.0, (py - self.c.1) / self.h.1);
        let (u2, v2) = (u * u, v * v);
        let q = u2 * u2 + v2 * v2;
        if q >= 1.0 {
            return None;
        }
        let mut puff = 0.0f32;
        for &(x, y, rad) in &self.puffs {
            let (dx, dy) = ((px - x) / rad, (py - y) / rad);
            let d = 1.0 - (dx * dx + dy * dy);
            if d > 0.0 {
                puff += d * d;
            }
        }
        let density = (1.0 - q) * (1.0 - q) * (0.5 + 0.5 * puff.min(1.0));
        // Lower fog is a little darker (ground shadow), higher a little brighter.
        let height = 0.9 + 0.2 * (1.0 - py / self.s);
        Some(Shade {
            depth: self.z,
            color: self.base.map(|c| c * height),
            alpha: self.amin + (self.peak - self.amin) * density,
            light: [0.0; 3],
        })
    }

    /// [`Self::shade`], eight lanes at once (see [`Shade8`]).
    #[inline(always)]
    pub(super) fn shade8(&self, px: F8, py: f32, _want: u8) -> (u8, Shade8) {
        let (u, v) = ((px - splat(self.c.0)) / splat(self.h.0), (py - self.c.1) / self.h.1);
        let (u2, v2) = (u * u, v * v);
        let q = u2 * u2 + splat(v2 * v2);
        let keep = !(q.simd_ge(splat(1.0)).to_bitmask() as u8);
        let mut puff = splat(0.0);
        for &(x, y, rad) in &self.puffs {
            let (dx, dy) = ((px - splat(x)) / splat(rad), (py - y) / rad);
            let d = splat(1.0) - (dx * dx + splat(dy * dy));
            // `puff += d * d` where `d > 0`.
            puff = d.simd_gt(splat(0.0)).select(puff + d * d, puff);
        }
        let one_q = splat(1.0) - q;
        let density = one_q * one_q * (splat(0.5) + splat(0.5) * min_sel(puff, 1.0));
        let height = 0.9 + 0.2 * (1.0 - py / self.s);
        let sh = Shade8 {
            depth: splat(self.z),
            color: self.base.map(|c| splat(c * height)),
            alpha: splat(self.amin) + splat(self.peak - self.amin) * density,
            light: [splat(0.0); 3],
        };
        (keep, sh)
    }
}

/// A Gaussian splat.
#[derive(Clone, Copy, Debug)]
pub struct Splat {
    pub(super) sx: f32,
    pub(super) sy: f32,
    pub(super) ax: f32,
    pub(super) ay: f32,
    pub(super) sa: f32,
    pub(super) sb: f32,
    pub(super) opacity: f32,
    pub(super) z: f32,
    pub(super) color: [f32; 3],
}

impl Splat {
    /// A conservative range of pixel-centre `x` on line `py` outside which [`Self::shade`] gives
    /// nothing: alpha `>= 1/255` needs `falloff(q) >= 1 / (255 opacity)`, that is `q <= 18 (1 -
    /// (255 opacity)^(-1/9))`, an ellipse whose slice on the line is solved in f64 with the
    /// bound widened by 1/1024 (relative and absolute) and the slice by 1/16 pixel, far more
    /// than the f32 shading's rounding. The whole line when a parameter is degenerate.
    #[inline(always)]
    pub(super) fn line_range(&self, py: f32) -> Option<(f32, f32)> {
        let all = Some((f32::NEG_INFINITY, f32::INFINITY));
        let op = self.opacity as f64;
        if op.is_nan() {
            // Alpha `min(NaN, 0.99)` is 0.99 everywhere.
            return all;
        }
        if op <= 0.0 {
            // Alpha `min(opacity * falloff, 0.99)` is at most 0.
            return None;
        }
        let k = 1.0 / (255.0 * op);
        let qmax = if k >= 1.0 {
            0.0
        } else {
            18.0 * (1.0 - k.powf(1.0 / 9.0))
        };
        let q = qmax * (1.0 + 1.0 / 1024.0) + 1.0 / 1024.0;
        let (sa, sb, ax, ay) = (self.sa as f64, self.sb as f64, self.ax as f64, self.ay as f64);
        let (ia, ib) = (1.0 / (sa * sa), 1.0 / (sb * sb));
        // q(dx) = a dx^2 + 2 b dx dy + c dy^2.
        let (a, b, c) = (
            ax * ax * ia + ay * ay * ib,
            ax * ay * (ia - ib),
            ay * ay * ia + ax * ax * ib,
        );
        let dy = py as f64 - self.sy as f64;
        let disc = b * b * dy * dy - a * (c * dy * dy - q);
        if !(a > 0.0 && a.is_finite() && b.is_finite() && c.is_finite() && disc.is_finite()) {
            return all;
        }
        if disc < 0.0 {
            return None;
        }
        let (mid, half) = (-b * dy / a, disc.sqrt() / a);
        let x = self.sx as f64 + mid;
        Some(((x - half - 1.0 / 16.0) as f32, (x + half + 1.0 / 16.0) as f32))
    }

    #[inline(always)]
    pub(super) fn shade(&self, px: f32, py: f32) -> Option<Shade> {
        let (dx, dy) = (px - self.sx, py - self.sy);
        let (ax, ay) = (self.ax, self.ay);
        let (u, v) = ((dx * ax + dy * ay) / self.sa, (dy * ax - dx * ay) / self.sb);
        let alpha = (self.opacity * super::splat_falloff(u * u + v * v)).min(0.99);
        (alpha >= 1.0 / 255.0).then_some(Shade {
            depth: self.z,
            color: self.color,
            alpha,
            light: [0.0; 3],
        })
    }

    /// [`Self::shade`], eight lanes at once (see [`Shade8`]).
    #[inline(always)]
    pub(super) fn shade8(&self, px: F8, py: f32, _want: u8) -> (u8, Shade8) {
        let dx = px - splat(self.sx);
        let dy = py - self.sy;
        let (ax, ay) = (self.ax, self.ay);
        let u = (dx * splat(ax) + splat(dy * ay)) / splat(self.sa);
        let v = (splat(dy * ax) - dx * splat(ay)) / splat(self.sb);
        let fall = super::lanes8::splat_falloff8(u * u + v * v);
        let alpha = min_sel(splat(self.opacity) * fall, 0.99);
        let keep = alpha.simd_ge(splat(1.0 / 255.0)).to_bitmask() as u8;
        let sh = Shade8 {
            depth: splat(self.z),
            color: self.color.map(splat),
            alpha,
            light: [splat(0.0); 3],
        };
        (keep, sh)
    }
}

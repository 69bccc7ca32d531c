//! The scenes' primitive lists, built from the seed in submission order (the same random
//! draws, in the same order, as when each primitive was scanned as it was made: the streams
//! are unchanged, pinned in `lab/tests/scenes_and_dump.rs`).

use super::prims::{FogSlice, Kind, Leaf, Panel, Primitive, SphereBand, Splat, Sprite, Strand, Trunk};
use super::{Rng, clamp01, lerp3};

/// Collects primitives with their pixel boxes.
pub(super) struct Builder {
    pub(super) w: u32,
    pub(super) h: u32,
    /// Pixels per unit of frame height.
    pub(super) s: f32,
    pub(super) prims: Vec<Primitive>,
}

impl Builder {
    pub(super) fn new(w: u32, h: u32) -> Builder {
        Builder {
            w,
            h,
            s: h as f32,
            prims: Vec::new(),
        }
    }

    /// Add a primitive covering the box `[x0, x1] x [y0, y1]` (in pixels): the pixels whose
    /// centres a scan of that box visits, clamped to the frame. Its id is its number in the
    /// list: every scene builds the same list of primitives whatever the frame size (the
    /// boxes are clamped, never dropped), so an id names the same primitive at every size.
    fn push(&mut self, (x0, y0, x1, y1): (f32, f32, f32, f32), kind: Kind) {
        let xa = (x0.floor().max(0.0)) as u32;
        let ya = (y0.floor().max(0.0)) as u32;
        let xb = (x1.ceil().min(self.w as f32).max(0.0)) as u32;
        let yb = (y1.ceil().min(self.h as f32).max(0.0)) as u32;
        let id = u32::try_from(self.prims.len()).unwrap_or(u32::MAX);
        self.prims.push(Primitive {
            id,
            x0: xa,
            y0: ya,
            x1: xb,
            y1: yb,
            kind,
        });
    }
}

/// Number of HAIR strands.
const HAIR_STRANDS: usize = 3000;

/// HAIR: a ponytail seen from behind. Strands start on a scalp arc, are combed over the
/// head to a tie at its back, where they all pass within a small box (hundreds of strands
/// over the densest pixels, as the Adaptive Transparency slides count on hair, seed 002: "Max
/// fragment per pixel: 663"), then hang and fan out as the tail. Each strand is a polyline
/// of segments drawn root to tip; a pixel belongs to the nearest segment of its strand (one
/// fragment per strand per pixel, as a triangle strip gives). Strands at the sides of the
/// head lie deeper; the tail swings in depth. Color goes from blond (near) to dark brown
/// (far) for contrast.
pub(super) fn hair(r: &mut Builder, rng: &mut Rng) -> [f32; 3] {
    let (w, s) = (r.w as f32, r.s);
    // Segments from the root to the tie, and of the tail.
    let (head_segs, tail_segs) = (6, 11);
    let segs = head_segs + tail_segs;
    let tie = (w * 0.5, s * 0.42, 9.5f32);
    let hw = 0.45 * s / 360.0;
    // The head, seen from behind: a disc of radius `rh` around `head`.
    let (head, rh) = ((w * 0.5, s * 0.24), s * 0.2);
    for _ in 0..HAIR_STRANDS {
        // The root on the hairline, at angle 2 atan(p) from the crown (rational parametrization
        // of the circle: no trigonometry), from the crown down to a little below the ears.
        let p = rng.range(-1.3, 1.3);
        let (sx, cy) = (2.0 * p / (1.0 + p * p), (1.0 - p * p) / (1.0 + p * p));
        let rr = rh * rng.range(0.97, 1.03);
        let (rx, ry) = (head.0 + rr * sx, head.1 - rr * cy);
        // Strands at the sides of the head lie deeper.
        let z0 = rng.range(8.0, 12.0) - 0.5 * cy;
        // Where the strand passes the tie.
        let (tx, ty) = (
            tie.0 + rng.range(-0.012, 0.012) * s,
            tie.1 + rng.range(-0.008, 0.008) * s,
        );
        let tz = tie.2 + rng.range(-0.4, 0.4);
        let len = s * rng.range(0.4, 0.62);
        let drift = rng.range(-0.3, 0.3);
        let curl = rng.range(-0.5, 0.5);
        let dz = rng.range(-1.5, 2.5);
        let alpha = rng.range(0.3, 0.6);
        let tint = rng.range(-0.08, 0.08);
        let mut pts = Vec::with_capacity(segs + 1);
        for k in 0..=head_segs {
            let t = k as f32 / head_segs as f32;
            // Around the skull: a quarter ellipse from a root at the side, a straight line
            // from the crown.
            let x = tx + (rx - tx) * (1.0 - t * t).sqrt();
            let y = ry + (ty - ry) * t;
            pts.push((x, y, z0 + (tz - z0) * t));
        }
        for k in 1..=tail_segs {
            let t = k as f32 / tail_segs as f32;
            let x = tx + len * (drift * t + curl * t * t * (1.0 - t) + 0.08 * t * t);
            let y = ty + len * t;
            pts.push((x, y, tz + dz * t * t));
        }
        for i in 0..segs {
            let (a, b) = ((pts[i].0, pts[i].1), (pts[i + 1].0, pts[i + 1].1));
            let pad = hw + 1.0;
            let (x0, x1) = (a.0.min(b.0) - pad, a.0.max(b.0) + pad);
            let (y0, y1) = (a.1.min(b.1) - pad, a.1.max(b.1) + pad);
            let (za, zb) = (pts[i].2, pts[i + 1].2);
            let prev = (i > 0).then(|| (pts[i - 1].0, pts[i - 1].1));
            let next = (i + 1 < segs).then(|| (pts[i + 2].0, pts[i + 2].1));
            r.push(
                (x0, y0, x1, y1),
                Kind::Strand(Strand {
                    a,
                    b,
                    prev,
                    next,
                    hw,
                    za,
                    zb,
                    tint,
                    alpha,
                }),
            );
        }
    }
    [0.8, 0.82, 0.88]
}

/// Number of PARTICLES sprites.
const PARTICLE_COUNT: usize = 2600;

/// PARTICLES: soft round sprites of smoke (grey, faint) rising from a fire (orange, partly or
/// fully additive), in random order, lit by a light above, to the right and in front of the
/// column. Like the paper's scenes, which are lit through adaptive volumetric shadow maps "to
/// increase color variability and contrast across transparent fragments" (seed 000, lines
/// 514-516), each smoke sprite is shaded by the light left after the sprites between it and
/// the light ([`smoke_light`]): smoke at the back and at the bottom of the column is darker
/// than smoke in front, so that the fragments of one pixel differ in color with depth. The
/// fire is dim enough that no covered pixel of the exact image exceeds 1 (`oit-lab scenes`
/// counts them): a display clamp would hide errors there.
pub(super) fn particles(r: &mut Builder, rng: &mut Rng) -> [f32; 3] {
    let (w, s) = (r.w as f32, r.s);
    let mut sprites = Vec::with_capacity(PARTICLE_COUNT);
    for _ in 0..PARTICLE_COUNT {
        let fire = rng.f() < 0.3;
        let h = if fire {
            rng.range(0.0, 0.35)
        } else {
            rng.range(0.1, 1.0)
        };
        let spread = if fire { 0.12 } else { 0.1 + 0.35 * h };
        let cx = w * 0.5 + rng.range(-1.0, 1.0) * spread * s + h * h * 0.4 * s;
        let cy = s * (0.95 - 0.9 * h);
        let rad = s * if fire {
            rng.range(0.015, 0.045)
        } else {
            rng.range(0.02, 0.06) + 0.03 * h
        };
        let z = rng.range(20.0, 40.0);
        let grey = rng.range(0.3, 0.7);
        let a0 = if fire { 0.0 } else { rng.range(0.03, 0.15) };
        let additive_only = fire && rng.f() < 0.3;
        let fa = if additive_only { 0.0 } else { 0.02 };
        let heat = rng.range(0.01, 0.04);
        sprites.push(Sprite {
            cx,
            cy,
            rad,
            z,
            fire,
            fa,
            heat,
            grey,
            a0,
        });
    }
    let lit = smoke_light(&sprites, w, s);
    for (mut sp, l) in sprites.into_iter().zip(lit) {
        if !sp.fire {
            // Ambient light plus the direct light that reaches the sprite.
            sp.grey *= 0.15 + 0.85 * l;
        }
        r.push(
            (sp.cx - sp.rad, sp.cy - sp.rad, sp.cx + sp.rad, sp.cy + sp.rad),
            Kind::Sprite(sp),
        );
    }
    [0.05, 0.05, 0.08]
}

/// The light reaching each sprite's centre: the product of `1 - alpha` of every sprite the
/// ray from that centre towards the light crosses, `alpha` the crossed sprite's opacity at the
/// ray's closest approach to its centre (its screen falloff `(1 - q)^2`, as if the sprite
/// were a disc facing the light). Sprites live in frame-height units: `x` and `y` from the
/// screen, depth 20..40 mapped to 0..0.6 frame heights; the light direction is up, right and
/// towards the viewer, so the sprites in front shadow those behind them. Quadratic in the
/// number of sprites (a few million products at build time).
fn smoke_light(sprites: &[Sprite], w: f32, s: f32) -> Vec<f32> {
    let pos = |p: &Sprite| [(p.cx - 0.5 * w) / s, p.cy / s, (p.z - 20.0) * 0.03];
    // Towards the light: right, up (screen y points down) and towards the viewer.
    let l = {
        let v = [0.35f32, -0.75, -0.55];
        let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        v.map(|c| c / n)
    };
    let centres: Vec<[f32; 3]> = sprites.iter().map(pos).collect();
    centres
        .iter()
        .map(|pi| {
            let mut t = 1.0f32;
            for (pj, sj) in centres.iter().zip(sprites) {
                let a = if sj.fire { sj.fa } else { sj.a0 };
                if a <= 0.0 {
                    continue;
                }
                let v = [pj[0] - pi[0], pj[1] - pi[1], pj[2] - pi[2]];
                let along = v[0] * l[0] + v[1] * l[1] + v[2] * l[2];
                if along <= 0.0 {
                    continue;
                }
                let r = sj.rad / s;
                let d2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2] - along * along;
                let q = d2 / (r * r);
                if q < 1.0 {
                    t *= 1.0 - a * (1.0 - q) * (1.0 - q);
                }
            }
            t
        })
        .collect()
}

/// Leaves per FOREST tree.
const LEAVES_PER_TREE: usize = 800;

/// FOREST: trees in random order, each a trunk then its leaves; leaves are ellipses with an
/// alpha edge (opaque-ish core, soft border), slightly tilted in depth.
pub(super) fn forest(r: &mut Builder, rng: &mut Rng) -> [f32; 3] {
    let (w, s) = (r.w as f32, r.s);
    let trees = 36;
    for _ in 0..trees {
        let z = rng.range(10.0, 80.0);
        let scale = 10.0 / z;
        let bx = rng.range(-0.1, 1.1) * w;
        let by = s * (0.75 + 0.25 * scale);
        let height = s * 0.9 * scale;
        let top = (bx, by - height);
        let trunk_hw = s * 0.02 * scale;
        r.push(
            (bx - trunk_hw - 1.0, top.1 - 1.0, bx + trunk_hw + 1.0, by + 1.0),
            Kind::Trunk(Trunk {
                bx,
                by,
                top,
                hw: trunk_hw,
                z,
            }),
        );
        let crown = height * 0.45;
        for _ in 0..LEAVES_PER_TREE {
            let (ux, uy) = rng.unit2();
            let rr = rng.f().sqrt() * crown;
            let cx = top.0 + ux * rr;
            let cy = top.1 + crown * 0.4 + uy * rr * 0.8;
            let (ax, ay) = rng.unit2();
            let (la, lb) = (s * 0.042 * scale, s * 0.022 * scale);
            let lz = z + rng.range(-2.0, 2.0);
            let (tx, ty) = (rng.range(-0.1, 0.1), rng.range(-0.1, 0.1));
            let col = [rng.range(0.08, 0.3), rng.range(0.35, 0.65), rng.range(0.05, 0.15)];
            let edge = 1.0 + s * scale * 0.02;
            r.push(
                (cx - la, cy - la, cx + la, cy + la),
                Kind::Leaf(Leaf {
                    cx,
                    cy,
                    ax,
                    ay,
                    la,
                    lb,
                    lz,
                    tx,
                    ty,
                    s,
                    col,
                    edge,
                }),
            );
        }
    }
    [0.55, 0.7, 0.9]
}

const PALETTE: [[f32; 3]; 8] = [
    [0.9, 0.15, 0.1],
    [0.1, 0.7, 0.2],
    [0.15, 0.3, 0.95],
    [0.95, 0.8, 0.1],
    [0.8, 0.2, 0.8],
    [0.1, 0.8, 0.85],
    [0.95, 0.5, 0.1],
    [0.5, 0.9, 0.3],
];

/// The frame height TEAPOTS' bands are laid out for, in lines ...
const TEAPOTS_LAYOUT_LINES: f32 = 360.0;
/// ... and a band's height there, in lines.
const TEAPOTS_BAND_LINES: f32 = 7.0;

/// TEAPOTS (a PWRPLANT stand-in): intersecting spheres, each rasterized as horizontal bands
/// of front and back faces submitted in a shuffled order (like an unsorted mesh); alpha
/// rises towards the silhouette (Fresnel-like).
///
/// The bands are laid out once, in units of the frame height like the rest of the scene, as
/// for a frame of 360 lines: bands of 7 lines from the line above the sphere's box there, as
/// many as cover it. So the list of bands, their shuffle, every later random draw and every
/// primitive id depend on neither the frame size nor the camera, and at 360 lines the bands
/// are exactly the whole-line bands the scene always had. At another size a band is
/// rasterized to the lines whose centres fall between its bounds scaled to that size (none
/// where it is thinner than a line); the first band starts, and the last one ends, at the
/// sphere's pixel box at least, so a sphere's bands cover each of its lines exactly once.
pub(super) fn teapots(r: &mut Builder, rng: &mut Rng) -> [f32; 3] {
    let (w, s) = (r.w as f32, r.s);
    let focal = s * 1.1;
    for _ in 0..22 {
        let cx = rng.range(0.05, 0.95) * w;
        let cyn = rng.range(0.1, 0.9);
        let rn = rng.range(0.1, 0.28);
        let (cy, rad) = (cyn * s, s * rn);
        let zc = rng.range(20.0, 40.0);
        let rw = rad * zc / focal;
        let col = PALETTE[rng.below(PALETTE.len())];
        let a0 = rng.range(0.2, 0.45);
        // The layout frame's sphere box and bands (whole lines there).
        let (cy_l, rad_l) = (cyn * TEAPOTS_LAYOUT_LINES, TEAPOTS_LAYOUT_LINES * rn);
        let top_l = (cy_l - rad_l - 1.0).floor();
        let bands = ((2.0 * rad_l + 2.0) / TEAPOTS_BAND_LINES).ceil() as usize + 1;
        // Bound `b` of the bands at this size, as the first line whose centre is below it;
        // the outer bounds reach the sphere's box at this size.
        let scale = s / TEAPOTS_LAYOUT_LINES;
        let bound = |b: usize| ((top_l + b as f32 * TEAPOTS_BAND_LINES) * scale - 0.5).ceil();
        let top = (cy - rad - 1.0).floor();
        let bottom = bound(bands).max((cy + rad + 1.0).ceil());
        let line = |b: usize| match b {
            0 => top,
            b if b >= bands => bottom,
            b => bound(b).clamp(top, bottom),
        };
        let mut order: Vec<(usize, bool)> = (0..bands).flat_map(|b| [(b, true), (b, false)]).collect();
        rng.shuffle(&mut order);
        for (b, front) in order {
            r.push(
                (cx - rad - 1.0, line(b), cx + rad + 1.0, line(b + 1)),
                Kind::SphereBand(SphereBand {
                    cx,
                    cy,
                    rad,
                    zc,
                    rw,
                    col,
                    a0,
                    front,
                }),
            );
        }
    }
    [0.45, 0.45, 0.48]
}

/// GLASS: tinted panels of high alpha, each with a front and a back face, slanted in depth
/// so that some intersect.
pub(super) fn glass(r: &mut Builder, rng: &mut Rng) -> [f32; 3] {
    let (w, s) = (r.w as f32, r.s);
    let tints = [
        [0.7, 0.85, 1.0],
        [0.75, 1.0, 0.8],
        [1.0, 0.85, 0.55],
        [0.9, 0.9, 0.95],
        [1.0, 0.7, 0.7],
    ];
    for _ in 0..9 {
        let (cx, cy) = (rng.range(0.15, 0.85) * w, rng.range(0.2, 0.8) * s);
        let (hx, hy) = (s * rng.range(0.12, 0.35), s * rng.range(0.1, 0.3));
        let z = rng.range(5.0, 15.0);
        let thick = rng.range(0.3, 1.5);
        let (sx, sy) = (rng.range(-6.0, 6.0) / s, rng.range(-3.0, 3.0) / s);
        let tint = tints[rng.below(tints.len())];
        let alpha = rng.range(0.55, 0.85);
        let back_first = rng.f() < 0.5;
        for face in 0..2 {
            let front = (face == 0) != back_first;
            r.push(
                (cx - hx - 1.0, cy - hy - 1.0, cx + hx + 1.0, cy + hy + 1.0),
                Kind::Panel(Panel {
                    cx,
                    cy,
                    hx,
                    hy,
                    z,
                    sx,
                    sy,
                    thick,
                    tint,
                    alpha,
                    front,
                }),
            );
        }
    }
    [0.75, 0.72, 0.65]
}

/// FOG: a volume of faint slices over a bright sky (issue 9). Each slice is a soft
/// superellipse `q = (dx/hx)^4 + (dy/hy)^4 < 1` with density `(1 - q)^2`, modulated by three
/// soft puffs; its alpha runs from `1/255` at the rim to the slice's peak (0.006 to 0.05, skewed
/// low: `0.006 + 0.044 u^2`), so
/// every fragment's alpha is in `[1/255, 0.05]`. Color depends on depth (warm and bright near,
/// cool and darker far) and a little on height, so compositing out of order shows. Slices are
/// made front to back at stratified depths, then submitted in shuffled order.
pub(super) fn fog(r: &mut Builder, rng: &mut Rng) -> [f32; 3] {
    let (w, s) = (r.w as f32, r.s);
    let slices = FOG_SLICES;
    let (z_near, z_far) = (4.0f32, 60.0f32);
    struct Slice {
        z: f32,
        c: (f32, f32),
        h: (f32, f32),
        peak: f32,
        puffs: [(f32, f32, f32); 3],
        tint: f32,
    }
    let mut list: Vec<Slice> = (0..slices)
        .map(|i| {
            let z = z_near + (z_far - z_near) * (i as f32 + rng.f()) / slices as f32;
            let c = (w * 0.5 + rng.range(-0.35, 0.35) * s, s * rng.range(0.35, 0.65));
            let h = (s * rng.range(0.55, 1.15), s * rng.range(0.3, 0.55));
            let u = rng.f();
            let peak = 0.006 + 0.044 * u * u;
            let puffs = [0; 3].map(|_| {
                (
                    c.0 + rng.range(-1.0, 1.0) * h.0,
                    c.1 + rng.range(-1.0, 1.0) * h.1,
                    s * rng.range(0.15, 0.4),
                )
            });
            let tint = rng.range(-0.05, 0.05);
            Slice {
                z,
                c,
                h,
                peak,
                puffs,
                tint,
            }
        })
        .collect();
    rng.shuffle(&mut list);
    let amin = 1.0 / 255.0;
    for sl in &list {
        let k = (sl.z - z_near) / (z_far - z_near);
        let near = [1.0, 0.9, 0.75];
        let far = [0.55, 0.62, 0.75];
        let base = lerp3(near, far, clamp01(k + sl.tint));
        r.push(
            (sl.c.0 - sl.h.0, sl.c.1 - sl.h.1, sl.c.0 + sl.h.0, sl.c.1 + sl.h.1),
            Kind::FogSlice(FogSlice {
                z: sl.z,
                c: sl.c,
                h: sl.h,
                peak: sl.peak,
                puffs: sl.puffs,
                base,
                s,
                amin,
            }),
        );
    }
    [0.92, 0.95, 1.0]
}

/// Number of FOG slices.
const FOG_SLICES: usize = 320;

/// Number of SPLATS splats.
const SPLAT_COUNT: usize = 12_000;

/// The Gaussian falloff of a splat without transcendental functions:
/// `(1 - q/18)^9` for `q = (x/sigma)^2 + (y/sigma)^2 < 18`, 0 beyond. It is
/// `(1 - q/(2n))^n` with `n = 9`, which tends to `exp(-q/2)` as `n` grows; with `n = 9` it
/// is within 0.032 of `exp(-q/2)` everywhere (largest gap near `q = 3.85`, 0.115 against
/// 0.146), and it reaches 0 exactly at 3 sigma, where 3D Gaussian Splatting cuts its splats.
pub fn splat_falloff(q: f32) -> f32 {
    if !(0.0..18.0).contains(&q) {
        return 0.0;
    }
    let x = 1.0 - q / 18.0;
    let x2 = x * x;
    let x4 = x2 * x2;
    x4 * x4 * x
}

/// SPLATS: a dense cloud of soft anisotropic Gaussian splats, as a 3D Gaussian Splatting
/// renderer emits them: per splat a 2D elliptical footprint, `alpha = min(0.99, opacity *
/// falloff)` ([`splat_falloff`]), fragments below `1/255` dropped, splats in random order.
/// Centres are drawn around six clusters (a sum of three uniforms per axis, bell-shaped)
/// and projected with a pinhole camera (focal length 1.2 frame heights); footprints shrink
/// with depth. Opacities are skewed low (`0.02 + 0.93 u^2`). Color is a depth gradient (warm
/// near, blue far) (three quarters) mixed with a per-cluster hue (a quarter) and a per-splat jitter of
/// +-0.05.
pub(super) fn splats(r: &mut Builder, rng: &mut Rng) -> [f32; 3] {
    let (w, s) = (r.w as f32, r.s);
    let focal = 1.2 * s;
    let (z_near, z_far) = (3.0f32, 7.0f32);
    let clusters: Vec<([f32; 3], [f32; 3], [f32; 3])> = (0..6)
        .map(|_| {
            let c = [rng.range(-1.5, 1.5), rng.range(-0.8, 0.8), rng.range(3.6, 6.4)];
            let rad = [rng.range(0.5, 1.1), rng.range(0.4, 0.8), rng.range(0.6, 1.2)];
            let hue = PALETTE[rng.below(PALETTE.len())];
            (c, rad, hue)
        })
        .collect();
    let bell = |rng: &mut Rng| (rng.f() + rng.f() + rng.f() - 1.5) / 1.5;
    for _ in 0..SPLAT_COUNT {
        let (c, rad, hue) = clusters[rng.below(clusters.len())];
        let p = [0, 1, 2].map(|i| c[i] + rad[i] * bell(rng));
        let z = p[2].clamp(z_near, z_far);
        let (sx, sy) = (w * 0.5 + focal * p[0] / z, s * 0.5 + focal * p[1] / z);
        let major = rng.range(0.015, 0.06);
        let minor = major * rng.range(0.25, 1.0);
        // Screen sigmas, at least 0.3 px (a splat smaller than a pixel still covers its centre
        // pixel, as the screen-space dilation of 3D Gaussian Splatting ensures).
        let (sa, sb) = ((focal * major / z).max(0.3), (focal * minor / z).max(0.3));
        let (ax, ay) = rng.unit2();
        let opacity = {
            let u = rng.f();
            0.02 + 0.93 * u * u
        };
        // Warm at z = 3.5, blue at z = 6 (most of the cloud lies in between).
        let k = clamp01((z - 3.5) / 2.5);
        let depth_color = lerp3([0.98, 0.62, 0.3], [0.2, 0.4, 0.95], k);
        let jitter = [0; 3].map(|_| rng.range(-0.05, 0.05));
        let color = [0, 1, 2].map(|i| clamp01(0.75 * depth_color[i] + 0.25 * hue[i] + jitter[i]));
        let ext = 3.0 * sa.max(sb) + 1.0;
        r.push(
            (sx - ext, sy - ext, sx + ext, sy + ext),
            Kind::Splat(Splat {
                sx,
                sy,
                ax,
                ay,
                sa,
                sb,
                opacity,
                z,
                color,
            }),
        );
    }
    [0.9, 0.9, 0.92]
}

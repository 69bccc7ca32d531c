//! Seven deterministic procedural scenes: five after the paper's (section 5, Figure 3) and
//! two of many faint or dense layers for issue 9 (FOG, SPLATS).
//!
//! Each scene is a list of primitives submitted in a fixed order; each primitive is
//! "rasterized" by scanning its screen box and evaluating its coverage analytically at the
//! pixel centre, as a rasterizer with one sample per pixel would. Everything is derived from
//! a seed with a small integer generator and only `+ - * / sqrt` in f32, so a stream is the
//! same bytes on every machine (the tests pin each stream's hash).
//!
//! Geometry is laid out in units of the frame height, so a larger frame gives the same
//! picture with more fragments (about 4x from 640x360 to 1280x720).

use crate::stream::{Frag, Stream};

/// The scenes. The discriminants seed each scene's generator: new scenes go at the end.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scene {
    /// Thousands of thin strands, drawn strand by strand, root to tip.
    Hair,
    /// Soft smoke and fire sprites, low alpha, some additive, unsorted.
    Particles,
    /// Trees of alpha-edged leaves, tree by tree.
    Forest,
    /// Large colorful intersecting transparent spheres, front and back faces in bands
    /// submitted in no particular order.
    Teapots,
    /// A few layers of high-alpha tinted panels with front and back faces.
    Glass,
    /// A volume of hundreds of faint slices (alpha 1/255 to 0.05) over a bright sky, warm
    /// near and cool far, submitted in shuffled order.
    Fog,
    /// A dense cloud of soft anisotropic Gaussian splats (up to about 300 per pixel), colors
    /// varying with depth, in random order.
    Splats,
}

impl Scene {
    /// Every scene, in table order.
    pub const ALL: [Scene; 7] = [
        Scene::Hair,
        Scene::Particles,
        Scene::Forest,
        Scene::Teapots,
        Scene::Glass,
        Scene::Fog,
        Scene::Splats,
    ];

    /// The scenes of the main job (`oit-lab run`): the paper's five. FOG and SPLATS have
    /// tens of millions of fragments at 640x360 and are in `oit-lab faint`.
    pub const MAIN: [Scene; 5] = [
        Scene::Hair,
        Scene::Particles,
        Scene::Forest,
        Scene::Teapots,
        Scene::Glass,
    ];

    /// Upper-case name, as in the paper.
    pub fn name(self) -> &'static str {
        match self {
            Scene::Hair => "HAIR",
            Scene::Particles => "PARTICLES",
            Scene::Forest => "FOREST",
            Scene::Teapots => "TEAPOTS",
            Scene::Glass => "GLASS",
            Scene::Fog => "FOG",
            Scene::Splats => "SPLATS",
        }
    }

    /// The scene with this name (case-insensitive; `pwrplant` is an alias of TEAPOTS).
    pub fn from_name(s: &str) -> Option<Scene> {
        let s = s.to_ascii_uppercase();
        if s == "PWRPLANT" {
            return Some(Scene::Teapots);
        }
        Scene::ALL.into_iter().find(|sc| sc.name() == s)
    }

    /// The fragment stream at `width x height` from `seed`.
    pub fn generate(self, width: u32, height: u32, seed: u64) -> Stream {
        let mut r = Raster::new(width, height);
        let mut rng = Rng::new(seed ^ (self as u64 + 1).wrapping_mul(0x9e37_79b9_7f4a_7c15));
        let background = match self {
            Scene::Hair => hair(&mut r, &mut rng),
            Scene::Particles => particles(&mut r, &mut rng),
            Scene::Forest => forest(&mut r, &mut rng),
            Scene::Teapots => teapots(&mut r, &mut rng),
            Scene::Glass => glass(&mut r, &mut rng),
            Scene::Fog => fog(&mut r, &mut rng),
            Scene::Splats => splats(&mut r, &mut rng),
        };
        Stream {
            width,
            height,
            background,
            frags: r.frags,
        }
    }
}

/// SplitMix64: small, fast, and the same on every machine.
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    /// A generator from a seed.
    pub fn new(seed: u64) -> Rng {
        Rng(seed)
    }
    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    /// Uniform in `[0, 1)` with 24 bits.
    pub fn f(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 * (1.0 / 16_777_216.0)
    }
    /// Uniform in `[a, b)`.
    pub fn range(&mut self, a: f32, b: f32) -> f32 {
        a + (b - a) * self.f()
    }
    /// Uniform integer in `0..n` (`n > 0`).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
    /// A random unit vector in 2D (rejection sampling, no trigonometry).
    pub fn unit2(&mut self) -> (f32, f32) {
        loop {
            let (x, y) = (self.range(-1.0, 1.0), self.range(-1.0, 1.0));
            let l2 = x * x + y * y;
            if l2 > 0.01 && l2 <= 1.0 {
                let l = l2.sqrt();
                return (x / l, y / l);
            }
        }
    }
    /// Fisher-Yates shuffle.
    pub fn shuffle<T>(&mut self, v: &mut [T]) {
        for i in (1..v.len()).rev() {
            let j = self.below(i + 1);
            v.swap(i, j);
        }
    }
}

fn clamp01(x: f32) -> f32 {
    x.clamp(0.0, 1.0)
}

fn lerp3(a: [f32; 3], b: [f32; 3], t: f32) -> [f32; 3] {
    [
        a[0] + (b[0] - a[0]) * t,
        a[1] + (b[1] - a[1]) * t,
        a[2] + (b[2] - a[2]) * t,
    ]
}

/// Emits fragments for primitives by scanning their screen boxes.
struct Raster {
    w: u32,
    h: u32,
    /// Pixels per unit of frame height.
    s: f32,
    frags: Vec<Frag>,
}

/// What a primitive gives at one pixel centre: depth, straight color, alpha (coverage
/// included), and additive light (premultiplied, added on top of `color * alpha`).
struct Shade {
    depth: f32,
    color: [f32; 3],
    alpha: f32,
    light: [f32; 3],
}

impl Raster {
    fn new(w: u32, h: u32) -> Raster {
        Raster {
            w,
            h,
            s: h as f32,
            frags: Vec::new(),
        }
    }

    /// Scan the box `[x0, x1] x [y0, y1]` (in pixels) and emit what `f` returns at each
    /// pixel centre. Fragments that carry neither opacity nor light are not emitted.
    fn scan(&mut self, x0: f32, y0: f32, x1: f32, y1: f32, mut f: impl FnMut(f32, f32) -> Option<Shade>) {
        let xa = (x0.floor().max(0.0)) as u32;
        let ya = (y0.floor().max(0.0)) as u32;
        let xb = (x1.ceil().min(self.w as f32).max(0.0)) as u32;
        let yb = (y1.ceil().min(self.h as f32).max(0.0)) as u32;
        for y in ya..yb {
            for x in xa..xb {
                if let Some(sh) = f(x as f32 + 0.5, y as f32 + 0.5) {
                    let a = clamp01(sh.alpha);
                    let c = [0, 1, 2].map(|i| (clamp01(sh.color[i]) * a + sh.light[i].max(0.0)).min(1.0));
                    if a < 1.0 / 1024.0 && c.iter().all(|&v| v < 1.0 / 1024.0) {
                        continue;
                    }
                    self.frags.push(Frag {
                        pixel: y * self.w + x,
                        depth: sh.depth,
                        color: c,
                        alpha: a,
                    });
                }
            }
        }
    }
}

/// Distance from `p` to segment `a-b` and the parameter of the closest point.
fn seg_dist(px: f32, py: f32, a: (f32, f32), b: (f32, f32)) -> (f32, f32) {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let l2 = dx * dx + dy * dy;
    let t = if l2 > 0.0 {
        clamp01(((px - a.0) * dx + (py - a.1) * dy) / l2)
    } else {
        0.0
    };
    let (ex, ey) = (px - a.0 - t * dx, py - a.1 - t * dy);
    ((ex * ex + ey * ey).sqrt(), t)
}

/// HAIR: strands hang from a scalp, each a polyline of segments drawn root to tip; a pixel
/// belongs to the nearest segment of its strand (one fragment per strand per pixel, as a
/// triangle strip gives). Color goes from blond (near) to dark brown (far) for contrast.
fn hair(r: &mut Raster, rng: &mut Rng) -> [f32; 3] {
    let (w, s) = (r.w as f32, r.s);
    let strands = 2600;
    let segs = 12;
    for _ in 0..strands {
        let u = rng.f();
        let rx = w * 0.5 + (u - 0.5) * s * 0.9;
        let ry = s * (0.12 + 0.35 * (u - 0.5) * (u - 0.5)) + rng.range(0.0, 0.03) * s;
        let len = s * rng.range(0.55, 0.85);
        let drift = (u - 0.5) * 0.9 + rng.range(-0.15, 0.15);
        let curl = rng.range(-0.6, 0.6);
        let z0 = rng.range(8.0, 12.0) - 2.0 * (0.25 - (u - 0.5) * (u - 0.5));
        let dz = rng.range(-0.5, 0.5);
        let hw = 0.45 * s / 360.0;
        let alpha = rng.range(0.3, 0.6);
        let tint = rng.range(-0.08, 0.08);
        let mut pts = Vec::with_capacity(segs + 1);
        for k in 0..=segs {
            let t = k as f32 / segs as f32;
            let x = rx + len * (drift * t + curl * t * t * (1.0 - t));
            let y = ry + len * t;
            pts.push((x, y, z0 + dz * segs as f32 * t * t));
        }
        for i in 0..segs {
            let (a, b) = ((pts[i].0, pts[i].1), (pts[i + 1].0, pts[i + 1].1));
            let pad = hw + 1.0;
            let (x0, x1) = (a.0.min(b.0) - pad, a.0.max(b.0) + pad);
            let (y0, y1) = (a.1.min(b.1) - pad, a.1.max(b.1) + pad);
            let (za, zb) = (pts[i].2, pts[i + 1].2);
            r.scan(x0, y0, x1, y1, |px, py| {
                let (d, t) = seg_dist(px, py, a, b);
                // Owned by the nearest segment (ties to the earlier one).
                if i > 0 && seg_dist(px, py, (pts[i - 1].0, pts[i - 1].1), a).0 <= d {
                    return None;
                }
                if i + 1 < segs && seg_dist(px, py, b, (pts[i + 2].0, pts[i + 2].1)).0 < d {
                    return None;
                }
                let cov = clamp01(hw + 0.5 - d);
                if cov <= 0.0 {
                    return None;
                }
                let z = za + (zb - za) * t;
                let k = clamp01((z - 6.0) / 8.0 + tint);
                Some(Shade {
                    depth: z,
                    color: lerp3([0.95, 0.78, 0.45], [0.22, 0.1, 0.04], k),
                    alpha: alpha * cov,
                    light: [0.0; 3],
                })
            });
        }
    }
    [0.8, 0.82, 0.88]
}

/// PARTICLES: soft round sprites of smoke (grey, faint) and fire (orange, partly or fully
/// additive), in random order.
fn particles(r: &mut Raster, rng: &mut Rng) -> [f32; 3] {
    let (w, s) = (r.w as f32, r.s);
    for _ in 0..2600 {
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
        let grey = rng.range(0.25, 0.6);
        let a0 = if fire { 0.0 } else { rng.range(0.03, 0.15) };
        let additive_only = fire && rng.f() < 0.3;
        let fa = if additive_only { 0.0 } else { 0.02 };
        let heat = rng.range(0.15, 0.45);
        r.scan(cx - rad, cy - rad, cx + rad, cy + rad, |px, py| {
            let (dx, dy) = ((px - cx) / rad, (py - cy) / rad);
            let q = dx * dx + dy * dy;
            if q >= 1.0 {
                return None;
            }
            let fall = (1.0 - q) * (1.0 - q);
            if fire {
                Some(Shade {
                    depth: z,
                    color: [1.0, 0.5, 0.2],
                    alpha: fa * fall,
                    light: [heat * fall, heat * 0.45 * fall, heat * 0.1 * fall],
                })
            } else {
                Some(Shade {
                    depth: z,
                    color: [grey, grey, grey * 1.05],
                    alpha: a0 * fall,
                    light: [0.0; 3],
                })
            }
        });
    }
    [0.05, 0.05, 0.08]
}

/// FOREST: trees in random order, each a trunk then its leaves; leaves are ellipses with an
/// alpha edge (opaque-ish core, soft border), slightly tilted in depth.
fn forest(r: &mut Raster, rng: &mut Rng) -> [f32; 3] {
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
        r.scan(
            bx - trunk_hw - 1.0,
            top.1 - 1.0,
            bx + trunk_hw + 1.0,
            by + 1.0,
            |px, py| {
                let (d, _) = seg_dist(px, py, (bx, by), top);
                let cov = clamp01(trunk_hw + 0.5 - d);
                (cov > 0.0).then_some(Shade {
                    depth: z + 0.5,
                    color: [0.3, 0.2, 0.12],
                    alpha: 0.9 * cov,
                    light: [0.0; 3],
                })
            },
        );
        let crown = height * 0.45;
        for _ in 0..260 {
            let (ux, uy) = rng.unit2();
            let rr = rng.f().sqrt() * crown;
            let cx = top.0 + ux * rr;
            let cy = top.1 + crown * 0.4 + uy * rr * 0.8;
            let (ax, ay) = rng.unit2();
            let (la, lb) = (s * 0.035 * scale, s * 0.018 * scale);
            let lz = z + rng.range(-2.0, 2.0);
            let (tx, ty) = (rng.range(-0.1, 0.1), rng.range(-0.1, 0.1));
            let col = [rng.range(0.08, 0.3), rng.range(0.35, 0.65), rng.range(0.05, 0.15)];
            let edge = 1.0 + s * scale * 0.02;
            r.scan(cx - la, cy - la, cx + la, cy + la, |px, py| {
                let (dx, dy) = (px - cx, py - cy);
                let (u, v) = ((dx * ax + dy * ay) / la, (dy * ax - dx * ay) / lb);
                let q = (u * u + v * v).sqrt();
                let alpha = 0.85 * clamp01((1.0 - q) * edge);
                (alpha > 0.0).then_some(Shade {
                    depth: lz + tx * dx / s * 30.0 + ty * dy / s * 30.0,
                    color: col,
                    alpha,
                    light: [0.0; 3],
                })
            });
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

/// TEAPOTS (a PWRPLANT stand-in): intersecting spheres, each rasterized as horizontal bands
/// of front and back faces submitted in a shuffled order (like an unsorted mesh); alpha
/// rises towards the silhouette (Fresnel-like).
fn teapots(r: &mut Raster, rng: &mut Rng) -> [f32; 3] {
    let (w, s) = (r.w as f32, r.s);
    let focal = s * 1.1;
    for _ in 0..22 {
        let cx = rng.range(0.05, 0.95) * w;
        let cy = rng.range(0.1, 0.9) * s;
        let rad = s * rng.range(0.1, 0.28);
        let zc = rng.range(20.0, 40.0);
        let rw = rad * zc / focal;
        let col = PALETTE[rng.below(PALETTE.len())];
        let a0 = rng.range(0.2, 0.45);
        // Bands of whole pixel rows, so that no pixel is scanned twice.
        let band = (s * 0.02).max(2.0).floor();
        let top = (cy - rad - 1.0).floor();
        let bands = ((2.0 * rad + 2.0) / band).ceil() as usize + 1;
        let mut order: Vec<(usize, bool)> = (0..bands).flat_map(|b| [(b, true), (b, false)]).collect();
        rng.shuffle(&mut order);
        for (b, front) in order {
            let y0 = top + b as f32 * band;
            r.scan(cx - rad - 1.0, y0, cx + rad + 1.0, y0 + band, |px, py| {
                let (dx, dy) = ((px - cx) / rad, (py - cy) / rad);
                let q = dx * dx + dy * dy;
                let dist = q.sqrt();
                let cov = clamp01((1.0 - dist) * rad + 0.5);
                if cov <= 0.0 {
                    return None;
                }
                // At the anti-aliased rim the faces would meet: keep them apart.
                let h = (1.0 - q.min(1.0)).sqrt().max(0.05);
                let q2 = q.min(1.0) * q.min(1.0);
                let shade = if front { 1.0 } else { 0.7 };
                Some(Shade {
                    depth: if front { zc - rw * h } else { zc + rw * h },
                    color: col.map(|c| c * shade),
                    alpha: (a0 + (0.9 - a0) * q2) * cov,
                    light: [0.0; 3],
                })
            });
        }
    }
    [0.45, 0.45, 0.48]
}

/// GLASS: tinted panels of high alpha, each with a front and a back face, slanted in depth
/// so that some intersect.
fn glass(r: &mut Raster, rng: &mut Rng) -> [f32; 3] {
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
            r.scan(cx - hx - 1.0, cy - hy - 1.0, cx + hx + 1.0, cy + hy + 1.0, |px, py| {
                let cov = clamp01(hx + 0.5 - (px - cx).abs()) * clamp01(hy + 0.5 - (py - cy).abs());
                if cov <= 0.0 {
                    return None;
                }
                let zf = z + sx * (px - cx) + sy * (py - cy);
                Some(Shade {
                    depth: if front { zf } else { zf + thick },
                    color: if front { tint } else { tint.map(|c| c * 0.6) },
                    alpha: alpha * cov,
                    light: [0.0; 3],
                })
            });
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
fn fog(r: &mut Raster, rng: &mut Rng) -> [f32; 3] {
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
        r.scan(
            sl.c.0 - sl.h.0,
            sl.c.1 - sl.h.1,
            sl.c.0 + sl.h.0,
            sl.c.1 + sl.h.1,
            |px, py| {
                let (u, v) = ((px - sl.c.0) / sl.h.0, (py - sl.c.1) / sl.h.1);
                let (u2, v2) = (u * u, v * v);
                let q = u2 * u2 + v2 * v2;
                if q >= 1.0 {
                    return None;
                }
                let mut puff = 0.0f32;
                for &(x, y, rad) in &sl.puffs {
                    let (dx, dy) = ((px - x) / rad, (py - y) / rad);
                    let d = 1.0 - (dx * dx + dy * dy);
                    if d > 0.0 {
                        puff += d * d;
                    }
                }
                let density = (1.0 - q) * (1.0 - q) * (0.5 + 0.5 * puff.min(1.0));
                // Lower fog is a little darker (ground shadow), higher a little brighter.
                let height = 0.9 + 0.2 * (1.0 - py / s);
                Some(Shade {
                    depth: sl.z,
                    color: base.map(|c| c * height),
                    alpha: amin + (sl.peak - amin) * density,
                    light: [0.0; 3],
                })
            },
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
fn splats(r: &mut Raster, rng: &mut Rng) -> [f32; 3] {
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
        r.scan(sx - ext, sy - ext, sx + ext, sy + ext, |px, py| {
            let (dx, dy) = (px - sx, py - sy);
            let (u, v) = ((dx * ax + dy * ay) / sa, (dy * ax - dx * ay) / sb);
            let alpha = (opacity * splat_falloff(u * u + v * v)).min(0.99);
            (alpha >= 1.0 / 255.0).then_some(Shade {
                depth: z,
                color,
                alpha,
                light: [0.0; 3],
            })
        });
    }
    [0.9, 0.9, 0.92]
}

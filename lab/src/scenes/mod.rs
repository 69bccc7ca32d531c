//! Seven deterministic procedural scenes: five after the paper's (section 5, Figure 3) and
//! two of many faint or dense layers for issue 9 (FOG, SPLATS).
//!
//! Each scene is a list of primitives submitted in a fixed order ([`Primitives`]: strand
//! segments, sprites, trunks, leaves, sphere bands, panels, fog slices, splats); each kind has
//! a rasterizer ([`raster`]) that scans the primitive's screen box clipped to any rectangle
//! in 8-pixel spans and evaluates its coverage analytically at the pixel centres, as a
//! rasterizer with one sample per pixel would. The fragment stream of the quality tables is
//! the same rasterizer over the whole frame ([`Primitives::stream`]); the tiled frame
//! renderer ([`crate::tiled`]) calls it per tile. Everything is derived from
//! a seed with a small integer generator and only `+ - * / sqrt` in f32, so a stream is the
//! same bytes on every machine (the tests pin each stream's hash).
//!
//! Geometry is laid out in units of the frame height, so a larger frame gives the same
//! picture with more fragments (about 4x from 640x360 to 1280x720).

mod build;
mod lanes8;
mod prims;
mod raster;
pub mod stats;

pub use build::splat_falloff;
pub use prims::{Kind, Primitive, Primitives};
pub use raster::{Clip, PushFrags, SpanLanes};

use crate::stream::Stream;
use build::Builder;

/// The scenes. The discriminants seed each scene's generator: new scenes go at the end.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scene {
    /// A ponytail seen from behind: thousands of thin strands combed to a tie (hundreds over
    /// its densest pixels), drawn strand by strand, root to tip.
    Hair,
    /// Soft smoke and fire sprites, low alpha, some additive, unsorted; the smoke is shaded by
    /// the light the sprites between it and a light leave (a volumetric shadow).
    Particles,
    /// Trees of alpha-edged leaves, tree by tree (dense crowns: about 11 leaves over a covered
    /// pixel).
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

    /// The scene's primitives at `width x height` from `seed`, in submission order.
    pub fn primitives(self, width: u32, height: u32, seed: u64) -> Primitives {
        let mut b = Builder::new(width, height);
        let mut rng = Rng::new(seed ^ (self as u64 + 1).wrapping_mul(0x9e37_79b9_7f4a_7c15));
        let background = match self {
            Scene::Hair => build::hair(&mut b, &mut rng),
            Scene::Particles => build::particles(&mut b, &mut rng),
            Scene::Forest => build::forest(&mut b, &mut rng),
            Scene::Teapots => build::teapots(&mut b, &mut rng),
            Scene::Glass => build::glass(&mut b, &mut rng),
            Scene::Fog => build::fog(&mut b, &mut rng),
            Scene::Splats => build::splats(&mut b, &mut rng),
        };
        Primitives {
            width,
            height,
            background,
            prims: b.prims,
        }
    }

    /// The fragment stream at `width x height` from `seed`: the primitives rasterized over
    /// the whole frame, in submission order ([`Primitives::stream`]).
    pub fn generate(self, width: u32, height: u32, seed: u64) -> Stream {
        self.primitives(width, height, seed).stream()
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

#[cfg(test)]
mod tests;

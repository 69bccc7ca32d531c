//! The 8-wide shading against the scalar reference, bit for bit: per kind, lane by lane at
//! many positions of many random primitives (degenerate ones, exact ties between neighbouring
//! segments, signed zeros and NaN parameters included), then whole rasterizations (spans,
//! masks and lanes) under clips that cut boxes anywhere, and every scene's primitives.

use super::lanes8::{F8, centres};
use super::prims::{FogSlice, Kind, Primitive, Shade, Shade8, Splat, Sprite, Strand};
use super::raster::{Clip, SpanLanes};
use super::{Rng, Scene};

/// A value for a test primitive: mostly ordinary, often on the half-pixel grid (so that
/// distances tie exactly at pixel centres), sometimes a signed zero.
fn val(rng: &mut Rng, lo: f32, hi: f32) -> f32 {
    match rng.below(10) {
        0 => 0.0,
        1 => -0.0,
        2..=4 => (rng.range(lo, hi) * 2.0).round() * 0.5,
        _ => rng.range(lo, hi),
    }
}

fn pt(rng: &mut Rng) -> (f32, f32) {
    (val(rng, -4.0, 36.0), val(rng, -4.0, 28.0))
}

/// A strand segment, its neighbours sometimes mirrored about its ends (exact ties), sometimes
/// equal to them (zero-length segments).
fn strand(rng: &mut Rng) -> Strand {
    let (a, b) = (pt(rng), pt(rng));
    let b = if rng.below(12) == 0 { a } else { b };
    let near = |rng: &mut Rng, end: (f32, f32), other: (f32, f32)| match rng.below(5) {
        0 => None,
        1 => Some((2.0 * end.0 - other.0, 2.0 * end.1 - other.1)),
        2 => Some(end),
        _ => Some(pt(rng)),
    };
    let (prev, next) = (near(rng, a, b), near(rng, b, a));
    Strand {
        a,
        b,
        prev,
        next,
        hw: val(rng, 0.0, 3.0),
        za: val(rng, 5.0, 14.0),
        zb: val(rng, 5.0, 14.0),
        tint: val(rng, -0.5, 0.5),
        alpha: val(rng, 0.0, 1.2),
    }
}

fn sprite(rng: &mut Rng) -> Sprite {
    let fire = rng.below(2) == 0;
    Sprite {
        cx: val(rng, -4.0, 36.0),
        cy: val(rng, -4.0, 28.0),
        rad: val(rng, 0.0, 14.0),
        z: val(rng, 20.0, 40.0),
        fire,
        fa: if rng.below(3) == 0 { 0.0 } else { val(rng, 0.0, 1.5) },
        heat: val(rng, -0.5, 2.0),
        grey: val(rng, -0.2, 1.2),
        a0: val(rng, 0.0, 1.5),
    }
}

fn fog(rng: &mut Rng) -> FogSlice {
    let puff = |rng: &mut Rng| (val(rng, -8.0, 40.0), val(rng, -8.0, 32.0), val(rng, 0.0, 20.0));
    FogSlice {
        z: val(rng, 4.0, 60.0),
        c: (val(rng, -4.0, 36.0), val(rng, -4.0, 28.0)),
        h: (val(rng, 0.0, 30.0), val(rng, 0.0, 20.0)),
        peak: val(rng, 0.0, 0.3),
        puffs: [puff(rng), puff(rng), puff(rng)],
        base: [val(rng, 0.0, 1.1), val(rng, 0.0, 1.1), val(rng, 0.0, 1.1)],
        s: val(rng, 1.0, 40.0),
        amin: if rng.below(2) == 0 {
            1.0 / 255.0
        } else {
            val(rng, 0.0, 0.01)
        },
    }
}

fn splat(rng: &mut Rng) -> Splat {
    let (ax, ay) = if rng.below(4) == 0 { (1.0, 0.0) } else { rng.unit2() };
    Splat {
        sx: val(rng, -4.0, 36.0),
        sy: val(rng, -4.0, 28.0),
        ax,
        ay,
        sa: val(rng, 0.0, 6.0),
        sb: val(rng, 0.0, 6.0),
        opacity: val(rng, 0.0, 1.2),
        z: val(rng, 3.0, 7.0),
        color: [val(rng, 0.0, 1.0), val(rng, 0.0, 1.0), val(rng, 0.0, 1.0)],
    }
}

/// The bits of `v`, every NaN as one: Rust leaves the sign and payload of a NaN an operation
/// returns unspecified (RFC 3514; LLVM may swap the operands of `+` and `*`), so only "NaN"
/// is compared (no scene emits a NaN: the quantizer would refuse it).
fn fbits(v: f32) -> u32 {
    if v.is_nan() { f32::NAN.to_bits() } else { v.to_bits() }
}

/// Every field's bits.
fn bits(depth: f32, color: [f32; 3], alpha: f32, light: [f32; 3]) -> [u32; 8] {
    let v = [depth, color[0], color[1], color[2], alpha, light[0], light[1], light[2]];
    v.map(fbits)
}

/// Compares `shade8` with `shade` lane by lane at the centres `px` of line `py`; returns the
/// number of lanes the scalar shade keeps.
fn same_lanes(
    what: &str,
    shade: impl Fn(f32, f32) -> Option<Shade>,
    shade8: impl Fn(F8, f32) -> (u8, Shade8),
    px: [f32; 8],
    py: f32,
) -> usize {
    let (keep, s8) = shade8(F8::from(px), py);
    let lane = |v: F8, i: usize| v.to_array()[i];
    let mut kept = 0;
    for (i, &x) in px.iter().enumerate() {
        let want = shade(x, py);
        assert_eq!(
            keep & (1 << i) != 0,
            want.is_some(),
            "{what}: lane {i} at ({x}, {py}) kept"
        );
        if let Some(w) = want {
            kept += 1;
            let got = bits(
                lane(s8.depth, i),
                s8.color.map(|c| lane(c, i)),
                lane(s8.alpha, i),
                s8.light.map(|c| lane(c, i)),
            );
            assert_eq!(
                got,
                bits(w.depth, w.color, w.alpha, w.light),
                "{what}: lane {i} at ({x}, {py})"
            );
        }
    }
    kept
}

/// Positions: pixel centres of spans over the test area, and arbitrary points.
fn positions(rng: &mut Rng) -> ([f32; 8], f32) {
    match rng.below(8) {
        0 => (std::array::from_fn(|_| rng.range(-6.0, 40.0)), rng.range(-6.0, 30.0)),
        1 => (std::array::from_fn(|_| val(rng, -6.0, 40.0)), val(rng, -6.0, 30.0)),
        _ => {
            let sx = 8 * rng.below(5) as u32;
            (centres(sx).to_array(), rng.below(28) as f32 + 0.5)
        }
    }
}

#[test]
fn shade8_is_the_scalar_shade_lane_by_lane() {
    let mut rng = Rng::new(11);
    let mut kept = [0usize; 4];
    for _ in 0..3000 {
        let (s, sp, f, sl) = (strand(&mut rng), sprite(&mut rng), fog(&mut rng), splat(&mut rng));
        for _ in 0..12 {
            let (px, py) = positions(&mut rng);
            kept[0] += same_lanes("strand", |x, y| s.shade(x, y), |x, y| s.shade8(x, y, 0xff), px, py);
            kept[1] += same_lanes("sprite", |x, y| sp.shade(x, y), |x, y| sp.shade8(x, y, 0xff), px, py);
            kept[2] += same_lanes("fog", |x, y| f.shade(x, y), |x, y| f.shade8(x, y, 0xff), px, py);
            kept[3] += same_lanes("splat", |x, y| sl.shade(x, y), |x, y| sl.shade8(x, y, 0xff), px, py);
        }
    }
    // Both outcomes are exercised for every kind (of 288 000 lanes each).
    assert!(kept.iter().all(|&k| k > 10_000 && k < 280_000), "{kept:?}");
    // NaN positions: NaN flows through both the same way.
    let nan = [
        f32::NAN,
        0.5,
        f32::NAN,
        1.5,
        f32::INFINITY,
        f32::NEG_INFINITY,
        -0.0,
        7.5,
    ];
    for _ in 0..200 {
        let (s, sp, f, sl) = (strand(&mut rng), sprite(&mut rng), fog(&mut rng), splat(&mut rng));
        for py in [0.5, f32::NAN] {
            same_lanes("strand", |x, y| s.shade(x, y), |x, y| s.shade8(x, y, 0xff), nan, py);
            same_lanes("sprite", |x, y| sp.shade(x, y), |x, y| sp.shade8(x, y, 0xff), nan, py);
            same_lanes("fog", |x, y| f.shade(x, y), |x, y| f.shade8(x, y, 0xff), nan, py);
            same_lanes("splat", |x, y| sl.shade(x, y), |x, y| sl.shade8(x, y, 0xff), nan, py);
        }
    }
}

/// Every span `raster` emits: position, mask and the bits of the lanes in the mask.
fn spans(p: &Primitive, clip: Clip, scalar: bool) -> Vec<(u32, u32, u8, Vec<u32>)> {
    let mut out = Vec::new();
    let mut emit = |x: u32, y: u32, mask: u8, l: &SpanLanes| {
        let mut v = Vec::new();
        for i in (0..8).filter(|i| mask & (1 << i) != 0) {
            v.extend([l.color[0][i], l.color[1][i], l.color[2][i], l.alpha[i], l.depth[i]].map(fbits));
        }
        out.push((x, y, mask, v));
    };
    if scalar {
        p.raster_scalar(clip, &mut emit);
    } else {
        p.raster(clip, &mut emit);
    }
    out
}

fn random_clip(rng: &mut Rng, w: u32, h: u32) -> Clip {
    let (a, b) = (rng.below(w as usize + 1) as u32, rng.below(w as usize + 1) as u32);
    let (c, d) = (rng.below(h as usize + 1) as u32, rng.below(h as usize + 1) as u32);
    Clip {
        x0: a.min(b),
        y0: c.min(d),
        x1: a.max(b),
        y1: c.max(d),
    }
}

#[test]
fn raster_is_the_scalar_raster_span_by_span() {
    let mut rng = Rng::new(12);
    let (w, h) = (37, 29);
    let mut emitted = 0;
    for n in 0..4000 {
        let kind = match n % 4 {
            0 => Kind::Strand(strand(&mut rng)),
            1 => Kind::Sprite(sprite(&mut rng)),
            2 => Kind::FogSlice(fog(&mut rng)),
            _ => Kind::Splat(splat(&mut rng)),
        };
        // Boxes anywhere in the frame, sometimes cutting the primitive.
        let (x0, x1) = (rng.below(w as usize) as u32, rng.below(w as usize + 1) as u32);
        let (y0, y1) = (rng.below(h as usize) as u32, rng.below(h as usize + 1) as u32);
        let p = Primitive {
            id: n,
            x0: x0.min(x1),
            y0: y0.min(y1),
            x1: x0.max(x1),
            y1: y0.max(y1),
            kind,
        };
        for clip in [
            Clip::frame(w, h),
            random_clip(&mut rng, w, h),
            random_clip(&mut rng, w, h),
        ] {
            let want = spans(&p, clip, true);
            emitted += want.len();
            assert_eq!(spans(&p, clip, false), want, "{p:?} clipped to {clip:?}");
        }
    }
    assert!(emitted > 10_000, "{emitted} spans");
}

#[test]
fn every_scene_rasterizes_as_the_scalar_reference() {
    for scene in Scene::ALL {
        let (w, h) = if matches!(scene, Scene::Fog | Scene::Splats) {
            (61, 35)
        } else {
            (203, 117)
        };
        let prims = scene.primitives(w, h, 4);
        // The whole frame and bands of 8 lines offset by 3 columns.
        let mut clips = vec![Clip::frame(w, h)];
        clips.extend((0..h).step_by(8).map(|y| Clip {
            x0: 3,
            y0: y,
            x1: w,
            y1: (y + 8).min(h),
        }));
        for p in &prims.prims {
            for &clip in &clips {
                assert_eq!(spans(p, clip, false), spans(p, clip, true), "{}: {p:?}", scene.name());
            }
        }
    }
}

/// Whether the scalar shade covers `(x, y)`.
type Covers<'a> = dyn Fn(f32, f32) -> bool + 'a;
/// A kind's line range.
type Range<'a> = dyn Fn(f32) -> Option<(f32, f32)> + 'a;

/// The line ranges of strands, sprites and splats hold every pixel their scalar shade covers, so
/// skipping the rest changes nothing (the scans above share the ranges, so this is the test
/// that a range is not too tight).
#[test]
fn line_ranges_hold_every_covered_pixel() {
    let check = |p: &Primitive, step: u32| {
        let (shade, range): (Box<Covers>, Box<Range>) = match &p.kind {
            Kind::Strand(s) => (Box::new(|x, y| s.shade(x, y).is_some()), Box::new(|y| s.line_range(y))),
            Kind::Sprite(s) => (Box::new(|x, y| s.shade(x, y).is_some()), Box::new(|y| s.line_range(y))),
            Kind::Splat(s) => (Box::new(|x, y| s.shade(x, y).is_some()), Box::new(|y| s.line_range(y))),
            _ => return 0,
        };
        let mut covered = 0;
        for y in p.y0..p.y1 {
            let py = y as f32 + 0.5;
            let r = range(py);
            // Every `step` quarter pixels (the range is claimed for any `x`, not only
            // centres), and the pixel centres through the scan's own rounding to columns.
            for q in (4 * p.x0..4 * p.x1).step_by(step as usize) {
                let px = q as f32 * 0.25 + 0.125;
                if shade(px, py) {
                    covered += 1;
                    assert!(
                        r.is_some_and(|(lo, hi)| lo <= px && px <= hi),
                        "({px}, {py}) outside {r:?}: {p:?}"
                    );
                }
            }
            for x in p.x0..p.x1 {
                if shade(x as f32 + 0.5, py) {
                    let (xa, xb) = r.map_or((1, 0), |r| Primitive::narrow((p.x0, p.x1), r));
                    assert!(xa <= x && x < xb, "pixel ({x}, {y}) outside {r:?}: {p:?}");
                }
            }
        }
        covered
    };
    let mut rng = Rng::new(13);
    let mut covered = 0;
    for n in 0..3000 {
        let kind = if n % 3 == 0 {
            Kind::Strand(strand(&mut rng))
        } else if n % 3 == 1 {
            Kind::Splat(splat(&mut rng))
        } else {
            // Radius 0 divides 0 by 0 on the centre line (a NaN `q` covers the whole line);
            // the scenes' radii are positive.
            let mut sp = sprite(&mut rng);
            if sp.rad <= 0.0 {
                sp.rad = 0.75;
            }
            Kind::Sprite(sp)
        };
        covered += check(
            &Primitive {
                id: n,
                x0: 0,
                y0: 0,
                x1: 40,
                y1: 32,
                kind,
            },
            1,
        );
    }
    for (scene, w, h) in [
        (Scene::Hair, 1280, 720),
        (Scene::Particles, 1280, 720),
        (Scene::Splats, 640, 360),
    ] {
        for p in &scene.primitives(w, h, 1).prims {
            covered += check(p, 2);
        }
    }
    assert!(covered > 1_000_000, "{covered}");
}

/// Every scene numbers its primitives 0, 1, 2, ... in submission order, and each fragment of
/// its stream carries the number of the primitive that emitted it.
#[test]
fn fragments_carry_their_primitives_ids() {
    for scene in Scene::ALL {
        let (w, h) = (61, 35);
        let prims = scene.primitives(w, h, 5);
        assert!(
            prims.prims.iter().enumerate().all(|(i, p)| p.id == i as u32),
            "{}: ids are not the list's numbering",
            scene.name()
        );
        let s = prims.stream();
        assert!(s.frags.windows(2).all(|f| f[0].prim <= f[1].prim), "{}", scene.name());
        let mut counts = vec![0usize; prims.prims.len()];
        for f in &s.frags {
            counts[f.prim as usize] += 1;
        }
        for p in &prims.prims {
            let mut n = 0;
            p.raster(Clip::frame(w, h), &mut |_, _, mask, _| n += mask.count_ones() as usize);
            assert_eq!(counts[p.id as usize], n, "{}: primitive {}", scene.name(), p.id);
        }
    }
}

/// What a primitive is, apart from where the frame size puts it: the parameters its builder
/// draws in units that do not scale with the frame (depths, colors, alphas, faces).
fn size_free(k: &Kind) -> Vec<f32> {
    let b = |v: bool| f32::from(u8::from(v));
    match k {
        Kind::Strand(s) => vec![0.0, s.alpha, s.tint],
        Kind::Sprite(s) => vec![1.0, s.z, s.a0, b(s.fire), s.heat],
        Kind::Trunk(t) => vec![2.0, t.z],
        Kind::Leaf(l) => vec![3.0, l.lz, l.col[0], l.col[1], l.col[2]],
        Kind::SphereBand(s) => vec![4.0, s.zc, s.a0, s.col[0], s.col[1], s.col[2], b(s.front)],
        Kind::Panel(p) => vec![5.0, p.z, p.alpha, p.thick, b(p.front)],
        Kind::FogSlice(f) => vec![6.0, f.z, f.peak],
        Kind::Splat(s) => vec![7.0, s.z, s.opacity, s.color[0], s.color[1], s.color[2]],
    }
}

/// The primitive list does not depend on the frame size: at every size the same primitives
/// (the same kinds, depths, colors, alphas and faces) in the same order under the same ids,
/// so an id names the same primitive in every frame of the camera path (which builds the
/// scene for a frame a line taller per frame, `peers::camera_stream`). TEAPOTS' bands
/// included: a sphere has as many bands at 36 lines as at 720.
#[test]
fn primitive_lists_do_not_depend_on_the_frame_size() {
    for scene in Scene::ALL {
        let a = scene.primitives(64, 36, 1);
        for (w, h) in [(64, 37), (65, 37), (203, 117), (320, 180), (1280, 720)] {
            let b = scene.primitives(w, h, 1);
            assert_eq!(a.prims.len(), b.prims.len(), "{} at {w}x{h}", scene.name());
            for (p, q) in a.prims.iter().zip(&b.prims) {
                assert_eq!(p.id, q.id);
                assert_eq!(
                    size_free(&p.kind),
                    size_free(&q.kind),
                    "{} at {w}x{h}: primitive {}",
                    scene.name(),
                    p.id
                );
            }
        }
    }
}

/// A sphere's face: its centre's bits and whether it is the front.
type Face = (u32, u32, bool);

/// TEAPOTS' bands of a sphere's face cover each of its lines exactly once at every size: the
/// fragments of all the bands of a face are those of one primitive over the face's whole box
/// (the same pixels, bit for bit the same values), whatever the bands' heights there.
#[test]
fn teapots_bands_cover_each_line_once() {
    for (w, h) in [(64, 36), (65, 37), (203, 117), (320, 180), (640, 360), (1000, 571)] {
        let prims = Scene::Teapots.primitives(w, h, 2);
        // Faces in order of first appearance: (cx, cy, front) -> bands.
        let mut faces: Vec<(Face, Vec<&Primitive>)> = Vec::new();
        for p in &prims.prims {
            let Kind::SphereBand(s) = &p.kind else {
                panic!("TEAPOTS has only sphere bands");
            };
            let key = (s.cx.to_bits(), s.cy.to_bits(), s.front);
            match faces.iter_mut().find(|(k, _)| *k == key) {
                Some((_, v)) => v.push(p),
                None => faces.push((key, vec![p])),
            }
        }
        assert_eq!(faces.len(), 44, "{w}x{h}");
        let clip = Clip::frame(w, h);
        for (_, bands) in &faces {
            let mut got = Vec::new();
            for p in bands {
                got.extend(spans(p, clip, true));
            }
            got.sort_by_key(|s| (s.1, s.0));
            let whole = Primitive {
                y0: bands.iter().map(|p| p.y0).min().unwrap_or(0),
                y1: bands.iter().map(|p| p.y1).max().unwrap_or(0),
                ..*bands[0]
            };
            assert_eq!(got, spans(&whole, clip, true), "{w}x{h}");
        }
    }
}

//! A minimal triangle rasterizer and a procedural transparent mesh, shared by
//! `examples/rasterizer.rs` and `benches/batch.rs` (the per-pixel replay of a mesh). Plain
//! `[f32; N]` arrays, no graphics crate: copy it, or put your own rasterizer in its place.

/// A triangle in screen space: `x`, `y` in pixels, `z` the view depth; one straight
/// linear color and alpha per triangle.
#[derive(Clone, Copy, Debug)]
pub struct Triangle {
    /// Vertices `[x, y, z]`.
    pub v: [[f32; 3]; 3],
    /// Straight linear RGB.
    pub color: [f32; 3],
    /// Alpha (coverage).
    pub alpha: f32,
}

/// Call `emit(x, y, z)` for every pixel center inside the triangle, line by line, left to
/// right (the order a scanline rasterizer emits them). Top-left fill rule, so triangles
/// sharing an edge do not both cover a pixel on it. `z` is interpolated linearly in screen
/// space.
pub fn rasterize(t: &Triangle, width: u32, height: u32, mut emit: impl FnMut(u32, u32, f32)) {
    let [a, b, c] = t.v;
    let edge = |p: [f32; 3], q: [f32; 3], x: f32, y: f32| (q[0] - p[0]) * (y - p[1]) - (q[1] - p[1]) * (x - p[0]);
    let area = edge(a, b, c[0], c[1]);
    if area == 0.0 || !area.is_finite() {
        return;
    }
    // Counter-clockwise or clockwise: both faces are drawn (the mesh is transparent).
    let (b, c, area) = if area < 0.0 { (c, b, -area) } else { (b, c, area) };
    // A top-left edge includes its pixels; the others exclude them (`>= 0` or `> 0`).
    let top_left = |p: [f32; 3], q: [f32; 3]| {
        let (dx, dy) = (q[0] - p[0], q[1] - p[1]);
        (dy == 0.0 && dx < 0.0) || dy > 0.0
    };
    let (tl0, tl1, tl2) = (top_left(b, c), top_left(c, a), top_left(a, b));
    let xmin = a[0].min(b[0]).min(c[0]).floor().max(0.0) as u32;
    let ymin = a[1].min(b[1]).min(c[1]).floor().max(0.0) as u32;
    let xmax = (a[0].max(b[0]).max(c[0]).ceil().max(0.0) as u32).min(width);
    let ymax = (a[1].max(b[1]).max(c[1]).ceil().max(0.0) as u32).min(height);
    for y in ymin..ymax {
        for x in xmin..xmax {
            let (px, py) = (x as f32 + 0.5, y as f32 + 0.5);
            let (w0, w1, w2) = (edge(b, c, px, py), edge(c, a, px, py), edge(a, b, px, py));
            let inside = |w: f32, tl: bool| w > 0.0 || (w == 0.0 && tl);
            if inside(w0, tl0) && inside(w1, tl1) && inside(w2, tl2) {
                let z = (w0 * a[2] + w1 * b[2] + w2 * c[2]) / area;
                emit(x, y, z);
            }
        }
    }
}

/// A procedural transparent mesh: three interlocked tori of `rings x segments` quads (two
/// triangles each), in mesh order (not sorted), projected onto `width x height` pixels.
/// Colors follow the normal, alpha 0.25-0.6; up to about 12 layers per pixel.
pub fn scene(width: u32, height: u32, rings: u32, segments: u32) -> Vec<Triangle> {
    let mut out = Vec::new();
    for (i, (dx, tilt)) in [(-0.8f32, 0.9f32), (0.0, 2.0), (0.8, 0.4)].into_iter().enumerate() {
        torus(&mut out, width, height, rings, segments, dx, tilt, i as u32);
    }
    out
}

/// One torus, shifted by `dx` and tilted by `tilt` radians about x, appended to `out`.
#[allow(clippy::too_many_arguments)]
fn torus(out: &mut Vec<Triangle>, width: u32, height: u32, rings: u32, segments: u32, dx: f32, tilt: f32, seed: u32) {
    let (w, h) = (width as f32, height as f32);
    let (big, small) = (0.7f32, 0.28f32);
    let point = |i: u32, j: u32| {
        let u = i as f32 / rings as f32 * core::f32::consts::TAU;
        let v = j as f32 / segments as f32 * core::f32::consts::TAU;
        let n = [u.cos() * v.cos(), u.sin() * v.cos(), v.sin()];
        let p = [
            (big + small * v.cos()) * u.cos(),
            (big + small * v.cos()) * u.sin(),
            small * v.sin(),
        ];
        // Tilt the torus (rotation about x), shift it, then a perspective camera.
        let (s, c) = (tilt.sin(), tilt.cos());
        let q = [p[0] + dx, p[1] * c - p[2] * s, p[1] * s + p[2] * c + 3.0];
        let f = 0.9 * h;
        ([w / 2.0 + f * q[0] / q[2], h / 2.0 - f * q[1] / q[2], q[2]], n)
    };
    for i in 0..rings {
        for j in 0..segments {
            let (p00, n) = point(i, j);
            let (p10, _) = point(i + 1, j);
            let (p01, _) = point(i, j + 1);
            let (p11, _) = point(i + 1, j + 1);
            let color = n.map(|x| 0.5 + 0.5 * x);
            let alpha = 0.25 + 0.35 * ((i * 7 + j * 3 + seed * 5) % 11) as f32 / 10.0;
            out.push(Triangle {
                v: [p00, p10, p11],
                color,
                alpha,
            });
            out.push(Triangle {
                v: [p00, p11, p01],
                color,
                alpha,
            });
        }
    }
}

/// The pixel events of [`scene`] with `rings` x `segments` quads per torus, in submission
/// order, as a renderer holds them before validation: `(x, y, straight [R, G, B, A], z)`.
#[allow(dead_code)] // the benches' client streams; the examples draw triangles directly
pub fn events(width: u32, height: u32, rings: u32, segments: u32) -> Vec<(u32, u32, [f32; 4], f32)> {
    let mut out = Vec::new();
    for t in scene(width, height, rings, segments) {
        let [r, g, b] = t.color;
        rasterize(&t, width, height, |x, y, z| out.push((x, y, [r, g, b, t.alpha], z)));
    }
    out
}

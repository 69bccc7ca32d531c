//! The scene of `examples/triangles.c`, written again in Rust against the Rust API
//! (`DynFramebuffer`): the PPM of every method, size and arithmetic, which the C program must
//! reproduce byte for byte. Here the same stream also goes through the C ABI (from Rust) and
//! must give the same bytes; with `MLAB_CAPI_PPM_DIR` set, the Rust API's files are written
//! there for `capi/ci.sh` to compare with the C program's (`cmp`). Every fragment carries its
//! triangle's index as its stable key (`Fragment::with_key`, `mlab_insert_straight_keyed`).

use mlab::glam::Vec3;
use mlab::{Arithmetic, Background, DynFramebuffer, Fragment, Framebuffer, Layers, Paper, Row, Unbiased};
use mlab_capi::*;

const WIDTH: u32 = 96;
const HEIGHT: u32 = 64;

/// Vertices in 1/16 pixel; depth `(z0 + dzdx * x + dzdy * y) / 256`; straight color, alpha.
struct Triangle {
    x: [i32; 3],
    y: [i32; 3],
    z0: i32,
    dzdx: i32,
    dzdy: i32,
    rgb: [f32; 3],
    alpha: f32,
}

const fn t(x: [i32; 3], y: [i32; 3], z0: i32, dzdx: i32, dzdy: i32, rgb: [f32; 3], alpha: f32) -> Triangle {
    Triangle {
        x,
        y,
        z0,
        dzdx,
        dzdy,
        rgb,
        alpha,
    }
}

/// `SCENE` of `examples/triangles.c`, in the same order.
const SCENE: [Triangle; 8] = [
    t([160, 1400, 300], [100, 300, 980], 2560, 8, 0, [1.0, 0.2, 0.1], 0.6),
    t([1500, 1480, 200], [60, 1000, 700], 4096, -24, 4, [0.1, 0.4, 1.0], 0.5),
    t([700, 1200, 100], [20, 900, 600], 1024, 12, 12, [0.2, 0.9, 0.3], 0.45),
    t([300, 900, 1500], [900, 40, 800], 3000, 0, -16, [1.0, 0.9, 0.1], 0.35),
    t([40, 1520, 760], [500, 500, 1000], 2000, 0, 0, [0.8, 0.1, 0.9], 0.3),
    t([600, 1000, 800], [200, 200, 960], 2000, 0, 0, [0.1, 0.9, 0.9], 0.7),
    t([0, 1536, 0], [0, 0, 1024], 500, 2, 2, [1.0, 1.0, 1.0], 0.04),
    t([1536, 1536, 0], [0, 1024, 1024], 6000, -8, -8, [0.05, 0.05, 0.05], 0.8),
];

/// The fragments of the scene in submission order: `(x, y, straight [r, g, b, a], depth,
/// key)`, the key the triangle's index.
fn fragments() -> Vec<(u32, u32, [f32; 4], f32, u32)> {
    let mut out = Vec::new();
    for (key, t) in (0u32..).zip(&SCENE) {
        let edge = |i: usize, px: i64, py: i64| {
            let j = (i + 1) % 3;
            (t.x[j] - t.x[i]) as i64 * (py - t.y[i] as i64) - (t.y[j] - t.y[i]) as i64 * (px - t.x[i] as i64)
        };
        for y in 0..HEIGHT {
            for x in 0..WIDTH {
                let (px, py) = (16 * x as i64 + 8, 16 * y as i64 + 8);
                let e = [edge(0, px, py), edge(1, px, py), edge(2, px, py)];
                if e.iter().all(|&v| v >= 0) || e.iter().all(|&v| v <= 0) {
                    let depth = (t.z0 + t.dzdx * x as i32 + t.dzdy * y as i32) as f32 / 256.0;
                    let [r, g, b] = t.rgb;
                    out.push((x, y, [r, g, b, t.alpha], depth, key));
                }
            }
        }
    }
    out
}

fn ppm(rgba: &[[u8; 4]]) -> Vec<u8> {
    let mut out = format!("P6\n{WIDTH} {HEIGHT}\n255\n").into_bytes();
    out.extend(rgba.iter().flat_map(|p| [p[0], p[1], p[2]]));
    out
}

/// The image through the Rust API.
fn rust_image<A: Arithmetic>(layers: Layers) -> Vec<[u8; 4]> {
    let mut storage = vec![Row::EMPTY; layers.rows_needed(WIDTH, HEIGHT).unwrap()];
    let mut fb = DynFramebuffer::<A>::new_cleared(layers, &mut storage, WIDTH, HEIGHT).unwrap();
    for (x, y, rgba, depth, key) in fragments() {
        let f = Fragment::straight_rgba(rgba, depth).unwrap().with_key(key);
        fb.insert(x, y, &f).unwrap();
    }
    let mut out = vec![[0; 4]; (WIDTH * HEIGHT) as usize];
    fb.resolve_rgba8(&mut out, Background::Opaque(Vec3::ONE)).unwrap();
    out
}

/// The image through the C ABI, as `examples/triangles.c` calls it.
fn c_image(method: MlabMethod, layers: u32, arith: MlabArithmetic) -> Vec<[u8; 4]> {
    let mut rows = 0;
    let mut out = vec![[0; 4]; (WIDTH * HEIGHT) as usize];
    // SAFETY: every pointer is valid for what it is passed with; the storage outlives `fb`.
    unsafe {
        assert_eq!(
            mlab_rows_needed(method, layers, WIDTH, HEIGHT, &mut rows),
            MlabStatus::Ok
        );
        let mut storage = vec![MlabRow { bytes: [0; 8] }; rows];
        let mut fb = std::mem::MaybeUninit::uninit();
        let st = mlab_framebuffer_init(
            fb.as_mut_ptr(),
            method,
            layers,
            arith,
            storage.as_mut_ptr(),
            rows,
            WIDTH,
            HEIGHT,
        );
        assert_eq!(st, MlabStatus::Ok);
        let fb = fb.as_mut_ptr();
        for (x, y, [r, g, b, a], depth, key) in fragments() {
            assert_eq!(
                mlab_insert_straight_keyed(fb, x, y, r, g, b, a, depth, key),
                MlabStatus::Ok
            );
        }
        let white = MlabBackground {
            kind: MLAB_BACKGROUND_OPAQUE,
            rgb: [1.0; 3],
        };
        let st = mlab_resolve_rgba8(fb, white, out.as_mut_ptr().cast(), out.len());
        assert_eq!(st, MlabStatus::Ok);
    }
    out
}

#[test]
fn the_c_example_scene_through_the_rust_api_and_the_c_abi() {
    let dir = std::env::var_os("MLAB_CAPI_PPM_DIR").map(std::path::PathBuf::from);
    if let Some(d) = &dir {
        std::fs::create_dir_all(d).unwrap();
    }
    let n = fragments().len();
    assert!(n > 6000, "{n} fragments");
    let mut images = Vec::new();
    for (method, name) in [(MLAB_METHOD_MLAB, "mlab"), (MLAB_METHOD_HYBRID, "ht")] {
        for m in 1..=8 {
            let layers = if method == MLAB_METHOD_MLAB {
                Layers::Mlab(m as usize)
            } else {
                Layers::Hybrid(m as usize)
            };
            for (arith, aname) in [(MLAB_ARITHMETIC_UNBIASED, "unbiased"), (MLAB_ARITHMETIC_PAPER, "paper")] {
                let want = if arith == MLAB_ARITHMETIC_UNBIASED {
                    rust_image::<Unbiased>(layers)
                } else {
                    rust_image::<Paper>(layers)
                };
                assert!(want == c_image(method, m, arith), "{name}{m} {aname}: C ABI differs");
                let bytes = ppm(&want);
                if let Some(d) = &dir {
                    std::fs::write(d.join(format!("{name}{m}_{aname}.ppm")), &bytes).unwrap();
                }
                images.push(bytes);
            }
        }
    }
    // Not a trivial picture: most pixels covered, and the methods and sizes differ.
    let header = format!("P6\n{WIDTH} {HEIGHT}\n255\n").len();
    let pixels = &images[0][header..];
    let white = pixels.chunks(3).filter(|p| *p == [255; 3]).count();
    assert!(
        white < (WIDTH * HEIGHT / 3) as usize,
        "mostly covered: {white} white pixels"
    );
    let mut distinct = images.clone();
    distinct.sort();
    distinct.dedup();
    assert!(distinct.len() > 16, "{} distinct images of 32", distinct.len());
}

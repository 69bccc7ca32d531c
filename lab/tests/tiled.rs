//! The tiled renderer (`oit_lab::tiled`): every band height and thread count gives the same
//! bytes as one band over the whole frame on one thread, and that frame equals the kernel fed
//! the scene's fragment stream fragment by fragment (scalar inserts), so the rasterizer's
//! spans, the lanes quantization and the span inserts together change nothing.

use mlab::glam::{Vec3, Vec4};
use mlab::{Arithmetic, Background, Framebuffer, Paper, Row, SpanFramebuffer, Unbiased, to_rgba8};
use oit_lab::methods::{BinnedStream, Method, Weight};
use oit_lab::scenes::{Primitives, Scene};
use oit_lab::stream::Stream;
use oit_lab::tiled::{TileSize, TiledMethod, TiledRenderer, replay_mlab4, storage_bytes};

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("thread pool")
}

fn render(p: &Primitives, m: TiledMethod, lines: u32, threads: usize) -> (Vec<[u8; 4]>, u64) {
    render_tiled(p, m, TileSize::band(lines), threads)
}

fn render_tiled(p: &Primitives, m: TiledMethod, tile: TileSize, threads: usize) -> (Vec<[u8; 4]>, u64) {
    let mut out = vec![[7u8; 4]; p.width as usize * p.height as usize];
    let mut r = TiledRenderer::tiled(tile);
    let n = pool(threads).install(|| r.render(m, p, &mut out)).unwrap();
    (out, n)
}

/// The kernel, scalar inserts, fragment by fragment in stream order, one framebuffer.
fn mlab_sequential<A: Arithmetic>(s: &Stream) -> Vec<[u8; 4]> {
    let mut storage = vec![Row::EMPTY; SpanFramebuffer::<4, A>::rows_needed(s.width, s.height).unwrap()];
    let mut fb = SpanFramebuffer::<4, A>::new_cleared(&mut storage, s.width, s.height).unwrap();
    for f in &s.frags {
        fb.insert(f.pixel % s.width, f.pixel / s.width, &f.to_kernel().unwrap())
            .unwrap();
    }
    let mut out = vec![[0u8; 4]; s.pixels()];
    fb.resolve_rgba8(&mut out, Background::Opaque(Vec3::from(s.background)))
        .unwrap();
    out
}

/// The A-buffer written plainly over the stream: per pixel, sort by depth (later submission
/// first on equal depth), composite the quantized rows front to back in f32.
fn abuffer_sequential(s: &Stream) -> Vec<[u8; 4]> {
    let mut lists: Vec<Vec<(usize, Row)>> = vec![Vec::new(); s.pixels()];
    for (i, f) in s.frags.iter().enumerate() {
        let k = f.to_kernel().unwrap();
        lists[f.pixel as usize].push((i, Unbiased::quantize(&k, k.hash(f.pixel))));
    }
    let bg = Vec3::from(s.background);
    lists
        .iter_mut()
        .map(|l| {
            l.sort_by(|a, b| a.1.depth().total_cmp(&b.1.depth()).then(b.0.cmp(&a.0)));
            let (mut c, mut t) = (Vec3::ZERO, 1.0f32);
            for (_, r) in l.iter() {
                let ([cr, cg, cb], tr) = (r.color(), r.transmittance());
                c += t * Vec3::new(cr as f32, cg as f32, cb as f32) * (1.0 / 255.0);
                t *= tr as f32 * (1.0 / 255.0);
            }
            to_rgba8((c + t * bg).extend(1.0))
        })
        .collect()
}

fn lab_rgba8(m: Method, s: &Stream) -> Vec<[u8; 4]> {
    let img = m.render(&BinnedStream::new(s)).unwrap();
    img.rgb
        .iter()
        .map(|c| to_rgba8(Vec4::new(c[0], c[1], c[2], 1.0)))
        .collect()
}

/// The test frame of `scene`: `small` for FOG and SPLATS (hundreds of layers per pixel, kept
/// small to stay quick), `size` for the others.
fn frame(scene: Scene, size: (u32, u32), small: (u32, u32)) -> (u32, u32) {
    if matches!(scene, Scene::Fog | Scene::Splats) {
        small
    } else {
        size
    }
}

#[test]
fn every_tile_size_and_thread_count_equals_one_band_one_thread() {
    // Widths not a multiple of 8 (a partial last span), 37 and 19 lines leave a short last
    // band; FOG and SPLATS (hundreds of layers per pixel) on a smaller frame to stay quick.
    // Tiles: whole lines, 8 columns (the narrowest), 16 and 40 columns (a short last tile;
    // 13 rounds up to 16), one tile wider than the frame.
    for scene in Scene::ALL {
        let (w, h) = frame(scene, (150, 37), (43, 19));
        let p = scene.primitives(w, h, 3);
        let frags = p.stream().frags.len() as u64;
        for m in TiledMethod::ALL {
            let (whole, n) = render(&p, m, p.height, 1);
            assert_eq!(n, frags, "{} {}: fragment count", scene.name(), m.name());
            for (width, lines, threads) in [
                (0, 1, 2),
                (0, 8, 3),
                (0, h - 1, 1),
                (8, 8, 2),
                (13, 5, 3),
                (40, 16, 2),
                (8, h, 1),
                (w + 9, 3, 2),
            ] {
                let tile = TileSize { width, lines };
                let (got, n) = render_tiled(&p, m, tile, threads);
                assert_eq!(n, frags);
                assert!(
                    got == whole,
                    "{} {}: tiles {tile}, {threads} threads differ from one band",
                    scene.name(),
                    m.name()
                );
            }
        }
    }
}

#[test]
fn mlab_frame_equals_the_kernel_fed_the_stream() {
    for scene in Scene::ALL {
        let (w, h) = frame(scene, (96, 40), (43, 21));
        let p = scene.primitives(w, h, 2);
        let s = p.stream();
        assert_eq!(
            render(&p, TiledMethod::Mlab4, 8, 2).0,
            mlab_sequential::<Unbiased>(&s),
            "{}",
            scene.name()
        );
        assert_eq!(
            render(&p, TiledMethod::Mlab4Paper, 8, 2).0,
            mlab_sequential::<Paper>(&s),
            "{}",
            scene.name()
        );
        // The two arithmetics are told apart by the frame (the test can fail).
        if scene == Scene::Fog {
            assert_ne!(mlab_sequential::<Unbiased>(&s), mlab_sequential::<Paper>(&s));
        }
    }
}

#[test]
fn baselines_equal_their_plain_versions() {
    for scene in [Scene::Hair, Scene::Particles, Scene::Teapots, Scene::Splats] {
        let p = scene.primitives(64, 48, 5);
        let s = p.stream();
        assert_eq!(
            render(&p, TiledMethod::ABuffer, 8, 2).0,
            abuffer_sequential(&s),
            "{}",
            scene.name()
        );
        assert_eq!(
            render(&p, TiledMethod::Over, 8, 2).0,
            lab_rgba8(Method::Over, &s),
            "{}",
            scene.name()
        );
        // The lab's WBOIT uses the frame's window depth for eq. 7's weight only through `z`:
        // eq. 7 reads the view depth, so the images agree.
        assert_eq!(
            render(&p, TiledMethod::Wboit, 8, 2).0,
            lab_rgba8(Method::Wboit(Weight::Eq7), &s),
            "{}",
            scene.name()
        );
    }
}

#[test]
fn abuffer_is_close_to_the_exact_reference() {
    let p = Scene::Hair.primitives(64, 48, 5);
    let exact = lab_rgba8(Method::Reference, &p.stream());
    let got = render(&p, TiledMethod::ABuffer, 16, 2).0;
    let worst = exact
        .iter()
        .zip(&got)
        .flat_map(|(a, b)| (0..3).map(move |k| a[k].abs_diff(b[k])))
        .max()
        .unwrap();
    // Only the 8-bit quantization of each fragment differs (the plain 8-bit A-buffer equals
    // the tiled one exactly: `baselines_equal_their_plain_versions`). Its errors add up over
    // a pixel's fragments: since HAIR has the paper's depth (issue 10), the worst pixel holds
    // 76 faint fragments whose transmittances sum to 12.4 and is off by 4 levels (3 before).
    assert!(worst <= 4, "largest channel difference {worst}");
}

#[test]
fn replay_counts_the_same_fragments() {
    let p = Scene::Particles.primitives(80, 40, 1);
    for tile in [TileSize::band(8), TileSize { width: 24, lines: 8 }] {
        let (times, _, n) = replay_mlab4(&p, tile, 0, 3, || 0.0).unwrap();
        assert_eq!(times.len(), 3);
        assert_eq!(n, p.stream().frags.len() as u64, "{tile}");
    }
}

#[test]
fn tile_sizes_parse_and_print() {
    assert_eq!("16".parse::<TileSize>(), Ok(TileSize::band(16)));
    assert_eq!("64x32".parse::<TileSize>(), Ok(TileSize { width: 64, lines: 32 }));
    assert_eq!("0x8".parse::<TileSize>(), Ok(TileSize::band(8)));
    for bad in ["0", "64x0", "x8", "64x", "a", "-8", ""] {
        assert!(bad.parse::<TileSize>().is_err(), "{bad}");
    }
    let t = TileSize { width: 64, lines: 32 };
    assert_eq!(t.to_string().parse::<TileSize>(), Ok(t));
}

#[test]
fn no_primitives_is_the_background_and_bad_output_is_refused() {
    let mut p = Scene::Glass.primitives(9, 3, 1);
    p.prims.clear();
    let want = to_rgba8(Vec4::new(p.background[0], p.background[1], p.background[2], 1.0));
    for m in TiledMethod::ALL {
        let (out, n) = render(&p, m, 2, 2);
        assert_eq!(n, 0);
        assert!(out.iter().all(|px| *px == want), "{}", m.name());
        let mut short = vec![[0u8; 4]; 26];
        assert!(TiledRenderer::new(2).render(m, &p, &mut short).is_err());
    }
}

#[test]
fn table_1_memory() {
    // The paper's Table 1 at 1280x720: MLAB 2 rows 14.1 MB (hence 4 rows 28.2 MB); plus the
    // 4-byte RGBA8 output.
    let px = 1280 * 720;
    assert_eq!(storage_bytes(TiledMethod::Mlab4, px, 0), 29_491_200 + 4 * px);
    assert_eq!(storage_bytes(TiledMethod::ABuffer, px, 1_000_000), 8 * px + 12_000_000);
}

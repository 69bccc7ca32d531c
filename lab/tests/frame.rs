//! The frame compositor (`oit_lab::frame`): banded and threaded results are byte-identical
//! to one thread over the whole frame, for every band height and thread count tried.

use mlab::glam::{Vec3, Vec4};
use mlab::{Background, Framebuffer, Paper, Row, SpanFramebuffer, to_rgba8};
use oit_lab::frame::{CHUNK, Compositor, FrameMethod};
use oit_lab::methods::{Frame, Method, Weight};
use oit_lab::scenes::Scene;
use oit_lab::stream::{Frag, Stream};

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("thread pool")
}

/// The untiled single-threaded kernel: every fragment in submission order into one
/// framebuffer, then the lanes resolve.
fn mlab_sequential(s: &Stream) -> (Vec<Row>, Vec<[u8; 4]>) {
    let mut storage = vec![Row::EMPTY; SpanFramebuffer::<4, Paper>::rows_needed(s.width, s.height).unwrap()];
    let mut fb = SpanFramebuffer::<4, Paper>::new_cleared(&mut storage, s.width, s.height).unwrap();
    for f in &s.frags {
        fb.insert(f.pixel % s.width, f.pixel / s.width, &f.to_kernel().unwrap())
            .unwrap();
    }
    let mut out = vec![[0u8; 4]; s.pixels()];
    fb.resolve_rgba8(&mut out, Background::Opaque(Vec3::from(s.background)))
        .unwrap();
    (storage, out)
}

/// The A-buffer written plainly: per pixel, sort by depth (later submission first on equal
/// depth), composite the quantized rows front to back in f32.
fn abuffer_sequential(s: &Stream) -> Vec<[u8; 4]> {
    let mut lists: Vec<Vec<(usize, Row)>> = vec![Vec::new(); s.pixels()];
    for (i, f) in s.frags.iter().enumerate() {
        lists[f.pixel as usize].push((i, f.to_kernel().unwrap().row()));
    }
    let bg = Vec3::from(s.background);
    lists
        .iter_mut()
        .map(|l| {
            l.sort_by(|a, b| a.1.depth().total_cmp(&b.1.depth()).then(b.0.cmp(&a.0)));
            let (mut c, mut t) = (Vec3::ZERO, 1.0f32);
            for (_, r) in l.iter() {
                let [cr, cg, cb, tr] = r.rgbt();
                c += t * Vec3::new(cr as f32, cg as f32, cb as f32) * (1.0 / 255.0);
                t *= tr as f32 * (1.0 / 255.0);
            }
            to_rgba8((c + t * bg).extend(1.0))
        })
        .collect()
}

fn lab_rgba8(m: Method, s: &Stream) -> Vec<[u8; 4]> {
    let img = m.render(&Frame::new(s)).unwrap();
    img.rgb
        .iter()
        .map(|c| to_rgba8(Vec4::new(c[0], c[1], c[2], 1.0)))
        .collect()
}

fn render(c: &mut Compositor, m: FrameMethod, s: &Stream) -> Vec<[u8; 4]> {
    let mut out = vec![[7u8; 4]; s.pixels()];
    c.render(m, s, &mut out).unwrap();
    out
}

#[test]
fn banded_threaded_equals_whole_frame_one_thread() {
    // 150x37: the width is not a multiple of 8 and the bands do not divide the height;
    // chunks of 1000 fragments (and one of the default size): fragments of a pixel
    // spread over several chunks.
    for scene in [Scene::Hair, Scene::Particles, Scene::Teapots] {
        let s = scene.generate(150, 37, 3);
        assert!(s.frags.len() > 4000, "{}: {} fragments", scene.name(), s.frags.len());
        let (rows, mlab) = mlab_sequential(&s);
        let abuf = abuffer_sequential(&s);
        let over = lab_rgba8(Method::Over, &s);
        let wboit = lab_rgba8(Method::Wboit(Weight::Eq7), &s);
        for (threads, lines, chunk) in [(1, 8, CHUNK), (1, 5, 1000), (2, 1, 1000), (3, 8, 1000), (2, 64, 999)] {
            {
                pool(threads).install(|| {
                    let mut c = Compositor::new(lines);
                    c.chunk = chunk;
                    let what = format!("{} threads {threads} bands of {lines} chunks of {chunk}", scene.name());
                    // Twice: the second frame reuses the bins and storage.
                    for _ in 0..2 {
                        assert!(render(&mut c, FrameMethod::Mlab4, &s) == mlab, "MLAB {what}");
                        assert!(c.mlab_rows() == rows.as_slice(), "MLAB rows {what}");
                    }
                    assert!(render(&mut c, FrameMethod::ABuffer, &s) == abuf, "A-buffer {what}");
                    assert!(render(&mut c, FrameMethod::Over, &s) == over, "OVER {what}");
                    assert!(render(&mut c, FrameMethod::Wboit, &s) == wboit, "WBOIT {what}");
                });
            }
        }
    }
}

#[test]
fn abuffer_is_close_to_the_exact_reference() {
    let s = Scene::Hair.generate(64, 48, 5);
    let exact = lab_rgba8(Method::Reference, &s);
    let got = render(&mut Compositor::default(), FrameMethod::ABuffer, &s);
    let worst = exact
        .iter()
        .zip(&got)
        .flat_map(|(a, b)| (0..3).map(move |k| a[k].abs_diff(b[k])))
        .max()
        .unwrap();
    // Only the 8-bit quantization of each fragment differs.
    assert!(worst <= 3, "largest channel difference {worst}");
}

#[test]
fn bad_input_is_refused_with_the_fragment() {
    let mut s = Scene::Particles.generate(40, 24, 1);
    let mut out = vec![[0u8; 4]; s.pixels()];
    let i = s.frags.len() / 2 + 3;
    s.frags[i].depth = f32::NAN;
    let e = Compositor::default()
        .render(FrameMethod::Mlab4, &s, &mut out)
        .unwrap_err();
    assert!(e.starts_with(&format!("fragment {i}:")), "{e}");
    s.frags[i].depth = 1.0;
    s.frags[i].pixel = s.pixels() as u32;
    let e = Compositor::default()
        .render(FrameMethod::Over, &s, &mut out)
        .unwrap_err();
    assert!(e.contains("outside the frame"), "{e}");
    let e = Compositor::default()
        .render(FrameMethod::Over, &s, &mut out[1..])
        .unwrap_err();
    assert!(e.contains("output"), "{e}");
    let e = Compositor::new(0).render(FrameMethod::Mlab4, &s, &mut out).unwrap_err();
    assert!(e.contains("band lines"), "{e}");
}

#[test]
fn empty_stream_is_the_background() {
    let s = Stream {
        width: 9,
        height: 3,
        background: [0.25, 0.5, 1.0],
        frags: Vec::<Frag>::new(),
    };
    let want = to_rgba8(Vec4::new(0.25, 0.5, 1.0, 1.0));
    for m in FrameMethod::ALL {
        assert!(
            render(&mut Compositor::new(2), m, &s).iter().all(|p| *p == want),
            "{}",
            m.name()
        );
    }
}

#[test]
fn table_1_memory() {
    // The paper's Table 1 at 1280x720: MLAB 2 rows 14.1 MB (hence 4 rows 28.2 MB).
    let px = 1280 * 720;
    assert_eq!(FrameMethod::Mlab4.frame_bytes(px, 0), 29_491_200);
    assert_eq!(FrameMethod::ABuffer.frame_bytes(px, 1_000_000), 4 * px + 12_000_000);
}

//! The C API against the Rust API on the same streams: MLAB 1-8 and HT 1-8, both
//! arithmetics, through the `extern "C"` functions (called by their Rust declarations). The
//! storage after the inserts, every status, and the RGBA8, f32 and RGBA16F resolves over an
//! opaque and a transparent background must equal `DynFramebuffer`'s byte for byte.

use mlab::glam::Vec4;
use mlab::half::f16;
use mlab::lanes::FragmentLanes;
use mlab::{Arithmetic, Background, DynFramebuffer, Fragment, Framebuffer, Layers, Paper, Row, Unbiased};
use mlab_capi::*;

/// xorshift64*: a fixed-seed stream, no dependency.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
    fn unit(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32
    }
}

const W: u32 = 21; // not a multiple of 8: a partial span on every line
const H: u32 = 6;

/// One fragment of a stream: pixel (sometimes outside), RGBA, depth; some invalid.
fn event(rng: &mut Rng) -> MlabPixelFragment {
    let mut rgba = [rng.unit(), rng.unit(), rng.unit(), rng.unit()];
    let mut depth = 10.0 * rng.unit();
    match rng.below(40) {
        0 => rgba[3] = f32::NAN,
        1 => rgba[0] = -0.25,
        2 => depth = f32::INFINITY,
        3 => depth = f32::NAN,
        4 => rgba[1] = 3.0, // straight: above 1 after alpha unless alpha is small
        5 => rgba[3] = 1.5,
        6..=11 => rgba[3] *= 0.05, // faint: the unbiased arithmetic dithers these
        12..=13 => depth = 2.0,    // equal depths
        _ => {}
    }
    let (x, y) = match rng.below(30) {
        0 => (W + rng.below(3) as u32, rng.below(H as u64) as u32),
        1 => (rng.below(W as u64) as u32, H),
        _ => (rng.below(W as u64) as u32, rng.below(H as u64) as u32),
    };
    MlabPixelFragment { x, y, rgba, depth }
}

fn stream(seed: u64, n: usize) -> Vec<MlabPixelFragment> {
    let mut rng = Rng(seed);
    (0..n).map(|_| event(&mut rng)).collect()
}

/// A C framebuffer over its own storage (the Vec's buffer does not move with the Vec).
struct CFb {
    storage: Vec<MlabRow>,
    fb: MlabFramebuffer,
}

fn c_fb(method: MlabMethod, layers: u32, arith: MlabArithmetic, w: u32, h: u32) -> CFb {
    let mut rows = 0usize;
    // SAFETY: a valid `size_t` to write.
    assert_eq!(
        unsafe { mlab_rows_needed(method, layers, w, h, &mut rows) },
        MlabStatus::Ok
    );
    // Garbage in the storage: init must clear it.
    let mut storage = vec![MlabRow { bytes: [0xa5; 8] }; rows];
    let mut fb = std::mem::MaybeUninit::<MlabFramebuffer>::uninit();
    // SAFETY: the storage holds `rows` rows and outlives the framebuffer (both in `CFb`).
    let st = unsafe { mlab_framebuffer_init(fb.as_mut_ptr(), method, layers, arith, storage.as_mut_ptr(), rows, w, h) };
    assert_eq!(st, MlabStatus::Ok);
    // SAFETY: init returned Ok, so it wrote the struct.
    CFb {
        storage,
        fb: unsafe { fb.assume_init() },
    }
}

impl CFb {
    fn bytes(&self) -> Vec<u8> {
        self.storage.iter().flat_map(|r| r.bytes).collect()
    }
}

/// Equal bytes, or a panic naming the first difference (not thousands of bytes).
#[track_caller]
fn same<T: PartialEq + std::fmt::Debug>(got: &[T], want: &[T], what: &str) {
    assert_eq!(got.len(), want.len(), "{what}: lengths");
    if let Some(i) = got.iter().zip(want).position(|(a, b)| a != b) {
        let n = got.iter().zip(want).filter(|(a, b)| a != b).count();
        panic!(
            "{what}: {n} elements differ, the first at {i}: {:?} against {:?}",
            got[i], want[i]
        );
    }
}

fn rust_bytes<A: Arithmetic>(fb: &DynFramebuffer<'_, A>) -> Vec<u8> {
    fb.as_bytes().to_vec()
}

fn backgrounds() -> [(MlabBackground, Background); 2] {
    let rgb = [0.25, 0.5, 1.0];
    [
        (
            MlabBackground {
                kind: MLAB_BACKGROUND_OPAQUE,
                rgb,
            },
            Background::Opaque(mlab::glam::Vec3::from_array(rgb)),
        ),
        (
            MlabBackground {
                kind: MLAB_BACKGROUND_TRANSPARENT,
                rgb: [0.0; 3],
            },
            Background::Transparent,
        ),
    ]
}

/// Every resolve of the C framebuffer equals the Rust one's, byte for byte.
fn check_resolves<A: Arithmetic>(c: &CFb, r: &DynFramebuffer<'_, A>, what: &str) {
    let n = (W * H) as usize;
    for (cbg, rbg) in backgrounds() {
        let mut want8 = vec![[0u8; 4]; n];
        r.resolve_rgba8(&mut want8, rbg).unwrap();
        let mut got8 = vec![[0u8; 4]; n];
        // SAFETY: `n` pixels of 4 bytes.
        let st = unsafe { mlab_resolve_rgba8(&c.fb, cbg, got8.as_mut_ptr().cast(), n) };
        assert_eq!(st, MlabStatus::Ok);
        same(&got8, &want8, &format!("{what}: RGBA8 over {rbg:?}"));

        let mut want = vec![Vec4::ZERO; n];
        r.resolve_into(&mut want, rbg).unwrap();
        let mut got = vec![Vec4::splat(7.0); n]; // 16-byte aligned (glam's Vec4)
        // SAFETY: `n` pixels of 4 floats, 16-byte aligned.
        let st = unsafe { mlab_resolve_f32(&c.fb, cbg, got.as_mut_ptr().cast(), n) };
        assert_eq!(st, MlabStatus::Ok);
        let bits = |v: &[Vec4]| {
            v.iter()
                .flat_map(|p| p.to_array().map(f32::to_bits))
                .collect::<Vec<_>>()
        };
        same(&bits(&got), &bits(&want), &format!("{what}: f32 over {rbg:?}"));

        let mut want16 = vec![[f16::ZERO; 4]; n];
        r.resolve_rgba16f(&mut want16, rbg).unwrap();
        let mut got16 = vec![[0u16; 4]; n];
        // SAFETY: `n` pixels of 4 u16.
        let st = unsafe { mlab_resolve_rgba16f(&c.fb, cbg, got16.as_mut_ptr().cast(), n) };
        assert_eq!(st, MlabStatus::Ok);
        same(&got16, &want16.map_bits(), &format!("{what}: RGBA16F over {rbg:?}"));
    }
}

trait Bits {
    fn map_bits(&self) -> Vec<[u16; 4]>;
}
impl Bits for Vec<[f16; 4]> {
    fn map_bits(&self) -> Vec<[u16; 4]> {
        self.iter().map(|p| p.map(f16::to_bits)).collect()
    }
}

/// Per-pixel inserts (straight, then premultiplied), span inserts and the batch, against
/// the Rust API in arithmetic `A` (`arith` is its C constant).
fn check_config<A: Arithmetic>(method: MlabMethod, layers: u32, arith: MlabArithmetic) {
    let kind = match method {
        MLAB_METHOD_MLAB => Layers::Mlab(layers as usize),
        _ => Layers::Hybrid(layers as usize),
    };
    let what = format!("{kind:?} arith {arith}");
    let events = stream(0x9e37_79b9_7f4a_7c15 ^ (layers as u64) << 8 ^ method as u64, 900);

    // Per pixel, straight then premultiplied color.
    let mut c = c_fb(method, layers, arith, W, H);
    let mut storage = vec![Row::EMPTY; kind.rows_needed(W, H).unwrap()];
    let mut r = DynFramebuffer::<A>::new_cleared(kind, &mut storage, W, H).unwrap();
    same(&c.bytes(), &rust_bytes(&r), &format!("{what}: cleared"));
    let mut errors = 0;
    for (i, e) in events.iter().enumerate() {
        let [cr, cg, cb, ca] = e.rgba;
        let straight = i % 3 != 0;
        // SAFETY: `c.fb` is initialized over its live storage.
        let got = unsafe {
            if straight {
                mlab_insert_straight(&mut c.fb, e.x, e.y, cr, cg, cb, ca, e.depth)
            } else {
                mlab_insert_premultiplied(&mut c.fb, e.x, e.y, cr, cg, cb, ca, e.depth)
            }
        };
        let f = if straight {
            Fragment::straight_rgba(e.rgba, e.depth)
        } else {
            Fragment::premultiplied_rgba(e.rgba, e.depth)
        };
        let want = match f {
            Err(err) => MlabStatus::from(err),
            Ok(f) => r
                .insert(e.x, e.y, &f)
                .map_or_else(MlabStatus::from, |()| MlabStatus::Ok),
        };
        assert_eq!(got, want, "{what}: fragment {i} {e:?}");
        errors += (got != MlabStatus::Ok) as usize;
    }
    assert!(
        errors > 20 && errors < 300,
        "{what}: the stream has some bad fragments ({errors})"
    );
    same(&c.bytes(), &rust_bytes(&r), &format!("{what}: per-pixel inserts"));
    check_resolves(&c, &r, &what);

    // Span inserts on top (both color kinds), lanes inside the line, masks random.
    let mut rng = Rng(layers as u64 * 77 + method as u64);
    for i in 0..120 {
        let x = rng.below(W as u64 - 7) as u32 + if i % 5 == 0 { 7 } else { 0 }; // some past the edge
        let y = rng.below(H as u64) as u32;
        let mask = rng.below(256) as u8;
        let mut span = MlabFragmentSpan {
            r: [0.0; 8],
            g: [0.0; 8],
            b: [0.0; 8],
            a: [0.0; 8],
            depth: [0.0; 8],
        };
        for lane in 0..8 {
            let e = event(&mut rng);
            [span.r[lane], span.g[lane], span.b[lane], span.a[lane]] = e.rgba;
            span.depth[lane] = e.depth;
        }
        let lanes = FragmentLanes {
            color: [span.r, span.g, span.b],
            alpha: span.a,
            depth: span.depth,
            key: None,
        };
        let straight = i % 2 == 0;
        let mut refused = 0xeeu8;
        // SAFETY: initialized framebuffer, a span to read, a byte to write.
        let got = unsafe {
            if straight {
                mlab_insert_span_straight(&mut c.fb, x, y, &span, mask, &mut refused)
            } else {
                mlab_insert_span_premultiplied(&mut c.fb, x, y, &span, mask, &mut refused)
            }
        };
        let want = if straight {
            r.insert_span_straight(x, y, &lanes, mask)
        } else {
            r.insert_span_fragments(x, y, &lanes, mask)
        };
        match want {
            Err(e) => {
                assert_eq!(got, MlabStatus::from(e), "{what}: span {i}");
                assert_eq!(refused, 0xee, "{what}: span {i}: refused untouched on error");
            }
            Ok(invalid) => {
                assert_eq!(refused, invalid.0, "{what}: span {i}: refused lanes");
                if invalid.0 == 0 {
                    assert_eq!(got, MlabStatus::Ok, "{what}: span {i}");
                } else {
                    let l = invalid.0.trailing_zeros() as usize;
                    let rgba = [span.r[l], span.g[l], span.b[l], span.a[l]];
                    let one = if straight {
                        Fragment::straight_rgba(rgba, span.depth[l])
                    } else {
                        Fragment::premultiplied_rgba(rgba, span.depth[l])
                    };
                    assert_eq!(got, MlabStatus::from(one.unwrap_err()), "{what}: span {i}");
                }
            }
        }
    }
    same(&c.bytes(), &rust_bytes(&r), &format!("{what}: span inserts"));
    check_resolves(&c, &r, &what);

    // The batch, resumed after each refused fragment, equals per-pixel inserts skipping them.
    for straight in [true, false] {
        let mut c = c_fb(method, layers, arith, W, H);
        let mut storage = vec![Row::EMPTY; kind.rows_needed(W, H).unwrap()];
        let mut r = DynFramebuffer::<A>::new_cleared(kind, &mut storage, W, H).unwrap();
        let mut want_stops = Vec::new();
        for (i, e) in events.iter().enumerate() {
            let f = if straight {
                Fragment::straight_rgba(e.rgba, e.depth)
            } else {
                Fragment::premultiplied_rgba(e.rgba, e.depth)
            };
            let st = match f {
                Err(err) => MlabStatus::from(err),
                Ok(f) => r
                    .insert(e.x, e.y, &f)
                    .map_or_else(MlabStatus::from, |()| MlabStatus::Ok),
            };
            if st != MlabStatus::Ok {
                want_stops.push((i, st));
            }
        }
        let mut got_stops = Vec::new();
        let mut start = 0;
        while start < events.len() {
            let rest = &events[start..];
            let mut inserted = usize::MAX;
            // SAFETY: `rest.len()` fragments to read, a size_t to write.
            let st = unsafe {
                if straight {
                    mlab_insert_batch_straight(&mut c.fb, rest.as_ptr(), rest.len(), &mut inserted)
                } else {
                    mlab_insert_batch_premultiplied(&mut c.fb, rest.as_ptr(), rest.len(), &mut inserted)
                }
            };
            if st == MlabStatus::Ok {
                assert_eq!(inserted, rest.len());
                break;
            }
            got_stops.push((start + inserted, st));
            start += inserted + 1;
        }
        assert_eq!(got_stops, want_stops, "{what}: batch stops (straight {straight})");
        same(
            &c.bytes(),
            &rust_bytes(&r),
            &format!("{what}: batch (straight {straight})"),
        );
        check_resolves(&c, &r, &what);
    }
}

#[test]
fn every_method_size_and_arithmetic_equals_the_rust_api() {
    for method in [MLAB_METHOD_MLAB, MLAB_METHOD_HYBRID] {
        for layers in 1..=8 {
            check_config::<Unbiased>(method, layers, MLAB_ARITHMETIC_UNBIASED);
            check_config::<Paper>(method, layers, MLAB_ARITHMETIC_PAPER);
        }
    }
}

/// Inserts into bands (coordinates relative to the band) on two threads at once equal
/// inserts into the whole framebuffer; clear resets the bands' rows.
#[test]
fn bands_on_threads_equal_the_whole_framebuffer() {
    struct Band(MlabFramebuffer);
    // SAFETY: the band's rows are used by one thread only (the bands do not overlap).
    unsafe impl Send for Band {}
    for (method, layers) in [(MLAB_METHOD_MLAB, 4), (MLAB_METHOD_HYBRID, 3)] {
        let events: Vec<_> = stream(5, 2000)
            .into_iter()
            .filter(|e| Fragment::straight_rgba(e.rgba, e.depth).is_ok() && e.x < W && e.y < H)
            .collect();
        let mut whole = c_fb(method, layers, MLAB_ARITHMETIC_UNBIASED, W, H);
        for e in &events {
            let [r, g, b, a] = e.rgba;
            // SAFETY: initialized framebuffer.
            let st = unsafe { mlab_insert_straight(&mut whole.fb, e.x, e.y, r, g, b, a, e.depth) };
            assert_eq!(st, MlabStatus::Ok);
        }
        let mut banded = c_fb(method, layers, MLAB_ARITHMETIC_UNBIASED, W, H);
        let split = 4;
        let mut top = Band(MlabFramebuffer::clone(&banded.fb));
        let mut bottom = Band(MlabFramebuffer::clone(&banded.fb));
        // SAFETY: initialized framebuffer; the bands are written to structs of their own.
        unsafe {
            assert_eq!(mlab_framebuffer_band(&banded.fb, 0, split, &mut top.0), MlabStatus::Ok);
            assert_eq!(
                mlab_framebuffer_band(&banded.fb, split, H - split, &mut bottom.0),
                MlabStatus::Ok
            );
        }
        std::thread::scope(|s| {
            for (band, first, lines) in [(top, 0, split), (bottom, split, H - split)] {
                let events = &events;
                s.spawn(move || {
                    let mut band = band; // the whole `Band` moves in (it is `Send`, its field is not)
                    for e in events.iter().filter(|e| (first..first + lines).contains(&e.y)) {
                        let [r, g, b, a] = e.rgba;
                        // SAFETY: the band's rows are this thread's alone.
                        let st = unsafe { mlab_insert_straight(&mut band.0, e.x, e.y - first, r, g, b, a, e.depth) };
                        assert_eq!(st, MlabStatus::Ok);
                    }
                    // A line past the band is refused.
                    // SAFETY: as above.
                    let st = unsafe { mlab_insert_straight(&mut band.0, 0, lines, 0.5, 0.5, 0.5, 0.5, 1.0) };
                    assert_eq!(st, MlabStatus::OutOfBounds);
                });
            }
        });
        same(&banded.bytes(), &whole.bytes(), "bands");
        // SAFETY: initialized framebuffers.
        unsafe {
            assert_eq!(mlab_framebuffer_clear(&mut banded.fb), MlabStatus::Ok);
        }
        let fresh = c_fb(method, layers, MLAB_ARITHMETIC_UNBIASED, W, H);
        same(&banded.bytes(), &fresh.bytes(), "cleared bands");
    }
}

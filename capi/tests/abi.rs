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

/// What the C API's per-pixel insert of `(x, y, rgba, depth)` (keyed or not) returns, through
/// the Rust API: the pixel checked first, then the fragment (the C API's order of the
/// checks; the Rust API builds the fragment before it knows the pixel), then the insert.
#[allow(clippy::too_many_arguments)]
fn rust_insert<A: Arithmetic>(
    r: &mut DynFramebuffer<'_, A>,
    x: u32,
    y: u32,
    rgba: [f32; 4],
    depth: f32,
    key: Option<u32>,
    straight: bool,
) -> MlabStatus {
    if x >= r.width() || y >= r.height() {
        return MlabStatus::OutOfBounds;
    }
    let f = if straight {
        Fragment::straight_rgba(rgba, depth)
    } else {
        Fragment::premultiplied_rgba(rgba, depth)
    };
    match f {
        Err(err) => MlabStatus::from(err),
        Ok(f) => r
            .insert(x, y, &key.map_or(f, |k| f.with_key(k)))
            .map_or_else(MlabStatus::from, |()| MlabStatus::Ok),
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
        let want = rust_insert(&mut r, e.x, e.y, e.rgba, e.depth, None, straight);
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
            let st = rust_insert(&mut r, e.x, e.y, e.rgba, e.depth, None, straight);
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

/// A stream of keyed fragments: keys shared by runs of fragments (the primitives' ids),
/// some arbitrary, some near `u32::MAX`; the same pixels and values as `stream`.
fn keyed_stream(seed: u64, n: usize) -> Vec<MlabPixelFragmentKeyed> {
    let mut rng = Rng(seed);
    (0..n)
        .map(|i| {
            let MlabPixelFragment { x, y, rgba, depth } = event(&mut rng);
            let key = match rng.below(8) {
                0 => rng.next() as u32,
                1 => u32::MAX - (i / 7) as u32,
                _ => (i / 6) as u32,
            };
            MlabPixelFragmentKeyed { x, y, rgba, depth, key }
        })
        .collect()
}

/// The Rust API's fragment of a keyed event, and the status the C API must return for it.
fn rust_keyed<A: Arithmetic>(r: &mut DynFramebuffer<'_, A>, e: &MlabPixelFragmentKeyed, straight: bool) -> MlabStatus {
    rust_insert(r, e.x, e.y, e.rgba, e.depth, Some(e.key), straight)
}

/// A random keyed span (some lanes invalid).
fn keyed_span(rng: &mut Rng) -> MlabFragmentSpanKeyed {
    let mut span = MlabFragmentSpanKeyed {
        r: [0.0; 8],
        g: [0.0; 8],
        b: [0.0; 8],
        a: [0.0; 8],
        depth: [0.0; 8],
        key: [0; 8],
    };
    let key = rng.next() as u32;
    for lane in 0..8 {
        let e = event(rng);
        [span.r[lane], span.g[lane], span.b[lane], span.a[lane]] = e.rgba;
        span.depth[lane] = e.depth;
        // Mostly one primitive over the span, sometimes another.
        span.key[lane] = if rng.below(4) == 0 { rng.next() as u32 } else { key };
    }
    span
}

fn keyed_lanes(span: &MlabFragmentSpanKeyed) -> FragmentLanes {
    FragmentLanes {
        color: [span.r, span.g, span.b],
        alpha: span.a,
        depth: span.depth,
        key: Some(span.key),
    }
}

/// The keyed inserts (per pixel, span, batch; straight and premultiplied) against
/// `DynFramebuffer` with `Fragment::with_key` and `FragmentLanes::key`, mixed with unkeyed
/// per-pixel inserts.
fn check_keyed<A: Arithmetic>(method: MlabMethod, layers: u32, arith: MlabArithmetic) {
    let kind = match method {
        MLAB_METHOD_MLAB => Layers::Mlab(layers as usize),
        _ => Layers::Hybrid(layers as usize),
    };
    let what = format!("keyed {kind:?} arith {arith}");
    let events = keyed_stream(0x51ed_270b_2f4a_9e33 ^ (layers as u64) << 8 ^ method as u64, 900);

    let mut c = c_fb(method, layers, arith, W, H);
    let mut storage = vec![Row::EMPTY; kind.rows_needed(W, H).unwrap()];
    let mut r = DynFramebuffer::<A>::new_cleared(kind, &mut storage, W, H).unwrap();
    let mut errors = 0;
    for (i, e) in events.iter().enumerate() {
        let [cr, cg, cb, ca] = e.rgba;
        let straight = i % 3 != 0;
        let keyed = i % 5 != 4;
        // SAFETY: `c.fb` is initialized over its live storage.
        let got = unsafe {
            match (keyed, straight) {
                (true, true) => mlab_insert_straight_keyed(&mut c.fb, e.x, e.y, cr, cg, cb, ca, e.depth, e.key),
                (true, false) => mlab_insert_premultiplied_keyed(&mut c.fb, e.x, e.y, cr, cg, cb, ca, e.depth, e.key),
                (false, true) => mlab_insert_straight(&mut c.fb, e.x, e.y, cr, cg, cb, ca, e.depth),
                (false, false) => mlab_insert_premultiplied(&mut c.fb, e.x, e.y, cr, cg, cb, ca, e.depth),
            }
        };
        let want = if keyed {
            rust_keyed(&mut r, e, straight)
        } else {
            rust_insert(&mut r, e.x, e.y, e.rgba, e.depth, None, straight)
        };
        assert_eq!(got, want, "{what}: fragment {i} {e:?}");
        errors += (got != MlabStatus::Ok) as usize;
    }
    assert!(errors > 20 && errors < 300, "{what}: some bad fragments ({errors})");
    same(&c.bytes(), &rust_bytes(&r), &format!("{what}: per-pixel inserts"));
    check_resolves(&c, &r, &what);

    // Keyed spans on top.
    let mut rng = Rng(layers as u64 * 91 + method as u64);
    for i in 0..120 {
        let x = rng.below(W as u64 - 7) as u32 + if i % 5 == 0 { 7 } else { 0 };
        let y = rng.below(H as u64) as u32;
        let mask = rng.below(256) as u8;
        let span = keyed_span(&mut rng);
        let straight = i % 2 == 0;
        let mut refused = 0xeeu8;
        // SAFETY: initialized framebuffer, a span to read, a byte to write.
        let got = unsafe {
            if straight {
                mlab_insert_span_straight_keyed(&mut c.fb, x, y, &span, mask, &mut refused)
            } else {
                mlab_insert_span_premultiplied_keyed(&mut c.fb, x, y, &span, mask, &mut refused)
            }
        };
        let lanes = keyed_lanes(&span);
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
                assert_eq!(got == MlabStatus::Ok, invalid.0 == 0, "{what}: span {i}: {got:?}");
            }
        }
    }
    same(&c.bytes(), &rust_bytes(&r), &format!("{what}: span inserts"));
    check_resolves(&c, &r, &what);

    // The keyed batch, resumed after each refused fragment, equals per-pixel keyed inserts.
    for straight in [true, false] {
        let mut c = c_fb(method, layers, arith, W, H);
        let mut storage = vec![Row::EMPTY; kind.rows_needed(W, H).unwrap()];
        let mut r = DynFramebuffer::<A>::new_cleared(kind, &mut storage, W, H).unwrap();
        let want_stops: Vec<_> = events
            .iter()
            .enumerate()
            .map(|(i, e)| (i, rust_keyed(&mut r, e, straight)))
            .filter(|&(_, st)| st != MlabStatus::Ok)
            .collect();
        let mut got_stops = Vec::new();
        let mut start = 0;
        while start < events.len() {
            let rest = &events[start..];
            let mut inserted = usize::MAX;
            // SAFETY: `rest.len()` fragments to read, a size_t to write.
            let st = unsafe {
                if straight {
                    mlab_insert_batch_straight_keyed(&mut c.fb, rest.as_ptr(), rest.len(), &mut inserted)
                } else {
                    mlab_insert_batch_premultiplied_keyed(&mut c.fb, rest.as_ptr(), rest.len(), &mut inserted)
                }
            };
            if st == MlabStatus::Ok {
                assert_eq!(inserted, rest.len());
                break;
            }
            got_stops.push((start + inserted, st));
            start += inserted + 1;
        }
        assert_eq!(got_stops, want_stops, "{what}: keyed batch stops (straight {straight})");
        same(
            &c.bytes(),
            &rust_bytes(&r),
            &format!("{what}: keyed batch (straight {straight})"),
        );
        check_resolves(&c, &r, &what);

        // The keys matter for the default arithmetic, and only for it: the same stream
        // without keys gives other bytes in Unbiased, the same in Paper.
        let mut u = c_fb(method, layers, arith, W, H);
        let unkeyed: Vec<_> = events
            .iter()
            .map(|e| MlabPixelFragment {
                x: e.x,
                y: e.y,
                rgba: e.rgba,
                depth: e.depth,
            })
            .collect();
        let mut start = 0;
        while start < unkeyed.len() {
            let rest = &unkeyed[start..];
            let mut inserted = 0;
            // SAFETY: as above.
            let st = unsafe {
                if straight {
                    mlab_insert_batch_straight(&mut u.fb, rest.as_ptr(), rest.len(), &mut inserted)
                } else {
                    mlab_insert_batch_premultiplied(&mut u.fb, rest.as_ptr(), rest.len(), &mut inserted)
                }
            };
            if st == MlabStatus::Ok {
                break;
            }
            start += inserted + 1;
        }
        assert_eq!(
            u.bytes() == c.bytes(),
            arith == MLAB_ARITHMETIC_PAPER,
            "{what}: the keys change the bytes in Unbiased only"
        );
    }
}

#[test]
fn keyed_inserts_equal_the_rust_api_with_keys() {
    for method in [MLAB_METHOD_MLAB, MLAB_METHOD_HYBRID] {
        for layers in 1..=8 {
            check_keyed::<Unbiased>(method, layers, MLAB_ARITHMETIC_UNBIASED);
            check_keyed::<Paper>(method, layers, MLAB_ARITHMETIC_PAPER);
        }
    }
}

/// A keyed stream through bands (a band of the whole and two bands of a band, on three
/// threads; per-pixel, span and batch inserts, coordinates relative to the band) equals the
/// same stream through the whole C framebuffer, the Rust API's whole `DynFramebuffer`, and
/// its `bands_mut`, byte for byte: a band keeps the whole framebuffer's pixel ids.
#[test]
fn keyed_bands_equal_the_whole_framebuffer_and_the_rust_api() {
    struct Band(MlabFramebuffer, u32, u32); // the view, its first line, its lines
    // SAFETY: the band's rows are used by one thread only (the bands do not overlap).
    unsafe impl Send for Band {}
    let (w, h) = (W, 9); // bands of 3 lines, 63 pixels: the first ids are not multiples of 8
    let events: Vec<_> = keyed_stream(77, 3000)
        .into_iter()
        .filter(|e| Fragment::straight_rgba(e.rgba, e.depth).is_ok() && e.x < w && e.y < h)
        .collect();
    let mut rng = Rng(78);
    let spans: Vec<_> = (0..60)
        .map(|_| {
            let (x, y) = (rng.below(w as u64 - 7) as u32, rng.below(h as u64) as u32);
            let mut span = keyed_span(&mut rng);
            for lane in 0..8 {
                // Valid premultiplied fragments, faint (dithered) in every other lane.
                let a = if lane % 2 == 0 { 0.03 } else { 0.6 };
                [span.r[lane], span.g[lane], span.b[lane], span.a[lane]] = [0.5 * a, 0.2 * a, 0.9 * a, a];
                span.depth[lane] = 0.25 * lane as f32 + (rng.below(100) as f32) / 50.0;
            }
            (x, y, span)
        })
        .collect();
    // Per pixel (straight), spans (premultiplied: all valid lanes then), batch (straight),
    // into `fb` for the lines `first..first + lines`, at coordinates relative to `first`.
    let feed = |fb: &mut MlabFramebuffer, first: u32, lines: u32| {
        let inside = |y: u32| (first..first + lines).contains(&y);
        for e in events.iter().filter(|e| inside(e.y)) {
            let [r, g, b, a] = e.rgba;
            // SAFETY: an initialized framebuffer or band, this thread's rows.
            let st = unsafe { mlab_insert_straight_keyed(fb, e.x, e.y - first, r, g, b, a, e.depth, e.key) };
            assert_eq!(st, MlabStatus::Ok);
        }
        for (x, y, span) in spans.iter().filter(|s| inside(s.1)) {
            let mut refused = 0xee;
            // SAFETY: as above.
            let st = unsafe { mlab_insert_span_premultiplied_keyed(fb, *x, y - first, span, 0xff, &mut refused) };
            assert_eq!((st, refused), (MlabStatus::Ok, 0));
        }
        let batch: Vec<_> = events
            .iter()
            .filter(|e| inside(e.y))
            .map(|e| MlabPixelFragmentKeyed {
                y: e.y - first,
                depth: e.depth + 0.5,
                ..*e
            })
            .collect();
        let mut inserted = 0;
        // SAFETY: as above.
        let st = unsafe { mlab_insert_batch_straight_keyed(fb, batch.as_ptr(), batch.len(), &mut inserted) };
        assert_eq!((st, inserted), (MlabStatus::Ok, batch.len()));
    };
    // The same through the Rust API, into a `Framebuffer` (whole or band).
    fn rust_feed<F: Framebuffer>(
        fb: &mut F,
        first: u32,
        events: &[MlabPixelFragmentKeyed],
        spans: &[(u32, u32, MlabFragmentSpanKeyed)],
    ) {
        let lines = fb.height();
        let inside = |y: u32| (first..first + lines).contains(&y);
        for e in events.iter().filter(|e| inside(e.y)) {
            let f = Fragment::straight_rgba(e.rgba, e.depth).unwrap().with_key(e.key);
            fb.insert(e.x, e.y - first, &f).unwrap();
        }
        for (x, y, span) in spans.iter().filter(|s| inside(s.1)) {
            let refused = fb.insert_span_fragments(*x, y - first, &keyed_lanes(span), 0xff);
            assert_eq!(refused.unwrap().0, 0);
        }
        for e in events.iter().filter(|e| inside(e.y)) {
            let f = Fragment::straight_rgba(e.rgba, e.depth + 0.5).unwrap().with_key(e.key);
            fb.insert(e.x, e.y - first, &f).unwrap();
        }
    }
    for (method, layers, arith) in [
        (MLAB_METHOD_MLAB, 4, MLAB_ARITHMETIC_UNBIASED),
        (MLAB_METHOD_HYBRID, 3, MLAB_ARITHMETIC_UNBIASED),
        (MLAB_METHOD_MLAB, 1, MLAB_ARITHMETIC_UNBIASED),
        (MLAB_METHOD_HYBRID, 8, MLAB_ARITHMETIC_UNBIASED),
        (MLAB_METHOD_MLAB, 2, MLAB_ARITHMETIC_PAPER),
    ] {
        let what = format!("method {method} layers {layers} arith {arith}");
        let mut whole = c_fb(method, layers, arith, w, h);
        feed(&mut whole.fb, 0, h);

        let banded = c_fb(method, layers, arith, w, h);
        let (mut top, mut rest, mut mid, mut low) = (banded.fb, banded.fb, banded.fb, banded.fb);
        // SAFETY: initialized framebuffers; the bands are written to structs of their own.
        unsafe {
            assert_eq!(mlab_framebuffer_band(&banded.fb, 0, 3, &mut top), MlabStatus::Ok);
            assert_eq!(mlab_framebuffer_band(&banded.fb, 3, 6, &mut rest), MlabStatus::Ok);
            assert_eq!(mlab_framebuffer_band(&rest, 0, 3, &mut mid), MlabStatus::Ok);
            assert_eq!(mlab_framebuffer_band(&rest, 3, 3, &mut low), MlabStatus::Ok);
        }
        std::thread::scope(|s| {
            for band in [Band(top, 0, 3), Band(mid, 3, 3), Band(low, 6, 3)] {
                let feed = &feed;
                s.spawn(move || {
                    let mut band = band;
                    feed(&mut band.0, band.1, band.2);
                });
            }
        });
        same(
            &banded.bytes(),
            &whole.bytes(),
            &format!("{what}: C bands against the C whole"),
        );

        let kind = match method {
            MLAB_METHOD_MLAB => Layers::Mlab(layers as usize),
            _ => Layers::Hybrid(layers as usize),
        };
        let mut storage = vec![Row::EMPTY; kind.rows_needed(w, h).unwrap()];
        let mut bands_storage = storage.clone();
        macro_rules! rust {
            ($a:ty) => {{
                let mut r = DynFramebuffer::<$a>::new_cleared(kind, &mut storage, w, h).unwrap();
                rust_feed(&mut r, 0, &events, &spans);
                let mut rb = DynFramebuffer::<$a>::new_cleared(kind, &mut bands_storage, w, h).unwrap();
                for (b, mut band) in rb.bands_mut(3).enumerate() {
                    rust_feed(&mut band, 3 * b as u32, &events, &spans);
                }
                (rust_bytes(&r), rust_bytes(&rb))
            }};
        }
        let (want, want_bands) = if arith == MLAB_ARITHMETIC_UNBIASED {
            rust!(Unbiased)
        } else {
            rust!(Paper)
        };
        same(
            &want_bands,
            &want,
            &format!("{what}: Rust bands against the Rust whole"),
        );
        same(
            &whole.bytes(),
            &want,
            &format!("{what}: the C whole against the Rust API"),
        );
        same(&banded.bytes(), &want, &format!("{what}: C bands against the Rust API"));
    }
}

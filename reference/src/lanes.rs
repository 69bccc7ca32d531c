//! Lanes against the scalar kernel: the checks shared by `tests/lanes.rs` and the fuzz
//! targets. Unlike the rest of this crate these call the kernel on both sides (the 8-wide
//! `mlab::lanes` entry points and the scalar ones, pixel by pixel), and require byte-for-byte
//! (rows, tails) and bit-for-bit (resolved f32, pixels) equality; the quantized rows are
//! also compared with the reference model ([`Model::ref_quantize`]). Each check returns
//! `Err` with a message naming the broken property (tests turn it into a proptest failure,
//! the fuzz targets into a panic).

use mlab::glam::Vec3;
use mlab::lanes::{self, FragmentLanes, HybridSpan, LANES, ResolvedLanes};

/// An MLAB span, layer-major (`span[j][lane]`).
type MlabSpan<const M: usize> = [[Row; LANES]; M];
use mlab::{
    Arithmetic, Background, Fragment, Framebuffer, Hybrid, HybridSpanFramebuffer, MlabFramebuffer, Resolved, Row,
    SpanFramebuffer, TailFormat, mlab as listing1, to_rgba8,
};

use crate::model::Model;

/// The backgrounds every resolve check uses: none, an opaque color, and one that is not a
/// valid color (NaN, infinity, negative: backgrounds are not validated, and the lanes must
/// do with them what the scalar code does).
pub const BACKGROUNDS: [Background; 3] = [
    Background::Transparent,
    Background::Opaque(Vec3::new(0.2, 0.5, 1.0)),
    Background::Opaque(Vec3::new(f32::NAN, f32::INFINITY, -1.0)),
];

/// The bits of a resolved pixel: color channels, then transmittance.
pub fn resolved_bits(r: Resolved) -> [u32; 4] {
    let c = r.color.to_array().map(f32::to_bits);
    [c[0], c[1], c[2], r.transmittance.to_bits()]
}

macro_rules! ensure {
    ($cond:expr, $($msg:tt)*) => {
        if !$cond {
            return Err(format!($($msg)*));
        }
    };
}

/// Resolved lanes against the scalar resolve of each pixel, bit for bit (`get` of each
/// lane, `None` past the last), and [`ResolvedLanes::rgba8`] and [`ResolvedLanes::pixels`]
/// against the scalar pixel writers for every background of [`BACKGROUNDS`].
pub fn check_resolved_lanes(got: &ResolvedLanes, want: &[Resolved; LANES]) -> Result<(), String> {
    for (lane, w) in want.iter().enumerate() {
        let g = got.get(lane).map(resolved_bits);
        ensure!(
            g == Some(resolved_bits(*w)),
            "lane {lane} resolve: {g:x?} vs scalar {w:?}"
        );
    }
    ensure!(got.get(LANES).is_none(), "a lane past the last: {:?}", got.get(LANES));
    for bg in BACKGROUNDS {
        let rgba = got.rgba8(bg);
        let pixels = got.pixels(bg);
        for (lane, w) in want.iter().enumerate() {
            let p = w.pixel(bg);
            ensure!(
                rgba[lane] == to_rgba8(p),
                "lane {lane} rgba8 {bg:?}: {:?} vs {:?}",
                rgba[lane],
                to_rgba8(p)
            );
            ensure!(
                pixels[lane].to_array().map(f32::to_bits) == p.to_array().map(f32::to_bits),
                "lane {lane} pixel {bg:?}: {:?} vs {p:?}",
                pixels[lane]
            );
        }
    }
    Ok(())
}

/// An MLAB span against 8 scalar arrays, byte for byte.
pub fn check_mlab_rows<const M: usize>(span: &MlabSpan<M>, pixels: &[[Row; M]; LANES]) -> Result<(), String> {
    let got = to_pixel_major(span);
    for (lane, (g, p)) in got.iter().zip(pixels).enumerate() {
        ensure!(g == p, "M = {M} lane {lane}: lanes {g:?}, scalar {p:?}");
    }
    Ok(())
}

/// An MLAB span against 8 scalar arrays: rows byte for byte ([`check_mlab_rows`]);
/// `lanes::mlab_resolve` bit for bit against `resolve_rows` of each pixel
/// ([`check_resolved_lanes`]); the integer RGBA8 resolve of both arrangements
/// (`Framebuffer::resolve_rgba8` of a `SpanFramebuffer` over the span and of an
/// `MlabFramebuffer` over the pixels) against [`crate::resolve_int::rgba8`] for every
/// background.
pub fn check_mlab_span<const M: usize>(span: &MlabSpan<M>, pixels: &[[Row; M]; LANES]) -> Result<(), String> {
    check_mlab_rows(span, pixels)?;
    let want = pixels.map(|p| mlab::resolve_rows(&p));
    for bg in BACKGROUNDS {
        let w = pixels.map(|p| crate::resolve_int::rgba8(&p, bg));
        let mut spans: Vec<Row> = span.iter().flatten().copied().collect();
        let got = mlab_rgba8(&mut SpanFramebuffer::<M>::new(&mut spans, 8, 1), bg);
        ensure!(got == w, "M = {M} span resolve_rgba8 {bg:?}: {got:?} vs {w:?}");
        let mut rows: Vec<Row> = pixels.iter().flatten().copied().collect();
        let got = mlab_rgba8(&mut MlabFramebuffer::<M>::new(&mut rows, 8, 1), bg);
        ensure!(got == w, "M = {M} pixel-major resolve_rgba8 {bg:?}: {got:?} vs {w:?}");
    }
    check_resolved_lanes(&lanes::mlab_resolve(span), &want)
}

/// `resolve_rgba8` of an 8 x 1 framebuffer.
fn mlab_rgba8<F: Framebuffer, E: core::fmt::Debug>(fb: &mut Result<F, E>, bg: Background) -> [[u8; 4]; LANES] {
    let mut out = [[0u8; 4]; LANES];
    fb.as_mut().expect("8 x 1").resolve_rgba8(&mut out, bg).expect("8 x 1");
    out
}

/// An HT span against 8 scalar pixels: head rows and tail bytes equal.
pub fn check_hybrid_rows<const K: usize, A: Arithmetic>(
    span: &HybridSpan<K, A>,
    pixels: &[Hybrid<K, A>; LANES],
) -> Result<(), String> {
    for (lane, p) in pixels.iter().enumerate() {
        for j in 0..K {
            ensure!(
                span.head[j][lane] == p.head()[j],
                "{} K = {K} lane {lane} head row {j}: lanes {:?}, scalar {:?}",
                A::NAME,
                span.head[j][lane],
                p.head()[j]
            );
        }
        ensure!(
            span.tails[lane].to_bytes() == p.tail().to_bytes(),
            "{} K = {K} lane {lane} tail: lanes {:?}, scalar {:?}",
            A::NAME,
            span.tails[lane],
            p.tail()
        );
    }
    Ok(())
}

/// An HT span against 8 scalar pixels: bytes ([`check_hybrid_rows`]); `lanes::hybrid_resolve`
/// bit for bit against `Hybrid::resolve` ([`check_resolved_lanes`]);
/// `Framebuffer::resolve_rgba8` of a `HybridSpanFramebuffer` over the span against the
/// reference integer resolve (`resolve_int::ht_rgba8`) for every background.
pub fn check_hybrid_span<const K: usize, A: Arithmetic>(
    span: &HybridSpan<K, A>,
    pixels: &[Hybrid<K, A>; LANES],
) -> Result<(), String> {
    check_hybrid_rows(span, pixels)?;
    let want = pixels.map(|p| p.resolve());
    for bg in BACKGROUNDS {
        let mut rows: Vec<Row> = span.head.iter().flatten().copied().collect();
        rows.extend(span.tails.iter().map(|t| Row::from_bytes(t.to_bytes())));
        let got = mlab_rgba8(&mut HybridSpanFramebuffer::<K, A>::new(&mut rows, 8, 1), bg);
        let w = pixels.map(|p| crate::resolve_int::ht_rgba8(p.head(), p.tail(), bg));
        ensure!(got == w, "K = {K} hybrid_resolve_rgba8 {bg:?}: {got:?} vs {w:?}");
    }
    check_resolved_lanes(&lanes::hybrid_resolve(span), &want)
}

/// Validation and quantization in lanes on 8 raw fragments `(color, alpha, depth)`, given
/// as premultiplied and as straight color: `FragmentLanes::quantize_with::<A>` and
/// `quantize_straight_with::<A>` report exactly the lanes of `mask` as valid or invalid,
/// valid exactly where the scalar constructor accepts, with the scalar row (`A::quantize`)
/// and the reference row ([`Model::ref_quantize`]); every other lane holds `Row::EMPTY`.
/// Then `Framebuffer::insert_span_fragments` on one span of MLAB (M = 2) and HT (K = 1)
/// report the invalid lanes and equal the scalar inserts of the valid rows. For the
/// default arithmetic, `quantize`, `quantize_straight` and `mlab_insert_fragments` give
/// the same.
///
/// Once with content keys and once with stable keys (`FragmentLanes::key`, derived from the
/// raw bits); the lanes' hashes equal `Fragment::hash` and the reference hash of their pixel.
pub fn check_fragment_lanes<A: Model>(raws: &[([f32; 3], f32, f32); LANES], mask: u8) -> Result<(), String> {
    let stable = raws.map(|r| r.0[0].to_bits().rotate_left(7) ^ r.2.to_bits().wrapping_mul(0x9e37_79b9));
    check_fragment_lanes_keyed::<A>(raws, None, mask)?;
    check_fragment_lanes_keyed::<A>(raws, Some(stable), mask)
}

fn check_fragment_lanes_keyed<A: Model>(
    raws: &[([f32; 3], f32, f32); LANES],
    key: Option<[u32; LANES]>,
    mask: u8,
) -> Result<(), String> {
    let fl = FragmentLanes {
        color: core::array::from_fn(|c| core::array::from_fn(|l| raws[l].0[c])),
        alpha: raws.map(|r| r.1),
        depth: raws.map(|r| r.2),
        key,
    };
    check_quantize_lanes::<A>(raws, &fl, mask)?;
    check_span_fragments::<A>(&fl, mask)
}

/// [`check_fragment_lanes`]'s quantization in lanes, both constructors, against the scalar
/// constructors, quantization and hash and the reference row and hash.
fn check_quantize_lanes<A: Model>(
    raws: &[([f32; 3], f32, f32); LANES],
    fl: &FragmentLanes,
    mask: u8,
) -> Result<(), String> {
    let (name, key) = (A::NAME, fl.key);
    // Pixel ids of a span that does not start at 0, wrapping past u32::MAX.
    let first = u32::MAX - 3;
    for straight in [false, true] {
        let q = if straight {
            fl.quantize_straight_at::<A>(mask, first)
        } else {
            fl.quantize_at::<A>(mask, first)
        };
        ensure!(q.valid & q.invalid == 0, "lanes both valid and invalid: {q:?}");
        ensure!(
            q.valid | q.invalid == mask,
            "not exactly the lanes of {mask:#010b}: {q:?}"
        );
        for (lane, &(c, a, z)) in raws.iter().enumerate() {
            let on = mask >> lane & 1 == 1;
            let scalar = if straight {
                Fragment::straight(Vec3::from_array(c), a, z)
            } else {
                Fragment::premultiplied(Vec3::from_array(c), a, z)
            };
            let scalar = scalar.map(|f| key.map_or(f, |k| f.with_key(k[lane])));
            let pixel = first.wrapping_add(lane as u32);
            match (on, scalar) {
                (true, Ok(f)) => {
                    ensure!(
                        q.valid >> lane & 1 == 1,
                        "lane {lane}: scalar accepts {:?}, lanes refuse (straight {straight})",
                        raws[lane]
                    );
                    let h = f.hash(pixel);
                    let want_h = crate::model::ref_fragment_hash(crate::model::ref_key(&f), pixel);
                    ensure!(
                        q.hashes[lane] == h && h == want_h,
                        "lane {lane} hash: lanes {:#x}, scalar {h:#x}, reference {want_h:#x}",
                        q.hashes[lane]
                    );
                    let (row, scalar_row, reference) = (q.rows[lane], A::quantize(&f, h), A::ref_row(&f, pixel));
                    ensure!(
                        row == scalar_row && row == reference,
                        "lane {lane} {name} straight {straight}: lanes {row:?}, scalar {scalar_row:?}, reference {reference:?}"
                    );
                }
                (true, Err(e)) => ensure!(
                    q.invalid >> lane & 1 == 1 && q.rows[lane] == Row::EMPTY,
                    "lane {lane}: scalar refuses {:?} ({e:?}), lanes give {q:?} (straight {straight})",
                    raws[lane]
                ),
                (false, _) => ensure!(q.rows[lane] == Row::EMPTY, "off lane {lane}: {:?}", q.rows[lane]),
            }
        }
    }
    Ok(())
}

/// [`check_fragment_lanes`]'s span inserts of fragments (`Framebuffer::insert_span_fragments`,
/// one span of 8 x 1 pixels, MLAB M = 2 and HT K = 1): invalid lanes reported and left
/// untouched, valid ones the scalar inserts of the quantized rows.
fn check_span_fragments<A: Model>(fl: &FragmentLanes, mask: u8) -> Result<(), String> {
    let q = fl.quantize_at::<A>(mask, 0);
    let mut storage = vec![Row::EMPTY; 16];
    let mut fb = SpanFramebuffer::<2, A>::new_cleared(&mut storage, 8, 1).map_err(|e| format!("{e}"))?;
    let invalid = fb.insert_span_fragments(0, 0, fl, mask).map_err(|e| format!("{e}"))?;
    ensure!(
        invalid.0 == q.invalid,
        "insert_span_fragments (MLAB): {invalid:?} vs {q:?}"
    );
    let span: [[Row; LANES]; 2] = core::array::from_fn(|j| core::array::from_fn(|l| fb.as_rows()[j * LANES + l]));
    let mut expected = [[Row::EMPTY; 2]; LANES];
    for (lane, p) in expected.iter_mut().enumerate() {
        if q.valid >> lane & 1 == 1 {
            listing1::insert_hashed::<A, 2>(p, q.rows[lane], q.hashes[lane]);
        }
    }
    check_mlab_rows(&span, &expected)?;
    let mut storage = vec![Row::EMPTY; 16];
    let mut fb = HybridSpanFramebuffer::<1, A>::new_cleared(&mut storage, 8, 1).map_err(|e| format!("{e}"))?;
    let invalid = fb.insert_span_fragments(0, 0, fl, mask).map_err(|e| format!("{e}"))?;
    ensure!(
        invalid.0 == q.invalid,
        "insert_span_fragments (HT): {invalid:?} vs {q:?}"
    );
    let rows = fb.as_rows();
    let hspan = HybridSpan::<1, A> {
        head: [core::array::from_fn(|l| rows[l])],
        tails: core::array::from_fn(|l| <A::Tail as TailFormat>::from_bytes(rows[LANES + l].to_bytes())),
    };
    let mut hexpected = [Hybrid::<1, A>::new(); LANES];
    for (lane, p) in hexpected.iter_mut().enumerate() {
        if q.valid >> lane & 1 == 1 {
            p.insert_row(q.rows[lane]);
        }
    }
    // Untouched invalid lanes: their tails are still empty.
    for lane in (0..LANES).filter(|&l| q.valid >> l & 1 == 0) {
        ensure!(
            hspan.tails[lane] == <A::Tail as TailFormat>::EMPTY && hspan.head[0][lane] == Row::EMPTY,
            "insert_span_fragments wrote lane {lane}, which is not valid"
        );
    }
    check_hybrid_span(&hspan, &hexpected)
}

/// The span in the per-pixel arrangement, `[pixel][row]` (a transpose).
fn to_pixel_major<const M: usize>(span: &[[Row; LANES]; M]) -> [[Row; M]; LANES] {
    core::array::from_fn(|lane| core::array::from_fn(|j| span[j][lane]))
}

/// The inverse of [`to_pixel_major`].
#[allow(dead_code)]
fn from_pixel_major<const M: usize>(pixels: &[[Row; M]; LANES]) -> [[Row; LANES]; M] {
    core::array::from_fn(|j| core::array::from_fn(|lane| pixels[lane][j]))
}

//! Four of the fuzz targets (the fifth, `batch_stream`, is in [`crate::batch`]). Each takes the raw fuzzer bytes; the first byte chooses the
//! const parameters (rows per pixel), the rest is decoded by [`Input`]. Every target runs
//! each input twice, once in each arithmetic of the kernel ([`Paper`], the paper's
//! rounding and tail, and [`Unbiased`], the default: dithered rounding and the wide
//! tail), against the reference model of that arithmetic ([`Model`]).

use mlab::framebuffer::Pixel;
use mlab::glam::{Vec3, Vec4};
use mlab::half::f16;
use mlab::{
    Arithmetic, Background, BlendingArray, Fragment, Framebuffer, FramebufferError, Grid, Ht, Hybrid, Mlab, Paper,
    PixelMajor, Resolved, Row, Spans, TailFormat, Unbiased, hybrid, hybrid::PaperTail, mlab as mlab_mod, resolve_rows,
    to_rgba8, to_rgba16f,
};

use mlab::lanes::{self, HybridSpan, LANES};

/// An MLAB span, layer-major (`span[j][lane]`).
type MlabSpan<const M: usize> = [[Row; LANES]; M];

use mlab_reference::lanes::{check_fragment_lanes, check_hybrid_span, check_mlab_span};
use mlab_reference::model::{
    Model, RefMlab, composite_rows_f64, ref_bubble, ref_fragment_hash, ref_hybrid, ref_key, ref_row_hash,
    ref_tail_fields, tail_f64,
};
use mlab_reference::oracle::{multilinear_bound, oracle, visibility_bound};

use crate::check::{check_close, check_invariants, check_resolved, distinct_depths, invariants_hold, validate};
use crate::input::Input;

/// The kernel's default arithmetic is [`Unbiased`]: `BlendingArray<M>` is
/// `BlendingArray<M, Unbiased>` (a compile error here if the default changes).
const _: fn(BlendingArray<1>) -> BlendingArray<1, Unbiased> = |a| a;

/// True for the default arithmetic, whose entry points without a type parameter
/// (`mlab::merge`, `lanes::mlab_insert`, `FragmentLanes::quantize`, ...) the targets
/// check too.
fn is_default<A: Arithmetic>() -> bool {
    A::NAME == Unbiased::NAME
}

/// Most fragments per stream (longer inputs are cut).
pub const MAX_FRAGMENTS: usize = 64;

/// The limit the targets check for a resolved tail's color: the documented
/// `COLOR_MAX * (1/255)` in f32 of the arithmetic's tail (`1023` for the paper's, `8191`
/// for the wide one), with the color maximum taken from the reference layout (equal to the
/// kernel's `TailFormat::COLOR_MAX`, checked by `rows_from_bytes`). Finding F1, the tail
/// amplifying its light above it, was fixed in d37150f: the color factor
/// `g = (1 - T_tail) / S_a` is evaluated as `S_n / n` and clamped to at most 1 (`S_n <= n`
/// but for rounding), and where the mean alpha exceeds 1 (arbitrary bytes) the mean is
/// clamped to 1 and `g = 1 / S_a < 1` (`resolve::tail_lanes`).
pub fn tail_color_limit<A: Model>() -> f32 {
    A::TAIL.max(0) as f32 * (1.0 / 255.0)
}

/// `(premultiplied color, alpha, depth)` of an accepted fragment, for the oracle.
fn parts(f: &Fragment) -> ([f32; 3], f32, f32) {
    (f.color().to_array(), f.alpha(), f.depth())
}

/// Premultiplied color not above alpha: the condition of the oracle bound.
fn occluding(frags: &[([f32; 3], f32, f32)]) -> bool {
    frags.iter().all(|(c, a, _)| c.iter().all(|v| v <= a))
}

/// The f64 oracle over a black background (the transparent layers alone), as
/// [`check_close`] compares it with a resolved pixel.
fn exact(frags: &[([f32; 3], f32, f32)]) -> ([f64; 3], f64) {
    oracle(frags, [0.0; 3])
}

/// A lanes check of `mlab_reference::lanes`: a failure is a crash.
fn lanes_ok(r: Result<(), String>) {
    if let Err(e) = r {
        panic!("lanes differ from scalar: {e}");
    }
}

// ---------------------------------------------------------------------------------------
// mlab_stream

/// `mlab_stream`: M from the first byte (1, 2, 3, 4 or 8), then a stream of fragments; the
/// stream runs in both arithmetics.
pub fn mlab_stream(data: &[u8]) {
    let mut input = Input::new(data);
    let Some(sel) = input.u8() else { return };
    mlab_stream_a::<Paper>(sel, input.clone());
    mlab_stream_a::<Unbiased>(sel, input);
}

fn mlab_stream_a<A: Model>(sel: u8, mut input: Input) {
    match sel % 5 {
        0 => mlab_stream_m::<1, A>(&mut input),
        1 => mlab_stream_m::<2, A>(&mut input),
        2 => mlab_stream_m::<3, A>(&mut input),
        3 => mlab_stream_m::<4, A>(&mut input),
        _ => mlab_stream_m::<8, A>(&mut input),
    }
}

fn mlab_stream_m<const M: usize, A: Model>(input: &mut Input) {
    let name = A::NAME;
    let mut array = BlendingArray::<M, A>::new();
    let mut reference = RefMlab::new::<A>(M);
    // Lanes: 8 pixels; lane 0 gets every fragment (it must equal `array`), the others the
    // fragments their bit of `lane_mask(n)` selects; off lanes are handed a garbage row.
    let mut span: MlabSpan<M> = [[Row::EMPTY; LANES]; M];
    let mut lane_arrays = [[Row::EMPTY; M]; LANES];
    let mut raws = Vec::new();
    let mut accepted = Vec::new();
    // Exact background visibility: the product of (1 - alpha).
    let mut visibility = 1.0f64;
    // Quantization error of each accepted fragment, in steps.
    let mut quant = Vec::new();
    while accepted.len() < MAX_FRAGMENTS {
        let Some(raw) = input.raw_fragment() else { break };
        raws.push(raw);
        if raws.len() == LANES {
            fragment_lanes::<A>(&raws, lane_mask(accepted.len() + 7));
            raws.clear();
        }
        let Some(f) = validate(&raw) else { continue };
        // The reference row (equal to the kernel's quantization in `A`: checked by `validate`)
        // and hash, of pixel 0 (`BlendingArray::insert`).
        let row = A::ref_row(&f, 0);
        let h = ref_fragment_hash(ref_key(&f), 0);
        array.insert(&f);
        let mask = lane_mask(accepted.len());
        let rows8 = lane_rows(row, mask);
        lanes::mlab_insert_hashed::<A, _>(&mut span, &rows8, &[h; LANES], mask);
        for (lane, a) in lane_arrays.iter_mut().enumerate() {
            if mask >> lane & 1 == 1 {
                mlab_mod::insert_hashed::<A, _>(a, rows8[lane], h);
            }
        }
        assert_eq!(
            to_pixel_major(&span),
            lane_arrays,
            "M = {M} {name}: lanes differ from scalar, mask {mask:#010b}"
        );
        assert_eq!(&lane_arrays[0], array.rows());
        lanes_ok(check_mlab_span(&span, &lane_arrays));
        reference.insert(row, h);
        accepted.push(parts(&f));
        quant.push(A::quant_error(f.alpha()));
        visibility *= 1.0 - f64::from(f.alpha());
        let n = accepted.len();
        let rows = array.rows();
        assert_eq!(
            rows.as_slice(),
            reference.rows().as_slice(),
            "M = {M} {name}: differs from reference Listing 1 after {accepted:?}"
        );
        check_invariants(rows, &accepted);
        let filled = rows.iter().filter(|r| !r.is_empty()).count();
        assert_eq!(filled, n.min(M), "M = {M} {name}: {rows:?} after {n} fragments");
        let r = array.resolve();
        check_resolved(r, M as f32, &accepted);
        // Every insert into a full array merges: `n - M` merges so far.
        let bound = visibility_bound(&quant, n.saturating_sub(M), A::MERGE_ERROR);
        let err = (f64::from(r.transmittance) - visibility).abs();
        assert!(
            err <= bound,
            "M = {M} {name}: visibility {r:?} vs exact {visibility} (error {err} > {bound}) after {accepted:?}"
        );
    }
    let n = accepted.len();
    if n <= M && occluding(&accepted) {
        check_close(array.resolve(), exact(&accepted), multilinear_bound(&quant), &accepted);
    }
    check_int_resolve(array.rows(), &accepted);
}

/// The integer RGBA8 resolve of MLAB rows (`SpanFramebuffer::resolve_rgba8` and
/// `MlabFramebuffer::resolve_rgba8` of one 8-pixel span holding them in every lane) against
/// the reference formula byte for byte, and the reference against the exact composite of
/// the rows within the derived bound (`mlab_reference::resolve_int`), over a transparent,
/// a black, a white and a colored background.
fn check_int_resolve<const M: usize>(rows: &[Row; M], context: &dyn core::fmt::Debug) {
    for bg in [
        Background::Transparent,
        Background::Opaque(Vec3::ZERO),
        Background::Opaque(Vec3::ONE),
        Background::Opaque(Vec3::new(0.2, 0.5, 0.7)),
    ] {
        let want = mlab_reference::resolve_int::rgba8(rows, bg);
        let mut pm: Vec<Row> = (0..LANES).flat_map(|_| rows.iter().copied()).collect();
        let mut out = [[0u8; 4]; LANES];
        Grid::<mlab::Mlab<M>, PixelMajor>::new(&mut pm, 8, 1)
            .expect("8 x 1")
            .resolve_rgba8(&mut out, bg)
            .expect("8 x 1");
        assert_eq!(
            out, [want; LANES],
            "M = {M} pixel-major integer resolve {bg:?} of {rows:?} ({context:?})"
        );
        let mut sp: Vec<Row> = rows.iter().flat_map(|&r| [r; LANES]).collect();
        Grid::<mlab::Mlab<M>, Spans>::new(&mut sp, 8, 1)
            .expect("8 x 1")
            .resolve_rgba8(&mut out, bg)
            .expect("8 x 1");
        assert_eq!(
            out, [want; LANES],
            "M = {M} span integer resolve {bg:?} of {rows:?} ({context:?})"
        );
        let exact = mlab_reference::resolve_int::exact(rows, bg);
        let bound = mlab_reference::resolve_int::bound(rows, bg);
        for ch in 0..4 {
            let err = (f64::from(want[ch]) - exact[ch]).abs();
            assert!(
                err <= bound[ch] + 1e-9,
                "M = {M} integer resolve {bg:?} of {rows:?}: channel {ch} {} vs exact {} (bound {}) ({context:?})",
                want[ch],
                exact[ch],
                bound[ch]
            );
        }
    }
}

// ---------------------------------------------------------------------------------------
// hybrid_stream

/// `hybrid_stream`: K from the first byte (0, 1, 2, 4 or 8), then a stream of fragments,
/// then the seed of a permutation; the stream runs in both arithmetics.
pub fn hybrid_stream(data: &[u8]) {
    let mut input = Input::new(data);
    let Some(sel) = input.u8() else { return };
    hybrid_stream_a::<Paper>(sel, input.clone());
    hybrid_stream_a::<Unbiased>(sel, input);
}

fn hybrid_stream_a<A: Model>(sel: u8, mut input: Input) {
    match sel % 5 {
        0 => hybrid_stream_k::<0, A>(&mut input),
        1 => hybrid_stream_k::<1, A>(&mut input),
        2 => hybrid_stream_k::<2, A>(&mut input),
        3 => hybrid_stream_k::<4, A>(&mut input),
        _ => hybrid_stream_k::<8, A>(&mut input),
    }
}

fn hybrid_stream_k<const K: usize, A: Model>(input: &mut Input) {
    let name = A::NAME;
    let mut ht = Hybrid::<K, A>::new();
    let mut span = HybridSpan::<K, A>::default();
    let mut lane_px = [Hybrid::<K, A>::new(); LANES];
    let mut frags = Vec::new();
    let mut rows = Vec::new();
    // The stream ends at a fragment tag 0xff (so the permutation seed can follow) or at the end.
    while frags.len() < MAX_FRAGMENTS {
        let Some(raw) = input.raw_fragment() else { break };
        if raw.ctor == crate::input::Ctor::PremultipliedRgba && raw.z.to_bits() == 0xffff_ffff {
            break;
        }
        let Some(f) = validate(&raw) else { continue };
        let row = A::ref_row(&f, 0);
        ht.insert(&f);
        let mask = lane_mask(frags.len());
        let rows8 = lane_rows(row, mask);
        lanes::hybrid_insert(&mut span, &rows8, mask);
        for (lane, px) in lane_px.iter_mut().enumerate() {
            if mask >> lane & 1 == 1 {
                px.insert_row(rows8[lane]);
            }
        }
        lanes_ok(check_hybrid_span(&span, &lane_px));
        assert_eq!(lane_px[0], ht);
        frags.push(f);
        rows.push(row);
        let (head, tail) = ref_hybrid(K, &rows, A::TAIL);
        assert_eq!(
            ht.head().as_slice(),
            head.as_slice(),
            "K = {K} {name}: head differs from the reference after {rows:?}"
        );
        assert_eq!(
            ht.tail().to_bytes(),
            tail,
            "K = {K} {name}: tail {:?} differs from the reference {:?} after {rows:?}",
            ht.tail(),
            A::TAIL.fields(tail)
        );
        check_invariants(ht.head(), &rows);
        check_resolved(ht.resolve(), K as f32 + tail_color_limit::<A>(), &rows);
    }
    check_ht_int_resolve(&ht, &rows);
    let n = frags.len();
    let accepted: Vec<_> = frags.iter().map(parts).collect();
    if n <= K {
        assert_eq!(
            ht.tail(),
            <A::Tail as TailFormat>::EMPTY,
            "K = {K} {name}: tail used with {n} fragments"
        );
        if occluding(&accepted) {
            let quant: Vec<f64> = frags.iter().map(|f| A::quant_error(f.alpha())).collect();
            check_close(ht.resolve(), exact(&accepted), multilinear_bound(&quant), &accepted);
        }
    }
    if !distinct_depths(&rows) {
        return;
    }
    // Order independence: a shuffled and a reversed stream give the same bytes and pixel.
    let mut seed = input.u32().unwrap_or(0x9e37_79b9) | 1;
    let mut order: Vec<usize> = (0..n).collect();
    for i in (1..n).rev() {
        seed ^= seed << 13;
        seed ^= seed >> 17;
        seed ^= seed << 5;
        order.swap(i, seed as usize % (i + 1));
    }
    let reversed: Vec<usize> = (0..n).rev().collect();
    for order in [order, reversed] {
        let mut other = Hybrid::<K, A>::new();
        for &i in &order {
            other.insert(&frags[i]);
        }
        assert_eq!(
            other, ht,
            "K = {K} {name}: HT depends on submission order {order:?} of {rows:?}"
        );
        let (a, b) = (other.resolve(), ht.resolve());
        assert_eq!(a.transmittance.to_bits(), b.transmittance.to_bits());
        assert_eq!(
            a.color.to_array().map(f32::to_bits),
            b.color.to_array().map(f32::to_bits)
        );
    }
}

/// The integer RGBA8 resolve of HT (`check_hybrid_span` compares the kernel's with the
/// reference formula after every fragment): the reference against the exact composite of the
/// head and tail within the derived bound (`mlab_reference::resolve_int::ht_bound`), over a
/// transparent, a black, a white and a colored background.
fn check_ht_int_resolve<const K: usize, A: Model>(ht: &Hybrid<K, A>, rows: &[Row]) {
    for bg in [
        Background::Transparent,
        Background::Opaque(Vec3::ZERO),
        Background::Opaque(Vec3::ONE),
        Background::Opaque(Vec3::new(0.2, 0.5, 0.7)),
    ] {
        let (head, tail) = (ht.head().as_slice(), ht.tail());
        let got = mlab_reference::resolve_int::ht_rgba8(head, tail, bg);
        let exact = mlab_reference::resolve_int::ht_exact(head, tail, bg);
        let bound = mlab_reference::resolve_int::ht_bound(head, tail, bg);
        for ch in 0..4 {
            let err = (f64::from(got[ch]) - exact[ch]).abs();
            assert!(
                err <= bound[ch] + 1e-9,
                "K = {K} {} integer HT resolve {bg:?}: channel {ch} {} vs exact {} (bound {}) after {rows:?}",
                A::NAME,
                got[ch],
                exact[ch],
                bound[ch]
            );
        }
    }
}

// ---------------------------------------------------------------------------------------
// Lanes differentials (lanes == scalar, byte for byte and bit for bit)

/// A mask for the n-th fragment of a stream: lane 0 always on, the others scattered.
pub fn lane_mask(n: usize) -> u8 {
    1 | ((n as u32 + 1).wrapping_mul(0x9e37_79b9) >> 24) as u8
}

/// A garbage row handed to lanes that are off (a NaN depth and full color): it must never
/// reach a pixel.
pub const OFF_LANE_ROW: Row = Row::from_bytes([0xab, 0xcd, 0xef, 0x01, 0xff, 0xff, 0xff, 0xff]);

/// `row` in the lanes that are on, [`OFF_LANE_ROW`] in the others.
pub fn lane_rows(row: Row, mask: u8) -> [Row; LANES] {
    core::array::from_fn(|lane| if mask >> lane & 1 == 1 { row } else { OFF_LANE_ROW })
}

/// The 8 raw fragments' `(color, alpha, depth)` as given, whatever constructor they were
/// drawn for, into [`check_fragment_lanes`] (both constructors, premultiplied and straight).
fn fragment_lanes<A: Model>(raws: &[crate::input::RawFragment], mask: u8) {
    let raws: [([f32; 3], f32, f32); LANES] = core::array::from_fn(|l| (raws[l].color, raws[l].a, raws[l].z));
    lanes_ok(check_fragment_lanes::<A>(&raws, mask));
}

// ---------------------------------------------------------------------------------------
// rows_from_bytes

/// Bytes of a row, or `fill` when the input is exhausted.
fn row_or(input: &mut Input, fill: Row) -> Row {
    input.array::<8>().map(Row::from_bytes).unwrap_or(fill)
}

/// Layout of any 8 bytes as a row and as a tail of both layouts, checked against the
/// documented tables.
pub fn check_layout(b: [u8; 8]) {
    let w = [
        u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        u32::from_le_bytes([b[4], b[5], b[6], b[7]]),
    ];
    let row = Row::from_bytes(b);
    assert_eq!(row.to_bytes(), b);
    assert_eq!(row.words(), w);
    assert_eq!(Row::from_words(w), row);
    assert_eq!(row.color(), [b[0], b[1], b[2]]);
    assert_eq!(row.transmittance(), b[3]);
    assert_eq!((row.color(), row.transmittance()), ([b[0], b[1], b[2]], b[3]));
    assert_eq!(row.depth().to_bits(), w[1]);
    assert_eq!(row.is_empty(), b == [0, 0, 0, 255, 0, 0, 0x80, 0x7f]);
    assert_eq!(row.is_invisible(), b[..4] == [0, 0, 0, 255]);
    // The paper's tail: two words, spare bits 30..32 of word0.
    let tail = PaperTail::from_bytes(b);
    assert_eq!(tail.to_bytes(), b);
    assert_eq!(mlab::Row::from_bytes(tail.to_bytes()).words(), w);
    assert_eq!(
        <PaperTail as mlab::TailFormat>::from_bytes(mlab::Row::from_words(w).to_bytes()),
        tail
    );
    assert_eq!(
        tail.color_sum(),
        [w[0] & 1023, (w[0] >> 10) & 1023, (w[0] >> 20) & 1023]
    );
    assert_eq!(tail.alpha_sum(), w[1] & 0xffff);
    assert_eq!(tail.count(), w[1] >> 16);
    check_tail_fields::<Paper>(b);
    // The wide tail: one little-endian u64.
    let v = u64::from_le_bytes(b);
    let wide = mlab::Tail::from_bytes(b);
    assert_eq!(wide.to_bytes(), b);
    assert_eq!(u64::from_le_bytes(wide.to_bytes()), v);
    assert_eq!(mlab::Row::from_bytes(wide.to_bytes()).words(), w);
    assert_eq!(
        <mlab::Tail as mlab::TailFormat>::from_bytes(mlab::Row::from_words(w).to_bytes()),
        wide
    );
    check_tail_fields::<Unbiased>(b);
}

/// The tail of `A` read from any 8 bytes: fields equal to the reference layout's,
/// `saturated` exactly when a field is at its maximum, and `from_sums` saturating each
/// field (with the spare bits 0), for the fields as read and for values past them.
fn check_tail_fields<A: Model>(b: [u8; 8]) {
    let layout = A::TAIL;
    assert_eq!(
        layout.max(0),
        u64::from(<A::Tail as TailFormat>::COLOR_MAX),
        "{}: the reference color field and the kernel's COLOR_MAX differ",
        A::NAME
    );
    let t = <A::Tail as TailFormat>::from_bytes(b);
    let f = layout.fields(b);
    assert_eq!(tail_fields(t), f, "{} tail fields of {b:02x?}", A::NAME);
    assert_eq!(t.saturated(), layout.saturated(b), "{} saturated() of {t:?}", A::NAME);
    let sums = |f: [u64; 5]| {
        let f = f.map(|x| u32::try_from(x).unwrap_or(u32::MAX));
        <A::Tail as TailFormat>::from_sums([f[0], f[1], f[2]], f[3], f[4]).to_bytes()
    };
    assert_eq!(sums(f), layout.pack(f, [0; 8]), "{} from_sums of {f:?}", A::NAME);
    // Past the maxima: the raw bytes as larger numbers (bits beyond the field kept).
    let v = u64::from_le_bytes(b);
    let big: [u64; 5] = core::array::from_fn(|i| (v >> (8 * i)) & 0xff_ffff);
    let sat: [u64; 5] = core::array::from_fn(|i| big[i].min(layout.max(i)));
    assert_eq!(sums(big), layout.pack(sat, [0; 8]), "{} from_sums of {big:?}", A::NAME);
}

fn tail_fields<T: TailFormat>(t: T) -> [u64; 5] {
    let [r, g, b] = t.color_sum();
    [r, g, b, t.alpha_sum(), t.count()].map(u64::from)
}

/// The merge of two arbitrary rows in both arithmetics: byte-equal to the reference
/// merges (the default `mlab::merge` to the unbiased one), each product within
/// `A::MERGE_ERROR` steps of the exact one (T always, colors unless they saturate at 255),
/// and `color <= 255 - T` kept when both rows have it (documented for both arithmetics).
///
/// The hash of the merge (the inserted fragment's) is taken from the rows' bits, so that
/// the input reaches every dither.
pub fn check_merges(front: Row, back: Row) {
    let h = front.words()[1].rotate_left(16) ^ back.words()[0];
    assert_eq!(
        <mlab::Unbiased as mlab::Arithmetic>::merge(front, back, h),
        <Unbiased as Model>::ref_merge(front, back, h),
        "default merge of {front:?}, {back:?}"
    );
    check_merge::<Paper>(front, back, h);
    check_merge::<Unbiased>(front, back, h);
}

fn check_merge<A: Model>(front: Row, back: Row, h: u32) {
    let name = A::NAME;
    let m = <A as mlab::Arithmetic>::merge(front, back, h);
    assert_eq!(m, A::ref_merge(front, back, h), "{name} merge of {front:?}, {back:?}");
    let [fr, fg, fb, ft, ..] = front.to_bytes().map(f64::from);
    let [br, bg, bb, bt, ..] = back.to_bytes().map(f64::from);
    let [mr, mg, mb, mt, ..] = m.to_bytes().map(f64::from);
    let within = |got: f64, exact: f64| (got - exact).abs() < A::MERGE_ERROR + 1e-9;
    assert!(
        within(mt, ft * bt / 255.0),
        "{name} merge T of {front:?}, {back:?}: {m:?}"
    );
    for (got, (a, b)) in [mr, mg, mb].into_iter().zip([(fr, br), (fg, bg), (fb, bb)]) {
        let exact = a + b * ft / 255.0;
        assert!(
            within(got, exact) || (got == 255.0 && exact > 254.0),
            "{name} merge color of {front:?}, {back:?}: {m:?}"
        );
    }
    // The merged depth: the front's (Paper; Unbiased where the back is not behind), else
    // between the two (the opacity-weighted depth, checked bit for bit by `ref_merge`).
    let (zf, zb, z) = (front.depth(), back.depth(), m.depth());
    if A::NAME == "paper" || zb <= zf {
        assert_eq!(
            z.to_bits(),
            zf.to_bits(),
            "{name} merge depth of {front:?}, {back:?}: {m:?}"
        );
    } else if zf < zb {
        assert!(zf <= z && z <= zb, "{name} merge depth of {front:?}, {back:?}: {m:?}");
    }
    let occludes = |r: Row| r.color().iter().all(|&c| c <= 255 - r.transmittance());
    if occludes(front) && occludes(back) {
        assert!(
            occludes(m),
            "{name} merge of {front:?}, {back:?}: {m:?} has color above alpha"
        );
    }
}

/// `rows_from_bytes`: the first byte picks M (1, 2, 3, 4, 8) and K (0, 1, 2, 4, 8); then
/// M rows, a row to insert, K head rows, a tail, a background (missing bytes: empty rows).
/// The MLAB part and the HT part each run on the same bytes in both arithmetics.
pub fn rows_from_bytes(data: &[u8]) {
    for chunk in data.chunks_exact(8) {
        check_layout(chunk.try_into().unwrap());
    }
    for pair in data.chunks_exact(16) {
        let (a, b) = pair.split_at(8);
        let (a, b) = (
            Row::from_bytes(a.try_into().unwrap()),
            Row::from_bytes(b.try_into().unwrap()),
        );
        check_merges(a, b);
        check_merges(b, a);
    }
    let mut input = Input::new(data);
    let Some(sel) = input.u8() else { return };
    let mut paper = input.clone();
    garbage_mlab_a::<Paper>(sel, &mut paper);
    garbage_mlab_a::<Unbiased>(sel, &mut input);
    assert_eq!(
        paper.remaining(),
        input.remaining(),
        "both arithmetics read the same bytes"
    );
    let mut paper = input.clone();
    garbage_hybrid_a::<Paper>(sel, &mut paper);
    garbage_hybrid_a::<Unbiased>(sel, &mut input);
}

fn garbage_mlab_a<A: Model>(sel: u8, input: &mut Input) {
    match sel % 5 {
        0 => garbage_mlab::<1, A>(input),
        1 => garbage_mlab::<2, A>(input),
        2 => garbage_mlab::<3, A>(input),
        3 => garbage_mlab::<4, A>(input),
        _ => garbage_mlab::<8, A>(input),
    }
}

fn garbage_hybrid_a<A: Model>(sel: u8, input: &mut Input) {
    match sel / 5 % 5 {
        0 => garbage_hybrid::<0, A>(input),
        1 => garbage_hybrid::<1, A>(input),
        2 => garbage_hybrid::<2, A>(input),
        3 => garbage_hybrid::<4, A>(input),
        _ => garbage_hybrid::<8, A>(input),
    }
}

fn garbage_mlab<const M: usize, A: Model>(input: &mut Input) {
    let name = A::NAME;
    let rows: [Row; M] = core::array::from_fn(|_| row_or(input, Row::EMPTY));
    let new = row_or(input, Row::EMPTY);
    let context = (name, &rows, new);
    check_merge::<A>(rows[0], new, ref_row_hash(new, 0));

    // Resolve of any rows: finite, in range, and Eq. 5 evaluated in f64.
    let r = resolve_rows(&rows);
    check_resolved(r, M as f32, &context);
    check_close(r, composite_rows_f64(&rows), 1e-5, &context);
    check_pixels(r, input, &context);
    // The integer RGBA8 resolve of any rows: the reference formula, within its bound.
    check_int_resolve(&rows, &context);

    // Insert of any row into any rows: Listing 1 step by step, never a panic.
    let (mut expected, pushed) = ref_bubble(&rows, new);
    let last = expected[M - 1];
    expected[M - 1] = A::ref_merge(last, pushed, ref_row_hash(new, 0));
    let mut after = rows;
    mlab_mod::insert_with::<A, _>(&mut after, new);
    assert_eq!(
        after.as_slice(),
        expected.as_slice(),
        "{name}: insert {new:?} into {rows:?}"
    );
    if is_default::<A>() {
        let mut d = rows;
        mlab_mod::insert_with::<mlab::Unbiased, _>(&mut d, new);
        assert_eq!(d, after, "the default insert is not {name}'s");
    }
    // Rows that satisfied the invariants keep them for any row that is not NaN or a
    // non-empty row at +infinity.
    let new_ok = new.is_empty() || new.depth() < f32::INFINITY;
    if invariants_hold(&rows) && new_ok {
        check_invariants(&after, &context);
    }
    check_resolved(resolve_rows(&after), M as f32, &context);

    // Lanes on garbage: lane l holds the rows rotated by l and gets `new` (even lanes) or
    // one of its own rows (odd lanes, a tie), under a mask from the input.
    let mask = input.u8().unwrap_or(0xff);
    let mut pixels = [rows; LANES];
    let mut rows8 = [new; LANES];
    for (lane, p) in pixels.iter_mut().enumerate() {
        p.rotate_left(lane % M);
        if lane % 2 == 1 {
            rows8[lane] = p[lane % M];
        }
    }
    let mut span = from_pixel_major(&pixels);
    lanes_ok(check_mlab_span(&span, &pixels));
    lanes::mlab_insert_with::<A, _>(&mut span, &rows8, mask);
    for (lane, p) in pixels.iter_mut().enumerate() {
        if mask >> lane & 1 == 1 {
            mlab_mod::insert_with::<A, _>(p, rows8[lane]);
        }
    }
    assert_eq!(
        to_pixel_major(&span),
        pixels,
        "{name}: lanes insert on garbage rows {rows:?}, mask {mask:#010b}"
    );
    lanes_ok(check_mlab_span(&span, &pixels));
}

fn garbage_hybrid<const K: usize, A: Model>(input: &mut Input) {
    let name = A::NAME;
    let layout = A::TAIL;
    let head: [Row; K] = core::array::from_fn(|_| row_or(input, Row::EMPTY));
    let tail_bytes = input.array::<8>().unwrap_or([0; 8]);
    let tail = <A::Tail as TailFormat>::from_bytes(tail_bytes);
    let new = row_or(input, Row::EMPTY);
    let context = (name, &head, tail, new);

    // The tail alone: finite, in range, and Bavoil-Myers evaluated in f64 from the fields of
    // the reference layout. Precision of the f32 evaluation: `1 - mean` is rounded (2^-25
    // absolute) and raised to the power n, so |dT| <= n 2^-24 (+ the multiplies); the color
    // is `S_c (1 - T) / S_a`, so its error is that of T divided by S_a. The same bounds for
    // both layouts: they depend on the count n, not on the field widths.
    let t = tail.resolve();
    let limit = tail_color_limit::<A>();
    check_resolved(t, limit, &tail);
    let fields = layout.fields(tail_bytes);
    let (c_ref, t_ref) = tail_f64(fields);
    let n = fields[4].max(1) as f64;
    let dt = 1e-5 + n * 2f64.powi(-24);
    let err = (f64::from(t.transmittance) - t_ref).abs();
    assert!(
        err <= dt,
        "{name} tail T: {t:?} vs {t_ref}, error {err} > {dt}, from {tail:?}"
    );
    let c = t.color.to_array();
    for i in 0..3 {
        let sum = fields[i] as f64 / 255.0;
        // What an evaluation without cancellation gives (the kernel's geometric sum since
        // the fix of finding F1b): n 2^-23 relative, always. The bound of the evaluation as
        // printed, `|dT| / S_a` relative, about `1 / (2 S_a)` times looser (128x at an alpha
        // sum of one byte: where F1b lived), went with the MLAB_FUZZ_STRICT switch that
        // chose between them.
        let bound = if fields[3] == 0 {
            1e-5
        } else {
            sum * (2e-5 + n * 2f64.powi(-23)) + 1e-5
        };
        let err = (f64::from(c[i]) - c_ref[i]).abs();
        assert!(
            err <= bound,
            "{name} tail color {i}: {t:?} vs {c_ref:?}, error {err} > {bound}, from {tail:?}"
        );
    }

    let r = Hybrid::<K, A>::from_parts(head, tail).resolve();
    check_resolved(r, K as f32 + limit, &context);
    check_pixels(r, input, &context);

    // Listing 2 on any head and tail: the head is the bubble, the tail adds the pushed-out
    // row field by field, saturating, unless it is invisible; spare bits are kept.
    let (expected_head, pushed) = ref_bubble(&head, new);
    let expected_tail = layout.pack(ref_tail_fields(layout, fields, &[pushed]), tail_bytes);
    let (mut h, mut t) = (head, tail);
    hybrid::insert(&mut h, &mut t, new);
    assert_eq!(
        h.as_slice(),
        expected_head.as_slice(),
        "{name}: HT insert {new:?} into {head:?}"
    );
    assert_eq!(
        t.to_bytes(),
        expected_tail,
        "{name}: HT tail after {new:?} into {tail:?}: {t:?}, expected {:?}",
        layout.fields(expected_tail)
    );
    let mut px = Hybrid::<K, A>::from_parts(head, tail);
    px.insert_row(new);
    assert_eq!((px.head(), px.tail()), (&h, t), "{name}: Hybrid::insert_row");
    let new_ok = new.is_empty() || new.depth() < f32::INFINITY;
    if invariants_hold(&head) && new_ok {
        check_invariants(&h, &context);
    }
    check_resolved(px.resolve(), K as f32 + limit, &context);

    // Lanes on garbage: lane l holds the head rotated by l and the tail bytes rotated by l.
    let mask = input.u8().unwrap_or(0xff);
    let mut pixels = [Hybrid::<K, A>::new(); LANES];
    for (lane, p) in pixels.iter_mut().enumerate() {
        let mut hd = head;
        if K > 0 {
            hd.rotate_left(lane % K);
        }
        let mut tb = tail_bytes;
        tb.rotate_left(lane);
        *p = Hybrid::from_parts(hd, <A::Tail as TailFormat>::from_bytes(tb));
    }
    let mut span = HybridSpan::<K, A>::default();
    for (lane, p) in pixels.iter().enumerate() {
        for j in 0..K {
            span.head[j][lane] = p.head()[j];
        }
        span.tails[lane] = p.tail();
    }
    lanes_ok(check_hybrid_span(&span, &pixels));
    let rows8 = [new; LANES];
    lanes::hybrid_insert(&mut span, &rows8, mask);
    for (lane, p) in pixels.iter_mut().enumerate() {
        if mask >> lane & 1 == 1 {
            p.insert_row(new);
        }
    }
    lanes_ok(check_hybrid_span(&span, &pixels));
}

/// The pixel writers on a resolved value and a background read from the input (any bits:
/// backgrounds are not validated; NaN gives byte 0 and a NaN half).
fn check_pixels(r: Resolved, input: &mut Input, context: &dyn core::fmt::Debug) {
    let bg = Vec3::new(
        input.unit().unwrap_or(0.0),
        input.unit().unwrap_or(0.5),
        input.unit().unwrap_or(1.0),
    );
    for background in [Background::Opaque(bg), Background::Transparent] {
        let p = r.pixel(background);
        let bytes = to_rgba8(p);
        let halves = to_rgba16f(p);
        for i in 0..4 {
            let x = p.to_array()[i];
            let want = if x.is_nan() {
                0
            } else {
                (f64::from(x.clamp(0.0, 1.0)) * 255.0 + 0.5).floor() as u8
            };
            assert!(
                bytes[i].abs_diff(want) <= 1,
                "rgba8 of {p:?} = {bytes:?} from {context:?}"
            );
            assert_eq!(halves[i].to_bits(), f16::from_f32(x).to_bits());
        }
        if let Background::Transparent = background {
            assert!((0.0..=1.0).contains(&p.w), "premultiplied alpha {p:?} from {context:?}");
        }
    }
}

// ---------------------------------------------------------------------------------------
// lanes_masks

/// What differs between the kinds of pixel the `spans` target drives: the kernel's kind
/// ([`Layout::P`], a pixel of both arrangements, `Grid<P, PixelMajor>` and `Grid<P, Spans>`,
/// driven by the generic code below) and the reference's model of one pixel's slots.
pub trait Layout {
    /// The kernel's pixel kind.
    type P: Pixel;
    /// Row-sized slots per pixel.
    const SLOTS: usize = <Self::P as Pixel>::ROWS;
    /// The arithmetic's name, for messages.
    const NAME: &'static str;
    /// The reference row of a valid fragment in the layout's arithmetic, in pixel `pixel`.
    fn ref_row(f: &Fragment, pixel: u32) -> Row;
    /// Largest resolved color.
    fn max_color() -> f32;
    /// The reference insert on one pixel's slots (any contents) of a row of hash `h`.
    fn ref_insert(slots: &mut [Row], row: Row, h: u32);
    /// The resolve of one pixel's slots, split here.
    fn ref_resolve(slots: &[Row]) -> Resolved;
    /// What `Framebuffer::resolve_rgba8` writes for one pixel's slots: the reference integer
    /// resolve (`mlab_reference::resolve_int`), MLAB's or HT's.
    fn ref_rgba8(slots: &[Row], bg: Background) -> [u8; 4];
    /// A cleared pixel.
    fn cleared(slots: &mut [Row]);
    /// One pixel's contents ([`Grid::pixel`]) as its `SLOTS` rows (HT: head rows, then the tail).
    fn slots(value: <Self::P as Pixel>::Value) -> Vec<Row>;
    /// The span `x0 .. x0 + 8` of line `y` through the lanes kernel: gather the pixels into
    /// a lanes span (lanes outside the buffer hold a sentinel), insert `row` in the lanes of
    /// `mask` that are inside, check that every other lane is unchanged, scatter back.
    #[allow(clippy::too_many_arguments)]
    fn lanes_span(
        storage: &mut [Row],
        w: u32,
        h: u32,
        x0: u32,
        y: u32,
        rows: &[Row; LANES],
        hashes: &[u32; LANES],
        mask: u8,
    );
}

/// The pixel-major framebuffer of a layout.
type View<'a, L> = Grid<'a, <L as Layout>::P, PixelMajor>;

/// The span framebuffer of a layout over `s` (its storage is always of the right length).
fn span_view<L: Layout>(s: &mut [Row], w: u32, h: u32) -> Grid<'_, L::P, Spans> {
    Grid::new(s, w, h).expect("span storage")
}

/// Run one of the three resolve writers of `v`; bytes and halves are widened to f32 so that
/// errors and untouched outputs compare the same way.
fn resolve_all<F: Framebuffer>(v: &F, which: u8, out: &mut [Vec4], bg: Background) -> Result<(), FramebufferError> {
    match which % 3 {
        0 => v.resolve_into(out, bg),
        1 => {
            let mut px: Vec<[u8; 4]> = out.iter().map(|p| p.to_array().map(|x| x as u8)).collect();
            let r = v.resolve_rgba8(&mut px, bg);
            for (o, p) in out.iter_mut().zip(px) {
                *o = Vec4::from_array(p.map(f32::from));
            }
            r
        }
        _ => {
            let mut px: Vec<[f16; 4]> = out.iter().map(|p| p.to_array().map(f16::from_f32)).collect();
            let r = v.resolve_rgba16f(&mut px, bg);
            for (o, p) in out.iter_mut().zip(px) {
                *o = Vec4::from_array(p.map(f16::to_f32));
            }
            r
        }
    }
}

/// Lanes of the span `x0 .. x0 + 8` that lie inside a `w x h` buffer on line `y`.
fn inside(w: u32, h: u32, x0: u32, y: u32) -> u8 {
    (0..LANES as u32)
        .filter(|&l| x0 + l < w && y < h)
        .fold(0, |m, l| m | 1 << l)
}

/// The sentinel row of lane `lane`, layer `j` of a span (outside the buffer).
fn sentinel(lane: usize, j: usize) -> Row {
    Row::new([lane as u8, j as u8, 0x5a], 0x33, -(lane as f32) - 0.5)
}

/// MLAB with `M` rows per pixel in the arithmetic `A`.
pub struct MlabLayout<const M: usize, A>(core::marker::PhantomData<A>);
/// HT with `K` head rows and a tail per pixel in the arithmetic `A`.
pub struct HybridLayout<const K: usize, A>(core::marker::PhantomData<A>);

impl<const M: usize, A: Model> Layout for MlabLayout<M, A> {
    type P = Mlab<M, A>;
    const NAME: &'static str = A::NAME;
    fn ref_row(f: &Fragment, pixel: u32) -> Row {
        A::ref_row(f, pixel)
    }
    fn max_color() -> f32 {
        M as f32
    }
    fn slots(value: [Row; M]) -> Vec<Row> {
        value.to_vec()
    }
    fn ref_insert(slots: &mut [Row], row: Row, h: u32) {
        let (mut rows, pushed) = ref_bubble(slots, row);
        let last = rows[M - 1];
        rows[M - 1] = A::ref_merge(last, pushed, h);
        slots.copy_from_slice(&rows);
    }
    fn ref_resolve(slots: &[Row]) -> Resolved {
        resolve_rows(slots)
    }
    fn ref_rgba8(slots: &[Row], bg: Background) -> [u8; 4] {
        mlab_reference::resolve_int::rgba8(slots, bg)
    }
    fn cleared(slots: &mut [Row]) {
        slots.fill(Row::EMPTY);
    }
    fn lanes_span(
        storage: &mut [Row],
        w: u32,
        h: u32,
        x0: u32,
        y: u32,
        rows: &[Row; LANES],
        hashes: &[u32; LANES],
        mask: u8,
    ) {
        let on = mask & inside(w, h, x0, y);
        let base = |lane: usize| (y as usize * w as usize + x0 as usize + lane) * M;
        let mut span: MlabSpan<M> = core::array::from_fn(|j| core::array::from_fn(|lane| sentinel(lane, j)));
        for lane in (0..LANES).filter(|&l| inside(w, h, x0, y) >> l & 1 == 1) {
            for (j, layer) in span.iter_mut().enumerate() {
                layer[lane] = storage[base(lane) + j];
            }
        }
        let before = span;
        let rows: [Row; LANES] = core::array::from_fn(|l| if on >> l & 1 == 1 { rows[l] } else { OFF_LANE_ROW });
        lanes::mlab_insert_hashed::<A, _>(&mut span, &rows, hashes, on);
        for lane in (0..LANES).filter(|&l| on >> l & 1 == 0) {
            for j in 0..M {
                assert_eq!(
                    span[j][lane], before[j][lane],
                    "lane {lane} is off (mask {mask:#010b}) but changed"
                );
            }
        }
        for lane in (0..LANES).filter(|&l| inside(w, h, x0, y) >> l & 1 == 1) {
            for (j, layer) in span.iter().enumerate() {
                storage[base(lane) + j] = layer[lane];
            }
        }
    }
}

impl<const K: usize, A: Model> Layout for HybridLayout<K, A> {
    type P = Ht<K, A>;
    const NAME: &'static str = A::NAME;
    fn ref_row(f: &Fragment, pixel: u32) -> Row {
        A::ref_row(f, pixel)
    }
    fn max_color() -> f32 {
        K as f32 + tail_color_limit::<A>()
    }
    fn slots((head, tail): ([Row; K], A::Tail)) -> Vec<Row> {
        let mut v = head.to_vec();
        v.push(Row::from_bytes(tail.to_bytes()));
        v
    }
    fn ref_insert(slots: &mut [Row], row: Row, _: u32) {
        let tail = slots[K].to_bytes();
        let (head, pushed) = ref_bubble(&slots[..K], row);
        slots[..K].copy_from_slice(&head);
        let t = A::TAIL.pack(ref_tail_fields(A::TAIL, A::TAIL.fields(tail), &[pushed]), tail);
        slots[K] = Row::from_bytes(t);
    }
    fn ref_resolve(slots: &[Row]) -> Resolved {
        Hybrid::<K, A>::from_parts(
            core::array::from_fn(|i| slots[i]),
            <A::Tail as TailFormat>::from_bytes(slots[K].to_bytes()),
        )
        .resolve()
    }
    fn ref_rgba8(slots: &[Row], bg: Background) -> [u8; 4] {
        let tail = <A::Tail as TailFormat>::from_bytes(slots[K].to_bytes());
        mlab_reference::resolve_int::ht_rgba8(&slots[..K], tail, bg)
    }
    fn cleared(slots: &mut [Row]) {
        slots[..K].fill(Row::EMPTY);
        slots[K] = Row::from_bytes([0; 8]);
    }
    fn lanes_span(
        storage: &mut [Row],
        w: u32,
        h: u32,
        x0: u32,
        y: u32,
        rows: &[Row; LANES],
        _: &[u32; LANES],
        mask: u8,
    ) {
        let on = mask & inside(w, h, x0, y);
        let base = |lane: usize| (y as usize * w as usize + x0 as usize + lane) * (K + 1);
        let mut span = HybridSpan::<K, A> {
            head: core::array::from_fn(|j| core::array::from_fn(|lane| sentinel(lane, j))),
            tails: core::array::from_fn(|lane| <A::Tail as TailFormat>::from_bytes(sentinel(lane, K).to_bytes())),
        };
        for lane in (0..LANES).filter(|&l| inside(w, h, x0, y) >> l & 1 == 1) {
            for (j, layer) in span.head.iter_mut().enumerate() {
                layer[lane] = storage[base(lane) + j];
            }
            span.tails[lane] = <A::Tail as TailFormat>::from_bytes(storage[base(lane) + K].to_bytes());
        }
        let before = span;
        let rows: [Row; LANES] = core::array::from_fn(|l| if on >> l & 1 == 1 { rows[l] } else { OFF_LANE_ROW });
        lanes::hybrid_insert(&mut span, &rows, on);
        for lane in (0..LANES).filter(|&l| on >> l & 1 == 0) {
            for j in 0..K {
                assert_eq!(
                    span.head[j][lane], before.head[j][lane],
                    "lane {lane} is off (mask {mask:#010b}) but changed"
                );
            }
            assert_eq!(
                span.tails[lane], before.tails[lane],
                "lane {lane} is off (mask {mask:#010b}): tail changed"
            );
        }
        for lane in (0..LANES).filter(|&l| inside(w, h, x0, y) >> l & 1 == 1) {
            for (j, layer) in span.head.iter().enumerate() {
                storage[base(lane) + j] = layer[lane];
            }
            storage[base(lane) + K] = Row::from_bytes(span.tails[lane].to_bytes());
        }
    }
}

/// Guard rows on each side of the storage handed to the framebuffer.
const GUARD: usize = 3;
/// A guard row (a pattern no operation writes).
const GUARD_ROW: Row = Row::new([0xde, 0xad, 0xbe], 0xef, -1234.5);

/// `lanes_masks`: the first byte picks the kind (MLAB with M = 1, 2, 4 or HT with
/// K = 0, 1, 3), then width, height, storage length, contents, and a list of operations.
///
/// Spans of up to 8 pixels with an 8-bit mask, starting anywhere (also past the right and
/// bottom edges), go through the scalar framebuffer one pixel per lane, and through the
/// lanes kernel (`mlab::lanes::mlab_insert` / `hybrid_insert`, gathered from and
/// scattered to the same storage, lanes outside the buffer holding a sentinel and masked
/// off). Pixels that are off, or outside the buffer, never change (in the storage and in
/// the lanes span); guard rows never change; an error changes nothing; the lanes storage
/// equals the scalar storage byte for byte.
///
/// Every input runs in both arithmetics (the same operations on the same contents).
pub fn lanes_masks(data: &[u8]) {
    let mut input = Input::new(data);
    let Some(sel) = input.u8() else { return };
    lanes_masks_a::<Paper>(sel, input.clone());
    lanes_masks_a::<Unbiased>(sel, input);
}

fn lanes_masks_a<A: Model>(sel: u8, mut input: Input) {
    match sel % 6 {
        0 => spans::<MlabLayout<1, A>>(&mut input),
        1 => spans::<MlabLayout<2, A>>(&mut input),
        2 => spans::<MlabLayout<4, A>>(&mut input),
        3 => spans::<HybridLayout<0, A>>(&mut input),
        4 => spans::<HybridLayout<1, A>>(&mut input),
        _ => spans::<HybridLayout<3, A>>(&mut input),
    }
}

fn spans<L: Layout>(input: &mut Input) {
    let (Some(w), Some(h), Some(len_sel), Some(fill)) = (input.u8(), input.u8(), input.u8(), input.u8()) else {
        return;
    };
    let (w, h) = (u32::from(w % 12) + 1, u32::from(h % 5) + 1);
    let needed = w as usize * h as usize * L::SLOTS;
    // Mostly the right length; sometimes one row short or long, or none at all.
    let len = match len_sel % 16 {
        13 => needed.saturating_sub(1),
        14 => needed + 1,
        15 => 0,
        _ => needed,
    };
    let mut buf = vec![GUARD_ROW; len + 2 * GUARD];
    for (i, slot) in buf[GUARD..GUARD + len].iter_mut().enumerate() {
        // Empty storage, or storage read back from arbitrary bytes (fill pattern + input).
        *slot = if fill & 1 == 0 {
            Row::EMPTY
        } else {
            input
                .array::<8>()
                .map(Row::from_bytes)
                .unwrap_or(Row::new([fill, i as u8, 0], fill, i as f32))
        };
    }
    let snapshot = buf.clone();
    match View::<L>::new(&mut buf[GUARD..GUARD + len], w, h).map(|v| v.as_bytes().to_vec()) {
        Err(e) => {
            assert_ne!(len, needed, "{w}x{h}: storage of the right length refused: {e:?}");
            assert_eq!(
                e,
                FramebufferError::StorageLength {
                    expected: needed,
                    actual: len
                }
            );
            assert_eq!(buf, snapshot, "a refused view changed the storage");
            return;
        }
        Ok(view_bytes) => {
            assert_eq!(len, needed, "{w}x{h}: storage of {len} rows accepted, {needed} needed");
            let bytes: Vec<u8> = buf[GUARD..GUARD + len].iter().flat_map(|r| r.to_bytes()).collect();
            assert_eq!(view_bytes, bytes, "as_bytes is not the rows' bytes");
        }
    }
    let pixel = |x: u32, y: u32| GUARD + (y as usize * w as usize + x as usize) * L::SLOTS;
    // The same pixels in a span framebuffer (lanes arrangement), placed by the documented
    // formula `((y * spans + x / 8) * R + j) * 8 + x % 8`; padding lanes hold a sentinel
    // that no insert may touch.
    let spans_per_line = (w as usize).div_ceil(LANES);
    let slen = spans_per_line * LANES * h as usize * L::SLOTS;
    assert_eq!(Grid::<L::P, Spans>::rows_needed(w, h), Ok(slen));
    let sidx = |x: usize, y: usize, j: usize| ((y * spans_per_line + x / LANES) * L::SLOTS + j) * LANES + x % LANES;
    let mut sbuf = vec![sentinel(7, 7); slen];
    for y in 0..h as usize {
        for x in 0..w as usize {
            for j in 0..L::SLOTS {
                sbuf[sidx(x, y, j)] = buf[pixel(x as u32, y as u32) + j];
            }
        }
    }
    let span_matches = |sbuf: &[Row], buf: &[Row], context: &dyn core::fmt::Debug| {
        for y in 0..h as usize {
            for x in 0..w as usize {
                for j in 0..L::SLOTS {
                    assert_eq!(
                        sbuf[sidx(x, y, j)],
                        buf[pixel(x as u32, y as u32) + j],
                        "span fb pixel ({x}, {y}) slot {j} after {context:?}"
                    );
                }
            }
            for x in w as usize..spans_per_line * LANES {
                for j in 0..L::SLOTS {
                    assert_eq!(
                        sbuf[sidx(x, y, j)],
                        sentinel(7, 7),
                        "padding lane ({x}, {y}) written after {context:?}"
                    );
                }
            }
        }
    };
    for _ in 0..32 {
        let Some(op) = input.u8() else { break };
        let before = buf.clone();
        let mut expected = buf.clone();
        let mut lanes_result: Option<Vec<Row>> = None;
        let mut v = View::<L>::new(&mut buf[GUARD..GUARD + len], w, h).expect("accepted above");
        match op % 4 {
            // A span: pixels x0 .. x0 + n on line y, lane i on if bit i of the mask.
            0 | 1 => {
                let (Some(x0), Some(y), Some(n), Some(mask)) = (input.u8(), input.u8(), input.u8(), input.u8()) else {
                    break;
                };
                let Some(raw) = input.raw_fragment() else { break };
                let Some(f) = validate(&raw) else { continue };
                let (x0, y, n) = (u32::from(x0) % (w + 4), u32::from(y) % (h + 2), u32::from(n % 9));
                // The lanes kernel on a copy: lanes 0 .. n of the mask, at the same place.
                let span_mask = (mask as u16 & ((1u16 << n) - 1)) as u8;
                // Each lane's pixel id, reference hash and row (`Framebuffer::pixel_id`).
                let pid = |lane: u32| y.wrapping_mul(w).wrapping_add(x0).wrapping_add(lane);
                let hashes: [u32; LANES] = core::array::from_fn(|l| ref_fragment_hash(ref_key(&f), pid(l as u32)));
                let all: [Row; LANES] = core::array::from_fn(|l| L::ref_row(&f, pid(l as u32)));
                let mut lanes_buf = before.clone();
                L::lanes_span(
                    &mut lanes_buf[GUARD..GUARD + len],
                    w,
                    h,
                    x0,
                    y,
                    &all,
                    &hashes,
                    span_mask,
                );
                lanes_result = Some(lanes_buf);
                // The span framebuffer: refused (and unchanged) if an on lane is outside, then
                // the same span with those lanes off.
                let rows8: [Row; LANES] =
                    core::array::from_fn(|l| if span_mask >> l & 1 == 1 { all[l] } else { OFF_LANE_ROW });
                let top = (0..LANES as u32).filter(|&l| span_mask >> l & 1 == 1).max();
                let expected_err = if y >= h {
                    Some(FramebufferError::OutOfBounds {
                        x: x0,
                        y,
                        width: w,
                        height: h,
                    })
                } else {
                    top.filter(|&l| x0 + l >= w).map(|l| FramebufferError::OutOfBounds {
                        x: x0 + l,
                        y,
                        width: w,
                        height: h,
                    })
                };
                let sbefore = sbuf.clone();
                let got = span_view::<L>(&mut sbuf, w, h).insert_span_hashed(x0, y, &rows8, &hashes, span_mask);
                match expected_err {
                    Some(e) => {
                        assert_eq!(got, Err(e), "span ({x0}, {y}) mask {span_mask:#010b} in {w}x{h}");
                        assert_eq!(sbuf, sbefore, "a refused span changed the span framebuffer");
                        let on = span_mask & inside(w, h, x0, y);
                        if on != 0 {
                            assert_eq!(
                                span_view::<L>(&mut sbuf, w, h).insert_span_hashed(x0, y, &rows8, &hashes, on),
                                Ok(())
                            );
                        }
                    }
                    None => assert_eq!(got, Ok(())),
                }
                for lane in 0..n {
                    let x = x0 + lane;
                    if mask >> lane & 1 == 0 {
                        continue;
                    }
                    let got = v.insert(x, y, &f);
                    if x < w && y < h {
                        assert_eq!(got, Ok(()));
                        let p = pixel(x, y);
                        L::ref_insert(
                            &mut expected[p..p + L::SLOTS],
                            all[lane as usize],
                            hashes[lane as usize],
                        );
                    } else {
                        assert_eq!(
                            got,
                            Err(FramebufferError::OutOfBounds {
                                x,
                                y,
                                width: w,
                                height: h
                            })
                        );
                    }
                }
            }
            // Resolve every pixel into an output of the right length, or one off.
            2 => {
                let (Some(which), Some(off), Some(b)) = (input.u8(), input.u8(), input.u8()) else {
                    break;
                };
                let pixels = (w * h) as usize;
                let n = match off % 8 {
                    6 => pixels - 1,
                    7 => pixels + 1,
                    _ => pixels,
                };
                let bg = if b == 255 {
                    Background::Transparent
                } else {
                    Background::Opaque(Vec3::splat(f32::from(b) / 254.0))
                };
                let sentinel_px = Vec4::new(7.0, 7.0, 7.0, 7.0);
                let mut out = vec![sentinel_px; n];
                let got = resolve_all(&v, which, &mut out, bg);
                let mut sout = vec![sentinel_px; n];
                assert_eq!(
                    resolve_all(&span_view::<L>(&mut sbuf, w, h), which, &mut sout, bg),
                    got,
                    "span fb resolve result"
                );
                assert_eq!(sout, out, "span fb resolve differs from the pixel-major resolve");
                if n != pixels {
                    assert_eq!(
                        got,
                        Err(FramebufferError::OutputLength {
                            expected: pixels,
                            actual: n
                        })
                    );
                    assert!(
                        out.iter().all(|&p| p == sentinel_px),
                        "a refused resolve wrote its output"
                    );
                } else {
                    assert_eq!(got, Ok(()));
                    for y in 0..h {
                        for x in 0..w {
                            let p = pixel(x, y);
                            let r = L::ref_resolve(&before[p..p + L::SLOTS]);
                            assert_eq!(v.resolve(x, y), Ok(r));
                            check_resolved(r, L::max_color(), &(x, y));
                            let want = r.pixel(bg);
                            let got = out[(y * w + x) as usize];
                            let want = match which % 3 {
                                0 => want,
                                1 => Vec4::from_array(L::ref_rgba8(&before[p..p + L::SLOTS], bg).map(f32::from)),
                                _ => Vec4::from_array(to_rgba16f(want).map(f16::to_f32)),
                            };
                            assert_eq!(got, want, "pixel ({x}, {y})");
                        }
                    }
                }
                let (Some(x), Some(y)) = (input.u8(), input.u8()) else {
                    break;
                };
                let (x, y) = (u32::from(x), u32::from(y) % (h + 2));
                let sp = span_view::<L>(&mut sbuf, w, h).pixel(x, y).map(L::slots);
                if x < w && y < h {
                    let p = pixel(x, y);
                    assert_eq!(sp, Ok(before[p..p + L::SLOTS].to_vec()), "span fb pixel ({x}, {y})");
                } else {
                    assert_eq!(
                        sp,
                        Err(FramebufferError::OutOfBounds {
                            x,
                            y,
                            width: w,
                            height: h
                        })
                    );
                }
                if x >= w || y >= h {
                    assert_eq!(
                        v.resolve(x, y),
                        Err(FramebufferError::OutOfBounds {
                            x,
                            y,
                            width: w,
                            height: h
                        })
                    );
                }
            }
            _ => {
                span_view::<L>(&mut sbuf, w, h).clear();
                for y in 0..h as usize {
                    for x in w as usize..spans_per_line * LANES {
                        for j in 0..L::SLOTS {
                            // Clearing resets the padding too; put the sentinel back.
                            sbuf[sidx(x, y, j)] = sentinel(7, 7);
                        }
                    }
                }
                v.clear();
                for p in 0..(w * h) as usize {
                    let p = GUARD + p * L::SLOTS;
                    L::cleared(&mut expected[p..p + L::SLOTS]);
                }
            }
        }
        let _ = v; // the view ends here: `buf` is read below
        assert_eq!(buf[..GUARD], before[..GUARD], "guard rows before the storage changed");
        assert_eq!(
            buf[GUARD + len..],
            before[GUARD + len..],
            "guard rows after the storage changed"
        );
        assert_eq!(
            buf, expected,
            "{w}x{h}: pixels differ from the per-pixel reference after op {op}"
        );
        span_matches(&sbuf, &buf, &op);
        if let Some(lanes_buf) = lanes_result {
            assert_eq!(
                lanes_buf, buf,
                "{w}x{h}: the lanes span differs from the scalar framebuffer"
            );
        }
    }
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

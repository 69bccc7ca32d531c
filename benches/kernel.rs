//! Criterion benches for the kernel (throughput in fragments or pixels).
//!
//! `cargo bench --bench kernel` (default target, wide on SSE2), and
//! `CARGO_TARGET_DIR=target-v3 RUSTFLAGS="-C target-cpu=x86-64-v3" cargo bench --bench kernel` (AVX2).
//! Results and analysis: docs/performance.md.
//!
//! Target: 128 x 128 pixels (16384 pixels; 512 KiB of rows at M = 4). Streams (same
//! fragments for scalar and lanes, generated once from a fixed seed):
//! - `random`: 8192 span operations, each on a random 8-pixel span with 8 random fragments
//!   (random depth, so every pixel sees its fragments in random depth order);
//! - `coherent`: random rectangles (primitives) scanned line by line in 8-pixel spans, with
//!   partial masks at the rectangle edges, as a rasterizer emits them.
//!
//! The blending arrays are not cleared between iterations: after the first pass every array
//! is full and every insert merges (the steady state of a heavy scene).

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use mlab::lanes::{self, HybridSpan, LANES};

/// An MLAB span, layer-major (`span[j][lane]`).
type MlabSpan<const M: usize> = [[Row; LANES]; M];
use mlab::{
    Arithmetic, Background, Framebuffer, Paper, Row, SpanFramebuffer, TailFormat, Unbiased, hybrid, mlab as listing1,
    resolve_rows, to_rgba8,
};
use mlab_reference::Rng;
use std::hint::black_box;
use wide::{u8x32, u16x16, u32x8};

const W: usize = 128;
const H: usize = 128;
const SPANS: usize = W * H / LANES;
/// Spans of the small target (32 x 32 pixels, 32 KiB of rows at M = 4: in L1).
const SMALL_SPANS: usize = 32 * 32 / LANES;

/// One span operation: span index, one row per lane, each row's fragment hash (its key and
/// pixel, `mlab::fragment_hash`: what a framebuffer's quantization hands its insert), coverage
/// mask.
#[derive(Clone, Copy)]
struct Step {
    span: usize,
    rows: [Row; LANES],
    hashes: [u32; LANES],
    mask: u8,
}

/// The hashes of a step's fragments: keys numbered in stream order, pixels of span `span`.
fn hashes(key: usize, span: usize) -> [u32; LANES] {
    core::array::from_fn(|l| mlab::fragment_hash((key * LANES + l) as u32, (span * LANES + l) as u32))
}

fn fragment_row(rng: &mut Rng, depth: f32) -> Row {
    let alpha = 0.1 + 0.8 * rng.unit();
    let c = mlab::glam::Vec3::new(rng.unit(), rng.unit(), rng.unit());
    <mlab::Paper as mlab::Arithmetic>::quantize(&mlab::Fragment::straight(c, alpha, depth).expect("valid"), 0)
}

fn random_stream(spans: usize) -> Vec<Step> {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    (0..8192)
        .map(|i| {
            let span = (rng.next_u64() % spans as u64) as usize;
            let rows = core::array::from_fn(|_| {
                let z = 100.0 * rng.unit();
                fragment_row(&mut rng, z)
            });
            Step {
                span,
                rows,
                hashes: hashes(i, span),
                mask: 0xff,
            }
        })
        .collect()
}

fn coherent_stream() -> Vec<Step> {
    let mut rng = Rng(0x2545_f491_4f6c_dd1d);
    let mut steps = Vec::new();
    while steps.len() < 8192 {
        let (x0, y0) = (
            (rng.next_u64() % W as u64) as usize,
            (rng.next_u64() % H as u64) as usize,
        );
        let (w, h) = (1 + (rng.next_u64() % 48) as usize, 1 + (rng.next_u64() % 24) as usize);
        let z0 = 100.0 * rng.unit();
        let row = fragment_row(&mut rng, z0);
        for y in y0..(y0 + h).min(H) {
            let x1 = (x0 + w).min(W);
            let mut sx = x0 / LANES * LANES;
            while sx < x1 {
                let mask = (0..LANES)
                    .filter(|l| (x0..x1).contains(&(sx + l)))
                    .fold(0u8, |m, l| m | 1 << l);
                // A slight depth gradient along x, as a sloped primitive.
                let rows =
                    core::array::from_fn(|l| Row::new(row.color(), row.transmittance(), z0 + 0.01 * (sx + l) as f32));
                let span = (y * W + sx) / LANES;
                steps.push(Step {
                    span,
                    rows,
                    hashes: hashes(steps.len(), span),
                    mask,
                });
                sx += LANES;
            }
        }
    }
    steps
}

fn fragments(stream: &[Step]) -> u64 {
    stream.iter().map(|s| s.mask.count_ones() as u64).sum()
}

#[inline(never)] // a symbol of its own, for callgrind (benches/callgrind.sh)
fn mlab_scalar<A: Arithmetic, const M: usize>(pixels: &mut [[Row; M]], stream: &[Step]) {
    for s in stream {
        for (lane, row) in s.rows.iter().enumerate() {
            if s.mask & (1 << lane) != 0 {
                listing1::insert_hashed::<A, M>(&mut pixels[s.span * LANES + lane], *row, s.hashes[lane]);
            }
        }
    }
}

#[inline(never)] // a symbol of its own, for callgrind (benches/callgrind.sh)
fn mlab_lanes<A: Arithmetic, const M: usize>(spans: &mut [MlabSpan<M>], stream: &[Step]) {
    for s in stream {
        lanes::mlab_insert_hashed::<A, M>(&mut spans[s.span], &s.rows, &s.hashes, s.mask);
    }
}

/// The alternative arrangement: lanes over pixel-major storage, transposing the span's
/// rows to layer-major and back around every insert.
#[inline(never)] // a symbol of its own, for callgrind (benches/callgrind.sh)
fn mlab_lanes_pixel_major<const M: usize>(pixels: &mut [[Row; M]], stream: &[Step]) {
    for s in stream {
        let chunk: &mut [[Row; M]; LANES] = (&mut pixels[s.span * LANES..(s.span + 1) * LANES])
            .try_into()
            .expect("8 pixels");
        let mut span = from_pixel_major(chunk);
        lanes::mlab_insert_hashed::<mlab::Unbiased, _>(&mut span, &s.rows, &s.hashes, s.mask);
        *chunk = to_pixel_major(&span);
    }
}

#[inline(never)] // a symbol of its own, for callgrind (benches/callgrind.sh)
fn hybrid_scalar<T: TailFormat, const K: usize>(pixels: &mut [([Row; K], T)], stream: &[Step]) {
    for s in stream {
        for (lane, row) in s.rows.iter().enumerate() {
            if s.mask & (1 << lane) != 0 {
                let (head, tail) = &mut pixels[s.span * LANES + lane];
                hybrid::insert(head, tail, *row);
            }
        }
    }
}

#[inline(never)] // a symbol of its own, for callgrind (benches/callgrind.sh)
fn hybrid_lanes<A: Arithmetic, const K: usize>(spans: &mut [HybridSpan<K, A>], stream: &[Step]) {
    for s in stream {
        lanes::hybrid_insert(&mut spans[s.span], &s.rows, s.mask);
    }
}

/// Baseline: unsorted OVER of the same fragments into an RGBA8 buffer (premultiplied,
/// exact unorm8 like the merge): `dst = src + round(dst * (255 - src.a) / 255)` per byte.
/// `round(x / 255)` for a product of two bytes (the kernel's exact identity, docs/layout.md).
#[inline(always)]
fn div255(x: u32) -> u32 {
    let y = x + 128;
    (y + (y >> 8)) >> 8
}

fn over_pixel(src: u32, dst: u32) -> u32 {
    let inv = 255 - (src >> 24);
    let s = src.to_le_bytes();
    let d = dst.to_le_bytes();
    let mut o = [0u8; 4];
    for c in 0..4 {
        o[c] = s[c].saturating_add(div255(d[c] as u32 * inv) as u8);
    }
    u32::from_le_bytes(o)
}

/// RGBA8 source pixels of a stream (alpha byte = 255 - T).
fn rgba_of(stream: &[Step]) -> Vec<[u32; LANES]> {
    stream
        .iter()
        .map(|s| s.rows.map(|r| r.words()[0] ^ 0xff00_0000))
        .collect()
}

#[inline(never)] // a symbol of its own, for callgrind (benches/callgrind.sh)
fn over_scalar(buf: &mut [u32], stream: &[Step], src: &[[u32; LANES]]) {
    for (s, px) in stream.iter().zip(src) {
        for lane in 0..LANES {
            if s.mask & (1 << lane) != 0 {
                let d = &mut buf[s.span * LANES + lane];
                *d = over_pixel(px[lane], *d);
            }
        }
    }
}

#[inline(never)] // a symbol of its own, for callgrind (benches/callgrind.sh)
fn over_lanes(buf: &mut [u32], stream: &[Step], src: &[[u32; LANES]]) {
    let bytes02 = u32x8::splat(0x00ff_00ff);
    let bits = u32x8::new([1, 2, 4, 8, 16, 32, 64, 128]);
    for (s, px) in stream.iter().zip(src) {
        let d8: &mut [u32; LANES] = (&mut buf[s.span * LANES..(s.span + 1) * LANES])
            .try_into()
            .expect("8 pixels");
        let dst = u32x8::new(*d8);
        let src = u32x8::new(*px);
        let inv = u32x8::splat(255) - (src >> 24);
        let inv2: u16x16 = bytemuck::cast(inv | (inv << 16));
        let div = |x: u32x8| {
            let y = x + u32x8::splat(0x0080_0080);
            ((y + ((y >> 8) & bytes02)) >> 8) & bytes02
        };
        let pe = div(bytemuck::cast(bytemuck::cast::<_, u16x16>(dst & bytes02) * inv2));
        let po = div(bytemuck::cast(bytemuck::cast::<_, u16x16>((dst >> 8) & bytes02) * inv2));
        let out: u32x8 = bytemuck::cast(bytemuck::cast::<_, u8x32>(src).saturating_add(bytemuck::cast(pe | (po << 8))));
        let on = (u32x8::splat(s.mask as u32) & bits).simd_eq(bits);
        *d8 = on.select(out, dst).to_array();
    }
}

/// Bench names: `mlab_scalar/M` and `mlab_lanes/M` in the default arithmetic (Unbiased),
/// `mlab_scalar_paper/M` and `mlab_lanes_paper/M` in the paper's; likewise `ht_*`.
macro_rules! mlab_group {
    ($g:expr, $stream:expr, $($m:literal),*) => {$(
        for (suffix, paper) in [("", false), ("_paper", true)] {
            let mut pixels = vec![[Row::EMPTY; $m]; W * H];
            let mut spans = vec![[[Row::EMPTY; LANES]; $m]; SPANS];
            $g.bench_function(BenchmarkId::new(format!("mlab_scalar{suffix}"), $m), |b| b.iter(|| if paper {
                mlab_scalar::<Paper, $m>(&mut pixels, black_box($stream))
            } else {
                mlab_scalar::<Unbiased, $m>(&mut pixels, black_box($stream))
            }));
            $g.bench_function(BenchmarkId::new(format!("mlab_lanes{suffix}"), $m), |b| b.iter(|| if paper {
                mlab_lanes::<Paper, $m>(&mut spans, black_box($stream))
            } else {
                mlab_lanes::<Unbiased, $m>(&mut spans, black_box($stream))
            }));
        }
    )*};
}

macro_rules! hybrid_group {
    ($g:expr, $stream:expr, $($k:literal),*) => {$(
        {
            let mut pixels = vec![([Row::EMPTY; $k], mlab::Tail::EMPTY); W * H];
            $g.bench_function(BenchmarkId::new("ht_scalar", $k), |b| b.iter(|| hybrid_scalar(&mut pixels, black_box($stream))));
            let mut spans = vec![HybridSpan::<$k>::default(); SPANS];
            $g.bench_function(BenchmarkId::new("ht_lanes", $k), |b| b.iter(|| hybrid_lanes(&mut spans, black_box($stream))));
            let mut pixels = vec![([Row::EMPTY; $k], hybrid::PaperTail::EMPTY); W * H];
            $g.bench_function(BenchmarkId::new("ht_scalar_paper", $k), |b| b.iter(|| hybrid_scalar(&mut pixels, black_box($stream))));
            let mut spans = vec![HybridSpan::<$k, Paper>::default(); SPANS];
            $g.bench_function(BenchmarkId::new("ht_lanes_paper", $k), |b| b.iter(|| hybrid_lanes(&mut spans, black_box($stream))));
        }
    )*};
}

fn insert(c: &mut Criterion) {
    println!("mlab lanes backend: {}", lanes::BACKEND);
    for (name, stream) in [
        ("insert_random", random_stream(SPANS)),
        ("insert_coherent", coherent_stream()),
    ] {
        let src = rgba_of(&stream);
        let mut g = c.benchmark_group(name);
        g.throughput(Throughput::Elements(fragments(&stream)));
        let mut buf = vec![0u32; W * H];
        g.bench_function("over_rgba8_scalar", |b| {
            b.iter(|| over_scalar(&mut buf, black_box(&stream), &src))
        });
        g.bench_function("over_rgba8_lanes", |b| {
            b.iter(|| over_lanes(&mut buf, black_box(&stream), &src))
        });
        mlab_group!(g, &stream, 1, 2, 4, 8);
        hybrid_group!(g, &stream, 1, 3, 7);
        let mut pixels = vec![[Row::EMPTY; 4]; W * H];
        g.bench_function(BenchmarkId::new("mlab_lanes_pixel_major", 4), |b| {
            b.iter(|| mlab_lanes_pixel_major::<4>(&mut pixels, black_box(&stream)))
        });
        g.finish();
    }
}

/// The random stream into a 32 x 32 target that stays in L1: compute bound, for comparison.
fn insert_small(c: &mut Criterion) {
    let stream = random_stream(SMALL_SPANS);
    let mut g = c.benchmark_group("insert_random_l1");
    g.throughput(Throughput::Elements(fragments(&stream)));
    let src = rgba_of(&stream);
    let mut buf = vec![0u32; SMALL_SPANS * LANES];
    g.bench_function("over_rgba8_scalar", |b| {
        b.iter(|| over_scalar(&mut buf, black_box(&stream), &src))
    });
    g.bench_function("over_rgba8_lanes", |b| {
        b.iter(|| over_lanes(&mut buf, black_box(&stream), &src))
    });
    let mut pixels = vec![[Row::EMPTY; 4]; SMALL_SPANS * LANES];
    g.bench_function(BenchmarkId::new("mlab_scalar", 4), |b| {
        b.iter(|| mlab_scalar::<Unbiased, 4>(&mut pixels, black_box(&stream)))
    });
    let mut spans = vec![[[Row::EMPTY; LANES]; 4]; SMALL_SPANS];
    g.bench_function(BenchmarkId::new("mlab_lanes", 4), |b| {
        b.iter(|| mlab_lanes::<Unbiased, 4>(&mut spans, black_box(&stream)))
    });
    g.finish();
}

#[inline(never)] // a symbol of its own, for callgrind (benches/callgrind.sh)
fn resolve_scalar<const M: usize>(out: &mut [[u8; 4]], pixels: &[[Row; M]], bg: Background) {
    for (o, p) in out.iter_mut().zip(pixels) {
        *o = to_rgba8(resolve_rows(p).pixel(bg));
    }
}

/// The integer RGBA8 resolve (what `resolve_rgba8` writes for MLAB), whole frame, span
/// storage. Its work is inlined into `Grid::resolve_rgba8`: count it inclusive.
#[inline(never)] // a symbol of its own, for callgrind (benches/callgrind.sh)
fn resolve_lanes<const M: usize>(out: &mut [[u8; 4]], fb: &SpanFramebuffer<'_, M>, bg: Background) {
    fb.resolve_rgba8(out, bg).expect("size");
}

/// The f32 resolve in lanes, then `to_rgba8` in lanes (`ResolvedLanes::rgba8`): the RGBA8
/// resolve before the integer one.
#[inline(never)] // a symbol of its own, for callgrind (benches/callgrind.sh)
fn resolve_lanes_f32<const M: usize>(out: &mut [[u8; 4]], spans: &[MlabSpan<M>], bg: Background) {
    for (o, s) in out.chunks_exact_mut(LANES).zip(spans) {
        o.copy_from_slice(&lanes::mlab_resolve(s).rgba8(bg));
    }
}

/// The integer HT RGBA8 resolve (what `resolve_rgba8` writes for HT), span storage, K = 3:
/// count it inclusive.
#[inline(never)] // a symbol of its own, for callgrind (benches/callgrind.sh)
fn resolve_ht_int<A: Arithmetic>(out: &mut [[u8; 4]], fb: &mlab::HybridSpanFramebuffer<'_, 3, A>, bg: Background) {
    fb.resolve_rgba8(out, bg).expect("size");
}

/// The f32 HT resolve in lanes, then `to_rgba8` in lanes (`ResolvedLanes::rgba8`): HT's
/// RGBA8 before the integer resolve.
#[inline(never)] // a symbol of its own, for callgrind (benches/callgrind.sh)
fn resolve_ht_f32<A: Arithmetic>(out: &mut [[u8; 4]], spans: &[HybridSpan<3, A>], bg: Background) {
    for (o, s) in out.chunks_exact_mut(LANES).zip(spans) {
        o.copy_from_slice(&lanes::hybrid_resolve(s).rgba8(bg));
    }
}

fn resolve_ht<A: Arithmetic>(
    g: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    stream: &[Step],
    name: &str,
) {
    let mut hs = vec![HybridSpan::<3, A>::default(); SPANS];
    hybrid_lanes(&mut hs, stream);
    let mut storage: Vec<Row> = hs
        .iter()
        .flat_map(|s| {
            let tails: [Row; LANES] = s.tails.map(|t| Row::from_bytes(t.to_bytes()));
            s.head.iter().flatten().copied().chain(tails).collect::<Vec<_>>()
        })
        .collect();
    let fb = mlab::HybridSpanFramebuffer::<3, A>::new(&mut storage, W as u32, H as u32).expect("size");
    let bg = Background::Opaque(mlab::glam::Vec3::new(0.2, 0.3, 0.4));
    let mut out = vec![[0u8; 4]; W * H];
    g.bench_function(BenchmarkId::new(format!("ht_int{name}"), 3), |b| {
        b.iter(|| resolve_ht_int::<A>(&mut out, black_box(&fb), bg))
    });
    g.bench_function(BenchmarkId::new(format!("ht_f32{name}"), 3), |b| {
        b.iter(|| resolve_ht_f32::<A>(&mut out, black_box(&hs), bg))
    });
}

fn resolve_m<const M: usize>(g: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>, stream: &[Step]) {
    let mut pixels = vec![[Row::EMPTY; M]; W * H];
    mlab_scalar::<Unbiased, M>(&mut pixels, stream);
    let spans: Vec<MlabSpan<M>> = pixels
        .chunks_exact(LANES)
        .map(|c| from_pixel_major(c.try_into().expect("8 pixels")))
        .collect();
    let mut storage: Vec<Row> = spans.iter().flatten().flatten().copied().collect();
    let fb = SpanFramebuffer::<M>::new(&mut storage, W as u32, H as u32).expect("size");
    let bg = Background::Opaque(mlab::glam::Vec3::new(0.2, 0.3, 0.4));
    let mut out = vec![[0u8; 4]; W * H];
    g.bench_function(BenchmarkId::new("mlab_scalar", M), |b| {
        b.iter(|| resolve_scalar::<M>(&mut out, black_box(&pixels), bg))
    });
    g.bench_function(BenchmarkId::new("mlab_lanes", M), |b| {
        b.iter(|| resolve_lanes::<M>(&mut out, black_box(&fb), bg))
    });
    g.bench_function(BenchmarkId::new("mlab_lanes_f32", M), |b| {
        b.iter(|| resolve_lanes_f32::<M>(&mut out, black_box(&spans), bg))
    });
}

fn resolve(c: &mut Criterion) {
    let stream = random_stream(SPANS);
    let bg = Background::Opaque(mlab::glam::Vec3::new(0.2, 0.3, 0.4));
    let mut out = vec![[0u8; 4]; W * H];
    let mut g = c.benchmark_group("resolve_rgba8");
    g.throughput(Throughput::Elements((W * H) as u64));
    resolve_m::<1>(&mut g, &stream);
    resolve_m::<4>(&mut g, &stream);
    resolve_m::<8>(&mut g, &stream);
    let mut hp = vec![([Row::EMPTY; 3], mlab::Tail::EMPTY); W * H];
    hybrid_scalar(&mut hp, &stream);
    let mut hs = vec![HybridSpan::<3>::default(); SPANS];
    hybrid_lanes(&mut hs, &stream);
    g.bench_function(BenchmarkId::new("ht_scalar", 3), |b| {
        b.iter(|| {
            for (o, (h, t)) in out.iter_mut().zip(black_box(&hp)) {
                *o = to_rgba8(mlab::Hybrid::<3>::from_parts(*h, *t).resolve().pixel(bg));
            }
        })
    });
    g.bench_function(BenchmarkId::new("ht_lanes", 3), |b| {
        b.iter(|| {
            for (o, s) in out.chunks_exact_mut(LANES).zip(black_box(&hs)) {
                o.copy_from_slice(&lanes::hybrid_resolve(s).rgba8(bg));
            }
        })
    });
    resolve_ht::<Unbiased>(&mut g, &stream, "");
    resolve_ht::<Paper>(&mut g, &stream, "_paper");
    // The random stream (4 full-span inserts per span on average: at K = 3 about 43 % of the
    // spans keep only empty tails, which HT's integer resolve skips) four times over: 16 per
    // span, every span's tails hold fragments.
    resolve_ht::<Unbiased>(&mut g, &stream.repeat(4), "_deep");
    g.finish();
}

/// The memory floor of a span insert (issue 31): the same span accesses as `mlab_lanes/M`, each
/// span read and written back whole (`M x 64` bytes: 32 bytes per fragment at `M = 4`) with
/// nothing computed but one xor per register, so that no insert can be faster than this
/// read-modify-write on this machine.
#[inline(never)] // a symbol of its own, for callgrind (benches/callgrind.sh)
fn span_rmw<const M: usize>(spans: &mut [MlabSpan<M>], stream: &[Step]) {
    for s in stream {
        let rows: [u64; LANES] = bytemuck::cast(s.rows);
        for layer in spans[s.span].iter_mut() {
            let mut words: [u64; LANES] = bytemuck::cast(*layer);
            for (w, r) in words.iter_mut().zip(rows) {
                *w ^= r;
            }
            *layer = bytemuck::cast(words);
        }
    }
}

/// `memory_floor/{l2,stream}/{span_rmw,mlab_lanes}/M`: the floor and the insert on the random
/// stream into the benches' 128 x 128 frame (`l2`: 512 KiB of spans at `M = 4`, resident in
/// the L2 cache of the machines we measure on) and into a 1920 x 1080 frame (`stream`: 66 MB at
/// `M = 4`, beyond the L3 cache: every access goes to memory). The ratio of the two is the
/// insert's cost in units of the floor (docs/performance.md).
fn memory_floor(c: &mut Criterion) {
    const BIG_SPANS: usize = 1920 * 1080 / LANES;
    for (name, spans_n) in [("memory_floor/l2", SPANS), ("memory_floor/stream", BIG_SPANS)] {
        let stream = random_stream(spans_n);
        let mut g = c.benchmark_group(name);
        g.throughput(Throughput::Elements(fragments(&stream)));
        macro_rules! each {
            ($($m:literal),*) => {$(
                let mut spans = vec![[[Row::EMPTY; LANES]; $m]; spans_n];
                g.bench_function(BenchmarkId::new("span_rmw", $m), |b| b.iter(|| span_rmw::<$m>(&mut spans, black_box(&stream))));
                g.bench_function(BenchmarkId::new("mlab_lanes", $m), |b| b.iter(|| mlab_lanes::<Unbiased, $m>(&mut spans, black_box(&stream))));
            )*};
        }
        each!(4, 8);
        g.finish();
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().warm_up_time(std::time::Duration::from_millis(500)).measurement_time(std::time::Duration::from_secs(2)).sample_size(30);
    targets = insert, insert_small, resolve, memory_floor
}
criterion_main!(benches);

/// The span in the per-pixel arrangement, `[pixel][row]` (a transpose).
fn to_pixel_major<const M: usize>(span: &[[Row; LANES]; M]) -> [[Row; M]; LANES] {
    core::array::from_fn(|lane| core::array::from_fn(|j| span[j][lane]))
}

/// The inverse of [`to_pixel_major`].
#[allow(dead_code)]
fn from_pixel_major<const M: usize>(pixels: &[[Row; M]; LANES]) -> [[Row; LANES]; M] {
    core::array::from_fn(|j| core::array::from_fn(|lane| pixels[lane][j]))
}

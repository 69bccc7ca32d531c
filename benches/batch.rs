//! Criterion benches for the framebuffer level: the span batcher against per-pixel inserts
//! (fragments per second), and every whole-framebuffer resolve (pixels per second).
//!
//! `cargo bench --bench batch` (default target: wide on SSE2) and
//! `CARGO_TARGET_DIR=target-v3 RUSTFLAGS="-C target-cpu=x86-64-v3" cargo bench --bench batch`
//! (AVX2). Results: docs/performance.md.
//!
//! Insert streams, one validated fragment per pixel event, in submission order:
//! - `coherent`: random rectangles (primitives) scanned line by line, pixel by pixel, into
//!   128 x 128 pixels (the `insert_coherent` stream of `benches/kernel.rs`, per pixel);
//! - `mesh`: the procedural tori of `examples/rasterizer.rs` (`examples/common/raster.rs`)
//!   rasterized into 320 x 240 pixels, unsorted, replayed pixel by pixel.
//!
//! - `client_mesh`: the same scene at 640 x 360 as a renderer holds it before validation
//!   (straight RGBA and depth per pixel event): every bench validates each fragment
//!   (`Fragment::straight_rgba`) in the loop, as a client does, in both arithmetics;
//!   `validate_only` is that validation alone (issue 21; `benches/previous_release.sh`
//!   runs the per-pixel passes against an older commit).
//!
//! Framebuffers are not cleared between iterations (steady state: every array full, every
//! insert merges), as in `benches/kernel.rs`.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use mlab::glam::{Vec3, Vec4};
use mlab::half::f16;
use mlab::{
    Background, DynFramebuffer, Fragment, Framebuffer, HybridFramebuffer, HybridSpanFramebuffer, Layers,
    MlabFramebuffer, Paper, Row, SpanBatcher, SpanFramebuffer,
};
use mlab_reference::Rng;
use std::hint::black_box;

#[path = "../examples/common/raster.rs"]
#[allow(dead_code)]
mod raster;

/// One pixel event: pixel and a validated fragment.
type Event = (u32, u32, Fragment);

/// Random rectangles up to 48 x 24 pixels, one fragment per covered pixel, with a slight
/// depth gradient along x; 65536 fragments.
fn coherent(w: u32, h: u32) -> Vec<Event> {
    let mut rng = Rng(0x2545_f491_4f6c_dd1d);
    let mut out = Vec::new();
    while out.len() < 65536 {
        let (x0, y0) = ((rng.next_u64() % w as u64) as u32, (rng.next_u64() % h as u64) as u32);
        let (rw, rh) = (1 + (rng.next_u64() % 48) as u32, 1 + (rng.next_u64() % 24) as u32);
        let z0 = 100.0 * rng.unit();
        let c = Vec3::new(rng.unit(), rng.unit(), rng.unit());
        let alpha = 0.1 + 0.8 * rng.unit();
        for y in y0..(y0 + rh).min(h) {
            for x in x0..(x0 + rw).min(w) {
                let f = Fragment::straight(c, alpha, z0 + 0.01 * x as f32).expect("valid");
                out.push((x, y, f));
            }
        }
    }
    out
}

/// The scene of the rasterizer example, unsorted, pixel by pixel.
fn mesh(w: u32, h: u32) -> Vec<Event> {
    let mut out = Vec::new();
    for t in raster::scene(w, h, 48, 24) {
        raster::rasterize(&t, w, h, |x, y, z| {
            let f = Fragment::straight(Vec3::from_array(t.color), t.alpha, z).expect("valid");
            out.push((x, y, f));
        });
    }
    out
}

/// A pixel event before validation: pixel, straight `[R, G, B, A]`, depth.
type RawEvent = (u32, u32, [f32; 4], f32);

/// The scene of the rasterizer example with more triangles, unvalidated.
fn mesh_raw(w: u32, h: u32) -> Vec<RawEvent> {
    raster::events(w, h, 96, 48)
}

#[inline(always)]
fn client_per_pixel<F: Framebuffer>(fb: &mut F, events: &[RawEvent]) {
    for &(x, y, rgba, z) in events {
        let f = Fragment::straight_rgba(rgba, z).expect("valid");
        fb.insert(x, y, &f).expect("inside");
    }
}

#[inline(always)]
fn client_batched<F: Framebuffer>(fb: &mut F, events: &[RawEvent]) {
    let mut batch = SpanBatcher::new(fb);
    for &(x, y, rgba, z) in events {
        let f = Fragment::straight_rgba(rgba, z).expect("valid");
        batch.insert(x, y, &f).expect("inside");
    }
    batch.finish().expect("flush");
}

/// The validation of the client benches alone (the sum keeps it from being removed).
#[inline(never)]
fn validate_only(events: &[RawEvent]) -> f32 {
    let mut sum = 0.0;
    for &(_, _, rgba, z) in events {
        sum += Fragment::straight_rgba(rgba, z).expect("valid").alpha();
    }
    sum
}

#[inline(always)]
fn per_pixel<F: Framebuffer>(fb: &mut F, events: &[Event]) {
    for (x, y, f) in events {
        fb.insert(*x, *y, f).expect("inside");
    }
}

#[inline(always)]
fn batched<F: Framebuffer>(fb: &mut F, events: &[Event]) {
    let mut batch = SpanBatcher::new(fb);
    for (x, y, f) in events {
        batch.insert(*x, *y, f).expect("inside");
    }
    batch.finish().expect("flush");
}

/// One driver per bench: a symbol of its own for callgrind (`benches/callgrind.sh ...
/// batch::mlab_batcher_spans N inclusive`).
macro_rules! drivers {
    ($($name:ident: $fb:ty => $f:ident;)*) => {$(
        #[inline(never)]
        fn $name(fb: &mut $fb, events: &[Event]) {
            $f(fb, events)
        }
    )*};
    ($($name:ident: $fb:ty => $f:ident (raw);)*) => {$(
        #[inline(never)]
        fn $name(fb: &mut $fb, events: &[RawEvent]) {
            $f(fb, events)
        }
    )*};
}

drivers! {
    client_mlab4_per_pixel: MlabFramebuffer<'_, 4> => client_per_pixel (raw);
    client_mlab4_paper_per_pixel: MlabFramebuffer<'_, 4, Paper> => client_per_pixel (raw);
    client_mlab8_per_pixel: MlabFramebuffer<'_, 8> => client_per_pixel (raw);
    client_ht3_per_pixel: HybridFramebuffer<'_, 3> => client_per_pixel (raw);
    client_ht3_paper_per_pixel: HybridFramebuffer<'_, 3, Paper> => client_per_pixel (raw);
    client_ht3_spans_per_pixel: HybridSpanFramebuffer<'_, 3> => client_per_pixel (raw);
    client_mlab4_batcher: SpanFramebuffer<'_, 4> => client_batched (raw);
    client_mlab4_paper_batcher: SpanFramebuffer<'_, 4, Paper> => client_batched (raw);
}

drivers! {
    mlab_per_pixel_pixel_major: MlabFramebuffer<'_, 4> => per_pixel;
    mlab_batcher_pixel_major: MlabFramebuffer<'_, 4> => batched;
    mlab_per_pixel_spans: SpanFramebuffer<'_, 4> => per_pixel;
    mlab_batcher_spans: SpanFramebuffer<'_, 4> => batched;
    ht_per_pixel_pixel_major: HybridFramebuffer<'_, 3> => per_pixel;
    // Passed straight through to per-pixel inserts (`Framebuffer::SPAN_INSERTS_PAY`).
    ht_batcher_pixel_major: HybridFramebuffer<'_, 3> => batched;
    ht_per_pixel_spans: HybridSpanFramebuffer<'_, 3> => per_pixel;
    ht_batcher_spans: HybridSpanFramebuffer<'_, 3> => batched;
    batcher_alone: Probe<'_> => batched;
    // The run-time sizes (`DynFramebuffer`, the same span grids behind one match per call).
    mlab_per_pixel_dyn: DynFramebuffer<'_> => per_pixel;
    mlab_batcher_dyn: DynFramebuffer<'_> => batched;
    ht_per_pixel_dyn: DynFramebuffer<'_> => per_pixel;
    ht_batcher_dyn: DynFramebuffer<'_> => batched;
}

/// A framebuffer that drops the span inserts it gets (after `black_box`, so the batcher's
/// work is kept): the batcher alone, without the insert it feeds. Unbiased arithmetic, as every framebuffer of the insert benches.
struct Probe<'a> {
    fb: SpanFramebuffer<'a, 1>,
}

impl Framebuffer for Probe<'_> {
    type Arith = mlab::Unbiased;
    type Band<'c>
        = SpanFramebuffer<'c, 1>
    where
        Self: 'c;
    fn width(&self) -> u32 {
        self.fb.width()
    }
    fn height(&self) -> u32 {
        self.fb.height()
    }
    fn layers(&self) -> mlab::Layers {
        self.fb.layers()
    }
    fn clear(&mut self) {}
    fn insert_row(&mut self, x: u32, y: u32, row: Row) -> Result<(), mlab::FramebufferError> {
        self.fb.insert_row(x, y, row)
    }
    #[inline]
    fn insert_span(&mut self, x: u32, y: u32, rows: &[Row; 8], mask: u8) -> Result<(), mlab::FramebufferError> {
        black_box((x, y, rows, mask));
        Ok(())
    }
    fn resolve(&self, x: u32, y: u32) -> Result<mlab::Resolved, mlab::FramebufferError> {
        self.fb.resolve(x, y)
    }
    fn resolve_span(&self, span: u32, y: u32) -> Option<mlab::lanes::ResolvedLanes> {
        self.fb.resolve_span(span, y)
    }
    fn as_rows(&self) -> &[Row] {
        self.fb.as_rows()
    }
    fn reborrow(&mut self) -> SpanFramebuffer<'_, 1> {
        self.fb.reborrow()
    }
    fn split_lines(self, _: u32) -> (Self, Self) {
        unreachable!("not split")
    }
}

/// Fragments per span insert of the batcher on a stream (printed once per stream).
fn occupancy(w: u32, h: u32, events: &[Event]) -> f64 {
    let mut storage = vec![Row::EMPTY; SpanFramebuffer::<1>::rows_needed(w, h).expect("size")];
    let mut fb = SpanFramebuffer::<1>::new_cleared(&mut storage, w, h).expect("size");
    let mut batch = SpanBatcher::new(&mut fb);
    for (x, y, f) in events {
        batch.insert(*x, *y, f).expect("inside");
    }
    batch.flush().expect("flush");
    events.len() as f64 / batch.span_inserts() as f64
}

macro_rules! insert_benches {
    ($g:expr, $events:expr, $w:expr, $h:expr, $m:literal, $k:literal) => {{
        let (w, h, ev) = ($w, $h, $events);
        let mut st = vec![Row::EMPTY; MlabFramebuffer::<$m>::rows_needed(w, h).expect("size")];
        let mut fb = MlabFramebuffer::<$m>::new_cleared(&mut st, w, h).expect("size");
        $g.bench_function(BenchmarkId::new("mlab_per_pixel_pixel_major", $m), |b| {
            b.iter(|| mlab_per_pixel_pixel_major(&mut fb, black_box(ev)))
        });
        $g.bench_function(BenchmarkId::new("mlab_batcher_pixel_major", $m), |b| {
            b.iter(|| mlab_batcher_pixel_major(&mut fb, black_box(ev)))
        });
        let mut st = vec![Row::EMPTY; SpanFramebuffer::<$m>::rows_needed(w, h).expect("size")];
        let mut fb = SpanFramebuffer::<$m>::new_cleared(&mut st, w, h).expect("size");
        $g.bench_function(BenchmarkId::new("mlab_per_pixel_spans", $m), |b| {
            b.iter(|| mlab_per_pixel_spans(&mut fb, black_box(ev)))
        });
        $g.bench_function(BenchmarkId::new("mlab_batcher_spans", $m), |b| {
            b.iter(|| mlab_batcher_spans(&mut fb, black_box(ev)))
        });
        let mut st = vec![Row::EMPTY; HybridFramebuffer::<$k>::rows_needed(w, h).expect("size")];
        let mut fb = HybridFramebuffer::<$k>::new_cleared(&mut st, w, h).expect("size");
        $g.bench_function(BenchmarkId::new("ht_per_pixel_pixel_major", $k), |b| {
            b.iter(|| ht_per_pixel_pixel_major(&mut fb, black_box(ev)))
        });
        $g.bench_function(BenchmarkId::new("ht_batcher_pixel_major", $k), |b| {
            b.iter(|| ht_batcher_pixel_major(&mut fb, black_box(ev)))
        });
        let mut st = vec![Row::EMPTY; HybridSpanFramebuffer::<$k>::rows_needed(w, h).expect("size")];
        let mut fb = HybridSpanFramebuffer::<$k>::new_cleared(&mut st, w, h).expect("size");
        $g.bench_function(BenchmarkId::new("ht_per_pixel_spans", $k), |b| {
            b.iter(|| ht_per_pixel_spans(&mut fb, black_box(ev)))
        });
        $g.bench_function(BenchmarkId::new("ht_batcher_spans", $k), |b| {
            b.iter(|| ht_batcher_spans(&mut fb, black_box(ev)))
        });
        for (layers, id, per_pixel, batcher) in [
            (
                Layers::Mlab($m),
                "mlab",
                mlab_per_pixel_dyn as fn(&mut DynFramebuffer<'_>, &[Event]),
                mlab_batcher_dyn as fn(&mut DynFramebuffer<'_>, &[Event]),
            ),
            (Layers::Hybrid($k), "ht", ht_per_pixel_dyn, ht_batcher_dyn),
        ] {
            let n = match layers {
                Layers::Mlab(n) | Layers::Hybrid(n) => n,
            };
            let mut st = vec![Row::EMPTY; layers.rows_needed(w, h).expect("size")];
            let mut fb: DynFramebuffer = DynFramebuffer::new_cleared(layers, &mut st, w, h).expect("size");
            $g.bench_function(BenchmarkId::new(format!("{id}_per_pixel_dyn"), n), |b| {
                b.iter(|| per_pixel(&mut fb, black_box(ev)))
            });
            $g.bench_function(BenchmarkId::new(format!("{id}_batcher_dyn"), n), |b| {
                b.iter(|| batcher(&mut fb, black_box(ev)))
            });
        }
        // The batcher's own work (push, quantization), the span inserts discarded: the part
        // of the batcher benches above that is not the framebuffer's insert.
        let mut st = vec![Row::EMPTY; SpanFramebuffer::<1>::rows_needed(w, h).expect("size")];
        let fb = SpanFramebuffer::<1>::new_cleared(&mut st, w, h).expect("size");
        let mut probe = Probe { fb };
        $g.bench_function("batcher_alone", |b| b.iter(|| batcher_alone(&mut probe, black_box(ev))));
    }};
}

/// `client_mesh/...`: validation in the loop, both arithmetics (see the module docs).
fn client(c: &mut Criterion) {
    let (w, h) = (640, 360);
    let events = mesh_raw(w, h);
    println!("client_mesh: {} fragments", events.len());
    let mut g = c.benchmark_group("client_mesh");
    g.throughput(Throughput::Elements(events.len() as u64));
    let ev = &events;
    macro_rules! bench {
        ($id:literal, $fb:ty, $driver:ident) => {{
            let mut st = vec![Row::EMPTY; <$fb>::rows_needed(w, h).expect("size")];
            let mut fb = <$fb>::new_cleared(&mut st, w, h).expect("size");
            g.bench_function($id, |b| b.iter(|| $driver(&mut fb, black_box(ev))));
        }};
    }
    bench!("mlab4_per_pixel", MlabFramebuffer<'_, 4>, client_mlab4_per_pixel);
    bench!(
        "mlab4_paper_per_pixel",
        MlabFramebuffer<'_, 4, Paper>,
        client_mlab4_paper_per_pixel
    );
    bench!("mlab8_per_pixel", MlabFramebuffer<'_, 8>, client_mlab8_per_pixel);
    bench!("ht3_per_pixel", HybridFramebuffer<'_, 3>, client_ht3_per_pixel);
    bench!(
        "ht3_paper_per_pixel",
        HybridFramebuffer<'_, 3, Paper>,
        client_ht3_paper_per_pixel
    );
    bench!(
        "ht3_spans_per_pixel",
        HybridSpanFramebuffer<'_, 3>,
        client_ht3_spans_per_pixel
    );
    bench!("mlab4_batcher", SpanFramebuffer<'_, 4>, client_mlab4_batcher);
    bench!(
        "mlab4_paper_batcher",
        SpanFramebuffer<'_, 4, Paper>,
        client_mlab4_paper_batcher
    );
    g.bench_function("validate_only", |b| b.iter(|| validate_only(black_box(ev))));
    g.finish();
}

fn batch(c: &mut Criterion) {
    println!("mlab lanes backend: {}", mlab::lanes::BACKEND);
    for (name, (w, h), events) in [
        ("batch_coherent", (128, 128), coherent(128, 128)),
        ("batch_mesh", (320, 240), mesh(320, 240)),
    ] {
        println!(
            "{name}: {} fragments, {:.2} fragments per span insert",
            events.len(),
            occupancy(w, h, &events)
        );
        let mut g = c.benchmark_group(name);
        g.throughput(Throughput::Elements(events.len() as u64));
        insert_benches!(g, &events, w, h, 4, 3);
        g.finish();
    }
}

/// Fill `fb` with the coherent stream (every array full), for the resolves.
fn filled<F: Framebuffer>(fb: &mut F, events: &[Event]) {
    fb.clear();
    batched(fb, events);
}

#[inline(never)] // a symbol of its own, for callgrind (benches/callgrind.sh)
fn resolve_rgba8<F: Framebuffer>(fb: &F, out: &mut [[u8; 4]], bg: Background) {
    fb.resolve_rgba8(out, bg).expect("size");
}

#[inline(never)] // a symbol of its own, for callgrind (benches/callgrind.sh)
fn resolve_f32<F: Framebuffer>(fb: &F, out: &mut [Vec4], bg: Background) {
    fb.resolve_into(out, bg).expect("size");
}

#[inline(never)] // a symbol of its own, for callgrind (benches/callgrind.sh)
fn resolve_f16<F: Framebuffer>(fb: &F, out: &mut [[f16; 4]], bg: Background) {
    fb.resolve_rgba16f(out, bg).expect("size");
}

/// `resolve_{rgba8,f32,rgba16f}/{mlab,ht}_{pixel_major,spans}/N` for one framebuffer,
/// filled (once, and only when one of its benches is selected) by the coherent stream.
fn resolve_all<F: Framebuffer>(c: &mut Criterion, id: &str, n: usize, fb: &mut F, events: &[Event]) {
    let (w, h) = (fb.width(), fb.height());
    let mut full = false;
    let px = (w * h) as usize;
    let bg = Background::Opaque(Vec3::new(0.2, 0.3, 0.4));
    let (mut o8, mut o32, mut o16) = (vec![[0u8; 4]; px], vec![Vec4::ZERO; px], vec![[f16::ZERO; 4]; px]);
    for (group, which) in [("resolve_rgba8", 0), ("resolve_f32", 1), ("resolve_rgba16f", 2)] {
        let mut g = c.benchmark_group(group);
        g.throughput(Throughput::Elements(px as u64));
        g.bench_function(BenchmarkId::new(id, n), |b| {
            if !full {
                filled(fb, events);
                full = true;
            }
            match which {
                0 => b.iter(|| resolve_rgba8(black_box(&*fb), &mut o8, bg)),
                1 => b.iter(|| resolve_f32(black_box(&*fb), &mut o32, bg)),
                _ => b.iter(|| resolve_f16(black_box(&*fb), &mut o16, bg)),
            }
        });
        g.finish();
    }
}

macro_rules! resolve_benches {
    ($c:expr, $events:expr, $w:expr, $h:expr, $($n:literal),*) => {$(
        let mut st = vec![Row::EMPTY; MlabFramebuffer::<$n>::rows_needed($w, $h).expect("size")];
        resolve_all($c, "mlab_pixel_major", $n, &mut MlabFramebuffer::<$n>::new(&mut st, $w, $h).expect("size"), $events);
        let mut st = vec![Row::EMPTY; SpanFramebuffer::<$n>::rows_needed($w, $h).expect("size")];
        resolve_all($c, "mlab_spans", $n, &mut SpanFramebuffer::<$n>::new(&mut st, $w, $h).expect("size"), $events);
        let mut st = vec![Row::EMPTY; HybridFramebuffer::<$n>::rows_needed($w, $h).expect("size")];
        resolve_all($c, "ht_pixel_major", $n, &mut HybridFramebuffer::<$n>::new(&mut st, $w, $h).expect("size"), $events);
        let mut st = vec![Row::EMPTY; HybridSpanFramebuffer::<$n>::rows_needed($w, $h).expect("size")];
        resolve_all($c, "ht_spans", $n, &mut HybridSpanFramebuffer::<$n>::new(&mut st, $w, $h).expect("size"), $events);
    )*};
}

/// Every resolve path, 128 x 128 pixels filled by the coherent stream.
fn resolve(c: &mut Criterion) {
    let events = coherent(128, 128);
    resolve_benches!(c, &events, 128, 128, 1, 2, 4, 8);
    for (layers, id) in [(Layers::Mlab(4), "mlab_dyn"), (Layers::Hybrid(4), "ht_dyn")] {
        let mut st = vec![Row::EMPTY; layers.rows_needed(128, 128).expect("size")];
        let mut fb: DynFramebuffer = DynFramebuffer::new(layers, &mut st, 128, 128).expect("size");
        resolve_all(c, id, 4, &mut fb, &events);
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().warm_up_time(std::time::Duration::from_millis(300)).measurement_time(std::time::Duration::from_secs(1)).sample_size(20);
    targets = client, batch, resolve
}
criterion_main!(benches);

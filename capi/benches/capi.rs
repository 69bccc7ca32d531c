//! What the C API costs beyond the Rust call: per-pixel inserts through the C ABI against
//! the Rust `DynFramebuffer::insert`, on the same stream, validation in the loop on both
//! sides (the C functions validate; the Rust loop calls `Fragment::straight_rgba`).
//!
//! Stream: `client_mesh` of `benches/batch.rs` (the rasterizer example's three tori, 96 x 48
//! quads each, 640 x 360 pixels, 159,120 straight-color fragments in submission order).
//! Framebuffers are not cleared between iterations (steady state), as in `benches/batch.rs`.
//!
//! The C functions are called through function pointers passed through `black_box`, so
//! nothing is inlined across the boundary: each fragment is one call of the exported
//! symbol, as from a C program (which cannot inline Rust either, short of cross-language
//! LTO). Results and commands: `docs/performance.md`, "C API".

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use mlab::{Arithmetic, DynFramebuffer, Fragment, Framebuffer, Layers, Row, SpanBatcher, Unbiased};
use mlab_capi::*;
use std::hint::black_box;

#[path = "../../examples/common/raster.rs"]
#[allow(dead_code)]
mod raster;

type RawEvent = (u32, u32, [f32; 4], f32);
type InsertFn = unsafe extern "C" fn(*mut MlabFramebuffer, u32, u32, f32, f32, f32, f32, f32) -> MlabStatus;
type BatchFn = unsafe extern "C" fn(*mut MlabFramebuffer, *const MlabPixelFragment, usize, *mut usize) -> MlabStatus;

/// The Rust loop: validate, insert (the match on the size is taken out of the loop).
#[inline(never)]
fn rust_per_pixel<A: Arithmetic>(fb: &mut DynFramebuffer<'_, A>, events: &[RawEvent]) {
    for &(x, y, rgba, z) in events {
        let f = Fragment::straight_rgba(rgba, z).expect("valid");
        fb.insert(x, y, &f).expect("inside");
    }
}

/// The Rust span batcher over the same framebuffer (what `mlab_insert_batch_straight` runs).
#[inline(never)]
fn rust_batcher<A: Arithmetic>(fb: &mut DynFramebuffer<'_, A>, events: &[RawEvent]) {
    let mut batch = SpanBatcher::new(fb);
    for &(x, y, rgba, z) in events {
        let f = Fragment::straight_rgba(rgba, z).expect("valid");
        batch.insert(x, y, &f).expect("inside");
    }
    batch.finish().expect("flush");
}

/// The C loop: one call per fragment, its status checked.
#[inline(never)]
fn c_per_pixel(fb: *mut MlabFramebuffer, insert: InsertFn, events: &[RawEvent]) {
    for &(x, y, [r, g, b, a], z) in events {
        // SAFETY: `fb` is initialized over storage that outlives the bench.
        let st = unsafe { insert(fb, x, y, r, g, b, a, z) };
        assert!(st == MlabStatus::Ok, "{st:?}");
    }
}

/// The C batch: the whole stream in one call.
#[inline(never)]
fn c_batch(fb: *mut MlabFramebuffer, batch: BatchFn, fragments: &[MlabPixelFragment]) {
    let mut inserted = 0;
    // SAFETY: as above; `fragments` is readable, `inserted` writable.
    let st = unsafe { batch(fb, fragments.as_ptr(), fragments.len(), &mut inserted) };
    assert!(st == MlabStatus::Ok && inserted == fragments.len(), "{st:?}");
}

fn bench(c: &mut Criterion) {
    let (w, h) = (640, 360);
    let events = raster::events(w, h, 96, 48);
    let fragments: Vec<MlabPixelFragment> = events
        .iter()
        .map(|&(x, y, rgba, depth)| MlabPixelFragment { x, y, rgba, depth })
        .collect();
    println!("capi client_mesh: {} fragments", events.len());
    let mut g = c.benchmark_group("capi");
    g.throughput(Throughput::Elements(events.len() as u64));
    for (name, method, layers, kind) in [
        ("mlab4", MLAB_METHOD_MLAB, 4, Layers::Mlab(4)),
        ("ht3", MLAB_METHOD_HYBRID, 3, Layers::Hybrid(3)),
    ] {
        let mut storage = vec![Row::EMPTY; kind.rows_needed(w, h).expect("size")];
        let mut fb = DynFramebuffer::<Unbiased>::new_cleared(kind, &mut storage, w, h).expect("size");
        g.bench_function(format!("{name}_rust_per_pixel"), |b| {
            b.iter(|| rust_per_pixel(&mut fb, black_box(&events)))
        });
        g.bench_function(format!("{name}_rust_batcher"), |b| {
            b.iter(|| rust_batcher(&mut fb, black_box(&events)))
        });

        let mut rows = 0;
        // SAFETY: a size_t to write.
        assert_eq!(
            unsafe { mlab_rows_needed(method, layers, w, h, &mut rows) },
            MlabStatus::Ok
        );
        let mut c_storage = vec![MlabRow { bytes: [0; 8] }; rows];
        let mut c_fb = std::mem::MaybeUninit::<MlabFramebuffer>::uninit();
        // SAFETY: `c_storage` holds `rows` rows and outlives every use of `c_fb`.
        let st = unsafe {
            mlab_framebuffer_init(
                c_fb.as_mut_ptr(),
                method,
                layers,
                MLAB_ARITHMETIC_UNBIASED,
                c_storage.as_mut_ptr(),
                rows,
                w,
                h,
            )
        };
        assert_eq!(st, MlabStatus::Ok);
        let fb = c_fb.as_mut_ptr();
        let insert: InsertFn = black_box(mlab_insert_straight);
        let batch: BatchFn = black_box(mlab_insert_batch_straight);
        g.bench_function(format!("{name}_c_per_pixel"), |b| {
            b.iter(|| c_per_pixel(fb, insert, black_box(&events)))
        });
        g.bench_function(format!("{name}_c_batch"), |b| {
            b.iter(|| c_batch(fb, batch, black_box(&fragments)))
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);

//! The per-pixel client passes of `benches/batch.rs` (`client_mesh`), written so that the same
//! file also compiles against an older kernel (before the `Framebuffer` trait and the
//! arithmetic parameter): `benches/previous_release.sh COMMIT` builds it against COMMIT and
//! against this checkout and runs both interleaved. Not a bench target of the kernel's
//! Cargo.toml (the script makes its own crates); the feature `current` selects today's API.
//!
//! Each pass validates every fragment (`Fragment::straight`) and inserts it into a pixel-major
//! framebuffer in the default arithmetic, 640 x 360 pixels, not cleared between iterations.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
#[cfg(feature = "current")]
use mlab::Framebuffer;
use mlab::glam::Vec3;
use mlab::{Fragment, HybridFramebuffer, MlabFramebuffer, Row};
use std::hint::black_box;

#[path = "../../examples/common/raster.rs"]
#[allow(dead_code)]
mod raster;

type RawEvent = (u32, u32, [f32; 4], f32);

fn mesh_raw(w: u32, h: u32) -> Vec<RawEvent> {
    raster::events(w, h, 96, 48) // the stream of `client_mesh` in benches/batch.rs
}

macro_rules! driver {
    ($name:ident, $fb:ty) => {
        #[inline(never)]
        fn $name(fb: &mut $fb, events: &[RawEvent]) {
            for &(x, y, [r, g, b, a], z) in events {
                let f = Fragment::straight(Vec3::new(r, g, b), a, z).expect("valid");
                fb.insert(x, y, &f).expect("inside");
            }
        }
    };
}
driver!(mlab4, MlabFramebuffer<'_, 4>);
driver!(mlab8, MlabFramebuffer<'_, 8>);
driver!(ht3, HybridFramebuffer<'_, 3>);

fn release(c: &mut Criterion) {
    let (w, h) = (640, 360);
    let events = mesh_raw(w, h);
    let mut g = c.benchmark_group("release");
    g.throughput(Throughput::Elements(events.len() as u64));
    let ev = &events;
    macro_rules! bench {
        ($id:literal, $fb:ident, $n:literal, $driver:ident) => {{
            let mut st = vec![Row::EMPTY; $fb::<$n>::rows_needed(w, h).expect("size")];
            let mut fb = $fb::<$n>::new_cleared(&mut st, w, h).expect("size");
            g.bench_function($id, |b| b.iter(|| $driver(&mut fb, black_box(ev))));
        }};
    }
    bench!("mlab4_per_pixel", MlabFramebuffer, 4, mlab4);
    bench!("mlab8_per_pixel", MlabFramebuffer, 8, mlab8);
    bench!("ht3_per_pixel", HybridFramebuffer, 3, ht3);
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().warm_up_time(std::time::Duration::from_millis(300)).measurement_time(std::time::Duration::from_secs(1)).sample_size(20);
    targets = release
}
criterion_main!(benches);

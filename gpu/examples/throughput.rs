//! Fragments per second: the GPU compositor against the CPU kernel on the same stream.
//!
//! ```sh
//! cargo run --release -p mlab-gpu --example throughput              # 4M fragments, 640x480
//! cargo run --release -p mlab-gpu --example throughput -- 2000000 ht 3
//! ```
//!
//! The stream: fragments at uniformly random pixels (13 per pixel at the default size), alpha
//! a mix of faint, mid and opaque, random depths, validated premultiplied colors. Both sides
//! include the validation of every fragment; the GPU side is the whole `Compositor::composite`
//! (validation, the sort by pixel, the upload and the read-back of the rows), once with the sort
//! on the GPU (`Sort::Gpu`, set explicitly: the default on a software adapter is `Sort::Cpu`) and once on the CPU (`Sort::Cpu`). The CPU side is one
//! thread inserting into `DynFramebuffer` (spans). Also timed: `Compositor::order` with each
//! sort (validation, upload, sort and the read-back of the 8-byte keys, no composite), and the
//! validation alone. The best of three runs each, after a warm-up; the rows are checked
//! identical.

use mlab::{ArithKind, Layers};
use mlab_gpu::{Compositor, Gpu, GpuFragment, Layout, Sort, cpu};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let n: usize = args.first().map_or(Ok(4_000_000), |s| s.parse())?;
    let k: usize = args.get(2).map_or(Ok(4), |s| s.parse())?;
    let layers = match args.get(1).map(String::as_str) {
        Some("ht") => Layers::Hybrid(k),
        _ => Layers::Mlab(k),
    };
    let (w, h) = (640u32, 480u32);
    let mut x = 0x2545_f491_4f6c_dd1du64;
    let mut next = move || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        x
    };
    let frags: Vec<GpuFragment> = (0..n)
        .map(|_| {
            let r = next();
            let a = match r % 3 {
                0 => (r >> 8 & 0xff) as f32 / 4096.0,
                1 => 1.0,
                _ => (r >> 8 & 0xffff) as f32 / 65535.0,
            };
            let c = |s: u32| ((r >> s) & 0xff) as f32 / 255.0 * a;
            GpuFragment::new(
                ((r >> 32) % u64::from(w * h)) as u32,
                [c(16), c(24), c(40), a],
                (r >> 48) as f32 / 65536.0,
            )
        })
        .collect();

    let gpu = Gpu::new()?;
    let info = gpu.adapter_info();
    println!(
        "adapter: {} / {} / {} ({:?})",
        info.name, info.driver, info.driver_info, info.backend
    );
    println!("{n} fragments on {w}x{h}, {layers:?}");
    for arith in ArithKind::ALL {
        let mut c = Compositor::new(&gpu, layers, arith, Layout::Spans)?;
        let best = |f: &mut dyn FnMut() -> Vec<u32>| {
            let out = f(); // warm-up
            let t = (0..3)
                .map(|_| {
                    let t0 = Instant::now();
                    std::hint::black_box(f());
                    t0.elapsed().as_secs_f64()
                })
                .fold(f64::INFINITY, f64::min);
            (out, t)
        };
        c.set_sort(Sort::Gpu);
        let (g, tg) = best(&mut || c.composite(w, h, &frags).expect("gpu"));
        let (_, og) = best(&mut || c.order(w, h, &frags).expect("gpu order"));
        c.set_sort(Sort::Cpu);
        let (gc, tgc) = best(&mut || c.composite(w, h, &frags).expect("gpu, cpu sort"));
        let (_, oc) = best(&mut || c.order(w, h, &frags).expect("cpu order"));
        let (q, tc) = best(&mut || cpu::composite(layers, arith, Layout::Spans, w, h, &frags).expect("cpu"));
        let (_, tv) = best(&mut || validate(&frags));
        let rate = |t: f64| n as f64 / t / 1e6;
        println!(
            "{arith:?}: GPU, sort on the GPU {:.1} M fragments/s ({tg:.3} s; order alone {og:.3} s); \
             GPU, sort on the CPU {:.1} M fragments/s ({tgc:.3} s; order alone {oc:.3} s); \
             CPU one thread {:.1} M fragments/s ({tc:.3} s); validation alone {tv:.3} s; rows {}",
            rate(tg),
            rate(tgc),
            rate(tc),
            if g == q && gc == q { "identical" } else { "DIFFERENT" }
        );
        if g != q || gc != q {
            return Err("the GPU and the CPU differ".into());
        }
    }
    Ok(())
}

/// The validation `Compositor::composite` does on the CPU before anything else, for timing.
fn validate(frags: &[GpuFragment]) -> Vec<u32> {
    let mut valid = 0;
    for f in frags {
        valid += u32::from(mlab::Fragment::premultiplied_rgba(f.rgba, f.depth).is_ok());
    }
    vec![valid]
}

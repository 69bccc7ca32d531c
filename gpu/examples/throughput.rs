//! Fragments per second: the GPU compositor against the CPU kernel on the same stream.
//!
//! ```sh
//! cargo run --release -p mlab-gpu --example throughput              # 4M fragments, 640x480
//! cargo run --release -p mlab-gpu --example throughput -- 2000000 ht 3
//! ```
//!
//! The stream: fragments at uniformly random pixels (13 per pixel at the default size), alpha
//! a mix of faint, mid and opaque, random depths, validated premultiplied colors. Both sides
//! include the validation of every fragment; the GPU side also includes the CPU's counting sort
//! by pixel, the upload and the read-back of the rows (the whole `Compositor::composite`).
//! The CPU side is one thread inserting pixel by pixel into `DynFramebuffer` (spans). The best of
//! three runs each, after a warm-up; the rows are checked identical.

use mlab::Layers;
use mlab_gpu::{Arith, Compositor, Gpu, GpuFragment, Layout, cpu};
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
            GpuFragment {
                pixel: ((r >> 32) % u64::from(w * h)) as u32,
                rgba: [c(16), c(24), c(40), a],
                depth: (r >> 48) as f32 / 65536.0,
            }
        })
        .collect();

    let gpu = Gpu::new()?;
    let info = gpu.adapter_info();
    println!(
        "adapter: {} / {} / {} ({:?})",
        info.name, info.driver, info.driver_info, info.backend
    );
    println!("{n} fragments on {w}x{h}, {layers:?}");
    for arith in Arith::ALL {
        let c = Compositor::new(&gpu, layers, arith, Layout::Spans)?;
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
        let (g, tg) = best(&mut || c.composite(w, h, &frags).expect("gpu"));
        let (q, tc) = best(&mut || cpu::composite(layers, arith, Layout::Spans, w, h, &frags).expect("cpu"));
        // The CPU's share of the GPU path: the same validation and stable counting sort by
        // pixel as `Compositor::composite` does before its upload.
        let (_, tp) = best(&mut || prepare(w, h, &frags));
        println!(
            "{arith:?}: GPU {:.1} M fragments/s ({:.3} s, of which {:.3} s validation and sort on the CPU), CPU one thread {:.1} M fragments/s ({:.3} s), GPU/CPU {:.2}x, rows {}",
            n as f64 / tg / 1e6,
            tg,
            tp,
            n as f64 / tc / 1e6,
            tc,
            tc / tg,
            if g == q { "identical" } else { "DIFFERENT" }
        );
        if g != q {
            return Err("the GPU and the CPU differ".into());
        }
    }
    Ok(())
}

/// Validation and a stable counting sort by pixel (the compositor's CPU work), for timing.
fn prepare(w: u32, h: u32, frags: &[GpuFragment]) -> Vec<u32> {
    let mut offsets = vec![0u32; (w * h) as usize + 1];
    for f in frags {
        mlab::Fragment::premultiplied_rgba(f.rgba, f.depth).expect("valid");
        offsets[f.pixel as usize + 1] += 1;
    }
    for i in 0..(w * h) as usize {
        offsets[i + 1] += offsets[i];
    }
    let mut sorted = vec![0u32; frags.len() * 5];
    for f in frags {
        let at = offsets[f.pixel as usize] as usize;
        offsets[f.pixel as usize] += 1;
        let [r, g, b, a] = f.rgba.map(f32::to_bits);
        sorted[5 * at..5 * at + 5].copy_from_slice(&[r, g, b, a, f.depth.to_bits()]);
    }
    sorted
}

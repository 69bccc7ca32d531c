use mlab::Layers;
use mlab_gpu::*;
#[test]
fn smoke() {
    let gpu = Gpu::new().unwrap();
    eprintln!("{:?}", gpu.adapter_info());
    for layers in [Layers::Mlab(4), Layers::Hybrid(3)] {
        for arith in Arith::ALL {
            for layout in [Layout::Spans, Layout::PixelMajor] {
                let c = Compositor::new(&gpu, layers, arith, layout).unwrap();
                let mut x = 1u32;
                let mut frags = vec![];
                for _ in 0..2000 {
                    x = x.wrapping_mul(1664525).wrapping_add(1013904223);
                    let a = (x >> 8) as f32 / 16777216.0;
                    frags.push(GpuFragment { pixel: x % 150, rgba: [a * 0.3, a * 0.5, a * 0.02, a], depth: (x % 7) as f32 });
                }
                let g = c.composite(15, 10, &frags).unwrap();
                let cpu = cpu::composite(layers, arith, layout, 15, 10, &frags).unwrap();
                assert_eq!(g.len(), cpu.len());
                let diff = g.iter().zip(&cpu).filter(|(a, b)| a != b).count();
                assert_eq!(diff, 0, "{layers:?} {arith:?} {layout:?}");
            }
        }
    }
}

//! Fragments in, PNG out, on the GPU: the rasterizer example's transparent torus
//! (`examples/common/raster.rs` of the kernel) composited by [`mlab_gpu::Compositor`], resolved
//! to RGBA8 on the GPU by the kernel's integer resolve (MLAB's, or HT's), and checked against the
//! CPU kernel on the same fragments: the rows and the RGBA8 image are compared byte for byte.
//!
//! ```sh
//! cargo run --release -p mlab-gpu --example torus                   # MLAB, 4 rows, Unbiased
//! cargo run --release -p mlab-gpu --example torus -- ht 3 paper     # HT, 3 head rows, Paper
//! ```
//!
//! Writes `out/gpu-torus.png` (linear RGBA8, the kernel's `resolve_rgba8`). Needs a Vulkan
//! driver (`apt-get install mesa-vulkan-drivers libvulkan1` gives Mesa's software one).

use mlab::{ArithKind, Background, DynFramebuffer, Fragment, Framebuffer, Layers, Paper, Row, Unbiased};
use mlab_gpu::{Compositor, Gpu, GpuFragment, Layout, cpu};

#[path = "../../examples/common/raster.rs"]
mod raster;

const W: u32 = 640;
const H: u32 = 480;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let n: usize = args.get(1).map_or(Ok(4), |s| s.parse())?;
    let layers = match args.first().map(String::as_str) {
        Some("ht") => Layers::Hybrid(n),
        _ => Layers::Mlab(n),
    };
    let arith = match args.get(2).map(String::as_str) {
        Some("paper") => ArithKind::Paper,
        _ => ArithKind::Unbiased,
    };

    // The fragments, in mesh order (unsorted), premultiplied by the kernel's own constructor,
    // keyed by their triangle's index (a primitive id: Unbiased's dithers stay put as the
    // camera moves).
    let mut fragments = Vec::new();
    for (prim, t) in (0u32..).zip(&raster::scene(W, H, 96, 48)) {
        raster::rasterize(t, W, H, |x, y, z| {
            if let Ok(f) = Fragment::straight(mlab::glam::Vec3::from_array(t.color), t.alpha, z) {
                let c = f.color();
                fragments.push(GpuFragment::new(y * W + x, [c.x, c.y, c.z, f.alpha()], z).with_key(prim));
            }
        });
    }

    let gpu = Gpu::new()?;
    let info = gpu.adapter_info();
    let compositor = Compositor::new(&gpu, layers, arith, Layout::Spans)?;
    let background = Background::Opaque(mlab::glam::Vec3::new(0.9, 0.9, 0.85));
    // The rows and the integer RGBA8 resolve, both on the GPU.
    let (words, image) = compositor.composite_rgba8(W, H, &fragments, background)?;
    let cpu_words = cpu::composite(layers, arith, Layout::Spans, W, H, &fragments)?;
    let cpu_image = resolve(layers, arith, &cpu_words, background)?;
    println!(
        "{layers:?} {arith:?} on {} ({}): {} fragments; rows {} the CPU's, RGBA8 {}",
        info.name,
        info.driver_info,
        fragments.len(),
        if words == cpu_words {
            "identical to"
        } else {
            "DIFFERENT from"
        },
        if image == cpu_image { "identical" } else { "DIFFERENT" },
    );

    std::fs::create_dir_all("out")?;
    let file = std::io::BufWriter::new(std::fs::File::create("out/gpu-torus.png")?);
    let mut enc = png::Encoder::new(file, W, H);
    enc.set_color(png::ColorType::Rgba);
    enc.set_depth(png::BitDepth::Eight);
    let mut writer = enc.write_header()?;
    writer.write_image_data(image.as_flattened())?;
    writer.finish()?;
    println!("wrote out/gpu-torus.png");
    if words != cpu_words || image != cpu_image {
        return Err("the GPU and the CPU differ".into());
    }
    Ok(())
}

/// The kernel's RGBA8 resolve of span-layout storage words (the CPU's image).
fn resolve(layers: Layers, arith: ArithKind, words: &[u32], bg: Background) -> Result<Vec<[u8; 4]>, mlab::Error> {
    let mut rows: Vec<Row> = words.chunks_exact(2).map(|w| Row::from_words([w[0], w[1]])).collect();
    let mut out = vec![[0u8; 4]; (W * H) as usize];
    match arith {
        ArithKind::Paper => DynFramebuffer::<Paper>::new(layers, &mut rows, W, H)?.resolve_rgba8(&mut out, bg)?,
        ArithKind::Unbiased => DynFramebuffer::<Unbiased>::new(layers, &mut rows, W, H)?.resolve_rgba8(&mut out, bg)?,
    }
    Ok(out)
}

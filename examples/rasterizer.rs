//! A renderer's view of the kernel: a small triangle rasterizer draws a procedural
//! transparent mesh (a torus, both faces, in mesh order: unsorted) one pixel at a time
//! through a [`SpanBatcher`] into a framebuffer whose method and size are picked at run
//! time ([`DynFramebuffer`]), resolves it, and writes a PNG beside the exact A-buffer
//! answer (every fragment kept per pixel, sorted in f64), with the PSNR between them.
//!
//! ```sh
//! cargo run --release --example rasterizer              # MLAB, 4 rows
//! cargo run --release --example rasterizer -- ht 3      # Hybrid Transparency, 3 head rows
//! ```
//!
//! Writes `out/rasterizer.png`: the kernel's image on the left, the A-buffer's on the right.
//! Needs `mlab` and `png` (and `examples/common/raster.rs`, the rasterizer) only: copy it
//! into a crate of your own as it is.
//! Colors are linear throughout; the PNG is sRGB-encoded at the end, for display only.

use mlab::{Background, DynFramebuffer, Fragment, Framebuffer, Layers, Row, SpanBatcher};

#[path = "common/raster.rs"]
mod raster;

const W: u32 = 640;
const H: u32 = 480;
const BACKGROUND: [f32; 3] = [0.9, 0.9, 0.85];

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let n: usize = args.get(1).map_or(Ok(4), |s| s.parse())?;
    let layers = match args.first().map(String::as_str) {
        Some("ht") => Layers::Hybrid(n),
        _ => Layers::Mlab(n),
    };

    // The kernel's framebuffer: storage is ours, the view checks every size.
    let mut storage = vec![Row::EMPTY; layers.rows_needed(W, H)?];
    let mut fb: DynFramebuffer = DynFramebuffer::new_cleared(layers, &mut storage, W, H)?;
    // The exact answer: every fragment of every pixel (premultiplied color, alpha, depth), in
    // submission order, sorted and composited in f64 at the end (`exact` below).
    let mut abuffer: Vec<Vec<Fragment>> = vec![Vec::new(); (W * H) as usize];

    let mesh = raster::scene(W, H, 96, 48);
    let mut covered = Vec::new();
    let mut fragments = 0usize;
    let mut batch = SpanBatcher::new(&mut fb);
    for t in &mesh {
        covered.clear();
        raster::rasterize(t, W, H, |x, y, z| covered.push((x, y, z)));
        for &(x, y, z) in &covered {
            // Straight linear color; the kernel premultiplies and quantizes it.
            let f = Fragment::straight(mlab::glam::Vec3::from_array(t.color), t.alpha, z)?;
            batch.insert(x, y, &f)?;
            abuffer[(y * W + x) as usize].push(f);
            fragments += 1;
        }
    }
    batch.finish()?; // the last pending spans

    let mut image = vec![mlab::glam::Vec4::ZERO; (W * H) as usize];
    fb.resolve_into(&mut image, Background::Opaque(BACKGROUND.into()))?;
    let exact: Vec<[f64; 3]> = abuffer.iter().map(|frags| exact(frags)).collect();

    let mse = image
        .iter()
        .zip(&exact)
        .map(|(p, e)| (0..3).map(|c| (p[c] as f64 - e[c]).powi(2)).sum::<f64>())
        .sum::<f64>()
        / (3 * W * H) as f64;
    let max_depth = abuffer.iter().map(Vec::len).max().unwrap_or(0);
    println!(
        "{layers:?}: {} triangles, {fragments} fragments (up to {max_depth} per pixel), PSNR {:.2} dB against the A-buffer",
        mesh.len(),
        10.0 * (1.0 / mse).log10()
    );

    // Side by side, sRGB-encoded for display.
    let mut png_rgb = vec![0u8; (2 * W * H * 3) as usize];
    for y in 0..H as usize {
        for x in 0..W as usize {
            let (k, e) = (image[y * W as usize + x], exact[y * W as usize + x]);
            for c in 0..3 {
                png_rgb[(y * 2 * W as usize + x) * 3 + c] = srgb8(k[c] as f64);
                png_rgb[(y * 2 * W as usize + W as usize + x) * 3 + c] = srgb8(e[c]);
            }
        }
    }
    std::fs::create_dir_all("out")?;
    let file = std::io::BufWriter::new(std::fs::File::create("out/rasterizer.png")?);
    let mut enc = png::Encoder::new(file, 2 * W, H);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut writer = enc.write_header()?;
    writer.write_image_data(&png_rgb)?;
    writer.finish()?;
    println!("wrote out/rasterizer.png (left: kernel, right: A-buffer)");
    Ok(())
}

/// The exact composite of one pixel's fragments (in submission order) over the background,
/// in f64: sorted front to back, and at equal depth **the later fragment in front**, the
/// kernel's rule (Listing 1's `<=`: a new fragment goes in front of rows at its depth, so
/// coplanar fragments blend like OVER in submission order). A stable sort by depth alone
/// puts the earlier one in front and differs from the kernel wherever depths tie.
fn exact(fragments: &[Fragment]) -> [f64; 3] {
    let mut order: Vec<usize> = (0..fragments.len()).collect();
    order.sort_by(|&a, &b| fragments[a].depth().total_cmp(&fragments[b].depth()).then(b.cmp(&a)));
    let (mut color, mut visible) = ([0.0f64; 3], 1.0f64);
    for f in order.iter().map(|&i| fragments[i]) {
        for (c, p) in color.iter_mut().zip(f.color().to_array()) {
            *c += f64::from(p) * visible;
        }
        visible *= 1.0 - f64::from(f.alpha());
    }
    core::array::from_fn(|c| color[c] + visible * f64::from(BACKGROUND[c]))
}

/// Linear `[0, 1]` to an sRGB-encoded byte (display only).
fn srgb8(v: f64) -> u8 {
    let v = v.clamp(0.0, 1.0);
    let s = if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5) as u8
}

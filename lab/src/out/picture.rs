//! PNG output: single images, difference images and the Figure 3 grid.

mod font;

pub use font::{ADVANCE, GLYPH_H, GLYPH_W, LINE, glyph, text_width};

use crate::methods::Image;
use std::path::Path;

/// Create a folder and its parents.
pub fn create_dir(p: &Path) -> Result<(), String> {
    std::fs::create_dir_all(p).map_err(|e| format!("cannot create {}: {e}", p.display()))
}

/// An 8-bit RGB picture.
#[derive(Clone, Debug)]
pub struct Picture {
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// RGB bytes, row major.
    pub data: Vec<u8>,
}

impl Picture {
    /// A picture filled with one color.
    pub fn filled(width: u32, height: u32, rgb: [u8; 3]) -> Picture {
        Picture {
            width,
            height,
            data: rgb.repeat(width as usize * height as usize),
        }
    }

    /// An image sRGB-encoded.
    pub fn from_image(img: &Image) -> Picture {
        Picture {
            width: img.width,
            height: img.height,
            data: crate::metrics::to_srgb8(img),
        }
    }

    /// The difference image gained in linear light: per channel `|test - reference|` on the
    /// display values (linear, clamped to `[0, 1]`), times `gain`, written to the byte as it
    /// is (`round(255 min(1, gain d))`, no sRGB encoding, which would lift small differences:
    /// an 8-bit quantization step of 1/255 gained 4x is 4/255 here, 33/255 sRGB-encoded).
    pub fn difference(reference: &Image, test: &Image, gain: f32) -> Picture {
        let d = |a: f32, b: f32| {
            let c = |x: f32| if x.is_finite() { x.clamp(0.0, 1.0) } else { 0.0 };
            ((c(a) - c(b)).abs() * gain * 255.0 + 0.5).floor().clamp(0.0, 255.0) as u8
        };
        let data = reference
            .rgb
            .iter()
            .zip(&test.rgb)
            .flat_map(|(a, b)| [0, 1, 2].map(|k| d(a[k], b[k])))
            .collect();
        Picture {
            width: reference.width,
            height: reference.height,
            data,
        }
    }

    /// Box-filtered down by an integer factor (at least 1).
    pub fn downscale(&self, f: u32) -> Picture {
        let f = f.max(1);
        let (w, h) = (self.width / f, self.height / f);
        let mut data = Vec::with_capacity((w * h * 3) as usize);
        for y in 0..h {
            for x in 0..w {
                for k in 0..3 {
                    let mut s = 0u32;
                    for dy in 0..f {
                        for dx in 0..f {
                            s += self.data[(((y * f + dy) * self.width + x * f + dx) * 3 + k) as usize] as u32;
                        }
                    }
                    data.push(((s + f * f / 2) / (f * f)) as u8);
                }
            }
        }
        Picture {
            width: w,
            height: h,
            data,
        }
    }

    /// Fill the rectangle at `(x, y)` of size `w x h` (clipped) with `rgb`.
    pub fn fill_rect(&mut self, x: u32, y: u32, w: u32, h: u32, rgb: [u8; 3]) {
        for yy in y..(y.saturating_add(h)).min(self.height) {
            for xx in x..(x.saturating_add(w)).min(self.width) {
                let i = ((yy * self.width + xx) * 3) as usize;
                self.data[i..i + 3].copy_from_slice(&rgb);
            }
        }
    }

    /// A 1-pixel outline of the rectangle at `(x, y)` of size `w x h` (clipped).
    pub fn outline(&mut self, x: u32, y: u32, w: u32, h: u32, rgb: [u8; 3]) {
        if w == 0 || h == 0 {
            return;
        }
        self.fill_rect(x, y, w, 1, rgb);
        self.fill_rect(x, y + h - 1, w, 1, rgb);
        self.fill_rect(x, y, 1, h, rgb);
        self.fill_rect(x + w - 1, y, 1, h, rgb);
    }

    /// The `w x h` part at `(x, y)` (clipped to the picture).
    pub fn crop(&self, x: u32, y: u32, w: u32, h: u32) -> Picture {
        let (w, h) = (
            w.min(self.width.saturating_sub(x)),
            h.min(self.height.saturating_sub(y)),
        );
        let mut out = Picture::filled(w, h, [0; 3]);
        for yy in 0..h {
            let s0 = (((y + yy) * self.width + x) * 3) as usize;
            let d0 = (yy * w * 3) as usize;
            out.data[d0..d0 + (w * 3) as usize].copy_from_slice(&self.data[s0..s0 + (w * 3) as usize]);
        }
        out
    }

    /// Enlarged by an integer factor, each pixel a square (nearest neighbour: what a zoom shows).
    pub fn upscale(&self, f: u32) -> Picture {
        let f = f.max(1);
        let mut out = Picture::filled(self.width * f, self.height * f, [0; 3]);
        for y in 0..out.height {
            for x in 0..out.width {
                let s = (((y / f) * self.width + x / f) * 3) as usize;
                let d = ((y * out.width + x) * 3) as usize;
                out.data[d..d + 3].copy_from_slice(&self.data[s..s + 3]);
            }
        }
        out
    }

    /// Values in `[0, 1]` (row major) through nv-flip's magma color map (what FLIP's error
    /// maps use).
    pub fn magma(width: u32, height: u32, values: &[f32]) -> Picture {
        let map = nv_flip::FlipImageFloat::with_data(width, height, values);
        Picture {
            width,
            height,
            data: map.apply_color_lut(&nv_flip::magma_lut()).to_vec(),
        }
    }

    /// Copy `src` with its top-left corner at `(x, y)` (clipped).
    pub fn blit(&mut self, src: &Picture, x: u32, y: u32) {
        for sy in 0..src.height.min(self.height.saturating_sub(y)) {
            let n = (src.width.min(self.width.saturating_sub(x)) * 3) as usize;
            let d0 = (((y + sy) * self.width + x) * 3) as usize;
            let s0 = ((sy * src.width) * 3) as usize;
            self.data[d0..d0 + n].copy_from_slice(&src.data[s0..s0 + n]);
        }
    }

    /// Write as an 8-bit RGB PNG, fast compression.
    pub fn write_png(&self, path: &Path) -> Result<(), String> {
        self.write_png_with(path, png::Compression::Fast)
    }

    /// Write as an 8-bit RGB PNG with the given compression.
    pub fn write_png_with(&self, path: &Path, compression: png::Compression) -> Result<(), String> {
        let file = std::fs::File::create(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let mut enc = png::Encoder::new(std::io::BufWriter::new(file), self.width, self.height);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_compression(compression);
        let mut w = enc.write_header().map_err(|e| format!("{}: {e}", path.display()))?;
        w.write_image_data(&self.data)
            .map_err(|e| format!("{}: {e}", path.display()))?;
        w.finish().map_err(|e| format!("{}: {e}", path.display()))
    }
}

/// One cell of the labelled figure: a method's image and, under it, its difference image
/// (or, for the reference, its fragment counts), each with a caption.
#[derive(Clone, Debug)]
pub struct Cell {
    /// Column title (the method's name).
    pub title: String,
    /// The image at full size.
    pub image: Picture,
    /// Caption under the image (PSNR / FLIP).
    pub caption: String,
    /// The lower picture at full size (difference image, or fragment counts).
    pub lower: Picture,
    /// Caption under the lower picture (may be empty).
    pub lower_caption: String,
}

/// One scene of the labelled figure.
#[derive(Clone, Debug)]
pub struct FigureRow {
    /// Scene name, written on the left.
    pub name: String,
    /// Smaller lines under the name.
    pub notes: Vec<String>,
    /// The zoomed region, `(x, y, w, h)` in full-size pixels.
    pub region: (u32, u32, u32, u32),
    /// The cells, reference first.
    pub cells: Vec<Cell>,
}

/// Zoom of the insets relative to the full-size image.
pub const INSET_ZOOM: u32 = 2;

/// The `(x, y, w, h)` window of `w x h` pixels holding the most fragments (`counts` per
/// pixel, `width` wide), searched on a grid of 4 pixels: the dense region of the insets.
pub fn densest(counts: &[u32], width: u32, height: u32, w: u32, h: u32) -> (u32, u32, u32, u32) {
    let (w, h) = (w.min(width), h.min(height));
    let (wi, hi) = (width as usize, height as usize);
    // Summed-area table with a zero first row and column.
    let mut sat = vec![0u64; (wi + 1) * (hi + 1)];
    for y in 0..hi {
        for x in 0..wi {
            sat[(y + 1) * (wi + 1) + x + 1] =
                counts[y * wi + x] as u64 + sat[y * (wi + 1) + x + 1] + sat[(y + 1) * (wi + 1) + x]
                    - sat[y * (wi + 1) + x];
        }
    }
    let sum = |x: usize, y: usize| {
        let (x1, y1) = (x + w as usize, y + h as usize);
        sat[y1 * (wi + 1) + x1] + sat[y * (wi + 1) + x] - sat[y * (wi + 1) + x1] - sat[y1 * (wi + 1) + x]
    };
    let mut best = (0u64, 0u32, 0u32);
    for y in (0..=(height - h)).step_by(4) {
        for x in (0..=(width - w)).step_by(4) {
            let s = sum(x as usize, y as usize);
            if s > best.0 {
                best = (s, x, y);
            }
        }
    }
    (best.1, best.2, w, h)
}

/// Fragment counts per pixel as a picture: `count / max` through nv-flip's magma.
pub fn counts_picture(counts: &[u32], width: u32, height: u32) -> Picture {
    let max = counts.iter().copied().max().unwrap_or(0).max(1) as f32;
    let v: Vec<f32> = counts.iter().map(|&c| c as f32 / max).collect();
    Picture::magma(width, height, &v)
}

/// The cell `pic` downscaled by `factor`, with the region outlined and its zoom
/// ([`INSET_ZOOM`] times the full size) in the corner of the cell farthest from it.
fn with_inset(pic: &Picture, factor: u32, region: (u32, u32, u32, u32)) -> Picture {
    let yellow = [255, 220, 0];
    let mut cell = pic.downscale(factor);
    let (rx, ry, rw, rh) = region;
    let inset = pic.crop(rx, ry, rw, rh).upscale(INSET_ZOOM);
    let (cx, cy) = ((rx + rw / 2) / factor, (ry + rh / 2) / factor);
    let ix = if cx < cell.width / 2 {
        cell.width.saturating_sub(inset.width)
    } else {
        0
    };
    let iy = if cy < cell.height / 2 {
        cell.height.saturating_sub(inset.height)
    } else {
        0
    };
    cell.outline(
        rx / factor,
        ry / factor,
        (rw / factor).max(2),
        (rh / factor).max(2),
        yellow,
    );
    cell.blit(&inset, ix, iy);
    cell.outline(
        ix,
        iy,
        inset.width.min(cell.width),
        inset.height.min(cell.height),
        yellow,
    );
    cell
}

/// Draw `text` with its top-left corner at `(x, y)`, each glyph pixel a `scale x scale`
/// square of `color` (clipped to the picture).
pub fn draw_text(pic: &mut Picture, x: u32, y: u32, text: &str, scale: u32, color: [u8; 3]) {
    let scale = scale.max(1);
    for (i, c) in text.chars().enumerate() {
        let gx = x + i as u32 * ADVANCE * scale;
        for (row, bits) in glyph(c).iter().enumerate() {
            for col in 0..GLYPH_W {
                if bits & (1 << (GLYPH_W - 1 - col)) != 0 {
                    pic.fill_rect(gx + col * scale, y + row as u32 * scale, scale, scale, color);
                }
            }
        }
    }
}

/// The labelled figure: legend lines at the top, method names over the columns, per scene
/// (name on the left) a row of images each with a zoomed inset of the scene's dense region and
/// a caption under it, then a row of lower pictures (difference images) with their captions.
/// Cells are the full-size pictures downscaled by `factor`.
pub fn labelled_figure(rows: &[FigureRow], factor: u32, legend: &[String]) -> Picture {
    let Some(first) = rows.first().and_then(|r| r.cells.first()) else {
        return Picture::filled(1, 1, [255; 3]);
    };
    let factor = factor.max(1);
    let (cw, ch) = (first.image.width / factor, first.image.height / factor);
    let (gap, scale) = (4u32, 2u32);
    let line = LINE * scale;
    let left = rows
        .iter()
        .map(|r| text_width(&r.name, scale))
        .chain(rows.iter().flat_map(|r| r.notes.iter().map(|n| text_width(n, 1))))
        .max()
        .unwrap_or(0)
        + 2 * gap;
    let cols = rows.iter().map(|r| r.cells.len()).max().unwrap_or(1) as u32;
    let width =
        (left + cols * (cw + gap) + gap).max(legend.iter().map(|l| text_width(l, scale) + 2 * gap).max().unwrap_or(0));
    let header = gap + legend.len() as u32 * line + gap + line + gap;
    let block = ch + gap + line + ch + gap + line + 2 * gap;
    let height = header + rows.len() as u32 * block;
    let mut out = Picture::filled(width, height, [255; 3]);
    let black = [0; 3];
    for (i, l) in legend.iter().enumerate() {
        draw_text(&mut out, gap, gap + i as u32 * line, l, scale, black);
    }
    let title_y = gap + legend.len() as u32 * line + gap;
    for (ci, cell) in rows[0].cells.iter().enumerate() {
        draw_text(
            &mut out,
            left + ci as u32 * (cw + gap),
            title_y,
            &cell.title,
            scale,
            black,
        );
    }
    for (ri, row) in rows.iter().enumerate() {
        let y0 = header + ri as u32 * block;
        draw_text(&mut out, gap, y0 + ch / 2 - line, &row.name, scale, black);
        for (ni, n) in row.notes.iter().enumerate() {
            draw_text(&mut out, gap, y0 + ch / 2 + ni as u32 * LINE + 4, n, 1, black);
        }
        for (ci, cell) in row.cells.iter().enumerate() {
            let x = left + ci as u32 * (cw + gap);
            out.blit(&with_inset(&cell.image, factor, row.region), x, y0);
            draw_text(&mut out, x, y0 + ch + gap, &cell.caption, scale, black);
            let y1 = y0 + ch + gap + line;
            out.blit(&with_inset(&cell.lower, factor, row.region), x, y1);
            draw_text(&mut out, x, y1 + ch + gap, &cell.lower_caption, scale, black);
        }
    }
    out
}

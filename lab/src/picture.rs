//! PNG output: single images, difference images and the Figure 3 grid.

use crate::methods::Image;
use std::path::Path;

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

/// The Figure 3 grid: for each scene two rows, the images (reference first, then each
/// method) and under each method its difference image; each cell downscaled by `factor`,
/// with a 2-pixel gap.
pub fn figure(rows: &[(Picture, Vec<(Picture, Picture)>)], factor: u32) -> Picture {
    let gap = 2;
    let Some((r0, _)) = rows.first() else {
        return Picture::filled(1, 1, [0; 3]);
    };
    let (cw, ch) = (r0.width / factor.max(1), r0.height / factor.max(1));
    let cols = rows.iter().map(|(_, m)| m.len() + 1).max().unwrap_or(1) as u32;
    let w = cols * (cw + gap) + gap;
    let h = rows.len() as u32 * 2 * (ch + gap) + gap;
    let mut out = Picture::filled(w, h, [255, 255, 255]);
    for (ri, (reference, methods)) in rows.iter().enumerate() {
        let y = gap + ri as u32 * 2 * (ch + gap);
        out.blit(&reference.downscale(factor), gap, y);
        for (mi, (img, diff)) in methods.iter().enumerate() {
            let x = gap + (mi as u32 + 1) * (cw + gap);
            out.blit(&img.downscale(factor), x, y);
            out.blit(&diff.downscale(factor), x, y + ch + gap);
        }
    }
    out
}

//! The main job's figure (Figure 3 of the paper, `OUT/figure.png` and `OUT/figure-small.png`):
//! per scene the A-buffer with its fragment counts, then each method with its difference
//! image, laid out by [`labelled_figure`]; and the PNGs of
//! every image, difference and FLIP map.

use crate::methods::Method;
use crate::out::picture::{Cell, FigureRow, INSET_ZOOM, Picture, counts_picture, create_dir, densest, labelled_figure};
use crate::study::evaluate::Evaluation;
use std::path::Path;

/// Gain of the difference images (linear light, [`Picture::difference`]).
pub const DIFF_GAIN: f32 = 8.0;

/// Write each image, its difference gained in linear light and its FLIP error map through
/// nv-flip's color map, and return the figure row.
pub fn write_pictures(e: &Evaluation, dir: Option<&Path>) -> Result<(Picture, Vec<(Picture, Picture)>), String> {
    let reference = Picture::from_image(&e.reference.image);
    if let Some(d) = dir {
        create_dir(d)?;
        reference.write_png(&d.join("a-buffer.png"))?;
    }
    let mut cells = Vec::new();
    for x in &e.entries {
        let img = Picture::from_image(&x.image);
        let diff = Picture::difference(&e.reference.image, &x.image, DIFF_GAIN);
        if let Some(d) = dir {
            let slug = x.method.slug();
            img.write_png(&d.join(format!("{slug}.png")))?;
            diff.write_png(&d.join(format!("{slug}-diff{DIFF_GAIN}x-linear.png")))?;
            if let Some(map) = &x.scores.flip_map {
                Picture {
                    width: map.width,
                    height: map.height,
                    data: map.magma(),
                }
                .write_png(&d.join(format!("{slug}-flip.png")))?;
            }
        }
        cells.push((img, diff));
    }
    Ok((reference, cells))
}

/// A method's column title in the figure: HT says which HT of the paper it is.
pub fn title(m: Method) -> String {
    match m {
        Method::Hybrid(k) => format!("HT {k} = paper HT {}", k + 1),
        _ => m.name(),
    }
}

/// The legend lines of the figure.
pub fn legend(size: (u32, u32), seed: u64) -> Vec<String> {
    vec![
        format!(
            "oit-lab main job, {}x{}, scene seed {seed}, each scene in its own submission order. Per scene, top: the image; the yellow box is shown zoomed in the inset ({INSET_ZOOM}x full size).",
            size.0, size.1
        ),
        "Under each image: PSNR dB / mean FLIP, both over the covered pixels (at least one fragment).".into(),
        format!(
            "Bottom: |method - A-buffer| x{DIFF_GAIN} in LINEAR light (byte = {DIFF_GAIN} x linear difference x 255, no sRGB encoding); under the A-buffer: fragments per pixel (magma)."
        ),
        "HT K = K head rows + tail = the paper's HT K+1 (same bytes as MLAB K+1).".into(),
    ]
}

/// One scene of the labelled figure: the reference with its fragment counts, then each
/// method with its difference image.
pub fn scene_row(
    e: &Evaluation,
    reference: Picture,
    cells: Vec<(Picture, Picture)>,
    size: (u32, u32),
    factor: u32,
) -> FigureRow {
    let (w, h) = size;
    let (cw, ch) = (w / factor, h / factor);
    let region = densest(&e.counts, w, h, cw * 2 / 5 / INSET_ZOOM, ch * 2 / 5 / INSET_ZOOM);
    let mut out = vec![Cell {
        title: "A-buffer (exact)".into(),
        image: reference,
        caption: "reference".into(),
        lower: counts_picture(&e.counts, w, h),
        lower_caption: format!("fragments/px, 0-{}", e.max_depth),
    }];
    for (x, (img, diff)) in e.entries.iter().zip(cells) {
        let q = &x.scores;
        let psnr = if q.covered.psnr.is_infinite() {
            "inf".to_string()
        } else {
            format!("{:.1}", q.covered.psnr)
        };
        out.push(Cell {
            title: title(x.method),
            image: img,
            caption: match q.flip_covered {
                Some(f) => format!("{psnr} dB / {f:.3}"),
                None => format!("{psnr} dB"),
            },
            lower: diff,
            lower_caption: String::new(),
        });
    }
    FigureRow {
        name: e.name.clone(),
        notes: vec![
            format!("{:.1} frags/px", e.depth.mean),
            format!("(covered), max {}", e.max_depth),
        ],
        region,
        cells: out,
    }
}

/// Methods shown in the small figure (docs/figure.png).
pub const SMALL: [&str; 10] = [
    "OVER unsorted",
    "MLAB 2",
    "MLAB 4",
    "HT 3",
    "HT 7",
    "AT 4",
    "WBOIT eq.7",
    "Meshkin",
    "K-closest 4",
    "MBOIT 6 power 16-bit",
];

/// The main job's two figures, built a scene at a time.
pub struct Figures {
    size: (u32, u32),
    factor: u32,
    rows: Vec<FigureRow>,
    small_rows: Vec<FigureRow>,
}

impl Figures {
    /// No scene yet, for frames of `size`.
    pub fn new(size: (u32, u32)) -> Figures {
        Figures {
            size,
            // Cells of the figure: 320 pixels wide at least (640x360 -> 320x180).
            factor: (size.0 / 320).max(1),
            rows: Vec::new(),
            small_rows: Vec::new(),
        }
    }

    /// Write the scene's PNGs into `dir` ([`write_pictures`]) and add its row to both
    /// figures (the small one with the [`SMALL`] methods only).
    pub fn add(&mut self, e: &Evaluation, dir: &Path) -> Result<(), String> {
        let (reference, cells) = write_pictures(e, Some(dir))?;
        let row = scene_row(e, reference, cells, self.size, self.factor);
        let mut small = row.clone();
        small.cells = row
            .cells
            .iter()
            .enumerate()
            .filter(|(i, _)| *i == 0 || SMALL.contains(&e.entries[i - 1].method.name().as_str()))
            .map(|(_, c)| c.clone())
            .collect();
        self.small_rows.push(small);
        self.rows.push(row);
        Ok(())
    }

    /// Write `out/figure.png` and `out/figure-small.png`.
    pub fn write(&self, out: &Path, seed: u64) -> Result<(), String> {
        create_dir(out)?;
        let legend = legend(self.size, seed);
        labelled_figure(&self.rows, self.factor, &legend).write_png(&out.join("figure.png"))?;
        labelled_figure(&self.small_rows, self.factor, &legend)
            .write_png_with(&out.join("figure-small.png"), png::Compression::High)
    }
}

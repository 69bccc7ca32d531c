//! Primitive bins: each band's primitives, by their screen bounds, in submission order.

use crate::scenes::Primitives;

/// Per band of `band_lines` lines, the indices of the primitives whose box meets it, in
/// submission order. Kept between frames (cleared, not freed).
#[derive(Clone, Debug, Default)]
pub struct PrimBins {
    band_lines: u32,
    bands: usize,
    lists: Vec<Vec<u32>>,
}

impl PrimBins {
    /// Bin `scene`'s primitives into bands of `band_lines` lines (at least 1).
    pub fn fill(&mut self, scene: &Primitives, band_lines: u32) {
        let band_lines = band_lines.max(1);
        let bands = scene.height.div_ceil(band_lines) as usize;
        (self.band_lines, self.bands) = (band_lines, bands);
        if self.lists.len() < bands {
            self.lists.resize_with(bands, Vec::new);
        }
        for l in &mut self.lists[..bands] {
            l.clear();
        }
        for (i, p) in scene.prims.iter().enumerate() {
            if p.x0 >= p.x1 || p.y0 >= p.y1 {
                continue;
            }
            let (b0, b1) = ((p.y0 / band_lines) as usize, ((p.y1 - 1) / band_lines) as usize);
            for l in self.lists.iter_mut().take(b1 + 1).skip(b0) {
                l.push(i as u32);
            }
        }
    }

    /// Lines per band.
    pub fn band_lines(&self) -> u32 {
        self.band_lines
    }

    /// Number of bands.
    pub fn bands(&self) -> usize {
        self.bands
    }

    /// The primitives of band `b`, in submission order.
    pub fn band(&self, b: usize) -> &[u32] {
        self.lists.get(b).map_or(&[], Vec::as_slice)
    }

    /// Bytes held by the lists (capacity, as allocated).
    pub fn bytes(&self) -> usize {
        self.lists.capacity() * std::mem::size_of::<Vec<u32>>()
            + self.lists.iter().map(|l| l.capacity() * 4).sum::<usize>()
    }
}

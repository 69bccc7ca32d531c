//! The tiled A-buffer's per-tile work: a fragment array in submission order, a counting sort
//! by pixel (a pixel's fragments newest first), an insertion sort by depth per pixel (stable:
//! on equal depth the later submission stays in front), then f32 front to back.

use mlab::glam::Vec3;
use mlab::lanes::LANES;
use mlab::{Row, to_rgba8};

/// A worker's arrays, reused from tile to tile.
#[derive(Debug, Default)]
pub(super) struct Scratch {
    /// `(pixel inside the band, row)` in submission order.
    frags: Vec<(u32, Row)>,
    /// Per pixel: the count, then the end offset of its fragments in `sorted`.
    start: Vec<u32>,
    sorted: Vec<Row>,
}

impl Scratch {
    /// Start a tile of `pixels` pixels.
    pub(super) fn begin(&mut self, pixels: usize) {
        self.frags.clear();
        self.start.clear();
        self.start.resize(pixels + 1, 0);
    }

    /// Add the lanes of `mask` at tile pixels `p .. p + 8`.
    #[inline]
    pub(super) fn push_span(&mut self, p: u32, rows: &[Row; LANES], mask: u8) {
        let mut m = mask;
        while m != 0 {
            let i = m.trailing_zeros();
            m &= m - 1;
            self.frags.push((p + i, rows[i as usize]));
        }
    }

    /// Bytes held (capacities, as allocated).
    pub(super) fn bytes(&self) -> usize {
        self.frags.capacity() * std::mem::size_of::<(u32, Row)>()
            + self.start.capacity() * 4
            + self.sorted.capacity() * std::mem::size_of::<Row>()
    }

    /// Fragments in the tile.
    pub(super) fn len(&self) -> usize {
        self.frags.len()
    }

    /// Sort and composite into `out` over `bg`.
    pub(super) fn resolve(&mut self, out: &mut [[u8; 4]], bg: Vec3) {
        let pixels = out.len();
        for &(p, _) in &self.frags {
            if let Some(c) = self.start.get_mut(p as usize) {
                *c += 1;
            }
        }
        // Exclusive end offsets.
        let mut acc = 0u32;
        for c in self.start.iter_mut() {
            acc += *c;
            *c = acc;
        }
        self.sorted.clear();
        self.sorted.resize(self.frags.len(), Row::EMPTY);
        // Placing at the decremented end reverses submission order within a pixel.
        for &(p, row) in &self.frags {
            if let Some(e) = self.start.get_mut(p as usize) {
                *e -= 1;
                if let Some(s) = self.sorted.get_mut(*e as usize) {
                    *s = row;
                }
            }
        }
        // Now start[p] is the first fragment of pixel p, start[p + 1] one past its last.
        for (p, o) in out.iter_mut().enumerate().take(pixels) {
            let (a, b) = (self.start[p] as usize, self.start[p + 1] as usize);
            let list = &mut self.sorted[a..b];
            sort_by_depth(list);
            let (mut c, mut t) = (Vec3::ZERO, 1.0f32);
            for r in list.iter() {
                let ([cr, cg, cb], tr) = (r.color(), r.transmittance());
                c += t * Vec3::new(cr as f32, cg as f32, cb as f32) * (1.0 / 255.0);
                t *= tr as f32 * (1.0 / 255.0);
            }
            *o = to_rgba8((c + t * bg).extend(1.0));
        }
    }
}

/// Stable sort by depth: insertion sort on short lists (most pixels), the standard library's
/// stable merge sort on long ones.
#[inline]
fn sort_by_depth(list: &mut [Row]) {
    if list.len() > 24 {
        list.sort_by(|a, b| a.depth().total_cmp(&b.depth()));
        return;
    }
    for i in 1..list.len() {
        let r = list[i];
        let d = r.depth();
        let mut j = i;
        while j > 0 && list[j - 1].depth().total_cmp(&d).is_gt() {
            list[j] = list[j - 1];
            j -= 1;
        }
        list[j] = r;
    }
}

//! Fragment streams: what a rasterizer emits, in primitive submission order.
//!
//! A [`Stream`] is a list of [`Frag`]s for one frame, plus the frame size and the opaque
//! background color. [`PixelBins`] groups the fragments per pixel, keeping submission order
//! inside each pixel (a stable counting sort), which is all that every method needs:
//! compositing is independent per pixel.

use mlab::{Fragment, FragmentError};

/// One transparent fragment: pixel index `y * width + x`, depth (distance from the
/// viewer, smaller is nearer), premultiplied color and alpha (coverage), and the id of the
/// primitive that emitted it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frag {
    /// `y * width + x`.
    pub pixel: u32,
    /// Distance from the viewer; smaller is nearer.
    pub depth: f32,
    /// Premultiplied color, each channel in `[0, 1]`; may exceed `alpha` (additive light).
    pub color: [f32; 3],
    /// Alpha in `[0, 1]`; 0 with a color is pure additive light.
    pub alpha: f32,
    /// The id of the primitive (strand segment, sprite, leaf, sphere band, panel face, fog
    /// slice, splat) that emitted the fragment: unique per primitive within a frame, and the
    /// same for the same primitive in every frame of a camera path and in every submission
    /// order (the scenes number their primitives in the order they build them, a list that
    /// depends on neither the camera nor the frame size; [`crate::scenes::Primitive::id`]).
    /// What the kernel's stable fragment key is made of (issue 30).
    pub prim: u32,
}

impl Frag {
    /// The kernel's validated fragment (same rules as [`mlab::Fragment::premultiplied`]),
    /// keyed by its primitive's id ([`Fragment::with_key`]): the kernel seeds its dithers with
    /// the id and the pixel, so a fragment rounds the same way in every frame of a camera
    /// path and in every submission order.
    pub fn to_kernel(&self) -> Result<Fragment, FragmentError> {
        Fragment::premultiplied(self.color.into(), self.alpha, self.depth).map(|f| f.with_key(self.prim))
    }
}

/// A frame's fragments in submission order.
#[derive(Clone, Debug, PartialEq)]
pub struct Stream {
    /// Frame width in pixels.
    pub width: u32,
    /// Frame height in pixels.
    pub height: u32,
    /// Opaque background color (linear RGB) behind every transparent fragment.
    pub background: [f32; 3],
    /// Fragments in submission order.
    pub frags: Vec<Frag>,
}

impl Stream {
    /// Number of pixels.
    pub fn pixels(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// FNV-1a (64 bit) over the size, background and every fragment's bytes (pixel, depth,
    /// color, alpha, primitive id), little endian: pins a scene's stream in tests.
    pub fn hash(&self) -> u64 {
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        let mut eat = |bytes: &[u8]| {
            for &b in bytes {
                h ^= b as u64;
                h = h.wrapping_mul(0x0000_0100_0000_01b3);
            }
        };
        eat(&self.width.to_le_bytes());
        eat(&self.height.to_le_bytes());
        for c in self.background {
            eat(&c.to_bits().to_le_bytes());
        }
        for f in &self.frags {
            eat(&f.pixel.to_le_bytes());
            eat(&f.depth.to_bits().to_le_bytes());
            for c in f.color {
                eat(&c.to_bits().to_le_bytes());
            }
            eat(&f.alpha.to_bits().to_le_bytes());
            eat(&f.prim.to_le_bytes());
        }
        h
    }

    /// The first fragment the kernel refuses, with its index, or `Ok`.
    pub fn validate(&self) -> Result<(), (usize, FragmentError)> {
        for (i, f) in self.frags.iter().enumerate() {
            f.to_kernel().map_err(|e| (i, e))?;
        }
        Ok(())
    }
}

/// Fragment indices grouped per pixel (CSR; the tiled renderer's bins of primitives per band
/// are [`crate::tiled::PrimBins`]): the fragments of pixel `p` are
/// `index[start[p]..start[p + 1]]`, in submission order (or sorted, see [`PixelBins::sorted`]).
#[derive(Clone, Debug)]
pub struct PixelBins {
    /// `pixels + 1` offsets into `index`.
    pub start: Vec<u32>,
    /// Fragment indices into the stream.
    pub index: Vec<u32>,
}

impl PixelBins {
    /// Group by pixel, keeping submission order inside each pixel.
    pub fn new(stream: &Stream) -> PixelBins {
        let n = stream.pixels();
        let mut start = vec![0u32; n + 1];
        for f in &stream.frags {
            start[f.pixel as usize + 1] += 1;
        }
        for p in 0..n {
            start[p + 1] += start[p];
        }
        let mut fill = start.clone();
        let mut index = vec![0u32; stream.frags.len()];
        for (i, f) in stream.frags.iter().enumerate() {
            let slot = &mut fill[f.pixel as usize];
            index[*slot as usize] = i as u32;
            *slot += 1;
        }
        PixelBins { start, index }
    }

    /// The same bins sorted front to back per pixel: by depth, and on equal depth the
    /// later submission first (it goes in front, as with OVER in submission order).
    pub fn sorted(&self, stream: &Stream) -> PixelBins {
        let mut index = self.index.clone();
        for p in 0..self.start.len() - 1 {
            let s = &mut index[self.start[p] as usize..self.start[p + 1] as usize];
            s.sort_by(|&a, &b| {
                let (fa, fb) = (&stream.frags[a as usize], &stream.frags[b as usize]);
                fa.depth
                    .partial_cmp(&fb.depth)
                    .unwrap_or(core::cmp::Ordering::Equal)
                    .then(b.cmp(&a))
            });
        }
        PixelBins {
            start: self.start.clone(),
            index,
        }
    }

    /// Fragment indices of pixel `p`.
    #[inline]
    pub fn of(&self, p: usize) -> &[u32] {
        &self.index[self.start[p] as usize..self.start[p + 1] as usize]
    }

    /// Largest number of fragments in one pixel.
    pub fn max_depth_complexity(&self) -> usize {
        self.start.windows(2).map(|w| (w[1] - w[0]) as usize).max().unwrap_or(0)
    }
}

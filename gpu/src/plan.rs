//! The plan of a composite, on the CPU alone: every fragment validated, the stored pixels per
//! line, and bands of whole lines whose every binding stays within the limit. No device: the
//! tests below run without one.

use std::borrow::Cow;

use crate::error::GpuError;
use crate::fragment::GpuFragment;
use mlab::{Fragment, Layers};

/// How the pixels' slots are laid out in the returned words (the kernel's arrangements).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Layout {
    /// [`mlab::PixelMajor`]: pixel `p` owns slots `p * R .. (p + 1) * R` (`R` = `M`, or `K + 1`
    /// with the tail last), as `MlabFramebuffer` and `HybridFramebuffer` store them.
    PixelMajor,
    /// [`mlab::Spans`]: slot `j` of pixel `(x, y)` is `((y * ceil(w / 8) + x / 8) * R + j) * 8 +
    /// x % 8`, padding lanes empty, as `DynFramebuffer` and the span framebuffers store them.
    Spans,
}

/// Validates a fragment as the compositor does; the [`Fragment`] carries its stable key, if
/// it has one.
pub(crate) fn validate(index: usize, f: &GpuFragment, pixels: u32) -> Result<Fragment, GpuError> {
    if f.pixel >= pixels {
        return Err(GpuError::PixelOutOfRange {
            index,
            pixel: f.pixel,
            pixels,
        });
    }
    let fragment =
        Fragment::premultiplied_rgba(f.rgba, f.depth).map_err(|error| GpuError::Fragment { index, error })?;
    Ok(match f.key() {
        Some(key) => fragment.with_key(key),
        None => fragment,
    })
}

/// Padded key count for `n` fragments: a power of two, at least 1.
pub(crate) fn key_count(n: u64) -> u64 {
    n.next_power_of_two().max(1)
}

/// Bytes of the largest binding of a band of `pixels` stored pixels and `n` fragments: its
/// rows, offsets, fragments (32 bytes each) or sort keys (8 bytes per padded key).
pub(crate) fn band_bytes(layers: Layers, pixels: u64, n: u64) -> u64 {
    let rows = pixels * layers.rows_per_pixel() as u64 * 8;
    rows.max(4 * (pixels + 1))
        .max(n * size_of::<GpuFragment>() as u64)
        .max(8 * key_count(n))
}

/// Stored pixels per line of `width` pixels: the width, or for spans the next multiple of 8
/// (`None` where that overflows).
pub(crate) fn pitch(layout: Layout, width: u32) -> Option<u32> {
    match layout {
        Layout::PixelMajor => Some(width),
        Layout::Spans => width.div_ceil(8).checked_mul(8),
    }
}

/// How one frame is composited: its stored pixels per line and its bands of whole lines.
#[derive(Debug, PartialEq, Eq)]
pub(crate) struct Plan {
    width: u32,
    /// Stored pixels per line ([`pitch`]).
    pitch: u32,
    /// Stored pixels of the frame.
    pub(crate) stored: u32,
    /// Lines `y0..y1` of each band, top to bottom.
    pub(crate) bands: Vec<(u32, u32)>,
}

impl Plan {
    /// Validates a `width x height` frame and every fragment, then splits the frame into bands
    /// of whole lines, as many lines to a band as keep each of its bindings within
    /// `max_binding` bytes ([`band_bytes`]). `Ok(None)`: nothing is stored (then no fragment
    /// can be valid, and the first one's error is returned).
    pub(crate) fn new(
        layers: Layers,
        layout: Layout,
        max_binding: u64,
        (width, height): (u32, u32),
        fragments: &[GpuFragment],
    ) -> Result<Option<Plan>, GpuError> {
        let too_large = GpuError::FrameTooLarge { width, height };
        let pixels = width.checked_mul(height).ok_or(too_large.clone())?;
        let pitch = pitch(layout, width).ok_or(too_large.clone())?;
        let stored = pitch.checked_mul(height).ok_or(too_large.clone())?;
        if stored >= u32::MAX / 8 {
            return Err(too_large);
        }
        if u32::try_from(fragments.len()).is_err() {
            return Err(GpuError::TooManyFragments { count: fragments.len() });
        }
        if stored == 0 {
            // Nothing stored; still every fragment must be valid (none can be: no pixel).
            return match fragments.first() {
                Some(f) => validate(0, f, 0).map(|_| None),
                None => Ok(None),
            };
        }
        // Validation, and the fragments of each line (for the bands).
        let mut lines = vec![0u32; height as usize];
        for (index, f) in fragments.iter().enumerate() {
            validate(index, f, pixels)?;
            lines[(f.pixel / width) as usize] += 1;
        }
        let bytes = |y0: u32, y1: u32, n: u64| band_bytes(layers, u64::from(y1 - y0) * u64::from(pitch), n);
        let mut bands = Vec::new();
        let mut y0 = 0u32;
        while y0 < height {
            let (mut y1, mut n) = (y0, 0u64);
            while y1 < height {
                let more = n + u64::from(lines[y1 as usize]);
                if bytes(y0, y1 + 1, more) > max_binding {
                    break;
                }
                (y1, n) = (y1 + 1, more);
            }
            if y1 == y0 {
                return Err(GpuError::LineTooLarge {
                    y: y0,
                    bytes: bytes(y0, y0 + 1, u64::from(lines[y0 as usize])),
                    limit: max_binding,
                });
            }
            bands.push((y0, y1));
            y0 = y1;
        }
        Ok(Some(Plan {
            width,
            pitch,
            stored,
            bands,
        }))
    }

    /// The band of lines `y0..y1` ([`bands`](Self::bands)): with one band the input itself,
    /// else its fragments copied out in submission order with their indices in the input.
    pub(crate) fn band<'a>(&self, fragments: &'a [GpuFragment], (y0, y1): (u32, u32)) -> Band<'a> {
        let (fragments, input) = if self.bands.len() == 1 {
            (Cow::Borrowed(fragments), Vec::new())
        } else {
            let (own, input): (Vec<GpuFragment>, Vec<u32>) = (0u32..)
                .zip(fragments)
                .filter(|(_, f)| (y0..y1).contains(&(f.pixel / self.width)))
                .map(|(i, f)| (*f, i))
                .unzip();
            (Cow::Owned(own), input)
        };
        Band {
            fragments,
            input,
            first: y0 * self.pitch,
            pixels: (y1 - y0) * self.pitch,
            width: self.width,
            line: self.pitch,
        }
    }
}

/// One band of whole lines: its fragments in submission order and where it lies.
pub(crate) struct Band<'a> {
    pub(crate) fragments: Cow<'a, [GpuFragment]>,
    /// The index in the input of each of `fragments`; empty where they are the input.
    input: Vec<u32>,
    /// The band's first stored pixel.
    pub(crate) first: u32,
    /// Its stored pixels.
    pub(crate) pixels: u32,
    /// The image's width.
    pub(crate) width: u32,
    /// Stored pixels per line.
    pub(crate) line: u32,
}

impl Band<'_> {
    /// The band's stored pixel of `f`, one of its fragments.
    pub(crate) fn local(&self, f: &GpuFragment) -> u32 {
        (f.pixel / self.width) * self.line + f.pixel % self.width - self.first
    }

    /// Indices into the band's fragments as indices into the input.
    pub(crate) fn to_input(&self, indices: Vec<u32>) -> Vec<u32> {
        if self.input.is_empty() {
            indices
        } else {
            indices.into_iter().map(|i| self.input[i as usize]).collect()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mlab::FragmentError;

    const MLAB2: Layers = Layers::Mlab(2);

    fn at(pixel: u32) -> GpuFragment {
        GpuFragment::new(pixel, [0.1, 0.0, 0.0, 0.2], 1.0)
    }

    #[test]
    fn spans_pad_each_line_to_eight_pixels() {
        assert_eq!(pitch(Layout::PixelMajor, 13), Some(13));
        assert_eq!(pitch(Layout::Spans, 13), Some(16));
        assert_eq!(pitch(Layout::Spans, 16), Some(16));
        assert_eq!(pitch(Layout::Spans, 0), Some(0));
        assert_eq!(pitch(Layout::Spans, u32::MAX), None);
    }

    #[test]
    fn the_largest_binding_is_rows_offsets_fragments_or_keys() {
        assert_eq!(key_count(0), 1);
        assert_eq!(key_count(5), 8);
        assert_eq!(key_count(8), 8);
        // 10 pixels: rows 10 * 3 * 8 = 240 (HT 2: 3 slots), offsets 44.
        assert_eq!(band_bytes(Layers::Hybrid(2), 10, 0), 240);
        // 5 fragments: 160 bytes of fragments, 64 of keys.
        assert_eq!(band_bytes(Layers::Mlab(1), 1, 5), 160);
        assert_eq!(band_bytes(Layers::Mlab(1), 0, 0), 8);
    }

    #[test]
    fn a_frame_within_the_limit_is_one_band() {
        let frags = [at(0), at(30), at(5)];
        let plan = Plan::new(MLAB2, Layout::Spans, 1 << 20, (13, 3), &frags)
            .expect("plan")
            .expect("stored");
        assert_eq!((plan.pitch, plan.stored, plan.bands.clone()), (16, 48, vec![(0, 3)]));
        let band = plan.band(&frags, (0, 3));
        assert!(matches!(band.fragments, Cow::Borrowed(_)));
        assert_eq!((band.first, band.pixels, band.line), (0, 48, 16));
        assert_eq!(band.local(&frags[1]), 2 * 16 + 4);
        assert_eq!(band.to_input(vec![2, 0, 1]), vec![2, 0, 1]);
    }

    #[test]
    fn bands_hold_whole_lines_within_the_limit() {
        // 8 x 4 pixel-major, MLAB 2: 128 bytes of rows per line. Line 2 holds 10 fragments
        // (320 bytes of fragments), the others one or none.
        let mut frags: Vec<GpuFragment> = (0..10).map(|_| at(17)).collect();
        frags.insert(3, at(1));
        frags.push(at(31));
        let plan = |limit| Plan::new(MLAB2, Layout::PixelMajor, limit, (8, 4), &frags);
        assert_eq!(plan(1 << 20).expect("plan").expect("stored").bands, vec![(0, 4)]);
        // 330 bytes: lines 0-1 (256 bytes of rows), line 2 alone (lines 2-3: 11 fragments,
        // 352 bytes), line 3.
        let banded = plan(330).expect("plan").expect("stored");
        assert_eq!(banded.bands, vec![(0, 2), (2, 3), (3, 4)]);
        let limit = 300;
        let line_too_large = GpuError::LineTooLarge {
            y: 2,
            bytes: 320,
            limit,
        };
        assert_eq!(plan(limit), Err(line_too_large));
        // The last band's fragments, in submission order, with their indices in the input.
        let band = banded.band(&frags, (3, 4));
        assert_eq!(band.fragments.as_ref(), &[at(31)]);
        assert_eq!((band.first, band.pixels), (24, 8));
        assert_eq!(band.local(&frags[11]), 7);
        assert_eq!(band.to_input(vec![0]), vec![11]);
        assert_eq!(banded.band(&frags, (2, 3)).to_input(vec![0, 9]), vec![0, 10]);
    }

    #[test]
    fn every_fragment_is_validated_before_anything_is_planned() {
        let nan = GpuFragment::new(1, [0.0, 0.0, 0.0, f32::NAN], 1.0);
        let plan = Plan::new(MLAB2, Layout::Spans, 1 << 20, (4, 4), &[at(0), nan]);
        assert!(matches!(
            plan,
            Err(GpuError::Fragment {
                index: 1,
                error: FragmentError::NanAlpha
            })
        ));
        let plan = Plan::new(MLAB2, Layout::Spans, 1 << 20, (4, 4), &[at(16)]);
        assert_eq!(
            plan,
            Err(GpuError::PixelOutOfRange {
                index: 0,
                pixel: 16,
                pixels: 16
            })
        );
        // An empty frame: nothing to plan, and no fragment can be valid.
        assert_eq!(Plan::new(MLAB2, Layout::Spans, 1 << 20, (0, 4), &[]), Ok(None));
        assert!(Plan::new(MLAB2, Layout::Spans, 1 << 20, (0, 4), &[at(0)]).is_err());
        let too_large = GpuError::FrameTooLarge {
            width: 1 << 16,
            height: 1 << 16,
        };
        assert_eq!(
            Plan::new(MLAB2, Layout::Spans, 1 << 20, (1 << 16, 1 << 16), &[]),
            Err(too_large)
        );
    }

    #[test]
    fn a_key_is_kept_and_a_fragment_without_one_gets_none() {
        let keyed = validate(0, &at(0).with_key(7), 1).expect("valid");
        assert_eq!(keyed.key(), Some(7));
        assert_eq!(validate(0, &at(0), 1).expect("valid").key(), None);
    }
}
